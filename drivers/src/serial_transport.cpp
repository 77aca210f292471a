#include "scanmesh/drivers/serial_transport.h"

#include <fcntl.h>
#include <poll.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "scanmesh/core/errors.h"

namespace scanmesh::drivers {
namespace {

speed_t baud_constant(int baud) {
  switch (baud) {
    case 9600:
      return B9600;
    case 19200:
      return B19200;
    case 38400:
      return B38400;
    case 57600:
      return B57600;
    case 115200:
      return B115200;
    case 230400:
      return B230400;
    case 250000:
      return B230400;  // not a termios constant; see docs/hardware.md
    default:
      return 0;
  }
}

std::string errno_text(int e) { return std::strerror(e); }

class SerialTransport final : public Transport {
 public:
  SerialTransport(std::string path, int fd) : path_(std::move(path)), fd_(fd) {}
  ~SerialTransport() override { close(); }

  void write(std::string_view bytes) override {
    check_open();
    std::size_t done = 0;
    while (done < bytes.size()) {
      const ssize_t n = ::write(fd_, bytes.data() + done, bytes.size() - done);
      if (n < 0) {
        if (errno == EINTR) continue;
        if (errno == EAGAIN) {
          pollfd p{fd_, POLLOUT, 0};
          if (::poll(&p, 1, 1000) <= 0) throw DeviceError(path_, "write stalled for 1000 ms");
          continue;
        }
        fail("write failed", errno);
      }
      done += static_cast<std::size_t>(n);
    }
  }

  std::optional<std::string> read_line(std::chrono::milliseconds timeout) override {
    check_open();
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    for (;;) {
      if (auto line = lines_.pop_line()) return line;
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
          deadline - std::chrono::steady_clock::now());
      if (left.count() <= 0) return std::nullopt;
      pollfd p{fd_, POLLIN, 0};
      const int r = ::poll(&p, 1, static_cast<int>(left.count()));
      if (r < 0) {
        if (errno == EINTR) continue;
        fail("poll failed", errno);
      }
      if (r == 0) return std::nullopt;
      if (p.revents & (POLLHUP | POLLERR | POLLNVAL)) {
        // A pty master that closed or a USB serial adapter that was pulled.
        if (!(p.revents & POLLIN)) throw DeviceError(path_, "unplugged (hang-up on the tty)");
      }
      char buffer[512];
      const ssize_t n = ::read(fd_, buffer, sizeof buffer);
      if (n < 0) {
        if (errno == EINTR || errno == EAGAIN) continue;
        if (errno == EIO || errno == ENODEV || errno == ENXIO)
          throw DeviceError(path_, "unplugged (" + errno_text(errno) + ")");
        fail("read failed", errno);
      }
      if (n == 0) throw DeviceError(path_, "unplugged (end of file on the tty)");
      lines_.append(std::string_view(buffer, static_cast<std::size_t>(n)));
      if (lines_.size() > (1u << 16)) throw DeviceError(path_, "line longer than 64 KiB");
    }
  }

  void discard_input() override {
    lines_.clear();
    if (fd_ >= 0) ::tcflush(fd_, TCIFLUSH);
  }

  void close() override {
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
  }

  std::string name() const override { return path_; }

 private:
  void check_open() const {
    if (fd_ < 0) throw DeviceError(path_, "transport is closed");
  }
  [[noreturn]] void fail(const std::string& what, int e) const {
    throw DeviceError(path_, what + ": " + errno_text(e));
  }

  std::string path_;
  int fd_;
  LineBuffer lines_;
};

}  // namespace

std::unique_ptr<Transport> open_serial_transport(const std::string& path, int baud) {
  const speed_t speed = baud_constant(baud);
  if (speed == 0) throw InvalidInputError("unsupported baud rate " + std::to_string(baud));
  const int flags = O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC;  // non-atomic: a tty, not a file
  const int fd = ::open(path.c_str(), flags);
  if (fd < 0) {
    const int e = errno;
    std::string problem = "cannot open: " + errno_text(e);
    if (e == EACCES) problem += " (install configs/udev/60-scanmesh.rules, see docs/hardware.md)";
    if (e == EBUSY) problem = "busy: another program has it open";
    throw DeviceError(path, problem);
  }
  termios tio{};
  if (::tcgetattr(fd, &tio) != 0) {
    const int e = errno;
    ::close(fd);
    throw DeviceError(path, "not a serial port (tcgetattr: " + errno_text(e) + ")");
  }
  ::cfmakeraw(&tio);
  tio.c_cflag |= CLOCAL | CREAD;
  tio.c_cflag &= ~(CSTOPB | PARENB | CRTSCTS);
  tio.c_cc[VMIN] = 0;
  tio.c_cc[VTIME] = 0;
  ::cfsetispeed(&tio, speed);
  ::cfsetospeed(&tio, speed);
  if (::tcsetattr(fd, TCSANOW, &tio) != 0) {
    const int e = errno;
    ::close(fd);
    throw DeviceError(path, "cannot configure the tty: " + errno_text(e));
  }
  return std::make_unique<SerialTransport>(path, fd);
}

}  // namespace scanmesh::drivers
