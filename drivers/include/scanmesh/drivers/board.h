// The turntable board: a stepper turntable and up to a few line lasers behind a line protocol.
// The protocol is a BoardDialect (the Horus/Ciclop G-code dialect is built in; another board is
// one more file implementing BoardDialect, see docs/hardware.md); Board adds what every dialect
// shares: the connect handshake, acknowledgements, per-command timeouts and retries where a
// repeated command is harmless.
#pragma once

#include <chrono>
#include <memory>
#include <string>
#include <string_view>

#include "scanmesh/drivers/transport.h"

namespace scanmesh::drivers {

//! One line the board sent, classified.
struct BoardReply {
  enum class Kind { Ok, Error, Banner, Other };
  Kind kind = Kind::Other;
  std::string text;       //!< the line without surrounding whitespace
  int version_major = 0;  //!< Banner only
  int version_minor = 0;
};

//! How one board family spells its commands and replies. Every function is pure, so the reply
//! parser can be fuzzed (tests/fuzz/fuzz_board_reply.cpp).
class BoardDialect {
 public:
  virtual ~BoardDialect() = default;
  virtual std::string name() const = 0;
  //! Commands, without the line terminator.
  virtual std::string set_feed_rate(double deg_per_s) const = 0;
  virtual std::string absolute_mode() const = 0;
  virtual std::string relative_mode() const = 0;
  virtual std::string move(double degrees) const = 0;
  //! Declares the current position to be `degrees` without moving.
  virtual std::string set_position(double degrees) const = 0;
  virtual std::string laser(int index, bool on) const = 0;
  virtual std::string motor(bool enabled) const = 0;
  virtual std::string line_terminator() const { return "\r\n"; }
  //! Classifies one received line. Never throws.
  virtual BoardReply parse_reply(std::string_view line) const = 0;
  //! Whether a banner's firmware version is one this dialect speaks.
  virtual bool version_supported(const BoardReply& banner) const = 0;
};

//! Horus/Ciclop firmware (horus-fw, a grbl derivative): banner "Horus 0.2 ['$' for help]",
//! "G1 F<deg/s>", "G90"/"G91", "G1 X<deg>", "G92 X<deg>" (set position, grbl),
//! "M71 T<n>"/"M70 T<n>" (laser n on/off, n from 1),
//! "M17"/"M18", replies "ok" or "error: ...".
std::unique_ptr<BoardDialect> make_horus_dialect();

//! Free-function form of the Horus reply parser (the fuzz entry point calls it).
BoardReply parse_horus_reply(std::string_view line);

struct BoardOptions {
  std::chrono::milliseconds banner_timeout{3000};
  std::chrono::milliseconds command_timeout{1000};  //!< non-moving commands
  double move_timeout_margin = 3.0;  //!< a move may take this many times its nominal duration
  std::chrono::milliseconds move_timeout_floor{2000};
  int retries = 2;  //!< for commands that are safe to repeat
  double feed_rate_deg_per_s = 90.0;
};

class Board {
 public:
  Board(std::unique_ptr<Transport> transport, std::unique_ptr<BoardDialect> dialect,
        BoardOptions options = {});
  //! Waits for the banner and checks the firmware version, then sets feed rate and absolute
  //! mode and enables the motor. Throws DeviceError (no banner, unsupported version, errors).
  void connect();
  //! Turns the table to `angle_rad` (absolute, from the connect position) and waits for the
  //! board's acknowledgement, which Horus sends once the move is complete.
  void move_to(double angle_rad);
  //! Relative move by `delta_rad`; never retried (a repeat would turn twice).
  void move_by(double delta_rad);
  //! Declares that the table stands at `angle_rad` now (the firmware forgets its position on
  //! reset). Used when resuming a scan. The firmware's own coordinate is set, not an offset in
  //! the driver: the firmware rounds every absolute target to whole motor steps, and only with
  //! the same coordinates does a resumed scan land on the same steps as an uninterrupted one.
  void declare_position(double angle_rad);
  void set_laser(int index, bool on);
  void set_motor(bool enabled);
  void set_feed_rate(double deg_per_s);
  //! Lasers off and motor released; errors are swallowed (used on the way out of a failure).
  //! One attempt per command; after the first that meets silence the rest are sent without
  //! waiting, so a dead board holds the caller one command timeout, not nine.
  void shutdown() noexcept;
  double angle_rad() const { return angle_rad_; }
  std::string device_name() const { return transport_->name(); }
  const BoardDialect& dialect() const { return *dialect_; }
  std::string firmware_banner() const { return banner_; }

 private:
  enum class Retry { Safe, Never };
  void command(const std::string& text, std::chrono::milliseconds timeout, Retry retry);
  //! One send and wait: an "ok", a garbled reply, or nothing within `timeout` (`problem` then
  //! says which). An "error:" reply throws.
  enum class Attempt { Ok, Garbled, Silent };
  Attempt attempt(const std::string& text, std::chrono::milliseconds timeout,
                  std::string& problem);
  std::chrono::milliseconds move_timeout(double degrees) const;

  std::unique_ptr<Transport> transport_;
  std::unique_ptr<BoardDialect> dialect_;
  BoardOptions options_;
  std::string banner_;
  double angle_rad_ = 0;
  bool relative_ = false;
};

}  // namespace scanmesh::drivers
