// The simulated board firmware behind a pseudo-terminal: the real termios transport opens
// slave_path() exactly as it would open /dev/ttyACM0. A pump thread moves bytes between the pty
// master and the firmware. Unplugging closes the master, which the slave side sees as a hang-up.
#pragma once

#include <atomic>
#include <memory>
#include <string>
#include <thread>

#include "scanmesh/sim/board_firmware.h"

namespace scanmesh::sim {

class PtyBoard {
 public:
  explicit PtyBoard(SimBoardOptions options = {});
  ~PtyBoard();
  PtyBoard(const PtyBoard&) = delete;
  PtyBoard& operator=(const PtyBoard&) = delete;

  //! "/dev/pts/N"; open it with drivers::open_serial_transport.
  const std::string& slave_path() const { return slave_path_; }
  SimBoardFirmware& firmware() { return *firmware_; }
  const std::shared_ptr<SimBoardFirmware>& shared_firmware() const { return firmware_; }

 private:
  void pump();
  std::shared_ptr<SimBoardFirmware> firmware_;
  int master_ = -1;
  int slave_keepalive_ = -1;
  std::string slave_path_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

}  // namespace scanmesh::sim
