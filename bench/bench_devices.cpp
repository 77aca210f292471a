// Devices and sessions in simulation:
//  1. capture-loop overhead per frame, excluding simulated time (exposure, moves, settling):
//     the loop with the real termios board driver over a pty and the simulated camera, minus
//     the simulated time it had to wait; anchor: grabbing the same frames alone (no board, no
//     session), same run.
//  2. session write throughput (MB/s of RGB pixels and frames/s) for PNG and MJPEG storage, in
//     memory (/dev/shm) and on disk (with fsync); anchor: writing the same raw bytes with
//     write_file_atomically (temp + fsync + rename), same run.
// A plain program printing a table; numbers depend on machine load (see docs/benchmarks.md).
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <thread>

#include "bench_support.h"
#include "scanmesh/acquisition/capture.h"
#include "scanmesh/core/atomic_file.h"
#include "scanmesh/core/image.h"
#include "scanmesh/drivers/board.h"
#include "scanmesh/drivers/serial_transport.h"
#include "scanmesh/sim/pty_board.h"
#include "scanmesh/sim/sim_camera.h"

namespace fs = std::filesystem;
using namespace scanmesh;

namespace {

// drivers::Camera over the simulated camera (as apps/src/sim_rig.h, kept minimal here).
class BenchCamera final : public drivers::Camera {
 public:
  BenchCamera(std::shared_ptr<sim::SimCamera> c, drivers::PixelFormat f) : cam_(c), format_(f) {}
  drivers::Frame grab() override {
    const auto sf = format_ == drivers::PixelFormat::Mjpeg ? sim::SimPixelFormat::Mjpeg
                                                           : sim::SimPixelFormat::Rgb24;
    for (;;) {
      auto c = cam_->capture(sf);
      if (c.status != sim::SimCamera::Capture::Status::Ok) {
        std::this_thread::yield();
        continue;
      }
      drivers::Frame f;
      const auto& o = cam_->options();
      f.rgb = drivers::decode_frame(format_, c.bytes, o.width, o.height);
      f.sequence = c.sequence;
      f.timestamp_s = c.timestamp_s;
      if (format_ == drivers::PixelFormat::Mjpeg) f.original = std::move(c.bytes);
      ++frames;
      return f;
    }
  }
  void flush() override {}
  void set_exposure(int exposure_100us) override { cam_->set_exposure_gain(exposure_100us / 150.0); }
  drivers::CameraDescriptor descriptor() const override {
    drivers::CameraDescriptor d;
    d.width = cam_->options().width;
    d.height = cam_->options().height;
    d.format = format_;
    d.fps = cam_->options().fps;
    return d;
  }
  std::size_t frames = 0;

 private:
  std::shared_ptr<sim::SimCamera> cam_;
  drivers::PixelFormat format_;
};

fs::path scratch(const fs::path& base, const std::string& name) {
  const fs::path d = base / ("scanmesh_bench_devices_" + std::to_string(getpid())) / name;
  fs::remove_all(d);
  return d;
}

SessionHeader header(std::size_t steps, int w, int h, FrameStorage s, drivers::PixelFormat f) {
  SessionHeader hd;
  hd.step_count = steps;
  hd.laser_count = 2;
  hd.storage = s;
  hd.camera = {"sim", "Simulated UVC Camera", "sim", "sim", w, h, f, 30};
  hd.board_device = "sim";
  hd.board_dialect = "horus";
  hd.board_firmware = "Horus 0.2";
  return hd;
}

}  // namespace

