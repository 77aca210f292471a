// Scanner calibration: OpenCV detection and initial estimates, one joint Ceres bundle adjustment
// (docs/acquisition.md, "Calibration").
#include "scanmesh/acquisition/calibration.h"

#include <ceres/ceres.h>
#include <ceres/rotation.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <memory_resource>
#include <numbers>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/utility.hpp>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <vector>

#include "scanmesh/core/errors.h"

namespace scanmesh {
namespace {

using Eigen::Vector2d;
using Eigen::Vector3d;
constexpr double kRadToDeg = 180.0 / std::numbers::pi;

template <typename T>
void distort(const T* in, T x, T y, T* u, T* v) {
  // in: fx fy cx cy k1 k2 p1 p2 k3
  const T r2 = x * x + y * y;
  const T radial = T(1) + r2 * (in[4] + r2 * (in[5] + r2 * in[8]));
  const T xd = x * radial + T(2) * in[6] * x * y + in[7] * (r2 + T(2) * x * x);
  const T yd = y * radial + in[6] * (r2 + T(2) * y * y) + T(2) * in[7] * x * y;
  *u = in[0] * xd + in[2];
  *v = in[1] * yd + in[3];
}

// Undistortion by fixed-point iteration (enough iterations for the mild distortion of webcams;
// differentiable through the Jets).
template <typename T>
void undistort(const T* in, double u, double v, T* x, T* y) {
  const T xd = (T(u) - in[2]) / in[0], yd = (T(v) - in[3]) / in[1];
  T px = xd, py = yd;
  for (int it = 0; it < 20; ++it) {
    const T r2 = px * px + py * py;
    const T radial = T(1) + r2 * (in[4] + r2 * (in[5] + r2 * in[8]));
    const T dx = T(2) * in[6] * px * py + in[7] * (r2 + T(2) * px * px);
    const T dy = in[6] * (r2 + T(2) * py * py) + T(2) * in[7] * px * py;
    px = (xd - dx) / radial;
    py = (yd - dy) / radial;
  }
  *x = px;
  *y = py;
}

// Board point -> camera frame for a view on the platter at angle theta:
// X(theta) = R(axis, theta) (X(0) - p) + p, X(0) = R0 Xb + t0.
template <typename T>
void turntable_point(const T* pose0, const T* axis, const T* point, double theta, const T* xb,
                     T* out) {
  T x0[3];
  ceres::AngleAxisRotatePoint(pose0, xb, x0);
  for (int k = 0; k < 3; ++k) x0[k] += pose0[3 + k] - point[k];
  const T aa[3] = {axis[0] * T(theta), axis[1] * T(theta), axis[2] * T(theta)};
  ceres::AngleAxisRotatePoint(aa, x0, out);
  for (int k = 0; k < 3; ++k) out[k] += point[k];
}

struct HandheldCorner {
  Vector2d obs;
  Vector3d xb;
  double sigma;
  template <typename T>
  bool operator()(const T* in, const T* pose, T* r) const {
    const T xbt[3] = {T(xb.x()), T(xb.y()), T(xb.z())};
    T p[3];
    ceres::AngleAxisRotatePoint(pose, xbt, p);
    for (int k = 0; k < 3; ++k) p[k] += pose[3 + k];
    T u, v;
    distort(in, p[0] / p[2], p[1] / p[2], &u, &v);
    r[0] = (u - obs.x()) / sigma;
    r[1] = (v - obs.y()) / sigma;
    return true;
  }
};

struct TurntableCorner {
  Vector2d obs;
  Vector3d xb;
  double theta, sigma;
  template <typename T>
  bool operator()(const T* in, const T* pose0, const T* axis, const T* point, T* r) const {
    const T xbt[3] = {T(xb.x()), T(xb.y()), T(xb.z())};
    T p[3];
    turntable_point(pose0, axis, point, theta, xbt, p);
    T u, v;
    distort(in, p[0] / p[2], p[1] / p[2], &u, &v);
    r[0] = (u - obs.x()) / sigma;
    r[1] = (v - obs.y()) / sigma;
    return true;
  }
};

// A laser peak on the board: its pixel ray meets the board plane at X; X must lie on the plane.
struct LaserOnBoard {
  Vector2d obs;
  double theta, sigma;
  template <typename T>
  bool operator()(const T* in, const T* pose0, const T* axis, const T* point, const T* normal,
                  const T* dist, T* r) const {
    T x, y;
    undistort(in, obs.x(), obs.y(), &x, &y);
    // Board plane at theta: through the image of the board origin, normal = image of board z.
    const T zero[3] = {T(0), T(0), T(0)}, ez[3] = {T(0), T(0), T(1)};
    T o[3], e[3];
    turntable_point(pose0, axis, point, theta, zero, o);
    turntable_point(pose0, axis, point, theta, ez, e);
    const T nb[3] = {e[0] - o[0], e[1] - o[1], e[2] - o[2]};
    const T ray[3] = {x, y, T(1)};
    const T den = nb[0] * ray[0] + nb[1] * ray[1] + nb[2] * ray[2];
    const T t = (nb[0] * o[0] + nb[1] * o[1] + nb[2] * o[2]) / den;
    const T X[3] = {t * ray[0], t * ray[1], t * ray[2]};
    r[0] = (normal[0] * X[0] + normal[1] * X[1] + normal[2] * X[2] - dist[0]) / sigma;
    return true;
  }
};

// The same for a hand-held view (the lasers are fixed in the rig, the board is anywhere).
struct HandheldLaser {
  Vector2d obs;
  double sigma;
  template <typename T>
  bool operator()(const T* in, const T* pose, const T* normal, const T* dist, T* r) const {
    T x, y;
    undistort(in, obs.x(), obs.y(), &x, &y);
    const T ez[3] = {T(0), T(0), T(1)};
    T nb[3];
    ceres::AngleAxisRotatePoint(pose, ez, nb);
    const T ray[3] = {x, y, T(1)};
    const T den = nb[0] * ray[0] + nb[1] * ray[1] + nb[2] * ray[2];
    const T t = (nb[0] * pose[3] + nb[1] * pose[4] + nb[2] * pose[5]) / den;
    r[0] = (normal[0] * t * ray[0] + normal[1] * t * ray[1] + normal[2] * t * ray[2] - dist[0]) /
           sigma;
    return true;
  }
};

// Keeps the axis point the one nearest the camera centre (removes the slide along the axis).
struct AxisGauge {
  template <typename T>
  bool operator()(const T* axis, const T* point, T* r) const {
    r[0] = T(10.0) * (axis[0] * point[0] + axis[1] * point[1] + axis[2] * point[2]);
    return true;
  }
};

Eigen::Matrix3d rodrigues(const Vector3d& aa) {
  const double a = aa.norm();
  if (a < 1e-15) return Eigen::Matrix3d::Identity();
  return Eigen::AngleAxisd(a, aa / a).toRotationMatrix();
}
Vector3d to_angle_axis(const Eigen::Matrix3d& r) {
  const Eigen::AngleAxisd aa(r);
  return aa.angle() * aa.axis();
}

Vector3d fit_plane(const std::vector<Vector3d>& pts, double* d) {
  Vector3d c = Vector3d::Zero();
  for (const auto& p : pts) c += p;
  c /= static_cast<double>(pts.size());
  Eigen::Matrix3d m = Eigen::Matrix3d::Zero();
  for (const auto& p : pts) m += (p - c) * (p - c).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(m);
  Vector3d n = es.eigenvectors().col(0);
  *d = n.dot(c);
  if (*d < 0) n = -n, *d = -*d;
  return n;
}

cv::Mat to_gray(const Image8& img) {
  cv::Mat gray(img.height, img.width, CV_8UC1);
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) {
      const std::uint8_t* p = img.at(x, y);
      gray.at<std::uint8_t>(y, x) =
          img.channels >= 3
              ? static_cast<std::uint8_t>((299 * p[0] + 587 * p[1] + 114 * p[2]) / 1000)
              : p[0];
    }
  return gray;
}

// True if the 2nd and 98th percentiles of the grey values are less than 64 DN apart: a dim or
// washed-out view, the case OpenCV's histogram normalisation is for.
bool low_contrast(const cv::Mat& gray) {
  int hist[256] = {};
  for (int y = 0; y < gray.rows; ++y)
    for (int x = 0; x < gray.cols; ++x) ++hist[gray.at<std::uint8_t>(y, x)];
  const long total = static_cast<long>(gray.rows) * gray.cols;
  long acc = 0;
  int lo = -1, hi = 255;
  for (int v = 0; v < 256; ++v) {
    acc += hist[v];
    if (lo < 0 && acc >= total / 50) lo = v;
    if (acc >= total - total / 50) {
      hi = v;
      break;
    }
  }
  return hi - lo < 64;
}

// Chessboard corners of one view, refined to sub-pixel accuracy. The search is a cascade of
// rising cost, stopping at the first success: a global threshold, then adaptive thresholds,
// then (only for a low-contrast view) adaptive thresholds on the histogram-equalised image.
// A view with a board finds it in the first step (2-4 ms at 1280 x 960, with the same corners
// after refinement as the full-flag search on all 60 found views of the test plan). The cost
// is in the views without a whole board: there the equalisation amplifies the noise of a dark
// background into thousands of quads, and the full-flag search took 19 s on one partly
// visible board; the cascade gives up on it in about 1 s. CALIB_CB_FAST_CHECK is not used:
// it rejected 4 of those 60 views. Views are searched in parallel.
std::optional<std::vector<cv::Point2f>> detect_chessboard(const cv::Mat& gray,
                                                          const cv::Size& pattern_size) {
  const int cascade[] = {0, cv::CALIB_CB_ADAPTIVE_THRESH,
                         cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_NORMALIZE_IMAGE};
  std::vector<cv::Point2f> corners;
  for (int flags : cascade) {
    // The contrast histogram only when the last step is reached (most views stop at the first).
    if ((flags & cv::CALIB_CB_NORMALIZE_IMAGE) && !low_contrast(gray)) break;
    if (!cv::findChessboardCorners(gray, pattern_size, corners, flags)) continue;
    cv::cornerSubPix(gray, corners, cv::Size(7, 7), cv::Size(-1, -1),
                     cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 100, 1e-4));
    return corners;
  }
  return std::nullopt;
}

