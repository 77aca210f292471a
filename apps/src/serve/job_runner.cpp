#include "serve/job_runner.h"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstring>

#include "scanmesh/core/errors.h"

namespace scanmesh::cli::web {
namespace {

// The last line of a child's stderr: its one-line error (docs/cli.md, "Exit codes").
std::string last_line(const std::string& text) {
  const std::size_t end = text.find_last_not_of("\r\n");
  if (end == std::string::npos) return {};
  const std::size_t newline = text.rfind('\n', end);
  const std::size_t begin = newline == std::string::npos ? 0 : newline + 1;
  return text.substr(begin, end + 1 - begin);
}

// Keeps at most `limit` bytes of a stream (the tail: a runaway child cannot fill the server's
// memory, and the error line is at the end).
void append_bounded(std::string& s, const char* data, std::size_t n, std::size_t limit) {
  s.append(data, n);
  if (s.size() > limit) s.erase(0, s.size() - limit);
}

}  // namespace

const char* job_state_name(JobState s) {
  switch (s) {
    case JobState::Idle: return "idle";
    case JobState::Running: return "running";
    case JobState::Stopping: return "stopping";
    case JobState::Succeeded: return "succeeded";
    case JobState::Failed: return "failed";
    case JobState::Stopped: return "stopped";
  }
  return "?";
}

JobRunner::JobRunner(std::string program) : program_(std::move(program)) {
  job_ = {{"state", "idle"}};
}

JobRunner::~JobRunner() {
  stop();
  if (worker_.joinable()) worker_.join();
}

bool JobRunner::start(JobRequest request) {
  std::lock_guard lock(mutex_);
  if (state_ == JobState::Running || state_ == JobState::Stopping) return false;
  for (const auto& folder : request.folders) {
    std::error_code ec;
    std::filesystem::create_directories(folder, ec);
    if (ec) throw IoError("cannot create '" + folder + "': " + ec.message());
  }
  if (worker_.joinable()) worker_.join();  // the previous job's thread has ended its work
  state_ = JobState::Running;
  stop_asked_ = false;
  job_ = {{"id", ++job_counter_},
          {"kind", request.kind},
          {"state", "running"},
          {"session", request.session},
          {"info", request.info},
          {"commands", nlohmann::json::array()},
          {"step", 0},
          {"steps", request.commands.size()}};
  for (const auto& c : request.commands) job_["commands"].push_back({{"argv", c}});
  worker_ = std::thread([this, r = std::move(request)]() mutable { run(std::move(r)); });
  return true;
}

bool JobRunner::stop() {
  std::lock_guard lock(mutex_);
  if (state_ != JobState::Running && state_ != JobState::Stopping) return false;
  stop_asked_ = true;
  state_ = JobState::Stopping;
  job_["state"] = "stopping";
  kill_at_ = std::chrono::steady_clock::now() + kKillAfter;
  if (child_ > 0) ::kill(-child_, SIGTERM);
  // A capture waiting at a pose prompt reads stdin: its end makes it give up.
  if (child_stdin_ >= 0) {
    ::close(child_stdin_);
    child_stdin_ = -1;
  }
  return true;
}

bool JobRunner::send_line(const std::string& line) {
  std::lock_guard lock(mutex_);
  if (child_stdin_ < 0) return false;
  const std::string text = line + "\n";
  // Non-blocking: a child that does not read its input cannot stall the server.
  return ::write(child_stdin_, text.data(), text.size()) == static_cast<ssize_t>(text.size());
}

bool JobRunner::busy() const {
  std::lock_guard lock(mutex_);
  return state_ == JobState::Running || state_ == JobState::Stopping;
}

void JobRunner::wait_idle() {
  std::unique_lock lock(mutex_);
  idle_.wait(lock, [this] { return state_ != JobState::Running && state_ != JobState::Stopping; });
}

nlohmann::json JobRunner::status() const {
  std::lock_guard lock(mutex_);
  return job_;
}

void JobRunner::run(JobRequest request) {
  JobState end = JobState::Succeeded;
  for (std::size_t i = 0; i < request.commands.size(); ++i) {
    {
      std::lock_guard lock(mutex_);
      if (stop_asked_) {
        end = JobState::Stopped;
        break;
      }
      job_["step"] = i;
    }
    const Outcome o = run_command(request.commands[i]);
    nlohmann::json parsed = nlohmann::json::parse(o.out, nullptr, false);
    std::lock_guard lock(mutex_);
    nlohmann::json& c = job_["commands"][i];
    c["exit_code"] = o.exit_code;
    c["result"] = parsed.is_discarded() ? nlohmann::json() : parsed;
    const bool is_result = std::find(request.result_codes.begin(), request.result_codes.end(),
                                     o.exit_code) != request.result_codes.end();
    if (o.exit_code != 0 && is_result) c["error"] = last_line(o.err);
    if (o.exit_code != 0 && !is_result) {
      const std::string error = last_line(o.err);
      c["error"] = error;
      job_["error"] = error.empty() ? "exit code " + std::to_string(o.exit_code) : error;
      // exit 11: a scan that stopped on request between two steps (docs/cli.md).
      end = (stop_asked_ || o.exit_code == 11) ? JobState::Stopped : JobState::Failed;
      break;
    }
  }
  std::lock_guard lock(mutex_);
  state_ = end;
  job_["state"] = job_state_name(end);
  idle_.notify_all();
}

JobRunner::Outcome JobRunner::run_command(const CommandLine& command) {
  Outcome o;
  std::array<int, 2> in{-1, -1}, out{-1, -1}, err{-1, -1};
  if (::pipe2(in.data(), O_CLOEXEC) != 0 || ::pipe2(out.data(), O_CLOEXEC) != 0 ||
      ::pipe2(err.data(), O_CLOEXEC) != 0) {
    o.err = std::string("scanmesh: cannot create pipes: ") + std::strerror(errno);
    for (int fd : {in[0], in[1], out[0], out[1], err[0], err[1]})
      if (fd >= 0) ::close(fd);
    return o;
  }
  // The "board placed" line is written without blocking the server (send_line).
  ::fcntl(in[1], F_SETFL, O_NONBLOCK);
  std::vector<std::string> args{program_};
  args.insert(args.end(), command.begin(), command.end());
  args.push_back("--json");
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);

