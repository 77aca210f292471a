// Adapters from sim's scene objects and animated skeletons to meshing's ImplicitSurface
// (seed 003 particles). They live here because meshing must not depend on sim and sim must
// not depend on meshing; the particle tests include this header too. Header-only.
#pragma once

#include <algorithm>
#include <memory>

#include "scanmesh/meshing/particles/implicit_surface.h"
#include "scanmesh/sim/animated_skeleton.h"
#include "scanmesh/sim/scene.h"

namespace scanmesh::cli {

//! A static sim::SceneObject (value < 0 inside, gradient outward: the same convention) inside
//! a caller-given box. dF/dt = 0.
class SceneObjectSurface final : public particles::ImplicitSurface {
 public:
  SceneObjectSurface(std::shared_ptr<const sim::SceneObject> object, Eigen::AlignedBox3d box)
      : object_(std::move(object)), box_(box) {}
  std::optional<particles::ImplicitValue> evaluate(const Eigen::Vector3d& x) const override {
    const sim::FieldSample f = object_->field(x);
    return particles::ImplicitValue{.value = f.value, .gradient = f.gradient, .dvalue_dt = 0.0};
  }
  std::optional<Eigen::Matrix3d> hessian(const Eigen::Vector3d& x) const override {
    return object_->field(x).hessian;
  }
  Eigen::AlignedBox3d bounds() const override { return box_; }
  const sim::SceneObject& object() const { return *object_; }

 private:
  std::shared_ptr<const sim::SceneObject> object_;
  Eigen::AlignedBox3d box_;
};

//! An animated skeleton frozen at time t, with dF/dt at t; bounds: the support of every
//! element over all keyframes (the same box every frame).
class AnimatedSkeletonSurface final : public particles::ImplicitSurface {
 public:
  AnimatedSkeletonSurface(std::shared_ptr<const sim::AnimatedSkeleton> skeleton, double t)
      : skeleton_(std::move(skeleton)), object_(skeleton_->object_at(t)) {
    // dF/dt by a central difference in time (positions are linear in t between keyframes),
    // one-sided at the ends of the keyframe range; the two fields are built once.
    const double h = 1e-6 * std::max(skeleton_->end_time() - skeleton_->start_time(), 1e-9);
    const double ta = std::max(t - h, skeleton_->start_time());
    const double tb = std::min(t + h, skeleton_->end_time());
    if (tb > ta) {
      before_ = skeleton_->object_at(ta);
      after_ = skeleton_->object_at(tb);
      inv_dt_ = 1.0 / (tb - ta);
    }
    Eigen::Vector3d lo, hi;
    skeleton_->support_bounds(lo, hi);
    box_ = Eigen::AlignedBox3d(lo, hi);
  }
  std::optional<particles::ImplicitValue> evaluate(const Eigen::Vector3d& x) const override {
    const sim::FieldSample f = object_->field(x);
    return particles::ImplicitValue{
        .value = f.value,
        .gradient = f.gradient,
        .dvalue_dt = before_ ? (after_->field(x).value - before_->field(x).value) * inv_dt_ : 0.0};
  }
  std::optional<Eigen::Matrix3d> hessian(const Eigen::Vector3d& x) const override {
    return object_->field(x).hessian;
  }
  Eigen::AlignedBox3d bounds() const override { return box_; }

 private:
  std::shared_ptr<const sim::AnimatedSkeleton> skeleton_;
  std::shared_ptr<const sim::SceneObject> object_, before_, after_;
  double inv_dt_ = 0.0;
  Eigen::AlignedBox3d box_;
};

}  // namespace scanmesh::cli