// calibrate_scanner's preconditions, checked before anything is computed.
void check_calibration_input(const std::vector<CalibrationView>& views, int laser_count,
                             const PatternSpec& pat) {
  if (pat.corner_cols < 3 || pat.corner_rows < 3 || !(pat.square_mm > 0))
    throw InvalidInputError("calibration: the pattern needs >= 3 x 3 corners and a square size");
  if (laser_count < 0 || laser_count > 8)
    throw InvalidInputError("calibration: laser count must be 0..8");
  if (views.empty()) throw InvalidInputError("calibration: no views");
  const int w = views[0].image.width, h = views[0].image.height;
  for (const auto& v : views) {
    if (v.image.width != w || v.image.height != h)
      throw InvalidInputError("calibration: all views must have the same image size");
    if (v.on_turntable && static_cast<int>(v.laser_on.size()) != laser_count && !v.laser_on.empty())
      throw InvalidInputError("calibration: a platter view has " +
                              std::to_string(v.laser_on.size()) + " laser frames, expected " +
                              std::to_string(laser_count));
  }
}

// The inner corners on the board (z = 0), row by row: index r * corner_cols + c.
std::vector<cv::Point3f> board_corners(const PatternSpec& pat) {
  std::vector<cv::Point3f> board;
  for (int r = 0; r < pat.corner_rows; ++r)
    for (int c = 0; c < pat.corner_cols; ++c)
      board.emplace_back(static_cast<float>(c * pat.square_mm),
                         static_cast<float>(r * pat.square_mm), 0.0f);
  return board;
}

