// `scanmesh scan --sim` end to end: injected faults exit with code 7 naming the device and the
// step, and --resume completes the session to the same result as an uninterrupted scan; the
// kill -9 test interrupts the scan at 50 progress points; `scanmesh replay` is deterministic.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "../acquisition/session_compare.h"
#include "cli_runner.h"
#include "scanmesh/core/atomic_file.h"

namespace scanmesh {
namespace {

namespace fs = std::filesystem;

// 7 steps: 3200 microsteps per turn are not a multiple of 7, so every resume also checks that
// the table lands on the same microsteps as in an uninterrupted scan (docs/hardware.md).
const std::string kScan =
    "scan --sim --steps 7 --lasers 2 --size 32x24 --time-scale 0.01 --settle 0.05";

using test::run;
using test::RunResult;

// Scratch space in /dev/shm when available (fsync is free there; a SIGKILL does not lose the
// page cache anyway, so the kill test checks the same thing on either file system).
fs::path scratch(const std::string& name) {
  const fs::path base =
      fs::is_directory("/dev/shm") ? fs::path("/dev/shm") : fs::temp_directory_path();
  const fs::path d = base / ("scanmesh_test_scan_" + std::to_string(getpid())) / name;
  fs::remove_all(d);
  fs::create_directories(d.parent_path());
  return d;
}

class ScanCli : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    reference_ = new fs::path(scratch("reference"));
    const RunResult r = run(kScan + " --out " + reference_->string());
    ASSERT_EQ(r.exit_code, 0) << r.output;
  }
  static void TearDownTestSuite() {
    fs::remove_all(reference_->parent_path());
    delete reference_;
  }
  static fs::path* reference_;
};
fs::path* ScanCli::reference_ = nullptr;

TEST_F(ScanCli, ReferenceSessionIsComplete) {
  const SessionReader reader(*reference_);
  EXPECT_TRUE(reader.complete());
  EXPECT_EQ(reader.step_count(), 7u);
  EXPECT_EQ(reader.manifest().header.board_firmware, "Horus 0.2 ['$' for help]");
}

struct FaultCase {
  const char* fault;
  const char* device;  // start of the error message
  const char* problem;
};

TEST_F(ScanCli, EveryFaultNamesDeviceAndStepAndResumesToTheSameSession) {
  // Board commands: 3 at connect, then 7 per step (2 lasers off, move, on/off per laser);
  // 3 + 7 * 3 + 3 = 27 is the move of step 3. Camera frames: 6 per step (one discarded each).
  const std::vector<FaultCase> cases = {
      {"board-unplug@27", "/dev/pts/", "step 3 of 7: unplugged"},
      {"board-stall@27", "/dev/pts/", "step 3 of 7: no 'ok' for 'G1 X"},
      {"board-hang-move@27", "/dev/pts/", "step 3 of 7: no 'ok' for 'G1 X"},
      {"camera-eio@20", "sim:camera", "step 3 of 7: VIDIOC_DQBUF: I/O error (EIO)"},
      {"camera-unplug@20", "sim:camera", "step 3 of 7: unplugged"},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.fault);
    const fs::path dir = scratch(std::string("fault_") + c.fault);
    const RunResult failed = run(kScan + " --out " + dir.string() + " --sim-fault " + c.fault);
    EXPECT_EQ(failed.exit_code, 7) << failed.output;
    EXPECT_NE(failed.output.find(std::string("scanmesh: device error: ") + c.device),
              std::string::npos)
        << failed.output;
    EXPECT_NE(failed.output.find(c.problem), std::string::npos) << failed.output;
    EXPECT_EQ(read_session_manifest(dir).steps.size(), 3u);
    const RunResult resumed = run(kScan + " --out " + dir.string() + " --resume");
    EXPECT_EQ(resumed.exit_code, 0) << resumed.output;
    EXPECT_NE(resumed.output.find("resumed at step 3"), std::string::npos) << resumed.output;
    EXPECT_TRUE(test::sessions_identical(dir, *reference_));
    fs::remove_all(dir);
  }
}

