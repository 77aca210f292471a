// The web UI's jobs: every action that takes time (a scan, a calibration, reconstruct + mesh,
// regions, animesh, replay) runs as a child process of this same binary with the subcommand a
// user would type, one job at a time. A child that fails or crashes cannot take the server down,
// and every job gets exactly the command line's checks, exit codes and atomic outputs
// (docs/ui.md, "Jobs").
#pragma once

#include <chrono>
#include <condition_variable>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <sys/types.h>
#include <thread>
#include <vector>

namespace scanmesh::cli::web {

//! One subcommand of a job: argv after the program name ("scan", "--sim", ...). `--json` is
//! added by the runner, so the child's stdout is its result object.
using CommandLine = std::vector<std::string>;

struct JobRequest {
  std::string kind;                   //!< "scan", "calibration", "reconstruct", ...
  std::vector<CommandLine> commands;  //!< run in order; the first non-zero exit ends the job
  std::string session;                //!< session folder the job records into (may be empty)
  nlohmann::json info;                //!< shown to the page as given (names, sizes)
  //! Exit codes that are results, not failures: a check's verdict (8: out of tolerance) or an
  //! incomplete but written animation mesh (9). The job goes on and ends "succeeded".
  std::vector<int> result_codes = {8, 9};
  //! Output folders the commands expect; made by start() once the job is accepted, so a
  //! refused job creates nothing.
  std::vector<std::string> folders;
};

enum class JobState { Idle, Running, Stopping, Succeeded, Failed, Stopped };
const char* job_state_name(JobState s);

class JobRunner {
 public:
  //! `program`: this binary (/proc/self/exe).
  explicit JobRunner(std::string program);
  ~JobRunner();
  JobRunner(const JobRunner&) = delete;
  JobRunner& operator=(const JobRunner&) = delete;

  //! Starts a job; false (and nothing started or created) when one runs already. Throws
  //! IoError when a folder of the request cannot be made (nothing started).
  bool start(JobRequest request);
  //! Asks the running command to stop: SIGTERM (a scan ends after its current step, exit 11)
  //! and end of its input (a pose prompt gives up); SIGKILL to its process group if it is still
  //! there kKillAfter later. False when nothing runs.
  bool stop();
  static constexpr std::chrono::seconds kKillAfter{15};
  //! Writes a line to the running command's stdin (a hardware calibration's "board placed").
  bool send_line(const std::string& line);
  bool busy() const;
  //! Blocks until no job runs (the server's shutdown, tests).
  void wait_idle();

  //! The job for the page: kind, state, commands with exit codes, result JSON, error line.
  nlohmann::json status() const;

 private:
  void run(JobRequest request);
  struct Outcome {
    int exit_code = -1;
    std::string out, err;
  };
  Outcome run_command(const CommandLine& command);

  std::string program_;
  mutable std::mutex mutex_;
  std::condition_variable idle_;
  std::thread worker_;
  JobState state_ = JobState::Idle;
  nlohmann::json job_;  //!< what status() reports
  pid_t child_ = -1;  //!< also its process group
  int child_stdin_ = -1;
  std::chrono::steady_clock::time_point kill_at_{};
  int job_counter_ = 0;
  bool stop_asked_ = false;
};

}  // namespace scanmesh::cli::web
