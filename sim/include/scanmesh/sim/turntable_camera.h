// The simulated turntable laser scanner camera (docs/acquisition.md, "Camera and laser model"):
// a pinhole camera with OpenCV lens distortion looking at a scene standing on a turntable, lit by
// ambient light and by up to a few line lasers (planes), with sensor noise, laser speckle,
// saturation and blooming. It renders RGB frames for any turntable angle and laser mask, and
// knows the exact answers: where each laser line's centre lies in every image row and which
// surface point it comes from, and where the corners of a calibration chessboard are imaged.
//
// Frames. The *rig frame* is fixed to the scanner: z is the turntable axis (up), the platter top
// lies at z = platform_height_mm; the camera and the lasers are fixed in it. The *object frame*
// turns with the platter; it is the frame of the scene, of the calibration pattern pose and of
// RangeGrid. At turntable angle theta an object point p is seen at R_z(theta) p in the rig frame
// (positive theta turns the platter counter-clockwise seen from above).
//
// Pixels: (u, v) with u to the right, v down, the centre of pixel (x, y) at u = x, v = y (the
// OpenCV convention).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "scanmesh/core/image.h"
#include "scanmesh/sim/scene.h"

namespace scanmesh::sim {

//! Pinhole intrinsics and OpenCV's radial-tangential distortion (k1 k2 p1 p2 k3).
struct CameraIntrinsics {
  double fx = 1430.0, fy = 1430.0, cx = 639.5, cy = 479.5;
  double k1 = 0.0, k2 = 0.0, p1 = 0.0, p2 = 0.0, k3 = 0.0;

  //! Normalised undistorted image coordinates (x, y) -> distorted pixel (u, v).
  Eigen::Vector2d distort_to_pixel(const Eigen::Vector2d& xy) const;
  //! Inverse of distort_to_pixel (iterated to full double precision).
  Eigen::Vector2d pixel_to_normalized(const Eigen::Vector2d& uv) const;
};

//! One line laser: its light fans out from `position_mm` in the plane through that point with
//! unit normal `normal` (rig frame).
struct LaserConfig {
  std::string name;
  Eigen::Vector3d position_mm = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::UnitY();
  //! Signed distance of a rig-frame point from the laser plane.
  double signed_distance(const Eigen::Vector3d& p) const { return normal.dot(p - position_mm); }
};

//! Everything about the simulated rig (YAML: docs/formats.md, "Turntable rig files").
struct RigConfig {
  int width = 1280, height = 960;
  CameraIntrinsics intrinsics;
  //! Camera pose in the rig frame: optical centre, a point it looks at, roll about the view axis.
  Eigen::Vector3d camera_position_mm{400.0, 0.0, 105.0};
  Eigen::Vector3d camera_look_at_mm{0.0, 0.0, 105.0};
  double camera_roll_rad = 0.0;
  std::vector<LaserConfig> lasers;
  double line_sigma_mm = 0.35;     //!< Gaussian sigma of the laser sheet across its plane
  double laser_power = 350.0;      //!< DN added on a white surface lit head-on at the line centre
  double ambient = 0.6;            //!< laser-off brightness of a white surface facing the camera
  double noise_sigma = 1.5;        //!< sensor read noise (DN)
  double shot_noise_gain = 0.02;   //!< shot-noise variance per DN of signal
  double speckle_contrast = 0.05;  //!< relative std. dev. of the laser intensity per pixel
  double bloom_fraction = 0.15;    //!< share of the light above saturation spilled around
  double bloom_radius_px = 1.5;    //!< e-folding distance of the spill
  bool platform = true;            //!< render the platter (a disc)
  double platform_radius_mm = 100.0, platform_height_mm = 0.0;
  Rgb8 platform_color{60, 60, 66};
  std::uint64_t seed = 1;