  const pid_t parent = ::getpid();
  const pid_t pid = ::fork();
  if (pid == 0) {
    // Only async-signal-safe calls until exec. Its own process group (stop() signals the group);
    // SIGTERM when the server dies, so no job outlives it holding the devices.
    ::setpgid(0, 0);
    ::prctl(PR_SET_PDEATHSIG, SIGTERM);
    if (::getppid() != parent) ::_exit(127);
    ::dup2(in[0], STDIN_FILENO);
    ::dup2(out[1], STDOUT_FILENO);
    ::dup2(err[1], STDERR_FILENO);
    // Nothing else of the server (its listening socket, the clients' connections) reaches the job.
    ::close_range(3, ~0U, 0);
    ::execv(argv[0], argv.data());
    ::_exit(127);
  }
  const int fork_errno = errno;
  ::close(in[0]);
  ::close(out[1]);
  ::close(err[1]);
  if (pid < 0) {
    o.err = "scanmesh: cannot start '" + program_ + "': " + std::strerror(fork_errno);
    for (int fd : {in[1], out[0], err[0]}) ::close(fd);
    return o;
  }
  ::setpgid(pid, pid);  // also from here: stop() may signal the group before the child ran
  {
    std::lock_guard lock(mutex_);
    child_ = pid;
    child_stdin_ = in[1];
    if (stop_asked_) {
      ::kill(-pid, SIGTERM);
      ::close(child_stdin_);
      child_stdin_ = -1;
    }
  }
  std::array<pollfd, 2> fds{pollfd{out[0], POLLIN, 0}, pollfd{err[0], POLLIN, 0}};
  char buffer[65536];
  int open_streams = 2;
  while (open_streams > 0) {
    const int ready = ::poll(fds.data(), fds.size(), 200);
    if (ready < 0 && errno != EINTR) {
      ::kill(-pid, SIGKILL);  // cannot read its output any more: it must not block on a pipe
      break;
    }
    {
      std::lock_guard lock(mutex_);
      if (stop_asked_ && std::chrono::steady_clock::now() > kill_at_) ::kill(-pid, SIGKILL);
    }
    if (ready <= 0) continue;
    for (std::size_t k = 0; k < fds.size(); ++k) {
      if (fds[k].fd < 0 || fds[k].revents == 0) continue;
      const ssize_t n = ::read(fds[k].fd, buffer, sizeof buffer);
      if (n > 0) {
        append_bounded(k == 0 ? o.out : o.err, buffer, static_cast<std::size_t>(n),
                       k == 0 ? (64u << 20) : (64u << 10));
      } else if (n == 0 || errno != EINTR) {
        ::close(fds[k].fd);
        fds[k].fd = -1;
        --open_streams;
      }
    }
  }
  for (auto& f : fds)
    if (f.fd >= 0) ::close(f.fd);
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  {
    std::lock_guard lock(mutex_);
    child_ = -1;
    if (child_stdin_ >= 0) ::close(child_stdin_);
    child_stdin_ = -1;
  }
  if (WIFEXITED(status)) {
    o.exit_code = WEXITSTATUS(status);
  } else if (WIFSIGNALED(status)) {
    o.exit_code = 128 + WTERMSIG(status);
    if (o.err.empty() || o.err.back() != '\n') o.err += '\n';
    o.err += std::string("scanmesh: the command ended by signal ") + strsignal(WTERMSIG(status));
  }
  return o;
}

}  // namespace scanmesh::cli::web
