#include "scanmesh/sim/board_firmware.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <numbers>

namespace scanmesh::sim {
namespace {

std::string upper_trimmed(std::string_view s) {
  std::string out;
  for (char c : s)
    if (c != '\r' && c != ' ' && c != '\t')
      out += static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return out;
}

// Parses the number after `key` in a compact G-code word list ("G1X12.5F30"). nullopt if absent
// or malformed.
std::optional<double> word(const std::string& cmd, char key, std::size_t from) {
  const auto p = cmd.find(key, from);
  if (p == std::string::npos) return std::nullopt;
  const char* begin = cmd.c_str() + p + 1;
  char* end = nullptr;
  const double v = std::strtod(begin, &end);
  if (end == begin || !std::isfinite(v)) return std::nullopt;
  return v;
}

}  // namespace

SimBoardFirmware::SimBoardFirmware(SimBoardOptions options) : options_(std::move(options)) {
  reset();
}

void SimBoardFirmware::reset() {
  std::lock_guard lock(mutex_);
  const auto now = Clock::now();
  input_.clear();
  output_.clear();
  relative_ = false;
  motor_ = false;
  lasers_ = 0;
  from_steps_ = to_steps_ = 0;
  initial_steps_ = std::llround(options_.initial_angle_rad / (2 * std::numbers::pi) *
                                options_.steps_per_revolution);
  move_start_ = move_end_ = now;
  move_hangs_ = false;
  const auto boot = std::chrono::duration_cast<Clock::duration>(
      std::chrono::duration<double>(options_.boot_time_s * options_.time_scale));
  busy_until_ = now + boot;
  output_.push_back({busy_until_, options_.banner + "\r\n"});
}

void SimBoardFirmware::set_faults(const BoardFaults& faults) {
  std::lock_guard lock(mutex_);
  options_.faults = faults;
}

void SimBoardFirmware::receive(std::string_view bytes) {
  std::lock_guard lock(mutex_);
  if (unplugged_) return;
  input_.append(bytes);
  const auto now = Clock::now();
  for (;;) {
    const auto nl = input_.find('\n');
    if (nl == std::string::npos) break;
    const std::string line = input_.substr(0, nl);
    input_.erase(0, nl + 1);
    execute(line, now);
    if (unplugged_) break;
  }
  if (input_.size() > 4096) input_.clear();  // the real firmware's line buffer overflows too
}

void SimBoardFirmware::reply(const std::string& text, Clock::time_point when, int n) {
  const BoardFaults& f = options_.faults;
  if (n == f.drop_ok_at_command && text == "ok") return;
  std::string t = text;
  if (n == f.garble_ok_at_command && text == "ok") t = "o\x7f#k";
  output_.push_back({when, t + "\r\n"});
}

void SimBoardFirmware::execute(const std::string& raw, Clock::time_point now) {
  const std::string cmd = upper_trimmed(raw);
  if (cmd.empty()) return;
  const int n = ++commands_;
  const BoardFaults& f = options_.faults;
  if (n == f.unplug_at_command) {
    unplugged_ = true;
    output_.clear();
    return;
  }
  if (f.stall_at_command > 0 && n >= f.stall_at_command) stalled_ = true;
  // A move that never completes leaves the firmware stuck in its stepping loop: it reads
  // nothing more until it is reset.
  if (move_hangs_) return;
  // Commands execute one after another: a command that arrives during a move is answered
  // after the move (grbl's planner with a depth of one).
  const auto start = std::max(now, busy_until_);
  const auto respond = [&](const std::string& text) { reply(text, start, n); };

  if (cmd.starts_with("G1") || cmd.starts_with("G0")) {
    if (const auto fr = word(cmd, 'F', 2)) {
      if (*fr <= 0 || *fr > options_.max_feed_deg_per_s) {
        respond("error: feed rate out of range");
        return;
      }
      feed_deg_per_s_ = *fr;
    }
    if (cmd.find('X') != std::string::npos) {
      const auto x = word(cmd, 'X', 2);
      if (!x) {
        respond("error: bad number");
        return;
      }
      if (!motor_) {
        respond("error: motor disabled");
        return;
      }
      // Position at `start` (the previous move is over by then unless it hangs).
      const double steps_per_deg = options_.steps_per_revolution / 360.0;
      const long long from = to_steps_;
      const long long to =
          relative_ ? from + std::llround(*x * steps_per_deg) : std::llround(*x * steps_per_deg);
      const double seconds = std::abs(static_cast<double>(to - from)) / steps_per_deg /
                             feed_deg_per_s_ * options_.time_scale;
      from_steps_ = from;
      to_steps_ = to;
      move_start_ = start;
      move_end_ = start + std::chrono::duration_cast<Clock::duration>(
                              std::chrono::duration<double>(seconds));
      if (n == f.hang_move_at_command) {
        // The stepper stalls halfway and the firmware never reports completion.
        move_hangs_ = true;
        to_steps_ = from + (to - from) / 2;
        busy_until_ = Clock::time_point::max();
        return;
      }
      busy_until_ = move_end_;
      reply("ok", move_end_, n);
      return;
    }
    respond("ok");
    return;
  }
  if (cmd.starts_with("G92")) {
    // Set position (grbl): the coordinate becomes X without moving the table.
    const auto x = word(cmd, 'X', 3);
    if (!x) {
      respond("error: bad number");
      return;
    }
    const long long physical = initial_steps_ + to_steps_;
    to_steps_ = from_steps_ = std::llround(*x * options_.steps_per_revolution / 360.0);
    initial_steps_ = physical - to_steps_;
    ++position_declarations_;
    respond("ok");
    return;
  }
  if (cmd == "G90" || cmd == "G91") {
    relative_ = cmd == "G91";
    respond("ok");
    return;
  }
  if (cmd.starts_with("M70") || cmd.starts_with("M71")) {
    const auto t = word(cmd, 'T', 3);
    const int index = t ? static_cast<int>(*t) : 0;
    if (!t || index < 1 || index > options_.laser_count) {
      respond("error: no laser T" + (t ? std::to_string(index) : std::string("?")));
      return;
    }
    if (f.refuse_lasers) {
      respond("error: laser driver fault");
      return;
    }
    const unsigned bit = 1u << (index - 1);
    lasers_ = cmd.starts_with("M71") ? (lasers_ | bit) : (lasers_ & ~bit);
    respond("ok");
    return;
  }
  if (cmd == "M17" || cmd == "M18") {
    motor_ = cmd == "M17";
    respond("ok");
    return;
  }
  if (cmd == "$") {
    respond("Horus firmware, simulated");
    respond("ok");
    return;
  }
  respond("error: unknown command '" + raw.substr(0, 32) + "'");
}

std::string SimBoardFirmware::transmit() {
  std::lock_guard lock(mutex_);
  std::string out;
  if (unplugged_ || stalled_) return out;
  const auto now = Clock::now();
  while (!output_.empty() && output_.front().when <= now) {
    out += output_.front().text;
    output_.pop_front();
  }
  return out;
}

bool SimBoardFirmware::has_output_ready() const {
  std::lock_guard lock(mutex_);
  return !unplugged_ && !stalled_ && !output_.empty() && output_.front().when <= Clock::now();
}

double SimBoardFirmware::angle_rad() const {
  std::lock_guard lock(mutex_);
  const auto now = Clock::now();
  double steps = static_cast<double>(initial_steps_ + to_steps_);
  if (!move_hangs_ && now < move_end_ && move_end_ > move_start_) {
    const double u = now <= move_start_
                         ? 0.0
                         : std::chrono::duration<double>(now - move_start_).count() /
                               std::chrono::duration<double>(move_end_ - move_start_).count();
    steps = static_cast<double>(initial_steps_ + from_steps_) +
            static_cast<double>(to_steps_ - from_steps_) * u;
  }
  return steps * 2 * std::numbers::pi / options_.steps_per_revolution;
}

unsigned SimBoardFirmware::laser_mask() const {
  std::lock_guard lock(mutex_);
  return lasers_;
}
bool SimBoardFirmware::motor_enabled() const {
  std::lock_guard lock(mutex_);
  return motor_;
}
bool SimBoardFirmware::unplugged() const {
  std::lock_guard lock(mutex_);
  return unplugged_;
}
bool SimBoardFirmware::stalled() const {
  std::lock_guard lock(mutex_);
  return stalled_;
}
int SimBoardFirmware::position_declarations() const {
  std::lock_guard lock(mutex_);
  return position_declarations_;
}

int SimBoardFirmware::commands_received() const {
  std::lock_guard lock(mutex_);
  return commands_;
}

}  // namespace scanmesh::sim
