// Calibration of a turntable laser scanner (docs/acquisition.md, "Calibration"): camera
// intrinsics and distortion, each laser plane, and the turntable axis, from chessboard views
// (hand-held and standing on the platter at several turntable angles) and the laser lines seen
// on the board. OpenCV detects the corners and gives initial estimates; Ceres refines everything
// in one joint bundle adjustment with a robust loss and reports per-parameter uncertainty.
//
// Frames. Everything estimated lives in the camera frame (OpenCV: x right, y down, z forward,
// millimetres). The *rig frame* of triangulated points is derived from it (rig_from_camera):
// origin on the turntable axis at the platter top, z along the axis (up), x toward the camera
// (horizontal). An object point p on the platter turned by theta is seen at R_z(theta) p in the
// rig frame; the object frame is the frame of RangeGrid.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "scanmesh/acquisition/line_extraction.h"
#include "scanmesh/core/image.h"

namespace scanmesh {

//! Pinhole + OpenCV radial-tangential distortion (k1 k2 p1 p2 k3).
struct CameraModel {
  int width = 0, height = 0;
  double fx = 0, fy = 0, cx = 0, cy = 0;
  double k1 = 0, k2 = 0, p1 = 0, p2 = 0, k3 = 0;

  Eigen::Vector2d project(const Eigen::Vector3d& p_camera) const;
  //! Undistorted normalised coordinates of a (distorted) pixel position.
  Eigen::Vector2d normalize(double u, double v) const;
  //! Unit ray through a pixel position, camera frame.
  Eigen::Vector3d ray(double u, double v) const;
};

//! A laser sheet: points X (camera frame) with normal . X = distance_mm.
struct LaserPlane {
  std::string name;
  Eigen::Vector3d normal = Eigen::Vector3d::UnitX();
  double distance_mm = 0;
};

//! One-sigma uncertainties of the estimated parameters (a-posteriori, from the covariance).
struct CalibrationUncertainty {
  double fx = 0, fy = 0, cx = 0, cy = 0, k1 = 0, k2 = 0, p1 = 0, p2 = 0, k3 = 0;
  std::vector<double> laser_normal_deg, laser_distance_mm;
  double axis_direction_deg = 0, axis_point_mm = 0;
};

struct Calibration {
  CameraModel camera;
  std::vector<LaserPlane> lasers;
  //! Turntable axis in the camera frame: a unit direction pointing up (away from the platter)
  //! and its point at the platter top.
  Eigen::Vector3d axis_direction = Eigen::Vector3d::UnitY();
  Eigen::Vector3d axis_origin_mm = Eigen::Vector3d::Zero();
  // Quality of the fit (informative; written to and read from the file).
  double reprojection_rms_px = 0, laser_rms_mm = 0;
  int views = 0, corners = 0, laser_points = 0;
  CalibrationUncertainty uncertainty;

  //! Camera frame -> rig frame (see the header comment).
  Eigen::Isometry3d rig_from_camera() const;

  //! Throws InvalidInputError when sizes, intrinsics or unit vectors are impossible.
  void validate() const;
  //! YAML (docs/formats.md, "Calibration files"). write_yaml writes atomically.
  std::string to_yaml() const;
  static Calibration from_yaml_text(const std::string& text, const std::string& source_name);
  static Calibration read_yaml(const std::filesystem::path& path);
  void write_yaml(const std::filesystem::path& path) const;
};

//! The printed chessboard: inner corners, square size, and (for views on the platter) the
//! distance on the board from its lowest corner row to the board's bottom edge, which rests on
//! the platter (Horus calls it the origin distance; for an upright board it is the height of the
//! lowest corner row above the platter top).
struct PatternSpec {
  int corner_cols = 11, corner_rows = 6;
  double square_mm = 13.0;
  double bottom_mm = 25.0;
};

//! One view of the chessboard. Hand-held views constrain the intrinsics; views standing on the
//! platter (on_turntable) at a known turntable angle also constrain the axis, and with their
//! laser frames (laser_on[k]: only laser k on) the laser planes. Platter views with the same
//! `placement` show the board standing in one place on the platter (one board pose turned with
//! the table); several placements at different distances from the axis observe the axis through
//! independent board poses.
struct CalibrationView {
  Image8 image;  //!< all lasers off
  bool on_turntable = false;
  double angle_rad = 0;
  std::vector<Image8> laser_on;
  int placement = 0;
};

struct CalibrationOptions {
  PatternSpec pattern;
  bool estimate_k3 = false;      //!< k3 is often not identifiable; fixed at 0 unless asked
  double corner_sigma_px = 0.1;  //!< expected corner noise (weights of the joint fit)
  double laser_sigma_mm = 0.1;   //!< expected laser-point scatter off its plane
  double robust_scale = 3.0;     //!< Huber loss threshold in sigmas
  //! Laser points closer than this to a square edge of the board are not used (the albedo step
  //! would move the line centre); half of it applies to edges along the line.
  double laser_edge_margin_mm = 2.5;
  LineExtractionOptions line;  //!< extraction of the laser lines on the board
};

struct CalibrationReport {
  Calibration calibration;
  int views_detected = 0, views_rejected = 0;
  //! Per view: detected corner positions (index r * corner_cols + c), empty if not detected.
  std::vector<std::vector<Eigen::Vector2d>> corners;
  double opencv_rms_px = 0;  //!< OpenCV calibrateCamera's RMS (initial estimate)
};

//! Calibrates from the views. Needs >= 3 detected hand-held or platter views, >= 3 platter views
//! at different angles for the axis, and laser points for every laser. Throws InvalidInputError
//! when the data cannot determine the parameters.
CalibrationReport calibrate_scanner(const std::vector<CalibrationView>& views, int laser_count,
                                    const CalibrationOptions& options = {});

}  // namespace scanmesh
