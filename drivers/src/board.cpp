#include "scanmesh/drivers/board.h"

#include <cmath>
#include <cstdio>
#include <numbers>
#include <sstream>

#include "scanmesh/core/errors.h"

namespace scanmesh::drivers {

std::optional<std::string> LineBuffer::pop_line() {
  const auto nl = pending_.find('\n');
  if (nl == std::string::npos) return std::nullopt;
  std::string line = pending_.substr(0, nl);
  pending_.erase(0, nl + 1);
  while (!line.empty() && (line.back() == '\r' || line.back() == '\0')) line.pop_back();
  return line;
}

namespace {

std::string_view trim(std::string_view s) {
  while (!s.empty() && static_cast<unsigned char>(s.front()) <= ' ') s.remove_prefix(1);
  while (!s.empty() && static_cast<unsigned char>(s.back()) <= ' ') s.remove_suffix(1);
  return s;
}

// Formats a number the way G-code expects: '.' decimal point whatever the locale, no exponent.
std::string gcode_number(double v) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.4f", v);
  std::string s = buffer;
  while (s.size() > 1 && s.back() == '0') s.pop_back();
  if (s.back() == '.') s.pop_back();
  if (s == "-0") s = "0";
  return s;
}

class HorusDialect final : public BoardDialect {
 public:
  std::string name() const override { return "horus"; }
  std::string set_feed_rate(double deg_per_s) const override {
    return "G1 F" + gcode_number(deg_per_s);
  }
  std::string absolute_mode() const override { return "G90"; }
  std::string relative_mode() const override { return "G91"; }
  std::string move(double degrees) const override { return "G1 X" + gcode_number(degrees); }
  std::string set_position(double degrees) const override {
    return "G92 X" + gcode_number(degrees);
  }
  std::string laser(int index, bool on) const override {
    return std::string(on ? "M71" : "M70") + " T" + std::to_string(index + 1);
  }
  std::string motor(bool enabled) const override { return enabled ? "M17" : "M18"; }
  BoardReply parse_reply(std::string_view line) const override { return parse_horus_reply(line); }
  bool version_supported(const BoardReply& banner) const override {
    return banner.kind == BoardReply::Kind::Banner && banner.version_major == 0 &&
           banner.version_minor >= 1 && banner.version_minor <= 2;
  }
};

}  // namespace

BoardReply parse_horus_reply(std::string_view line) {
  BoardReply reply;
  const std::string_view t = trim(line);
  reply.text = std::string(t);
  if (t == "ok") {
    reply.kind = BoardReply::Kind::Ok;
  } else if (t.starts_with("error")) {
    reply.kind = BoardReply::Kind::Error;
  } else if (t.starts_with("Horus ")) {
    // "Horus <major>.<minor> ['$' for help]"
    std::string_view v = t.substr(6);
    int major = 0, minor = 0, digits = 0;
    std::size_t i = 0;
    for (; i < v.size() && v[i] >= '0' && v[i] <= '9' && digits < 4; ++i, ++digits)
      major = major * 10 + (v[i] - '0');
    if (digits == 0 || i >= v.size() || v[i] != '.') return reply;
    ++i;
    digits = 0;
    for (; i < v.size() && v[i] >= '0' && v[i] <= '9' && digits < 4; ++i, ++digits)
      minor = minor * 10 + (v[i] - '0');
    if (digits == 0) return reply;
    reply.kind = BoardReply::Kind::Banner;
    reply.version_major = major;
    reply.version_minor = minor;
  }
  return reply;
}

std::unique_ptr<BoardDialect> make_horus_dialect() { return std::make_unique<HorusDialect>(); }

Board::Board(std::unique_ptr<Transport> transport, std::unique_ptr<BoardDialect> dialect,
             BoardOptions options)
    : transport_(std::move(transport)), dialect_(std::move(dialect)), options_(options) {
  if (!transport_ || !dialect_) throw InvalidInputError("Board needs a transport and a dialect");
}

void Board::connect() {
  const auto deadline = std::chrono::steady_clock::now() + options_.banner_timeout;
  for (;;) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0)
      throw DeviceError(transport_->name(), "no firmware banner within " +
                                                std::to_string(options_.banner_timeout.count()) +
                                                " ms (is this a " + dialect_->name() +
                                                " board, at the right baud rate?)");
    const auto line = transport_->read_line(left);
    if (!line) continue;
    const BoardReply reply = dialect_->parse_reply(*line);
    if (reply.kind != BoardReply::Kind::Banner) continue;  // boot noise before the banner
    if (!dialect_->version_supported(reply))
      throw DeviceError(transport_->name(), "unsupported firmware version '" + reply.text +
                                                "' for the " + dialect_->name() + " dialect");
    banner_ = reply.text;
    break;
  }
  set_feed_rate(options_.feed_rate_deg_per_s);
  command(dialect_->absolute_mode(), options_.command_timeout, Retry::Safe);
  relative_ = false;
  set_motor(true);
}

