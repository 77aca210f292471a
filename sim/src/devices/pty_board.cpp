#include "scanmesh/sim/pty_board.h"

#include <fcntl.h>
#include <poll.h>
#include <pty.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace scanmesh::sim {

PtyBoard::PtyBoard(SimBoardOptions options)
    : firmware_(std::make_shared<SimBoardFirmware>(std::move(options))) {
  char name[256] = {};
  termios tio{};
  ::cfmakeraw(&tio);
  if (::openpty(&master_, &slave_keepalive_, name, &tio, nullptr) != 0)
    throw std::runtime_error(std::string("openpty failed: ") + std::strerror(errno));
  ::fcntl(master_, F_SETFL, ::fcntl(master_, F_GETFL) | O_NONBLOCK);
  slave_path_ = name;
  thread_ = std::thread([this] { pump(); });
}

PtyBoard::~PtyBoard() {
  stop_ = true;
  if (thread_.joinable()) thread_.join();
  if (master_ >= 0) ::close(master_);
  if (slave_keepalive_ >= 0) ::close(slave_keepalive_);
}

void PtyBoard::pump() {
  char buffer[512];
  while (!stop_) {
    if (firmware_->unplugged()) {
      // Pulling the cable: the master goes away and the slave sees a hang-up (EIO on read).
      // The keep-alive slave descriptor must go too, or the kernel keeps the line up.
      if (master_ >= 0) ::close(master_);
      if (slave_keepalive_ >= 0) ::close(slave_keepalive_);
      master_ = slave_keepalive_ = -1;
      return;
    }
    pollfd p{master_, POLLIN, 0};
    ::poll(&p, 1, 1);
    if (p.revents & POLLIN) {
      const ssize_t n = ::read(master_, buffer, sizeof buffer);
      if (n > 0) firmware_->receive(std::string_view(buffer, static_cast<std::size_t>(n)));
    }
    const std::string out = firmware_->transmit();
    std::size_t done = 0;
    while (done < out.size() && !stop_) {
      const ssize_t n = ::write(master_, out.data() + done, out.size() - done);
      if (n > 0)
        done += static_cast<std::size_t>(n);
      else if (n < 0 && errno != EAGAIN && errno != EINTR)
        break;
    }
  }
}

}  // namespace scanmesh::sim
