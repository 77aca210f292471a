// Simulated turntable board firmware: speaks the Horus/Ciclop dialect (drivers/board.h) with the
// timing of a real stepper turntable, so the real board driver can be tested against it through
// a pty (termios transport) or an emulated USB device (libusb transport under umockdev).
// Thread-safe: the host side (pty pump, umockdev ioctl thread) and the simulated camera (which
// asks for the current angle and lasers) run on different threads.
#pragma once

#include <chrono>
#include <deque>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>

namespace scanmesh::sim {

//! Faults to inject. Command numbers count every command line received since power-on, from 1.
struct BoardFaults {
  int unplug_at_command = -1;     //!< the board vanishes when command N arrives
  int stall_at_command = -1;      //!< from command N on the IN endpoint stalls / the tty goes mute
  int drop_ok_at_command = -1;    //!< the "ok" to command N is never sent
  int garble_ok_at_command = -1;  //!< the "ok" to command N arrives garbled
  int hang_move_at_command = -1;  //!< command N (a move) never completes
  bool refuse_lasers = false;     //!< M70/M71 answer "error: laser driver fault"
};

struct SimBoardOptions {
  double time_scale = 1.0;   //!< 1: real time; 0.01: a 1 s move takes 10 ms
  double boot_time_s = 1.5;  //!< from reset to the banner (the Arduino bootloader)
  std::string banner = "Horus 0.2 ['$' for help]";
  int laser_count = 2;
  double max_feed_deg_per_s = 200.0;
  //! Microsteps per turn (200-step motor, 1/16 microstepping): positions are whole microsteps,
  //! so the same commanded angle always lands on the same position.
  int steps_per_revolution = 3200;
  //! Where the table physically stands at power-on (firmware coordinate 0). A resumed
  //! simulated scan starts where the interrupted one left the table.
  double initial_angle_rad = 0;
  BoardFaults faults;
};

class SimBoardFirmware {
 public:
  using Clock = std::chrono::steady_clock;
  explicit SimBoardFirmware(SimBoardOptions options = {});

  //! Power-on or DTR reset: state cleared, banner after the boot time.
  void reset();
  //! Bytes from the host.
  void receive(std::string_view bytes);
  //! Bytes the board has sent by now (removed from the queue).
  std::string transmit();
  bool has_output_ready() const;

  //! The turntable angle now (interpolated during a move), radians, and the laser bit mask.
  double angle_rad() const;
  unsigned laser_mask() const;
  bool motor_enabled() const;
  bool unplugged() const;
  bool stalled() const;
  int commands_received() const;
  //! G92 (set position) commands executed since the firmware object was made (resets too).
  int position_declarations() const;
  //! Changes the faults at run time (tests arm a fault after the connect handshake).
  void set_faults(const BoardFaults& faults);

 private:
  struct Pending {
    Clock::time_point when;
    std::string text;
  };
  void execute(const std::string& line, Clock::time_point now);
  void reply(const std::string& text, Clock::time_point when, int command_number);

  mutable std::mutex mutex_;
  SimBoardOptions options_;
  std::string input_;
  std::deque<Pending> output_;
  Clock::time_point busy_until_;
  int commands_ = 0;
  int position_declarations_ = 0;
  bool relative_ = false;
  bool motor_ = false;
  bool unplugged_ = false;
  bool stalled_ = false;
  unsigned lasers_ = 0;
  double feed_deg_per_s_ = 60.0;
  // The move in progress (or the last one), in microsteps of firmware coordinate.
  long long from_steps_ = 0, to_steps_ = 0, initial_steps_ = 0;
  Clock::time_point move_start_, move_end_;
  bool move_hangs_ = false;
};

}  // namespace scanmesh::sim