TEST_F(ScanCli, AbsorbedFaultsStillGiveTheSameSession) {
  const fs::path dir = scratch("absorbed");
  const RunResult r = run(kScan + " --out " + dir.string() +
                          " --sim-fault board-drop-ok@12 --sim-fault board-garble-ok@27"
                          " --sim-fault camera-drop@9 --sim-fault camera-corrupt@14 "
                          "--format mjpeg --storage mjpeg");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("2 frames dropped"), std::string::npos) << r.output;
  const SessionReader reader(dir);
  EXPECT_TRUE(reader.complete());
  EXPECT_EQ(reader.manifest().header.storage, FrameStorage::Mjpeg);
  fs::remove_all(dir);
}

TEST_F(ScanCli, WithoutResumeAnExistingSessionIsNotTouched) {
  const RunResult r = run(kScan + " --out " + reference_->string());
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_NE(r.output.find("--resume"), std::string::npos) << r.output;
  const RunResult mismatch = run("scan --sim --steps 9 --lasers 2 --size 32x24 --out " +
                                 reference_->string() + " --resume");
  EXPECT_EQ(mismatch.exit_code, 3) << mismatch.output;
}

TEST(DevicesCli, ListsCamerasAndBoardsEvenWhenThereAreNone) {
  const RunResult r = run("devices");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("cameras:"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("boards (USB):"), std::string::npos) << r.output;
  const RunResult j = run("devices --json");
  EXPECT_EQ(j.exit_code, 0) << j.output;
  EXPECT_NE(j.output.find("\"usb_boards\""), std::string::npos) << j.output;
}

TEST(ScanCliUsage, HardwareScanNeedsBothDevices) {
  const RunResult r = run("scan --device /dev/video0 --out /tmp/scanmesh-never");
  EXPECT_EQ(r.exit_code, 3) << r.output;
  const RunResult missing = run("scan --device /dev/video-none --board /dev/ttyACM-none --out " +
                                scratch("missing").string());
  EXPECT_EQ(missing.exit_code, 7) << missing.output;
  EXPECT_NE(missing.output.find("/dev/video-none: cannot open: no such device node"),
            std::string::npos)
      << missing.output;
}

TEST_F(ScanCli, ReplayIsDeterministic) {
  const fs::path a = scratch("replay_a"), b = scratch("replay_b");
  const RunResult ra = run("replay " + reference_->string() + " --out " + a.string() + " --frames");
  const RunResult rb = run("replay " + reference_->string() + " --out " + b.string() + " --frames");
  ASSERT_EQ(ra.exit_code, 0) << ra.output;
  ASSERT_EQ(rb.exit_code, 0) << rb.output;
  EXPECT_NE(ra.output.find("21 frames verified"), std::string::npos) << ra.output;
  for (const char* f : {"contact_sheet.png", "step_000005_laser1.png", "replay.json"})
    EXPECT_EQ(read_file_bytes(a / f), read_file_bytes(b / f)) << f;
  fs::remove_all(a);
  fs::remove_all(b);
}

// Entries in the session's frames/ folder (finished frames and the one being written): the
// progress marker the kill test waits for. 0 while the folder does not exist yet.
std::size_t frame_entries(const fs::path& session) {
  std::error_code ec;
  std::size_t n = 0;
  for (fs::directory_iterator it(session / "frames", ec), end; !ec && it != end;
       it.increment(ec))
    ++n;
  return n;
}