// The board plane of a platter view at turntable angle theta: the image of the board origin
// and the image of board z minus it (the plane normal).
void board_plane_at(const double* in_pose0, const double* ax, const double* pt, double theta,
                    Vector3d* origin, Vector3d* normal) {
  const double zero[3] = {0, 0, 0}, ez[3] = {0, 0, 1};
  double o[3], e[3];
  turntable_point(in_pose0, ax, pt, theta, zero, o);
  turntable_point(in_pose0, ax, pt, theta, ez, e);
  *origin = Vector3d(o[0], o[1], o[2]);
  *normal = Vector3d(e[0] - o[0], e[1] - o[1], e[2] - o[2]);
}

// A laser peak kept for the joint adjustment.
struct LaserObs {
  int laser;
  double theta;
  Vector2d uv;
  int handheld_view;  // index into `used_` of a hand-held view, -1 for platter views
  int placement;      // dense placement index of a platter view
};

// Throws when Ceres gives no usable solution.
ceres::Solver::Summary solve_joint_adjustment(ceres::Problem& problem) {
  ceres::Solver::Options so;
  so.linear_solver_type = ceres::DENSE_SCHUR;
  so.max_num_iterations = 200;
  so.function_tolerance = 1e-12;
  so.parameter_tolerance = 1e-12;
  so.num_threads = 1;
  ceres::Solver::Summary summary;
  ceres::Solve(so, &problem, &summary);
  if (!summary.IsSolutionUsable())
    throw InvalidInputError("calibration: the joint adjustment failed: " + summary.message);
  return summary;
}

// A-posteriori variance factor: the weighted residuals should have unit variance.
double variance_factor(const ceres::Solver::Summary& summary) {
  const int n_res = summary.num_residuals_reduced;
  const int n_par = summary.num_effective_parameters_reduced;
  return n_res > n_par ? 2.0 * summary.final_cost / (n_res - n_par) : 1.0;
}

// The steps of calibrate_scanner and the state they hand on: the views with corners, the
// platter placements, the laser observations, and the parameters of the joint adjustment
// (initial estimates from steps 2-4, refined in place by step 5). The ceres::Problem keeps
// pointers into the parameter arrays, so an instance must neither move nor be copied while a
// problem built from it lives.
class ScannerCalibrator {
 public:
  ScannerCalibrator(const std::vector<CalibrationView>& views, int laser_count,
                    const CalibrationOptions& opt)
      : views_(views),
        laser_count_(laser_count),
        opt_(opt),
        pat_(opt.pattern),
        w_(views[0].image.width),
        h_(views[0].image.height),
        board_(board_corners(opt.pattern)) {}
  ScannerCalibrator(const ScannerCalibrator&) = delete;
  ScannerCalibrator& operator=(const ScannerCalibrator&) = delete;

