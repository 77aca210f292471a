// Animated skeleton scenes (sim/animated_skeleton.h), the input of the particle animation.
#include <gtest/gtest.h>

#include "scanmesh/core/errors.h"
#include "scanmesh/sim/animated_skeleton.h"

namespace scanmesh::sim {
namespace {

using Eigen::Vector3d;

const char* kScene = R"(
name: t
elements:
  - {name: p, type: point, center: [0, 0, 0], radius: 2}
  - {name: s, type: segment, a: [0, 1, 0], b: [1, 1, 0], radius: 1.5}
keyframes:
  - time: 0
  - time: 2
    positions: {p: [2, 0, 0], s: [[0, 3, 0], [1, 3, 0]]}
)";

TEST(AnimatedSkeleton, InterpolatesKeyframesLinearly) {
  const auto a = AnimatedSkeleton::from_yaml_text(kScene, "test");
  EXPECT_TRUE(AnimatedSkeleton::is_animated_yaml(kScene));
  EXPECT_FALSE(AnimatedSkeleton::is_animated_yaml("objects: []"));
  const auto e = a.elements_at(0.5);
  EXPECT_TRUE(e[0].a.isApprox(Vector3d(0.5, 0, 0)));
  EXPECT_TRUE(e[1].a.isApprox(Vector3d(0, 1.5, 0)));
  EXPECT_TRUE(e[1].b.isApprox(Vector3d(1, 1.5, 0)));
  EXPECT_TRUE(a.elements_at(5.0)[0].a.isApprox(Vector3d(2, 0, 0)));  // clamped
}

TEST(AnimatedSkeleton, TimeDerivativeMatchesMotionOfThePoint) {
  const auto a = AnimatedSkeleton::from_yaml_text(kScene, "test");
  // Only p moves near x (s is out of reach): dF/dt = grad F . (-v) for the moving kernel,
  // i.e. value(x, t) = g(x - c(t)) gives d/dt = -grad_x value . c'(t), c' = (1, 0, 0).
  const Vector3d x(-0.6, -0.4, 0.2);
  const double t = 0.7;
  const FieldSample f = a.object_at(t)->field(x);
  EXPECT_NEAR(a.time_derivative(x, t), -f.gradient.dot(Vector3d(1, 0, 0)), 1e-6);
}

TEST(AnimatedSkeleton, RejectsMalformedScenes) {
  EXPECT_THROW(AnimatedSkeleton::from_yaml_text("elements: []\nkeyframes: [{time: 0}]", "x"),
               FileFormatError);
  const std::string backwards = std::string(kScene) + "  - time: 1\n";
  EXPECT_THROW(AnimatedSkeleton::from_yaml_text(backwards, "x"), FileFormatError);
  const std::string unknown = R"(
elements: [{name: p, type: point, center: [0, 0, 0], radius: 1}]
keyframes: [{time: 0, positions: {q: [0, 0, 0]}}]
)";
  EXPECT_THROW(AnimatedSkeleton::from_yaml_text(unknown, "x"), FileFormatError);
}

}  // namespace
}  // namespace scanmesh::sim