// The kill -9 test: the scan is started as a child process and killed with SIGKILL at 50 kill
// points; `--resume` then completes it, and the session must be identical (frames and step
// records) to the uninterrupted one. A kill point is a progress marker, not a wall time (issue
// 31: delays drawn from the reference run's duration depended on the machine's load): the test
// waits until the session's frames/ folder holds k entries (k random in [0, frames - 2]), then
// spins a random 0-400 us more so that the kill also lands inside a frame or a step record
// being written. With at least two frames still to come when it fires, the kill interrupts
// the scan however fast or slow the machine is.
TEST_F(ScanCli, KillNineAtFiftyProgressPointsLosesNothing) {
  const std::size_t frames = frame_entries(*reference_);
  ASSERT_GE(frames, 3u);
  std::mt19937 rng(20261122);
  std::uniform_int_distribution<std::size_t> marker(0, frames - 2);
  std::uniform_int_distribution<int> extra_us(0, 400);
  const fs::path dir = scratch("killed");
  int killed_mid_scan = 0;
  for (int trial = 0; trial < 50; ++trial) {
    SCOPED_TRACE("trial " + std::to_string(trial));
    fs::remove_all(dir);
    const std::string args = kScan + " --out " + dir.string() + " --resume";
    const std::size_t k = marker(rng);
    const auto extra = std::chrono::microseconds(extra_us(rng));
    const pid_t pid = fork();
    ASSERT_GE(pid, 0);
    if (pid == 0) {
      const int devnull = ::open("/dev/null", O_WRONLY);
      ::dup2(devnull, 1);
      ::dup2(devnull, 2);
      execl("/bin/sh", "sh", "-c",
            ("exec " + test::scanmesh_binary().string() + " " + args).c_str(),
            static_cast<char*>(nullptr));
      _exit(127);
    }
    // Wait for the marker (or the child's end, which would be a failure below).
    int status = 0;
    bool exited = false;
    while (frame_entries(dir) < k) {
      if (::waitpid(pid, &status, WNOHANG) == pid) {
        exited = true;
        break;
      }
      std::this_thread::yield();
    }
    if (!exited) {
      const auto until = std::chrono::steady_clock::now() + extra;
      while (std::chrono::steady_clock::now() < until) {
      }
      ::kill(pid, SIGKILL);
      ::waitpid(pid, &status, 0);
    }
    if (WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL) ++killed_mid_scan;
    const RunResult resumed = run(args);
    ASSERT_EQ(resumed.exit_code, 0) << resumed.output;
    ASSERT_TRUE(test::sessions_identical(dir, *reference_));
  }
  // Every kill point must really interrupt the scan, or the test proves nothing. One trial in
  // ten is allowed to miss: a scheduler can hold this process off the CPU while the child
  // finishes its last frames.
  EXPECT_GE(killed_mid_scan, 45);
  fs::remove_all(dir);
}

// Ctrl-C / SIGTERM (the web UI's pause and stop): the scan ends after the step in flight with
// exit 11 and a --resume hint; every complete step is kept and --resume completes the session
// to the same frames as an uninterrupted scan. Waits for a progress marker, not a time.
TEST_F(ScanCli, SigtermStopsBetweenStepsAndResumes) {
  const std::string scan =
      "scan --sim --steps 40 --lasers 2 --size 32x24 --time-scale 0.01 --settle 0.05";
  const fs::path dir = scratch("stopped"), whole = scratch("whole");
  ASSERT_EQ(run(scan + " --out " + whole.string()).exit_code, 0);
  int pipe_fds[2];
  ASSERT_EQ(::pipe(pipe_fds), 0);
  const pid_t pid = fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    ::dup2(pipe_fds[1], 1);
    ::dup2(pipe_fds[1], 2);
    ::close(pipe_fds[0]);
    execl("/bin/sh", "sh", "-c",
          ("exec " + test::scanmesh_binary().string() + " " + scan + " --out " + dir.string())
              .c_str(),
          static_cast<char*>(nullptr));
    _exit(127);
  }
  ::close(pipe_fds[1]);
  int status = 0;
  while (frame_entries(dir) < 4 && ::waitpid(pid, &status, WNOHANG) == 0) std::this_thread::yield();
  ::kill(pid, SIGTERM);
  std::string output;
  char buffer[4096];
  for (ssize_t n; (n = ::read(pipe_fds[0], buffer, sizeof buffer)) > 0;) output.append(buffer, n);
  ::close(pipe_fds[0]);
  ::waitpid(pid, &status, 0);
  ASSERT_TRUE(WIFEXITED(status)) << output;
  EXPECT_EQ(WEXITSTATUS(status), 11) << output;
  EXPECT_NE(output.find("stopped on request"), std::string::npos) << output;
  EXPECT_NE(output.find("--resume"), std::string::npos) << output;
  const RunResult replay = run("replay " + dir.string() + " --out " + scratch("stopped_replay").string() + " --json");
  ASSERT_EQ(replay.exit_code, 0) << replay.output;
  EXPECT_NE(replay.output.find("\"complete\": false"), std::string::npos) << replay.output;
  const RunResult resumed = run(scan + " --out " + dir.string() + " --resume");
  ASSERT_EQ(resumed.exit_code, 0) << resumed.output;
  EXPECT_TRUE(test::sessions_identical(dir, whole));
}

}  // namespace
}  // namespace scanmesh
