// Shared plumbing of the scanmesh command line: exit codes, error mapping, progress display.
#pragma once

#include <CLI/CLI.hpp>
#include <chrono>
#include <functional>
#include <nlohmann/json.hpp>
#include <ostream>
#include <string>

#include <numbers>

namespace scanmesh::cli {

//! Radians per degree (options are given in degrees, the libraries work in radians).
inline constexpr double kDeg = std::numbers::pi / 180.0;

//! Exit codes, documented in docs/cli.md.
enum ExitCode : int {
  kSuccess = 0,
  kInternalError = 1,
  kUsageError = 2,
  kInvalidInput = 3,     //!< impossible parameter or configuration value
  kBadFile = 4,          //!< malformed, truncated or corrupt input file
  kIoFailure = 5,        //!< the OS refused a read or write (missing file, disk full, ...)
  kNotEdgeManifold = 6,  //!< `scanmesh check`: the mesh has an edge with more than two faces
  kDeviceFailure = 7,    //!< a camera or board failed, vanished, stalled or answered nonsense
  kOutOfTolerance = 8,   //!< `scanmesh check-calibration`: a measured error exceeds its tolerance
  kMeshIncomplete = 9,   //!< `scanmesh animesh`: written, but with open fronts or failing its check
  kRequirementNotMet = 10,  //!< `scanmesh check --require`: a required property does not hold
  kStopped = 11,  //!< `scanmesh scan`: stopped on request (SIGINT/SIGTERM); --resume continues
};

//! Numeric option checks. Unlike CLI11's Range / PositiveNumber / NonNegativeNumber they refuse
//! NaN and infinities (every comparison with NaN is false, so those let it through) and name the
//! bounds in short form (CLI11 prints DBL_MAX with all its 309 digits). A failed check is a usage
//! error (exit 2) naming the option.
CLI::Validator in_range(double lo, double hi);
//! lo < value <= hi.
CLI::Validator above(double lo, double hi);
//! A seed: an unsigned 64-bit integer (CLI11 wrapped "-1" round to 2^64 - 1 without a word).
CLI::Validator seed_range();

//! Throws InvalidInputError (exit 3) "OPTION must be in [lo, hi], not VALUE" unless lo <= value
//! <= hi and value is finite: for commands that check their options together in code.
void require_in_range(const std::string& option, double value, double lo, double hi);

//! How a command reports (docs/cli.md, "Output"): lines of text for people (the default); one
//! JSON object on stdout for programs (--json: the result's fields, numbers as numbers, plus
//! "exit_code" and, on failure, "error"); or nothing but the error line (--quiet). Progress bars
//! go to stderr and only when it is a terminal; --quiet turns them off too.
enum class OutputMode { Text, Json, Quiet };
void set_output_mode(OutputMode mode);
OutputMode output_mode();
//! Where commands write their lines of text: stdout in Text mode, discarded otherwise.
std::ostream& say();
//! printf-style text to say().
void sayf(const char* format, ...) __attribute__((format(printf, 1, 2)));
//! The command's result, filled by the command as it goes; printed by run_guarded in Json mode.
nlohmann::json& result();
//! Adds --json and --quiet to every subcommand of `app` (a command that already has --json,
//! such as info, keeps its own flag, which then sets the same mode).
void add_output_flags(CLI::App& app);
//! The mode the parsed flags of the chosen subcommand ask for.
OutputMode parsed_output_mode(const CLI::App& app);
//! JSON text of a report or result (indented; bytes that are not UTF-8, e.g. from a grid's
//! metadata, become U+FFFD instead of throwing).
std::string json_text(const nlohmann::json& j, int indent = 2);

//! Runs a command; maps scanmesh's typed errors to an exit code and one line on stderr. In Json
//! mode it then prints result() with "exit_code" (and "error") on stdout.
int run_guarded(const std::function<int()>& command);

//! A one-line progress bar on stderr when stderr is a terminal; silent otherwise, so logs and
//! CI output stay clean.
class Progress {
 public:
  explicit Progress(std::string label);
  ~Progress();
  void update(int done, int total);
  void finish();

 private:
  std::string label_;
  bool enabled_;
  bool finished_ = false;
  int last_percent_ = -1;
};

//! Wall-clock stopwatch for the timings in report.json.
class Stopwatch {
 public:
  Stopwatch() : start_(std::chrono::steady_clock::now()) {}
  double seconds() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  }

 private:
  std::chrono::steady_clock::time_point start_;
};

}  // namespace scanmesh::cli
