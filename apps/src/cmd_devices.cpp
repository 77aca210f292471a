// Device subcommands: `scanmesh devices` (discovery), `scanmesh scan` (capture a session from
// real or simulated devices, resumable), `scanmesh replay` (verify and export a session).
#include <CLI/CLI.hpp>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <csignal>
#include <filesystem>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <numbers>
#include <thread>
#include <tuple>

#include "calibration_capture.h"
#include "cli_support.h"
#include "commands.h"
#include "scanmesh/acquisition/capture.h"
#include "scanmesh/acquisition/session.h"
#include "scanmesh/core/atomic_file.h"
#include "scanmesh/core/errors.h"
#include "scanmesh/drivers/board.h"
#include "scanmesh/drivers/camera.h"
#include "scanmesh/drivers/serial_transport.h"
#include "scanmesh/drivers/usb_transport.h"
#include "sim_rig.h"

namespace scanmesh::cli {
namespace {

namespace fs = std::filesystem;

struct ScanArgs {
  std::string device, board, scene, out;
  bool sim = false, resume = false;
  int steps = 400, lasers = 2;
  std::string format;  // default: rgb24 in simulation, yuyv on hardware
  std::string size = "640x480";
  double fps = 30;
  std::string io = "mmap";
  int buffers = 4;
  std::optional<int> exposure, gain, brightness;
  double settle_s = 0.2;
  int discard = 1;
  std::string storage = "png";
  double feed = 90;
  int baud = 115200;
  double time_scale = 1.0;
  std::vector<std::string> faults;
  // Calibration session (docs/acquisition.md, "Calibration sessions").
  bool calibration = false;
  CalibrationPlanArgs cal;
  double pose_wait_s = -1;
};

struct ReplayArgs {
  std::string session, out;
  bool frames = false;
  int sheet_columns = 10;
};

// Ctrl-C or SIGTERM (the web UI's pause and stop) during a scan: finish the step in flight,
// then end with every complete step kept and the lasers off. A second signal ends at once.
std::atomic<bool> g_stop_requested{false};
extern "C" void request_scan_stop(int signal_number) {
  g_stop_requested = true;
  std::signal(signal_number, SIG_DFL);
}

std::vector<std::string> tty_nodes() {
  std::vector<std::string> nodes;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator("/dev", ec)) {
    const std::string n = e.path().filename().string();
    if (n.starts_with("ttyUSB") || n.starts_with("ttyACM")) nodes.push_back(e.path().string());
  }
  std::sort(nodes.begin(), nodes.end());
  return nodes;
}

int run_devices() {
  const auto cameras = drivers::list_cameras();
  const auto boards = drivers::list_usb_boards();
  const auto ttys = tty_nodes();
  char id[16];
  {
    nlohmann::json& j = result();
    j["cameras"] = nlohmann::json::array();
    for (const auto& c : cameras)
      j["cameras"].push_back({{"path", c.path},
                              {"card", c.card},
                              {"driver", c.driver},
                              {"bus", c.bus_info},
                              {"formats", c.all_formats}});
    j["usb_boards"] = nlohmann::json::array();
    for (const auto& b : boards) {
      std::snprintf(id, sizeof id, "%04x:%04x", b.vendor_id, b.product_id);
      j["usb_boards"].push_back(
          {{"bus", b.bus}, {"address", b.address}, {"id", id}, {"kind", b.kind}});
    }
    j["tty"] = ttys;
  }
  say() << "cameras:\n";
  if (cameras.empty()) say() << "  (none)\n";
  for (const auto& c : cameras) {
    std::string formats;
    for (const auto& f : c.all_formats) formats += (formats.empty() ? "" : " ") + f;
    say() << "  " << c.path << "  '" << c.card << "'  bus " << c.bus_info << "  formats " << formats
          << "\n";
  }
  say() << "boards (USB):\n";
  if (boards.empty()) say() << "  (none)\n";
  for (const auto& b : boards) {
    std::snprintf(id, sizeof id, "%04x:%04x", b.vendor_id, b.product_id);
    say() << "  usb:" << b.bus << ":" << b.address << "  " << id << "  " << b.kind << "\n";
  }
  say() << "boards (tty):\n";
  if (ttys.empty()) say() << "  (none)\n";
  for (const auto& t : ttys) say() << "  " << t << "\n";
  return kSuccess;
}

// Every numeric option of `scan`, checked before a device is opened (exit 3 naming the option).
void validate_scan_args(const ScanArgs& a) {
  require_in_range("--steps", a.steps, 1, 100000);
  require_in_range("--lasers", a.lasers, 0, 2);
  if (!(a.time_scale > 0) || a.time_scale > 1)
    throw InvalidInputError("--time-scale must be in (0, 1]");
  if (!(a.fps > 0)) throw InvalidInputError("--fps must be above 0");
  require_in_range("--fps", a.fps, 0, 1000);
  require_in_range("--buffers", a.buffers, 1, 32);
  require_in_range("--settle", a.settle_s, 0, 3600);
  require_in_range("--discard", a.discard, 0, 100);
  if (!(a.feed > 0)) throw InvalidInputError("--feed must be above 0");
  require_in_range("--feed", a.feed, 0, 3600);
  require_in_range("--baud", a.baud, 300, 4000000);
  if (a.pose_wait_s != -1) require_in_range("--pose-wait", a.pose_wait_s, 0, 3600);
}

// What a scan will record, from the arguments alone: checked before anything is opened.
struct ScanPlan {
  std::optional<CalibrationSessionInfo> cal_plan;  // a calibration session's poses
  std::size_t planned_steps = 0;
  int width = 0, height = 0;
  drivers::PixelFormat format{};
  FrameStorage storage{};
};

// Throws InvalidInputError for arguments no scan can run with (before any device is opened).
ScanPlan plan_scan(const ScanArgs& a) {
  if (a.out.empty()) throw InvalidInputError("--out SESSION is required");
  validate_scan_args(a);
  if (a.sim == (!a.device.empty() || !a.board.empty()))
    throw InvalidInputError("give either --sim or both --device and --board");
  if (!a.sim && (a.device.empty() || a.board.empty()))
    throw InvalidInputError("a hardware scan needs --device CAM and --board BOARD");
  if (!a.faults.empty() && !a.sim) throw InvalidInputError("--sim-fault needs --sim");
  ScanPlan plan;
  if (a.calibration) {
    if (!a.scene.empty()) throw InvalidInputError("--calibration shows the board, not a --scene");
    plan.cal_plan = make_calibration_plan(a.cal);
  }
  plan.planned_steps =
      plan.cal_plan ? plan.cal_plan->step_count() : static_cast<std::size_t>(a.steps);
  std::tie(plan.width, plan.height) = parse_frame_size(a.size);
  plan.format =
      drivers::parse_pixel_format(a.format.empty() ? (a.sim ? "rgb24" : "yuyv") : a.format);
  if (a.storage != "png" && a.storage != "mjpeg")
    throw InvalidInputError("--storage must be png or mjpeg");
  plan.storage = a.storage == "png" ? FrameStorage::Png : FrameStorage::Mjpeg;
  if (plan.storage == FrameStorage::Mjpeg && plan.format != drivers::PixelFormat::Mjpeg)
    throw InvalidInputError("--storage mjpeg keeps the camera's MJPEG bytes: needs --format mjpeg");
  return plan;
}

// Throws unless the session in `out` was recorded as `a` and `plan` would record it now; a
// resumed calibration session brings its own recorded plan.
void adopt_resumed_session_plan(const SessionHeader& h, const ScanArgs& a, ScanPlan& plan,
                                const fs::path& out) {
  if (h.calibration.has_value() != a.calibration)
    throw InvalidInputError("--resume: '" + out.string() + "' is " +
                            (h.calibration ? "a calibration session: add --calibration"
                                           : "a scan session: drop --calibration"));
  // A calibration session resumes with its own recorded plan (--poses etc. need not be given
  // again).
  if (h.calibration) plan.cal_plan = h.calibration;
  if ((!h.calibration && h.step_count != plan.planned_steps) || h.laser_count != a.lasers ||
      h.camera.width != plan.width || h.camera.height != plan.height ||
      h.camera.format != plan.format || h.storage != plan.storage || h.simulated != a.sim)
    throw InvalidInputError(
        "--resume: steps, lasers, size, format, storage and --sim must "
        "match the session in '" +
        out.string() + "'");
}

// Rewinds a resumed session to where capturing must start again.
void rewind_to_first_step_to_capture(SessionWriter& session, const fs::path& out) {
  const SessionHeader& h = session.header();
  // Every recorded frame is read back first: a damaged one is captured again (with all
  // steps after it), never left for the replay to find.
  if (const auto damage = SessionReader(out).first_damaged_step()) {
    std::size_t from = damage->step;
    if (h.calibration) from = h.calibration->first_step(h.calibration->step(from).first);
    say() << "scan: step " << damage->step << " is damaged (" << damage->reason
          << "); capturing again from step " << from << "\n";
    result()["recaptured_from_step"] = from;
    session.rewind(from);
  }
  if (h.calibration && !session.complete()) {
    // The board may have moved while the scan was stopped: the interrupted pose starts over.
    session.rewind(h.calibration->first_step(h.calibration->step(session.steps_done()).first));
  }
}

int report_already_complete(const SessionHeader& h, const fs::path& out) {
  say() << "scan: " << out.string() << " is already complete (" << h.step_count << " steps)\n";
  result()["session"] = out.string();
  result()["steps_done"] = h.step_count;
  result()["already_complete"] = true;
  return kSuccess;
}

// The camera of a scan and, in simulation, the device side behind the board and the camera.
// The members are destroyed in reverse order: the simulated board (pty) last.
struct ScanDevices {
  std::unique_ptr<sim::PtyBoard> pty;
  std::shared_ptr<sim::SimCamera> sim_camera;
  std::unique_ptr<drivers::Camera> camera;
  std::shared_ptr<SimCalibrationBoard> sim_board;
};

// The simulated board (behind a pty, its table at `table_angle`) and the simulated camera that
// renders the scene, or the calibration board, as the simulated table and lasers stand.
ScanDevices open_sim_devices(const ScanArgs& a, const ScanPlan& plan, double scale,
                             double table_angle) {
  ScanDevices d;
  sim::SimBoardOptions bo;
  bo.time_scale = scale;
  bo.laser_count = std::max(a.lasers, 1);
  bo.initial_angle_rad = table_angle;
  sim::SimCameraOptions co;
  co.width = plan.width;
  co.height = plan.height;
  co.fps = a.fps;
  co.time_scale = scale;
  for (const auto& f : a.faults) apply_sim_fault(f, bo, co);
  d.pty = std::make_unique<sim::PtyBoard>(bo);
  auto firmware = d.pty->shared_firmware();
  if (plan.cal_plan)
    d.sim_board = std::make_shared<SimCalibrationBoard>(*plan.cal_plan, plan.width, plan.height);
  d.sim_camera = std::make_shared<sim::SimCamera>(
      d.sim_board ? d.sim_board->renderer() : make_sim_renderer(a.scene, plan.width, plan.height),
      [firmware] { return firmware->angle_rad(); }, [firmware] { return firmware->laser_mask(); },
      co);
  d.sim_camera->start_streaming();
  d.camera = std::make_unique<SimCameraSource>(d.sim_camera, plan.format, 5.0);
  return d;
}

std::unique_ptr<drivers::Camera> open_v4l2_camera(const ScanArgs& a, const ScanPlan& plan) {
  drivers::CameraSettings cs;
  cs.width = plan.width;
  cs.height = plan.height;
  cs.format = plan.format;
  cs.fps = a.fps;
  cs.io = a.io == "userptr" ? drivers::IoMethod::UserPtr : drivers::IoMethod::Mmap;
  if (a.io != "mmap" && a.io != "userptr") throw InvalidInputError("--io must be mmap or userptr");
  cs.buffer_count = a.buffers;
  cs.exposure = a.exposure;
  cs.gain = a.gain;
  cs.brightness = a.brightness;
  return std::make_unique<drivers::V4l2Camera>(a.device, cs);
}

drivers::BoardOptions scan_board_options(const ScanArgs& a) {
  drivers::BoardOptions board_options;
  board_options.feed_rate_deg_per_s = a.feed;
  if (a.sim) {
    // The simulated board answers within microseconds, but a loaded machine (ctest -j, the
    // sanitizer job) can hold either process off the CPU for a while: timeouts well above
    // that, so that only a real fault (--sim-fault) ever lets one fire.
    board_options.banner_timeout = std::chrono::milliseconds(5000);
    board_options.command_timeout = std::chrono::milliseconds(3000);
    board_options.move_timeout_floor = std::chrono::milliseconds(3000);
  }
  return board_options;
}

// The header of a new session: the plan, and what the opened camera and board report.
SessionHeader new_session_header(const ScanArgs& a, const ScanPlan& plan, double scale,
                                 const drivers::Camera& camera, const drivers::Board& board) {
  SessionHeader h;
  h.step_count = plan.planned_steps;
  h.calibration = plan.cal_plan;
  h.laser_count = a.lasers;
  h.storage = plan.storage;
  h.settle_s = a.settle_s;
  h.discard_frames = a.discard;
  h.camera = camera.descriptor();
  h.board_device = a.sim ? "sim:board" : board.device_name();
  h.board_dialect = board.dialect().name();
  h.board_firmware = board.firmware_banner();
  h.simulated = a.sim;
  if (a.sim) h.notes = "synthetic turntable renderer, time scale " + std::to_string(scale);
  return h;
}

// `progress` must outlive the options: their progress callback updates it.
CaptureOptions scan_capture_options(const ScanArgs& a, const ScanPlan& plan, double scale,
                                    const std::shared_ptr<SimCalibrationBoard>& sim_board,
                                    Progress& progress) {
  CaptureOptions options;
  options.settle_s = a.settle_s * scale;
  options.discard_frames = a.discard;
  if (sim_board) {
    const CalibrationSessionInfo info = *plan.cal_plan;
    options.before_step = [sim_board, info](std::size_t step) {
      sim_board->set_pose(info.step(step).first);
    };
  } else if (plan.cal_plan) {
    options.before_step = pose_prompter(*plan.cal_plan, a.pose_wait_s);
  }
  options.progress = [&progress](std::size_t done, std::size_t total) {
    progress.update(static_cast<int>(done), static_cast<int>(total));
  };
  options.stop_requested = [] { return g_stop_requested.load(); };
  return options;
}

// capture_steps with Ctrl-C and SIGTERM turned into a stop request (g_stop_requested).
CaptureReport capture_until_done_or_stopped(SessionWriter& session, drivers::Board& board,
                                            drivers::Camera& camera,
                                            const CaptureOptions& options) {
  g_stop_requested = false;
  std::signal(SIGINT, request_scan_stop);
  std::signal(SIGTERM, request_scan_stop);
  CaptureReport report = capture_steps(session, board, camera, options);
  std::signal(SIGINT, SIG_DFL);
  std::signal(SIGTERM, SIG_DFL);
  return report;
}

// Says how the capture ended and fills the JSON result; kStopped after a stop request.
int report_capture(const CaptureReport& report, std::size_t planned_steps, const fs::path& out) {
  result()["session"] = out.string();
  result()["steps_done"] = report.steps_done;
  result()["steps_planned"] = planned_steps;
  result()["stopped"] = report.stopped;
  if (report.stopped) {
    say() << "scan: stopped on request after step " << report.steps_done << " of " << planned_steps
          << "; 'scanmesh scan --resume --out " << out.string() << "' continues\n";
    return kStopped;
  }
  say() << "scan: " << report.steps_done << " steps (" << report.steps_done - report.first_step
        << " captured now";
  if (report.first_step > 0) say() << ", resumed at step " << report.first_step;
  say() << ") in " << report.seconds << " s, " << report.dropped_frames << " frames dropped -> "
        << out.string() << "\n";
  result()["captured_now"] = report.steps_done - report.first_step;
  result()["first_step"] = report.first_step;
  result()["seconds"] = report.seconds;
  result()["dropped_frames"] = report.dropped_frames;
  return kSuccess;
}

int run_scan(const ScanArgs& a) {
  ScanPlan plan = plan_scan(a);

  // The session: new, or continued from its last complete step.
  const fs::path out = a.out;
  const bool existing = fs::exists(out / "session.json");
  if (existing && !a.resume)
    throw InvalidInputError("'" + out.string() + "' already holds a session; add --resume");
  std::optional<SessionWriter> session;
  double table_angle = 0;  // where the table stands now (the last complete step)
  if (existing) {
    session.emplace(SessionWriter::resume(out));
    const SessionHeader& h = session->header();
    adopt_resumed_session_plan(h, a, plan, out);
    rewind_to_first_step_to_capture(*session, out);
    if (session->complete()) return report_already_complete(h, out);
    if (session->steps_done() > 0) table_angle = h.step_angle(session->steps_done() - 1);
  }

  // Devices.
  const double scale = a.sim ? a.time_scale : 1.0;
  ScanDevices devices;
  if (a.sim)
    devices = open_sim_devices(a, plan, scale, table_angle);
  else
    devices.camera = open_v4l2_camera(a, plan);
  drivers::Board board(open_board_transport(a.sim ? devices.pty->slave_path() : a.board, a.baud),
                       drivers::make_horus_dialect(), scan_board_options(a));
  board.connect();
  // A resumed scan continues where the table was left (docs/hardware.md).
  if (session && session->steps_done() > 0) board.declare_position(table_angle);

  if (!session)
    session.emplace(
        SessionWriter::create(out, new_session_header(a, plan, scale, *devices.camera, board)));

  Progress progress("scan");
  const CaptureOptions options = scan_capture_options(a, plan, scale, devices.sim_board, progress);
  const CaptureReport report =
      capture_until_done_or_stopped(*session, board, *devices.camera, options);
  progress.finish();
  return report_capture(report, plan.planned_steps, out);
}

Image8 downscale(const Image8& img, int factor) {
  Image8 out(std::max(1, img.width / factor), std::max(1, img.height / factor), 3);
  for (int y = 0; y < out.height; ++y)
    for (int x = 0; x < out.width; ++x)
      for (int c = 0; c < 3; ++c) {
        int sum = 0;
        for (int dy = 0; dy < factor; ++dy)
          for (int dx = 0; dx < factor; ++dx) sum += img.at(x * factor + dx, y * factor + dy)[c];
        out.at(x, y)[c] = static_cast<std::uint8_t>(sum / (factor * factor));
      }
  return out;
}

int run_replay(const ReplayArgs& a) {
  if (a.out.empty()) throw InvalidInputError("--out DIR is required");
  if (a.sheet_columns < 1 || a.sheet_columns > 100)
    throw InvalidInputError("--columns must be 1..100");
  const SessionReader reader(a.session);
  const fs::path out = a.out;
  OutputFolder folder(out);
  const auto& header = reader.manifest().header;
  const std::size_t n = reader.step_count();
  // Contact sheet: one tile per step, the frame with every laser's line (the max over the
  // laser-on frames), a quarter of the size (or less for big frames).
  const int factor = std::max(1, header.camera.width / 160);
  const int tw = std::max(1, header.camera.width / factor),
            th = std::max(1, header.camera.height / factor);
  const int cols = static_cast<int>(std::min<std::size_t>(n, a.sheet_columns));
  const int rows = static_cast<int>((n + cols - 1) / std::max(cols, 1));
  Image8 sheet(std::max(cols, 1) * tw, std::max(rows, 1) * th, 3, 0);
  Progress progress("replay");
  nlohmann::json steps = nlohmann::json::array();
  for (std::size_t i = 0; i < n; ++i) {
    const ScanStep s = reader.step(i);  // checks every frame's CRC
    Image8 combined = s.laser_off;
    for (const auto& on : s.laser_on)
      for (std::size_t p = 0; p < combined.pixels.size(); ++p)
        combined.pixels[p] = std::max(combined.pixels[p], on.pixels[p]);
    const Image8 tile = downscale(combined, factor);
    const int ox = static_cast<int>(i % cols) * tw, oy = static_cast<int>(i / cols) * th;
    for (int y = 0; y < tile.height && y < th; ++y)
      for (int x = 0; x < tile.width && x < tw; ++x)
        std::copy_n(tile.at(x, y), 3, sheet.at(ox + x, oy + y));
    if (a.frames) {
      char name[64];
      std::snprintf(name, sizeof name, "step_%06zu_off.png", i);
      write_png(out / name, s.laser_off);
      for (std::size_t k = 0; k < s.laser_on.size(); ++k) {
        std::snprintf(name, sizeof name, "step_%06zu_laser%zu.png", i, k);
        write_png(out / name, s.laser_on[k]);
      }
    }
    steps.push_back({{"step", s.index}, {"angle_deg", s.angle_rad * 180.0 / std::numbers::pi}});
    progress.update(static_cast<int>(i + 1), static_cast<int>(n));
  }
  progress.finish();
  write_png(out / "contact_sheet.png", sheet);
  nlohmann::json report = {{"session", fs::absolute(a.session).string()},
                           {"steps_recorded", n},
                           {"steps_planned", header.step_count},
                           {"complete", reader.complete()},
                           {"lasers", header.laser_count},
                           {"frames_verified", n * (header.laser_count + 1)},
                           {"camera", header.camera.card},
                           {"board_firmware", header.board_firmware},
                           {"steps", steps}};
  write_file_atomically(out / "replay.json", json_text(report) + "\n");
  say() << "replay: " << n << " of " << header.step_count << " steps, "
        << n * (header.laser_count + 1) << " frames verified -> " << out.string() << "\n";
  result() = report;
  result()["out"] = out.string();
  folder.keep();
  return kSuccess;
}

}  // namespace

