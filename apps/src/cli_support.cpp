#include "cli_support.h"

#include <unistd.h>

#include <cstdio>
#include <exception>
#include <iostream>
#include <new>

#include "scanmesh/core/errors.h"

namespace scanmesh::cli {

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