  //! Throws InvalidInputError for impossible values.
  void validate() const;
  static RigConfig from_yaml_text(const std::string& text, const std::string& source_name);
  static RigConfig from_yaml_file(const std::filesystem::path& path);
  //! YAML text that from_yaml_text reads back to the same config.
  std::string to_yaml() const;
};

//! A Ciclop-like rig: 1280 x 960 camera 400 mm from the axis, two lasers 30 degrees either side
//! of it, slightly misaligned as real ones are (docs/acquisition.md lists the numbers).
RigConfig builtin_ciclop_rig();

//! The same rig with a sensor of width x height pixels: the focal lengths and the principal point
//! scale with the sensor (pixel centres at x + 0.5 scale), everything else is kept. Used by
//! `scan --sim --scene` and the emulated scan tests to render small frames of the same view.
RigConfig rig_at_size(RigConfig rig, int width, int height);

//! A planar chessboard fixed on the platter. Board frame: x along the corner columns, y along
//! the corner rows, z = x cross y; inner corner (c, r) at (c * square_mm, r * square_mm, 0).
//! The printed side is the one seen looking along +z (OpenCV's convention); the back is grey.
//! The printed area has one full square beyond the outer inner corners plus a white margin.
//! Square (-1, -1) (the one left of and above corner (0, 0)) is black.
struct ChessboardPattern {
  int corner_cols = 11, corner_rows = 6;
  double square_mm = 13.0;
  double margin_mm = 8.0;
  //! Board frame -> object (platter) frame.
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  double white_albedo = 0.9, black_albedo = 0.06;

  //! Object-frame position of inner corner (c, r).
  Eigen::Vector3d corner(int c, int r) const;
  //! A board standing upright on the platter, facing the rig's +x side at turntable angle 0
  //! (the side where the built-in camera is), its lowest corner row `bottom_mm` above the platter
  //! top and its centre `offset_mm` off the axis along the board normal.
  static ChessboardPattern upright(double platform_height_mm, double bottom_mm = 25.0,
                                   double offset_mm = 0.0);
};

//! Ground truth of one laser-line centre in one image row.
struct LinePointTruth {
  int row = 0;
  double u = 0.0;             //!< distorted image column of the line centre (v = row)
  Eigen::Vector3d point_rig;  //!< the surface point lit at the centre of the sheet
  Eigen::Vector3d point_object;
  bool on_platform = false;  //!< the point lies on the platter (or on the pattern's backing)
};

class TurntableCamera {
 public:
  //! Keeps a reference to `scene` (it must outlive the camera). Throws InvalidInputError for an
  //! invalid rig.
  TurntableCamera(const Scene& scene, RigConfig rig);
  ~TurntableCamera();
  TurntableCamera(const TurntableCamera&) = delete;
  TurntableCamera& operator=(const TurntableCamera&) = delete;

  const RigConfig& rig() const { return rig_; }
  int laser_count() const { return static_cast<int>(rig_.lasers.size()); }

  //! Calibration-pattern mode: with a pattern set, render shows the board (and the platter)
  //! instead of the scene. nullopt returns to the scene.
  void set_pattern(std::optional<ChessboardPattern> pattern);
  const std::optional<ChessboardPattern>& pattern() const { return pattern_; }

  //! RGB frame at the turntable angle with laser k on iff bit k of laser_mask is set.
  //! Deterministic: the same rig (incl. seed), angle and mask give the same bytes.
  //! Thread-safe; the ray casts of the last angle are cached, so rendering all masks of one
  //! angle in a row costs one set of ray casts.
  Image8 render(double turntable_angle_rad, unsigned laser_mask) const;

  //! Exact laser-line centres of laser k at the angle: every image row where the sheet's centre
  //! plane meets a lit, visible surface (possibly several per row), with the surface point.
  std::vector<LinePointTruth> laser_line_truth(double turntable_angle_rad, int laser) const;

  //! Exact distorted image positions of the pattern's inner corners at the angle, index
  //! r * corner_cols + c; nullopt if a corner is outside the image or the board faces away.
  std::vector<std::optional<Eigen::Vector2d>> pattern_corner_truth(
      double turntable_angle_rad) const;

