#include "cli_support.h"

#include <unistd.h>

#include <charconv>
#include <cmath>
#include <cstdarg>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <iostream>
#include <new>
#include <streambuf>

#include "scanmesh/core/errors.h"

namespace scanmesh::cli {

namespace {

// The number in `text`, or NaN when it is not one (the option's own parser reports that).
double parse_number(const std::string& text) {
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  return end == text.c_str() ? std::nan("") : v;
}

CLI::Validator bounded(double lo, double hi, bool open_below) {
  const std::string range =
      (open_below ? "(" : "[") + format_number(lo) + ", " + format_number(hi) + "]";
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
  throw InvalidInputError(option + " must be in [" + format_number(lo) + ", " + format_number(hi) +
                          "], not " + format_number(value));
}

CLI::Validator in_range(double lo, double hi) { return bounded(lo, hi, false); }
CLI::Validator above(double lo, double hi) { return bounded(lo, hi, true); }
CLI::Validator seed_range() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        // Digits only: CLI11 would wrap "-1" round to 2^64 - 1 without a word.
        const bool digits = !text.empty() && text.size() <= 20 &&
                            text.find_first_not_of("0123456789") == std::string::npos;
        std::uint64_t v = 0;
        const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), v);
        return digits && error == std::errc() && end == text.data() + text.size()
                   ? std::string()
                   : "value " + text + " is not a whole number from 0 to 18446744073709551615";
      },
      "whole number >= 0");
}

namespace {

OutputMode g_output_mode = OutputMode::Text;

// A stream that drops everything (the text of --json and --quiet runs).
class NullBuffer : public std::streambuf {
 protected:
  int overflow(int c) override { return traits_type::not_eof(c); }
  std::streamsize xsputn(const char*, std::streamsize n) override { return n; }
};

// One line on stderr, and the same words in the JSON result.
int fail(ExitCode code, const std::string& what) {
  std::cerr << "scanmesh: " << what << "\n";
  result()["error"] = what;
  return code;
}

int run_mapped(const std::function<int()>& command) {
  try {
    return command();
  } catch (const FileFormatError& e) {
    return fail(kBadFile, std::string("bad file: ") + e.what());
  } catch (const InvalidInputError& e) {
    return fail(kInvalidInput, std::string("invalid input: ") + e.what());
  } catch (const IoError& e) {
    return fail(kIoFailure, std::string("I/O error: ") + e.what());
  } catch (const DeviceError& e) {
    return fail(kDeviceFailure, std::string("device error: ") + e.what());
  } catch (const std::bad_alloc&) {
    return fail(kInternalError, "out of memory");
  } catch (const std::exception& e) {
    return fail(kInternalError, std::string("internal error: ") + e.what());
  }
}

}  // namespace

void set_output_mode(OutputMode mode) { g_output_mode = mode; }
OutputMode output_mode() { return g_output_mode; }

std::ostream& say() {
  static NullBuffer null_buffer;
  static std::ostream null_stream(&null_buffer);
  return g_output_mode == OutputMode::Text ? std::cout : null_stream;
}

void sayf(const char* format, ...) {
  if (g_output_mode != OutputMode::Text) return;
  va_list args;
  va_start(args, format);
  std::vfprintf(stdout, format, args);
  va_end(args);
}

nlohmann::json& result() {
  static nlohmann::json j = nlohmann::json::object();
  return j;
}

std::string json_text(const nlohmann::json& j, int indent) {
  return j.dump(indent, ' ', false, nlohmann::json::error_handler_t::replace);
}

void add_output_flags(CLI::App& app) {
  static const std::string json_help =
      "Print the result as one JSON object on stdout (no other text)";
  static const std::string quiet_help = "Print nothing but errors (no text, no progress)";
  for (CLI::App* sub : app.get_subcommands([](CLI::App*) { return true; })) {
    if (!sub->get_option_no_throw("--json")) sub->add_flag("--json", json_help);
    sub->add_flag("--quiet", quiet_help)->excludes(sub->get_option("--json"));
  }
}

OutputMode parsed_output_mode(const CLI::App& app) {
  for (const CLI::App* sub : app.get_subcommands()) {
    if (sub->get_option("--json")->count() > 0) return OutputMode::Json;
    if (sub->get_option("--quiet")->count() > 0) return OutputMode::Quiet;
  }
  return OutputMode::Text;
}

int run_guarded(const std::function<int()>& command) {
  const int code = run_mapped(command);
  if (g_output_mode == OutputMode::Json) {
    nlohmann::json& j = result();
    j["exit_code"] = code;
    std::cout << json_text(j) << "\n";
  }
  return code;
}

Progress::Progress(std::string label)
    : label_(std::move(label)),
      enabled_(isatty(STDERR_FILENO) == 1 && g_output_mode != OutputMode::Quiet) {}

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