void register_devices_commands(CLI::App& app, CommandList& commands) {
  CLI::App* devices = app.add_subcommand("devices", "List cameras and scanner boards");
  commands.push_back({devices, [] { return run_devices(); }});

  auto s = std::make_shared<ScanArgs>();
  CLI::App* scan = app.add_subcommand("scan", "Capture a turntable scan into a session folder");
  scan->add_option("--device", s->device, "Camera: /dev/videoN or its card name");
  scan->add_option("--board", s->board, "Board: /dev/ttyACM0, VID:PID or usb:BUS:ADDR");
  scan->add_flag("--sim", s->sim, "Use the simulated board and camera");
  scan->add_option("--scene", s->scene,
                   "Scene YAML (or 'head') rendered by the simulated turntable camera; default: a "
                   "fast synthetic line pattern")
      ->check(CLI::ExistingFile | CLI::IsMember({"head"}));
  scan->add_option("--steps", s->steps, "Turntable steps per turn")->capture_default_str();
  scan->add_option("--lasers", s->lasers, "Lasers (0..2)")->capture_default_str();
  scan->add_option("--out", s->out, "Session folder")->required();
  scan->add_flag("--resume", s->resume, "Continue the session in --out from its last step");
  scan->add_option("--format", s->format, "yuyv | mjpeg | rgb24");
  scan->add_option("--size", s->size, "Frame size WIDTHxHEIGHT")->capture_default_str();
  scan->add_option("--fps", s->fps, "Frame rate")->capture_default_str();
  scan->add_option("--io", s->io, "V4L2 streaming: mmap | userptr")->capture_default_str();
  scan->add_option("--buffers", s->buffers, "V4L2 buffers")->capture_default_str();
  scan->add_option("--exposure", s->exposure, "Manual exposure (100 us units)");
  scan->add_option("--gain", s->gain, "Gain");
  scan->add_option("--brightness", s->brightness, "Brightness");
  scan->add_option("--settle", s->settle_s, "Wait after each move, seconds")->capture_default_str();
  scan->add_option("--discard", s->discard, "Frames discarded after a laser switch")
      ->capture_default_str();
  scan->add_option("--storage", s->storage, "png (lossless) | mjpeg (camera bytes)")
      ->capture_default_str();
  scan->add_option("--feed", s->feed, "Turntable speed, degrees per second")->capture_default_str();
  scan->add_option("--baud", s->baud, "Serial baud rate")->capture_default_str();
  scan->add_option("--time-scale", s->time_scale,
                   "Simulation: simulated time per real second (0.01 = 100x faster)")
      ->capture_default_str();
  scan->add_option("--sim-fault", s->faults, "Simulation fault KIND@N (repeatable)");
  scan->add_flag(
      "--calibration", s->calibration,
      "Record a calibration session: the chessboard in several poses (calibrate reads it)");
  scan->add_option("--poses", s->cal.platter_poses, "Calibration: board placements on the platter")
      ->capture_default_str();
  scan->add_option("--handheld", s->cal.handheld, "Calibration: hand-held board views")
      ->capture_default_str();
  scan->add_option("--pose-angle-step", s->cal.angle_step_deg,
                   "Calibration: table angle step per placement (deg)")
      ->capture_default_str();
  scan->add_option("--pose-angle-max", s->cal.angle_max_deg,
                   "Calibration: table turns within +- this per placement (deg)")
      ->capture_default_str();
  scan->add_option("--pose-wait", s->pose_wait_s,
                   "Calibration on hardware: wait this many seconds at each pose instead of "
                   "asking for Enter");
  commands.push_back({scan, [s] { return run_scan(*s); }});

  auto r = std::make_shared<ReplayArgs>();
  CLI::App* replay = app.add_subcommand("replay", "Verify a session and export its frames");
  replay->add_option("session", r->session, "Session folder")->required();
  replay->add_option("--out", r->out, "Output folder")->required();
  replay->add_flag("--frames", r->frames, "Also export every frame as PNG");
  replay->add_option("--columns", r->sheet_columns, "Contact sheet columns")
      ->capture_default_str()
      ->check(in_range(1, 1000));
  commands.push_back({replay, [r] { return run_replay(*r); }});
}

int run_sim_scan(const SimScanRequest& r) {
  ScanArgs a;
  a.sim = true;
  a.scene = r.scene;
  a.out = r.out;
  a.steps = r.steps;
  a.size = r.size;
  a.time_scale = r.time_scale;
  return run_scan(a);
}

}  // namespace scanmesh::cli