  //! Rig frame -> camera frame (x right, y down, z forward, OpenCV).
  const Eigen::Isometry3d& camera_from_rig() const { return camera_from_rig_; }
  //! Distorted pixel of a rig-frame point (nullopt if behind the camera).
  std::optional<Eigen::Vector2d> project(const Eigen::Vector3d& p_rig) const;
  //! Unit ray direction (rig frame) through distorted pixel position (u, v).
  Eigen::Vector3d pixel_ray(double u, double v) const;
  Eigen::Vector3d camera_center() const { return rig_.camera_position_mm; }

  struct HitBuffer;  // per-pixel ray casts of one angle (private detail)

 private:
  std::shared_ptr<const HitBuffer> hits(double angle) const;
  struct SurfaceHit;
  //! The turntable's rotation at one angle, built once per frame rather than once per ray.
  struct Turn {
    explicit Turn(double angle);
    Eigen::Matrix3d to_object, to_rig;
  };
  std::optional<SurfaceHit> cast(const Eigen::Vector3d& origin_rig, const Eigen::Vector3d& dir_rig,
                                 const Turn& turn) const;
  bool laser_reaches(const Eigen::Vector3d& p_rig, int laser, const Turn& turn) const;

  const Scene& scene_;
  RigConfig rig_;
  std::optional<ChessboardPattern> pattern_;
  Eigen::Isometry3d board_from_object_ = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d camera_from_rig_;
  std::vector<Eigen::Vector2f> normalized_;  // per pixel, undistorted normalised coordinates
  mutable std::mutex cache_mutex_;
  mutable std::shared_ptr<const HitBuffer> cache_;
};

//! Where the board stands on the platter in one placement of a calibration session: upright
//! (or leaning back by `tilt_rad` about its bottom edge, which rests on the platter), its printed
//! side toward the camera at turntable angle 0, its bottom edge `offset_mm` off the axis toward
//! the camera (negative: behind the axis) and shifted `shift_mm` sideways along the board.
struct BoardPlacement {
  double offset_mm = 30.0;
  double shift_mm = 0.0;
  double tilt_rad = 0.0;
};

//! `board` (size, squares) standing on the platter as `placement` says, its lowest corner row
//! `bottom_mm` above the bottom edge (along the board).
ChessboardPattern place_on_platter(const ChessboardPattern& board, double platform_height_mm,
                                   double bottom_mm, const BoardPlacement& placement);

//! A calibration session for the simulated rig: hand-held board poses (tilted views in front of
//! the camera, for the intrinsics) and the board standing on the platter in one or more
//! placements, each at several turntable angles with each laser's frame (for the laser planes
//! and the axis).
struct CalibrationPlan {
  ChessboardPattern board;          //!< size, squares, albedo; the pose is set per shot
  double platter_bottom_mm = 25.0;  //!< lowest corner row above the board's bottom edge
  double platter_offset_mm = 30.0;  //!< board plane this far off the axis (toward the camera)
  //! Empty: one upright placement `platter_offset_mm` off the axis.
  std::vector<BoardPlacement> placements;
  std::vector<double>
      platter_angles_rad;  //!< empty: -70..70 degrees every 10 degrees (tests and CLI use 5)
  int handheld_views = 16;
  bool handheld_lasers = true;  //!< also render each laser's frame of the hand-held views
};
struct CalibrationShot {
  Image8 image;  //!< lasers off
  bool on_turntable = false;
  double angle_rad = 0;
  std::vector<Image8> laser_on;  //!< laser k alone (platter shots; hand-held if asked)
  ChessboardPattern pattern;     //!< the exact board pose of the shot (object frame)
  int placement = 0;             //!< index into the plan's placements (platter shots)
};
//! The board poses of the plan's hand-held views (object frame, seen at turntable angle 0).
std::vector<ChessboardPattern> handheld_board_poses(const CalibrationPlan& plan,
                                                    double platform_height_mm);
//! Renders the plan's shots (restores the camera's pattern mode afterwards). Deterministic.
std::vector<CalibrationShot> render_calibration_shots(TurntableCamera& camera,
                                                      const CalibrationPlan& plan = {});

}  // namespace scanmesh::sim