  // Step 1: the corners of every view; fills the report's corners and view counts.
  void detect_corners(CalibrationReport& report);
  // Step 2: OpenCV's intrinsics and board poses; returns its RMS reprojection error.
  double estimate_initial_camera();
  // Step 3: the platter views by placement, the axis, and each placement's board at angle 0.
  void group_platter_views();
  Vector3d initial_axis_direction() const;
  Vector3d initial_axis_point(const Vector3d& axis) const;
  void init_turntable_parameters(const Vector3d& axis, const Vector3d& point);
  // Step 4: the laser observations, and per laser their points in the camera frame.
  std::vector<std::vector<Vector3d>> collect_laser_observations();
  void fit_initial_laser_planes(const std::vector<std::vector<Vector3d>>& laser_pts);
  // Step 5: every residual of the joint adjustment, the gauge and the manifolds.
  void build_joint_adjustment(ceres::Problem& problem);
  // Step 6: the result with its fit quality, and its uncertainty.
  Calibration calibration() const;
  CalibrationUncertainty uncertainty(ceres::Problem& problem, const ceres::Solver::Summary& summary,
                                     const Calibration& cal) const;

 private:
  // Camera-from-board rotation and translation of used view j (the initial estimate).
  Eigen::Matrix3d initial_rotation(int j) const {
    return rodrigues(Vector3d(pose_[j][0], pose_[j][1], pose_[j][2]));
  }
  Vector3d initial_translation(int j) const {
    return Vector3d(pose_[j][3], pose_[j][4], pose_[j][5]);
  }
  void add_corner_residuals(ceres::Problem& problem, ceres::LossFunction* loss);
  void add_laser_residuals(ceres::Problem& problem, ceres::LossFunction* loss);
  // Unweighted residuals, evaluated without the loss: sums of squares.
  double corner_sse() const;
  double laser_sse() const;
  Vector3d platter_top_on_axis(const Vector3d& a, const Vector3d& p) const;

  const std::vector<CalibrationView>& views_;
  const int laser_count_;
  const CalibrationOptions& opt_;
  const PatternSpec& pat_;
  const int w_, h_;  // image size, the same in every view
  const std::vector<cv::Point3f> board_;

  std::vector<int> used_;                               // view indices with corners
  std::vector<std::vector<cv::Point2f>> image_points_;  // per index into `used_`
  std::vector<int> tt_;                                 // indices into `used_` of platter views
  std::vector<int> placement_of_;  // per index into `used_`: dense placement index, -1 hand-held
  int n_place_ = 0;
  std::vector<int> ref_of_;  // first platter view of each placement
  std::vector<LaserObs> laser_obs_;
  int n_corners_ = 0;

  // Parameter blocks of the joint adjustment. Ceres' covariance orders the blocks by their
  // addresses, so the sizes of its dense SVD's rounding errors depend on where the blocks lie:
  // the variable-size ones come from one arena in a fixed order (with the general heap, their
  // order followed the allocator's history and the uncertainties changed in the 14th digit
  // from run to run). Each vector is sized once and the buffer holds them all; the arena has no
  // upstream, so a block that did not fit would throw instead of landing elsewhere.
  double in_[9] = {};                        // fx fy cx cy k1 k2 p1 p2 k3
  double axis_p_[3] = {}, point_p_[3] = {};  // turntable axis: direction, point
  std::vector<std::byte> parameter_buffer_ = std::vector<std::byte>(
      (2 * views_.size() * 6 + 4 * static_cast<std::size_t>(laser_count_)) * sizeof(double) + 1024);
  std::pmr::monotonic_buffer_resource parameter_arena_{
      parameter_buffer_.data(), parameter_buffer_.size(), std::pmr::null_memory_resource()};
  // Per index into `used_`: angle-axis, translation.
  std::pmr::vector<std::array<double, 6>> pose_{&parameter_arena_};
  // Per placement: the board's pose at turntable angle 0.
  std::pmr::vector<std::array<double, 6>> pose0s_{&parameter_arena_};
  // Per laser: the plane normal . X = ldist_.
  std::pmr::vector<std::array<double, 3>> lnormal_{&parameter_arena_};
  std::pmr::vector<double> ldist_{&parameter_arena_};
};

void ScannerCalibrator::detect_corners(CalibrationReport& report) {
  const cv::Size pattern_size(pat_.corner_cols, pat_.corner_rows);
  std::vector<std::optional<std::vector<cv::Point2f>>> found(views_.size());
  cv::parallel_for_(cv::Range(0, static_cast<int>(views_.size())), [&](const cv::Range& range) {
    for (int i = range.start; i < range.end; ++i)
      found[i] = detect_chessboard(to_gray(views_[i].image), pattern_size);
  });
  for (std::size_t i = 0; i < views_.size(); ++i) {
    if (!found[i]) {
      ++report.views_rejected;
      continue;
    }
    std::vector<cv::Point2f>& corners = *found[i];
    // OpenCV may start at either end of the board: put corner (0, 0) at the image top-left.
    if (corners.front().x + corners.front().y > corners.back().x + corners.back().y)
      std::reverse(corners.begin(), corners.end());
    for (const auto& c : corners) report.corners[i].emplace_back(c.x, c.y);
    used_.push_back(static_cast<int>(i));
    image_points_.push_back(corners);
  }
  report.views_detected = static_cast<int>(used_.size());
  if (used_.size() < 3)
    throw InvalidInputError("calibration: the chessboard was found in " +
                            std::to_string(used_.size()) + " views; at least 3 are needed");
}

