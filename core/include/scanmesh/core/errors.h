// Typed errors of scanmesh. Every module boundary throws one of these; the CLI maps each type
// to its own exit code (docs/cli.md) and prints the message as one line on stderr.
#pragma once

#include <filesystem>
#include <stdexcept>
#include <string>

namespace scanmesh {

//! Base of all scanmesh errors; `what()` is a sentence a user can act on.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

//! A parameter or configuration value is impossible (negative size, unknown option, ...).
class InvalidInputError : public Error {
 public:
  using Error::Error;
};

//! A file exists but its content is malformed, truncated, corrupt or inconsistent.
//! The message always names the file.
class FileFormatError : public Error {
 public:
  FileFormatError(const std::filesystem::path& file, const std::string& problem)
      : Error(file.string() + ": " + problem), file_(file) {}
  const std::filesystem::path& file() const { return file_; }

 private:
  std::filesystem::path file_;
};

//! The operating system refused a read or write (missing file, permission, disk full).
class IoError : public Error {
 public:
  using Error::Error;
};

//! A device (camera, turntable board) failed, vanished, stalled or answered nonsense. The
//! message names the device (path, bus:address or VID:PID) and, in a scan, the step.
class DeviceError : public Error {
 public:
  DeviceError(const std::string& device, const std::string& problem)
      : Error(device + ": " + problem), device_(device) {}
  const std::string& device() const { return device_; }

 private:
  std::string device_;
};

//! A number for a message: "%g" (six significant digits; 1e+300 instead of 301 digits).
std::string format_number(double value);

}  // namespace scanmesh