std::chrono::milliseconds Board::move_timeout(double degrees) const {
  const double nominal_s = std::abs(degrees) / std::max(options_.feed_rate_deg_per_s, 1e-6);
  const auto t = std::chrono::milliseconds(
      static_cast<long long>(nominal_s * options_.move_timeout_margin * 1e3));
  return std::max(t, options_.move_timeout_floor);
}

void Board::move_to(double angle_rad) {
  if (!std::isfinite(angle_rad)) throw InvalidInputError("turntable angle must be finite");
  if (relative_) {
    command(dialect_->absolute_mode(), options_.command_timeout, Retry::Safe);
    relative_ = false;
  }
  const double degrees = angle_rad * 180.0 / std::numbers::pi;
  const double delta = (angle_rad - angle_rad_) * 180.0 / std::numbers::pi;
  // An absolute move is idempotent: repeating it after a lost "ok" cannot turn the table twice.
  command(dialect_->move(degrees), move_timeout(delta), Retry::Safe);
  angle_rad_ = angle_rad;
}

void Board::move_by(double delta_rad) {
  if (!std::isfinite(delta_rad)) throw InvalidInputError("turntable angle must be finite");
  if (!relative_) {
    command(dialect_->relative_mode(), options_.command_timeout, Retry::Safe);
    relative_ = true;
  }
  const double degrees = delta_rad * 180.0 / std::numbers::pi;
  command(dialect_->move(degrees), move_timeout(degrees), Retry::Never);
  angle_rad_ += delta_rad;
}

void Board::declare_position(double angle_rad) {
  if (!std::isfinite(angle_rad)) throw InvalidInputError("turntable angle must be finite");
  command(dialect_->set_position(angle_rad * 180.0 / std::numbers::pi), options_.command_timeout,
          Retry::Safe);
  angle_rad_ = angle_rad;
}

void Board::set_laser(int index, bool on) {
  if (index < 0 || index > 8) throw InvalidInputError("laser index must be 0..8");
  command(dialect_->laser(index, on), options_.command_timeout, Retry::Safe);
}

void Board::set_motor(bool enabled) {
  command(dialect_->motor(enabled), options_.command_timeout, Retry::Safe);
}

void Board::set_feed_rate(double deg_per_s) {
  if (!(deg_per_s > 0) || !std::isfinite(deg_per_s))
    throw InvalidInputError("feed rate must be positive");
  options_.feed_rate_deg_per_s = deg_per_s;
  command(dialect_->set_feed_rate(deg_per_s), options_.command_timeout, Retry::Safe);
}

void Board::shutdown() noexcept {
  // Each command on its own: a board with one laser refuses "laser 2", which must not keep the
  // motor from being released. One attempt each, and once a command met silence (the usual
  // reason to shut down early: the board stalled or hangs in a move) the rest are only sent:
  // waiting out three attempts of three commands kept a user ~27 s at a dead board.
  bool silent = false;
  for (const std::string& text :
       {dialect_->laser(0, false), dialect_->laser(1, false), dialect_->motor(false)}) {
    try {
      if (silent) {
        transport_->write(text + dialect_->line_terminator());
        continue;
      }
      // A garbled reply means a live board that may not have switched: that one is repeated.
      std::string problem;
      Attempt result = Attempt::Garbled;
      for (int i = 0; i <= options_.retries && result == Attempt::Garbled; ++i) {
        if (i > 0) transport_->discard_input();
        result = attempt(text, options_.command_timeout, problem);
      }
      silent = result == Attempt::Silent;
    } catch (...) {
    }
  }
}

Board::Attempt Board::attempt(const std::string& text, std::chrono::milliseconds timeout,
                              std::string& problem) {
  transport_->write(text + dialect_->line_terminator());
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) break;
    const auto line = transport_->read_line(left);
    if (!line) break;
    const BoardReply reply = dialect_->parse_reply(*line);
    if (reply.kind == BoardReply::Kind::Ok) return Attempt::Ok;
    if (reply.kind == BoardReply::Kind::Error)
      throw DeviceError(transport_->name(), "board refused '" + text + "': " + reply.text);
    if (reply.kind == BoardReply::Kind::Other && !reply.text.empty()) {
      // Neither ok nor error: a garbled acknowledgement. Whether the command ran is unknown.
      problem = "garbled reply '" + reply.text.substr(0, 40) + "' to '" + text + "'";
      return Attempt::Garbled;
    }
  }
  problem = "no 'ok' for '" + text + "' within " + std::to_string(timeout.count()) + " ms";
  return Attempt::Silent;
}

void Board::command(const std::string& text, std::chrono::milliseconds timeout, Retry retry) {
  const int attempts = retry == Retry::Safe ? 1 + std::max(0, options_.retries) : 1;
  std::string last_problem;
  for (int i = 0; i < attempts; ++i) {
    if (i > 0) transport_->discard_input();
    if (attempt(text, timeout, last_problem) == Attempt::Ok) return;
  }
  throw DeviceError(
      transport_->name(),
      last_problem + (attempts > 1 ? " (after " + std::to_string(attempts) + " attempts)"
                                   : " (not retried: repeating it is unsafe)"));
}

}  // namespace scanmesh::drivers