double ScannerCalibrator::estimate_initial_camera() {
  std::vector<std::vector<cv::Point3f>> object_points(used_.size(), board_);
  cv::Mat k, dist;
  std::vector<cv::Mat> rvecs, tvecs;
  int flags = 0;
  if (!opt_.estimate_k3) flags |= cv::CALIB_FIX_K3;
  const double rms_px = cv::calibrateCamera(object_points, image_points_, cv::Size(w_, h_), k, dist,
                                            rvecs, tvecs, flags);
  const double in[9] = {
      k.at<double>(0, 0), k.at<double>(1, 1), k.at<double>(0, 2),
      k.at<double>(1, 2), dist.at<double>(0), dist.at<double>(1),
      dist.at<double>(2), dist.at<double>(3), dist.total() > 4 ? dist.at<double>(4) : 0.0};
  std::copy(in, in + 9, in_);
  pose_.resize(used_.size());
  for (std::size_t j = 0; j < used_.size(); ++j)
    for (int q = 0; q < 3; ++q) {
      pose_[j][q] = rvecs[j].at<double>(q);
      pose_[j][3 + q] = tvecs[j].at<double>(q);
    }
  return rms_px;
}

// Dense placement indices of the platter views and the first view of each placement.
void ScannerCalibrator::group_platter_views() {
  std::vector<int> placement_ids;
  for (std::size_t j = 0; j < used_.size(); ++j) {
    placement_of_.push_back(-1);
    const CalibrationView& v = views_[used_[j]];
    if (!v.on_turntable) continue;
    tt_.push_back(static_cast<int>(j));
    auto it = std::find(placement_ids.begin(), placement_ids.end(), v.placement);
    if (it == placement_ids.end()) {
      placement_ids.push_back(v.placement);
      it = placement_ids.end() - 1;
    }
    placement_of_[j] = static_cast<int>(it - placement_ids.begin());
  }
  if (tt_.size() < 3)
    throw InvalidInputError("calibration: the board was found standing on the platter in " +
                            std::to_string(tt_.size()) + " views; at least 3 are needed");
  n_place_ = static_cast<int>(placement_ids.size());
  ref_of_.assign(n_place_, -1);
  for (int j : tt_)
    if (ref_of_[placement_of_[j]] < 0) ref_of_[placement_of_[j]] = j;
}

// The mean rotation axis of the platter views relative to the first view of their placement,
// weighted by the turntable angle between them; a unit vector.
Vector3d ScannerCalibrator::initial_axis_direction() const {
  Vector3d axis = Vector3d::Zero();
  for (int j : tt_) {
    const int ref = ref_of_[placement_of_[j]];
    const double dtheta = views_[used_[j]].angle_rad - views_[used_[ref]].angle_rad;
    if (std::abs(dtheta) < 1e-3) continue;
    const Vector3d aa = to_angle_axis(initial_rotation(j) * initial_rotation(ref).transpose());
    axis += (dtheta > 0 ? 1.0 : -1.0) * aa.normalized() * std::abs(dtheta);
  }
  if (!(axis.norm() > 0))
    throw InvalidInputError(
        "calibration: the platter views of each board placement all have the same angle");
  axis.normalize();
  return axis;
}

// The point on the axis that turns each placement's first board origin into the others, in
// the least-squares sense; the last row picks the point nearest the camera centre.
Vector3d ScannerCalibrator::initial_axis_point(const Vector3d& axis) const {
  Eigen::MatrixXd a(3 * tt_.size() + 1, 3);
  Eigen::VectorXd b(3 * tt_.size() + 1);
  for (std::size_t q = 0; q < tt_.size(); ++q) {
    const int ref = ref_of_[placement_of_[tt_[q]]];
    const double dtheta = views_[used_[tt_[q]]].angle_rad - views_[used_[ref]].angle_rad;
    const Eigen::Matrix3d r = Eigen::AngleAxisd(dtheta, axis).toRotationMatrix();
    a.block<3, 3>(3 * q, 0) = Eigen::Matrix3d::Identity() - r;
    b.segment<3>(3 * q) = initial_translation(tt_[q]) - r * initial_translation(ref);
  }
  a.row(3 * tt_.size()) = axis.transpose();
  b(3 * tt_.size()) = 0;
  return a.colPivHouseholderQr().solve(b);
}

void ScannerCalibrator::init_turntable_parameters(const Vector3d& axis, const Vector3d& point) {
  for (int q = 0; q < 3; ++q) axis_p_[q] = axis[q], point_p_[q] = point[q];
  // Board pose at turntable angle 0, one per placement.
  pose0s_.resize(n_place_);
  for (int pk = 0; pk < n_place_; ++pk) {
    const int ref = ref_of_[pk];
    const double theta_ref = views_[used_[ref]].angle_rad;
    const Eigen::Matrix3d back = Eigen::AngleAxisd(-theta_ref, axis).toRotationMatrix();
    const Vector3d aa = to_angle_axis(back * initial_rotation(ref));
    const Vector3d t0 = back * (initial_translation(ref) - point) + point;
    for (int q = 0; q < 3; ++q) pose0s_[pk][q] = aa[q], pose0s_[pk][3 + q] = t0[q];
  }
}