int main() {
  const fs::path mem =
      fs::is_directory("/dev/shm") ? fs::path("/dev/shm") : fs::temp_directory_path();
  const fs::path disk = fs::temp_directory_path();

  // 1. Capture-loop overhead.
  {
    const int w = 320, h = 240;
    const std::size_t steps = 100;
    const double scale = 1e-3;  // simulated seconds per real second
    sim::SimBoardOptions bo;
    bo.time_scale = scale;
    sim::PtyBoard pty(bo);
    auto fw = pty.shared_firmware();
    sim::SimCameraOptions co;
    co.width = w;
    co.height = h;
    co.time_scale = scale;
    auto cam = std::make_shared<sim::SimCamera>(
        sim::synthetic_turntable_renderer(w, h), [fw] { return fw->angle_rad(); },
        [fw] { return fw->laser_mask(); }, co);
    cam->start_streaming();
    BenchCamera camera(cam, drivers::PixelFormat::Rgb24);
    drivers::BoardOptions opt;
    opt.feed_rate_deg_per_s = 90;
    drivers::Board board(drivers::open_serial_transport(pty.slave_path()),
                         drivers::make_horus_dialect(), opt);
    board.connect();
    const fs::path dir = scratch(mem, "capture");
    SessionWriter session = SessionWriter::create(
        dir, header(steps, w, h, FrameStorage::Png, drivers::PixelFormat::Rgb24));
    CaptureOptions o;
    o.settle_s = 0.2 * scale;
    o.discard_frames = 1;
    const double t0 = bench::now();
    capture_steps(session, board, camera, o);
    const double total = bench::now() - t0;
    // Simulated time the loop had to wait: every frame's exposure, every move, every settle.
    const double frame_period = scale / co.fps;
    const double move_s = 360.0 / steps / opt.feed_rate_deg_per_s * scale;
    const double simulated = camera.frames * frame_period + steps * (move_s + o.settle_s);
    const std::size_t kept = steps * 3;
    const double per_frame = (total - simulated) / kept;
    // Anchor: grabbing as many frames as the loop grabbed (kept and discarded), alone.
    const std::size_t grabbed = camera.frames;
    const double a0 = bench::now();
    for (std::size_t i = 0; i < grabbed; ++i) camera.grab();
    const double anchor_total = bench::now() - a0 - grabbed * frame_period;
    const double anchor_per_frame = anchor_total / kept;
    std::printf("capture loop, %zu steps x 3 frames %dx%d RGB24 -> PNG session in %s\n", steps, w,
                h, mem.c_str());
    std::printf("  %-44s %10.3f ms\n", "overhead per kept frame (minus simulated time)",
                per_frame * 1e3);
    std::printf("  %-44s %10.3f ms\n", "anchor: grab alone per frame (same frames)",
                anchor_per_frame * 1e3);
    std::printf("  %-44s %10.2f x\n", "ratio loop / anchor", per_frame / anchor_per_frame);
    std::printf("  %-44s %10.3f s (simulated %.3f s)\n", "wall time", total, simulated);
    std::printf("  %-44s %10zu\n", "frames grabbed (incl. discarded)", grabbed);
    fs::remove_all(dir.parent_path());
  }

  // 2. Session write throughput.
  std::printf("\nsession write, 640x480 RGB frames, 3 per step, 20 steps\n");
  std::printf("  %-28s %10s %10s %12s %10s\n", "storage / place", "MB/s", "frames/s", "anchor MB/s",
              "ratio");
  const int w = 640, h = 480;
  const auto render = sim::synthetic_turntable_renderer(w, h);
  std::vector<std::vector<drivers::Frame>> steps_frames;
  for (std::size_t i = 0; i < 20; ++i) {
    std::vector<drivers::Frame> frames;
    for (unsigned mask : {0u, 1u, 2u}) {
      drivers::Frame f;
      f.rgb = render(i * 0.1, mask);
      f.original = encode_jpeg(f.rgb, 90);
      frames.push_back(std::move(f));
    }
    steps_frames.push_back(std::move(frames));
  }
  const double raw_mb = 20.0 * 3 * w * h * 3 / 1e6;
  for (const auto& [place, base] : {std::pair{"memory", mem}, std::pair{"disk", disk}}) {
    // Anchor: the raw pixels through write_file_atomically.
    const fs::path adir = scratch(base, "anchor");
    fs::create_directories(adir);
    const double a0 = bench::now();
    int n = 0;
    for (const auto& frames : steps_frames)
      for (const auto& f : frames)
        write_file_atomically(adir / ("f" + std::to_string(n++)),
                              std::span<const std::uint8_t>(f.rgb.pixels));
    const double anchor_mbs = raw_mb / (bench::now() - a0);
    for (const auto storage : {FrameStorage::Png, FrameStorage::Mjpeg}) {
      const fs::path dir = scratch(base, storage == FrameStorage::Png ? "png" : "mjpeg");
      SessionWriter sw = SessionWriter::create(
          dir, header(20, w, h, storage,
                      storage == FrameStorage::Png ? drivers::PixelFormat::Rgb24
                                                   : drivers::PixelFormat::Mjpeg));
      const double t0 = bench::now();
      for (std::size_t i = 0; i < 20; ++i) sw.append_step(i * 0.1, steps_frames[i]);
      const double t = bench::now() - t0;
      const double mbs = raw_mb / t;
      const std::string label =
          std::string(storage == FrameStorage::Png ? "png" : "mjpeg") + " / " + place;
      std::printf("  %-28s %10.1f %10.1f %12.1f %10.2f\n", label.c_str(), mbs, 60 / t, anchor_mbs,
                  mbs / anchor_mbs);
    }
    fs::remove_all(adir.parent_path());
  }
  std::printf("  (MB/s counts the RGB pixels a frame holds, whatever the storage writes)\n");
  return 0;
}
