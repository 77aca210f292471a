#include "cli_support.h"

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <iostream>
#include <new>

#include "scanmesh/core/errors.h"

namespace scanmesh::cli {

namespace {

// The number in `text`, or NaN when it is not one (the option's own parser reports that).
double parse_number(const std::string& text) {
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  return end == text.c_str() ? std::nan("") : v;
}

std::string short_number(double v) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%g", v);
  return buffer;
}

CLI::Validator bounded(double lo, double hi, bool open_below) {
  const std::string range = (open_below ? "(" : "[") + short_number(lo) + ", " +
                            short_number(hi) + "]";
  return CLI::Validator(
      [lo, hi, open_below, range](std::string& text) -> std::string {
        const double v = parse_number(text);
        const bool ok = std::isfinite(v) && (open_below ? v > lo : v >= lo) && v <= hi;
        return ok ? std::string() : "value " + text + " is not in " + range;
      },
      "in " + range);
}

}  // namespace

void require_in_range(const std::string& option, double value, double lo, double hi) {
  if (std::isfinite(value) && value >= lo && value <= hi) return;
  throw InvalidInputError(option + " must be in [" + short_number(lo) + ", " + short_number(hi) +
                          "], not " + short_number(value));
}

CLI::Validator in_range(double lo, double hi) { return bounded(lo, hi, false); }
CLI::Validator above(double lo, double hi) { return bounded(lo, hi, true); }

int run_guarded(const std::function<int()>& command) {
  try {
    return command();
  } catch (const FileFormatError& e) {
    std::cerr << "scanmesh: bad file: " << e.what() << "\n";
    return kBadFile;
  } catch (const InvalidInputError& e) {
    std::cerr << "scanmesh: invalid input: " << e.what() << "\n";
    return kInvalidInput;
  } catch (const IoError& e) {
    std::cerr << "scanmesh: I/O error: " << e.what() << "\n";
    return kIoFailure;
  } catch (const DeviceError& e) {
    std::cerr << "scanmesh: device error: " << e.what() << "\n";
    return kDeviceFailure;
  } catch (const std::bad_alloc&) {
    std::cerr << "scanmesh: out of memory\n";
    return kInternalError;
  } catch (const std::exception& e) {
    std::cerr << "scanmesh: internal error: " << e.what() << "\n";
    return kInternalError;
  }
}

Progress::Progress(std::string label)
    : label_(std::move(label)), enabled_(isatty(STDERR_FILENO) == 1) {}

Progress::~Progress() { finish(); }

void Progress::update(int done, int total) {
  if (!enabled_ || finished_ || total <= 0) return;
  const int percent = static_cast<int>(100LL * done / total);
  if (percent == last_percent_) return;
  last_percent_ = percent;
  constexpr int kWidth = 30;
  const int filled = kWidth * percent / 100;
  std::fprintf(stderr, "\r%-14s [%s%s] %3d%%", label_.c_str(), std::string(filled, '#').c_str(),
               std::string(kWidth - filled, '.').c_str(), percent);
  std::fflush(stderr);
}

void Progress::finish() {
  if (!enabled_ || finished_) return;
  finished_ = true;
  if (last_percent_ >= 0) std::fprintf(stderr, "\n");
}

}  // namespace scanmesh::cli