// Laser peaks on the printed area of the board, in the views with every laser frame.
std::vector<std::vector<Vector3d>> ScannerCalibrator::collect_laser_observations() {
  std::vector<std::vector<Vector3d>> laser_pts(laser_count_);
  CameraModel cam0{w_, h_, in_[0], in_[1], in_[2], in_[3], in_[4], in_[5], in_[6], in_[7], in_[8]};
  for (int j = 0; j < static_cast<int>(used_.size()); ++j) {
    const CalibrationView& v = views_[used_[j]];
    if (static_cast<int>(v.laser_on.size()) != laser_count_) continue;
    Vector3d o, nb;
    if (v.on_turntable) {
      board_plane_at(pose0s_[placement_of_[j]].data(), axis_p_, point_p_, v.angle_rad, &o, &nb);
    } else {
      o = initial_translation(j);
      nb = initial_rotation(j).col(2);
    }
    const Eigen::Matrix3d rb = initial_rotation(j);
    for (int l = 0; l < laser_count_; ++l) {
      for (const LinePeak& p : extract_laser_line(v.laser_on[l], v.image, opt_.line)) {
        const Vector3d ray = cam0.ray(p.u, p.row);
        const double t = nb.dot(o) / nb.dot(ray);
        const Vector3d x = t * ray;
        const Vector3d q = rb.transpose() * (x - initial_translation(j));  // board coordinates
        const double s = pat_.square_mm, margin = 0.5 * s;
        if (q.x() < -s + margin || q.x() > pat_.corner_cols * s - margin || q.y() < -s + margin ||
            q.y() > pat_.corner_rows * s - margin)
          continue;
        // Only the middle of white squares: an albedo edge inside the line's profile moves its
        // centre (the line runs along the board's y, so the x edges matter most).
        const double ex = std::abs(std::remainder(q.x(), s));
        const double ey = std::abs(std::remainder(q.y(), s));
        if (ex < opt_.laser_edge_margin_mm || ey < 0.5 * opt_.laser_edge_margin_mm) continue;
        const int xc = static_cast<int>(std::lround(p.u));
        int bright = 0;
        for (int xx = std::max(0, xc - 40); xx <= std::min(w_ - 1, xc + 40); ++xx)
          bright = std::max<int>(bright, v.image.at(xx, p.row)[v.image.channels > 1 ? 1 : 0]);
        if (v.image.at(xc, p.row)[v.image.channels > 1 ? 1 : 0] < bright / 2) continue;
        laser_obs_.push_back(
            {l, v.angle_rad, Vector2d(p.u, p.row), v.on_turntable ? -1 : j, placement_of_[j]});
        laser_pts[l].push_back(x);
      }
    }
  }
  return laser_pts;
}

void ScannerCalibrator::fit_initial_laser_planes(
    const std::vector<std::vector<Vector3d>>& laser_pts) {
  lnormal_.resize(laser_count_);
  ldist_.assign(laser_count_, 0.0);
  for (int l = 0; l < laser_count_; ++l) {
    if (laser_pts[l].size() < 20)
      throw InvalidInputError("calibration: laser " + std::to_string(l) + " was seen at only " +
                              std::to_string(laser_pts[l].size()) +
                              " points on the board (need platter views with that laser on)");
    const Vector3d n = fit_plane(laser_pts[l], &ldist_[l]);
    lnormal_[l] = {n.x(), n.y(), n.z()};
  }
}

void ScannerCalibrator::build_joint_adjustment(ceres::Problem& problem) {
  ceres::LossFunction* loss = new ceres::HuberLoss(opt_.robust_scale);
  add_corner_residuals(problem, loss);
  add_laser_residuals(problem, loss);
  problem.AddResidualBlock(new ceres::AutoDiffCostFunction<AxisGauge, 1, 3, 3>(new AxisGauge),
                           nullptr, axis_p_, point_p_);
  problem.SetManifold(axis_p_, new ceres::SphereManifold<3>());
  for (int l = 0; l < laser_count_; ++l)
    problem.SetManifold(lnormal_[l].data(), new ceres::SphereManifold<3>());
  if (!opt_.estimate_k3) problem.SetManifold(in_, new ceres::SubsetManifold(9, {8}));
}

