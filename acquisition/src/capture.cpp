#include "scanmesh/acquisition/capture.h"

#include <thread>

#include "scanmesh/core/errors.h"

namespace scanmesh {

namespace {

drivers::Frame grab_settled(drivers::Camera& camera, int discard) {
  camera.flush();
  std::uint32_t dropped = 0;
  for (int i = 0; i < discard; ++i) dropped += camera.grab().dropped_before;
  drivers::Frame f = camera.grab();
  f.dropped_before += dropped;
  return f;
}

}  // namespace

CaptureReport capture_steps(SessionWriter& session, drivers::Board& board, drivers::Camera& camera,
                            const CaptureOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  const SessionHeader& h = session.header();
  CaptureReport report;
  report.first_step = session.steps_done();
  const auto sleep = [&](double s) {
    if (s <= 0) return;
    if (options.sleep)
      options.sleep(s);
    else
      std::this_thread::sleep_for(std::chrono::duration<double>(s));
  };
  for (std::size_t i = session.steps_done(); i < h.step_count; ++i) {
    const double angle = h.step_angle(i);
    std::vector<drivers::Frame> frames;
    if (options.stop_requested && options.stop_requested()) {
      report.stopped = true;
      break;
    }
    if (options.before_step) options.before_step(i);
    try {
      for (int k = 0; k < h.laser_count; ++k) board.set_laser(k, false);
      board.move_to(angle);
      sleep(options.settle_s);
      frames.push_back(grab_settled(camera, options.discard_frames));
      for (int k = 0; k < h.laser_count; ++k) {
        board.set_laser(k, true);
        frames.push_back(grab_settled(camera, options.discard_frames));
        board.set_laser(k, false);
      }
    } catch (const DeviceError& e) {
      board.shutdown();
      const std::string what = e.what();
      const std::string problem = what.substr(std::min(what.size(), e.device().size() + 2));
      throw DeviceError(e.device(), "step " + std::to_string(i) + " of " +
                                        std::to_string(h.step_count) + ": " + problem);
    }
    for (const auto& f : frames) report.dropped_frames += f.dropped_before;
    session.append_step(angle, frames);
    if (options.progress) options.progress(session.steps_done(), h.step_count);
  }
  board.shutdown();
  report.steps_done = session.steps_done();
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return report;
}

}  // namespace scanmesh
