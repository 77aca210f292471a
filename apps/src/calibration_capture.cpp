#include "calibration_capture.h"

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <iostream>
#include <numbers>
#include <string>
#include <thread>

#include "scanmesh/core/errors.h"
#include "scanmesh/sim/scene.h"
#include "cli_support.h"
#include "sim_rig.h"

namespace scanmesh::cli {
namespace {

// The platter placements, in the order they are asked for. Several placements at different
// distances from the axis (in front of it and behind it) observe the axis through independent
// board poses; the leaning ones show the board from above, which the focal length needs when
// there are no hand-held views (docs/acquisition.md, "Calibration sessions").
struct PlatterPose {
  sim::BoardPlacement placement;
  const char* text;
};
const PlatterPose kPlatterPoses[kMaxPlatterPoses] = {
    {{.offset_mm = 40.0},
     "stand the board upright on the platter, printed side to the camera, its bottom edge about "
     "40 mm in front of the axis (toward the camera)"},
    {{.offset_mm = -40.0, .tilt_rad = 20.0 * kDeg},
     "lean the board back by about 20 degrees against a support, printed side to the camera, its "
     "bottom edge about 40 mm behind the axis (away from the camera)"},
    {{.offset_mm = 40.0, .tilt_rad = 25.0 * kDeg},
     "lean the board back by about 25 degrees, its bottom edge about 40 mm in front of the axis"},
    {{.offset_mm = 60.0, .shift_mm = -30.0},
     "stand the board upright about 60 mm in front of the axis, shifted about 30 mm to the left"},
    {{.offset_mm = -10.0, .shift_mm = 30.0, .tilt_rad = 20.0 * kDeg},
     "lean the board back by about 20 degrees, its bottom edge about 10 mm behind the axis, "
     "shifted about 30 mm to the right"},
};

}  // namespace

CalibrationSessionInfo make_calibration_plan(const CalibrationPlanArgs& a) {
  if (a.platter_poses < 1 || a.platter_poses > kMaxPlatterPoses)
    throw InvalidInputError("--poses must be 1.." + std::to_string(kMaxPlatterPoses));
  if (a.handheld < 0 || a.handheld > 50) throw InvalidInputError("--handheld must be 0..50");
  if (!(a.angle_step_deg >= 1 && a.angle_step_deg <= 90))
    throw InvalidInputError("--pose-angle-step must be 1..90 degrees");
  if (!(a.angle_max_deg >= 0 && a.angle_max_deg <= 85))
    throw InvalidInputError("--pose-angle-max must be 0..85 degrees");
  CalibrationSessionInfo info;
  const sim::ChessboardPattern board;  // the Ciclop pattern: 11 x 6 inner corners, 13 mm
  info.pattern = {board.corner_cols, board.corner_rows, board.square_mm, 25.0};
  std::vector<double> angles;
  for (double d = -a.angle_max_deg; d <= a.angle_max_deg + 1e-9; d += a.angle_step_deg)
    angles.push_back(d * kDeg);
  for (int k = 0; k < a.platter_poses; ++k)
    info.poses.push_back({true, kPlatterPoses[k].text, angles});
  for (int k = 0; k < a.handheld; ++k)
    info.poses.push_back({false,
                          "hold the board still in front of the camera (view " +
                              std::to_string(k + 1) + " of " + std::to_string(a.handheld) +
                              "), tilted a different way each time, the whole board in the image",
                          {0.0}});
  return info;
}

std::vector<sim::BoardPlacement> builtin_platter_placements(int n) {
  std::vector<sim::BoardPlacement> p;
  for (int k = 0; k < n && k < kMaxPlatterPoses; ++k) p.push_back(kPlatterPoses[k].placement);
  return p;
}

SimCalibrationBoard::SimCalibrationBoard(const CalibrationSessionInfo& info, int width, int height)
    : info_(info) {
  unused_scene_ = std::make_shared<sim::Scene>(sim::Scene::from_yaml_text(
      "objects:\n  - {type: sphere, name: unused, center: [0, 0, -1000], radius: 1}\n", "unused"));
  camera_ =
      std::make_shared<sim::TurntableCamera>(*unused_scene_, scaled_ciclop_rig(width, height));
  sim::CalibrationPlan plan;
  plan.board.corner_cols = info.pattern.corner_cols;
  plan.board.corner_rows = info.pattern.corner_rows;
  plan.board.square_mm = info.pattern.square_mm;
  plan.platter_bottom_mm = info.pattern.bottom_mm;
  int handheld = 0;
  for (const auto& p : info.poses) handheld += p.on_platter ? 0 : 1;
  plan.handheld_views = handheld;
  const auto held = sim::handheld_board_poses(plan, camera_->rig().platform_height_mm);
  int platter = 0, h = 0;
  for (const auto& p : info.poses) {
    if (p.on_platter) {
      patterns_.push_back(sim::place_on_platter(
          plan.board, camera_->rig().platform_height_mm, plan.platter_bottom_mm,
          kPlatterPoses[platter % kMaxPlatterPoses].placement));
      ++platter;
    } else {
      patterns_.push_back(held[h++]);
    }
  }
  set_pose(0);
}

sim::FrameRenderer SimCalibrationBoard::renderer() const {
  auto scene = unused_scene_;
  auto camera = camera_;
  return [scene, camera](double angle_rad, unsigned laser_mask) {
    return camera->render(angle_rad, laser_mask);
  };
}

void SimCalibrationBoard::set_pose(std::size_t pose) { camera_->set_pattern(patterns_.at(pose)); }

sim::ChessboardPattern SimCalibrationBoard::pose_pattern(std::size_t pose) const {
  return patterns_.at(pose);
}

std::function<void(std::size_t)> pose_prompter(const CalibrationSessionInfo& info, double wait_s) {
  auto first = std::make_shared<bool>(true);
  return [info, wait_s, first](std::size_t step) {
    const auto [pose, angle] = info.step(step);
    const bool begins = step == info.first_step(pose);
    if (!begins && !*first) return;
    *first = false;
    const auto& p = info.poses[pose];
    std::cerr << "\ncalibration pose " << pose + 1 << " of " << info.poses.size() << ": "
              << p.description << ".\n";
    if (p.on_platter)
      std::cerr << "  The table then turns through " << p.angles_rad.size()
                << " angles; do not touch the board until the next pose is asked for.\n";
    if (wait_s >= 0) {
      std::cerr << "  Starting in " << wait_s << " s...\n";
      std::this_thread::sleep_for(std::chrono::duration<double>(wait_s));
      return;
    }
    std::cerr << "  Press Enter when the board is in place." << std::endl;
    std::string line;
    if (!std::getline(std::cin, line))
      throw InvalidInputError(
          "calibration: standard input ended before pose " + std::to_string(pose + 1) +
          " was confirmed (press Enter at each pose, or give --pose-wait SECONDS)");
  };
}

}  // namespace scanmesh::cli