void ScannerCalibrator::add_corner_residuals(ceres::Problem& problem, ceres::LossFunction* loss) {
  n_corners_ = 0;
  for (std::size_t j = 0; j < used_.size(); ++j) {
    const CalibrationView& v = views_[used_[j]];
    for (int c = 0; c < pat_.corner_cols * pat_.corner_rows; ++c) {
      const Vector2d obs(image_points_[j][c].x, image_points_[j][c].y);
      const Vector3d xb(board_[c].x, board_[c].y, 0.0);
      if (v.on_turntable) {
        problem.AddResidualBlock(
            new ceres::AutoDiffCostFunction<TurntableCorner, 2, 9, 6, 3, 3>(
                new TurntableCorner{obs, xb, v.angle_rad, opt_.corner_sigma_px}),
            loss, in_, pose0s_[placement_of_[j]].data(), axis_p_, point_p_);
      } else {
        problem.AddResidualBlock(new ceres::AutoDiffCostFunction<HandheldCorner, 2, 9, 6>(
                                     new HandheldCorner{obs, xb, opt_.corner_sigma_px}),
                                 loss, in_, pose_[j].data());
      }
      ++n_corners_;
    }
  }
}

void ScannerCalibrator::add_laser_residuals(ceres::Problem& problem, ceres::LossFunction* loss) {
  for (const auto& o : laser_obs_) {
    if (o.handheld_view >= 0)
      problem.AddResidualBlock(new ceres::AutoDiffCostFunction<HandheldLaser, 1, 9, 6, 3, 1>(
                                   new HandheldLaser{o.uv, opt_.laser_sigma_mm}),
                               loss, in_, pose_[o.handheld_view].data(), lnormal_[o.laser].data(),
                               &ldist_[o.laser]);
    else
      problem.AddResidualBlock(new ceres::AutoDiffCostFunction<LaserOnBoard, 1, 9, 6, 3, 3, 3, 1>(
                                   new LaserOnBoard{o.uv, o.theta, opt_.laser_sigma_mm}),
                               loss, in_, pose0s_[o.placement].data(), axis_p_, point_p_,
                               lnormal_[o.laser].data(), &ldist_[o.laser]);
  }
}

Calibration ScannerCalibrator::calibration() const {
  Calibration cal;
  cal.camera = {w_, h_, in_[0], in_[1], in_[2], in_[3], in_[4], in_[5], in_[6], in_[7], in_[8]};
  const double sse_corner = corner_sse(), sse_laser = laser_sse();
  cal.reprojection_rms_px = std::sqrt(sse_corner / (2.0 * n_corners_));
  cal.laser_rms_mm = laser_obs_.empty() ? 0.0 : std::sqrt(sse_laser / laser_obs_.size());
  cal.views = static_cast<int>(used_.size());
  cal.corners = n_corners_;
  cal.laser_points = static_cast<int>(laser_obs_.size());
  // Axis: pointing up means against the image's down direction (camera y).
  Vector3d a(axis_p_[0], axis_p_[1], axis_p_[2]);
  const Vector3d p(point_p_[0], point_p_[1], point_p_[2]);
  // The rotation model uses +theta about `a`; the platter turns counter-clockwise seen from
  // above, so `a` is already the up direction unless the angles were given clockwise.
  cal.axis_direction = a;
  cal.axis_origin_mm = platter_top_on_axis(a, p);
  for (int l = 0; l < laser_count_; ++l)
    cal.lasers.push_back({l == 0 && laser_count_ == 2   ? "left"
                          : l == 1 && laser_count_ == 2 ? "right"
                                                        : "laser" + std::to_string(l),
                          Vector3d(lnormal_[l][0], lnormal_[l][1], lnormal_[l][2]), ldist_[l]});
  return cal;
}

double ScannerCalibrator::corner_sse() const {
  double sse_corner = 0;
  for (std::size_t j = 0; j < used_.size(); ++j) {
    const CalibrationView& v = views_[used_[j]];
    for (int c = 0; c < pat_.corner_cols * pat_.corner_rows; ++c) {
      const Vector2d obs(image_points_[j][c].x, image_points_[j][c].y);
      const Vector3d xb(board_[c].x, board_[c].y, 0.0);
      double r[2];
      if (v.on_turntable)
        TurntableCorner{obs, xb, v.angle_rad, 1.0}(in_, pose0s_[placement_of_[j]].data(), axis_p_,
                                                   point_p_, r);
      else
        HandheldCorner{obs, xb, 1.0}(in_, pose_[j].data(), r);
      sse_corner += r[0] * r[0] + r[1] * r[1];
    }
  }
  return sse_corner;
}

double ScannerCalibrator::laser_sse() const {
  double sse_laser = 0;
  for (const auto& o : laser_obs_) {
    double r;
    if (o.handheld_view >= 0)
      HandheldLaser{o.uv, 1.0}(in_, pose_[o.handheld_view].data(), lnormal_[o.laser].data(),
                               &ldist_[o.laser], &r);
    else
      LaserOnBoard{o.uv, o.theta, 1.0}(in_, pose0s_[o.placement].data(), axis_p_, point_p_,
                                       lnormal_[o.laser].data(), &ldist_[o.laser], &r);
    sse_laser += r * r;
  }
  return sse_laser;
}

// Platter top: every placement's bottom edge (bottom_mm below the lowest corner row, along the
// board) rests on it; the mean over the placements.
Vector3d ScannerCalibrator::platter_top_on_axis(const Vector3d& a, const Vector3d& p) const {
  double height = 0;
  const double xb[3] = {0.5 * (pat_.corner_cols - 1) * pat_.square_mm,
                        (pat_.corner_rows - 1) * pat_.square_mm + pat_.bottom_mm, 0.0};
  for (int pk = 0; pk < n_place_; ++pk) {
    double e[3];
    turntable_point(pose0s_[pk].data(), axis_p_, point_p_, 0.0, xb, e);
    height += a.dot(Vector3d(e[0], e[1], e[2]) - p);
  }
  return p + (height / n_place_) * a;
}

// One-sigma uncertainties from the covariance of the adjusted parameters, scaled by the
// variance factor. When the covariance cannot be computed, the axis and laser fields are -1.
CalibrationUncertainty ScannerCalibrator::uncertainty(ceres::Problem& problem,
                                                      const ceres::Solver::Summary& summary,
                                                      const Calibration& cal) const {
  const double s2 = variance_factor(summary);
  ceres::Covariance::Options co;
  co.algorithm_type = ceres::DENSE_SVD;
  co.null_space_rank = -1;
  co.min_reciprocal_condition_number = 1e-14;
  ceres::Covariance cov(co);
  std::vector<std::pair<const double*, const double*>> blocks = {
      {in_, in_}, {axis_p_, axis_p_}, {point_p_, point_p_}};
  for (int l = 0; l < laser_count_; ++l) {
    blocks.emplace_back(lnormal_[l].data(), lnormal_[l].data());
    blocks.emplace_back(&ldist_[l], &ldist_[l]);
  }
  CalibrationUncertainty u;
  if (cov.Compute(blocks, &problem)) {
    double ci[81];
    cov.GetCovarianceBlock(in_, in_, ci);
    double* fields[9] = {&u.fx, &u.fy, &u.cx, &u.cy, &u.k1, &u.k2, &u.p1, &u.p2, &u.k3};
    for (int q = 0; q < 9; ++q) *fields[q] = std::sqrt(std::max(0.0, s2 * ci[q * 10]));
    auto angular = [&](const double* v, const Vector3d& dir) {
      double c[9];
      cov.GetCovarianceBlock(v, v, c);
      const Eigen::Matrix3d m = Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(c);
      const Eigen::Matrix3d pr = Eigen::Matrix3d::Identity() - dir * dir.transpose();
      const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(pr * m * pr);
      return std::sqrt(std::max(0.0, s2 * es.eigenvalues().maxCoeff())) * kRadToDeg;
    };
    u.axis_direction_deg = angular(axis_p_, cal.axis_direction);
    double cp[9];
    cov.GetCovarianceBlock(point_p_, point_p_, cp);
    const Eigen::Matrix3d mp = Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(cp);
    u.axis_point_mm = std::sqrt(std::max(
        0.0, s2 * Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(mp).eigenvalues().maxCoeff()));
    for (int l = 0; l < laser_count_; ++l) {
      u.laser_normal_deg.push_back(angular(lnormal_[l].data(), cal.lasers[l].normal));
      double cd;
      cov.GetCovarianceBlock(&ldist_[l], &ldist_[l], &cd);
      u.laser_distance_mm.push_back(std::sqrt(std::max(0.0, s2 * cd)));
    }
  } else {
    u.laser_normal_deg.assign(laser_count_, -1.0);
    u.laser_distance_mm.assign(laser_count_, -1.0);
    u.axis_direction_deg = u.axis_point_mm = -1.0;
  }
  return u;
}

}  // namespace

CalibrationReport calibrate_scanner(const std::vector<CalibrationView>& views, int laser_count,
                                    const CalibrationOptions& opt) {
  check_calibration_input(views, laser_count, opt.pattern);
  CalibrationReport report;
  report.corners.resize(views.size());
  ScannerCalibrator calibrator(views, laser_count, opt);

  // 1. Corners, every view independently (in parallel on OpenCV's thread pool).
  calibrator.detect_corners(report);

  // 2. OpenCV initial intrinsics and view poses.
  report.opencv_rms_px = calibrator.estimate_initial_camera();

  // 3. Initial axis from the platter views: relative rotations within each placement give the
  // direction, the positions of the board origin the point.
  calibrator.group_platter_views();
  const Vector3d axis = calibrator.initial_axis_direction();
  const Vector3d point = calibrator.initial_axis_point(axis);
  calibrator.init_turntable_parameters(axis, point);

  // 4. Laser peaks on the printed area of the board, and initial planes.
  calibrator.fit_initial_laser_planes(calibrator.collect_laser_observations());

  // 5. Joint bundle adjustment.
  ceres::Problem problem;
  calibrator.build_joint_adjustment(problem);
  const ceres::Solver::Summary summary = solve_joint_adjustment(problem);

  // 6. Quality and uncertainty.
  Calibration cal = calibrator.calibration();
  cal.uncertainty = calibrator.uncertainty(problem, summary, cal);
  report.calibration = cal;
  return report;
}

}  // namespace scanmesh
