// The PCL anchors shared by the benchmarks (docs/benchmarks.md): GreedyProjectionTriangulation
// of a cloud with given normals, NormalEstimationOMP + PrincipalCurvaturesEstimation of a point
// set, and the mean nearest-neighbour spacing that scales GP3's search radius.
// PCL headers only in the benchmarks.
#pragma once

#include <pcl/features/normal_3d_omp.h>
#include <pcl/features/principal_curvatures.h>
#include <pcl/point_types.h>
#include <pcl/search/kdtree.h>
#include <pcl/surface/gp3.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <vector>

#include "scanmesh/core/mesh.h"

namespace scanmesh::bench {

inline pcl::PointCloud<pcl::PointXYZ>::Ptr to_pcl_xyz(const std::vector<Eigen::Vector3d>& pts) {
  auto c = pcl::make_shared<pcl::PointCloud<pcl::PointXYZ>>();
  c->reserve(pts.size());
  for (const auto& p : pts) c->push_back(pcl::PointXYZ(float(p.x()), float(p.y()), float(p.z())));
  return c;
}

//! Mean distance to the nearest other point, over at most ~2000 evenly strided points.
inline double mean_spacing(const std::vector<Eigen::Vector3d>& pts) {
  pcl::search::KdTree<pcl::PointXYZ> tree;
  tree.setInputCloud(to_pcl_xyz(pts));
  double sum = 0;
  std::vector<int> idx;
  std::vector<float> d2;
  const std::size_t step = std::max<std::size_t>(1, pts.size() / 2000);
  std::size_t n = 0;
  for (std::size_t i = 0; i < pts.size(); i += step, ++n) {
    tree.nearestKSearch(static_cast<int>(i), 2, idx, d2);
    sum += std::sqrt(d2[1]);
  }
  return sum / static_cast<double>(n);
}

//! Largest and mean distance from `samples` to their nearest point of `cloud` (a kd-tree).
inline std::array<double, 2> distance_to_points(const std::vector<Eigen::Vector3d>& samples,
                                                const std::vector<Eigen::Vector3d>& cloud) {
  pcl::search::KdTree<pcl::PointXYZ> tree;
  tree.setInputCloud(to_pcl_xyz(cloud));
  std::vector<int> idx;
  std::vector<float> d2;
  double mx = 0, sum = 0;
  for (const auto& s : samples) {
    tree.nearestKSearch(pcl::PointXYZ(float(s.x()), float(s.y()), float(s.z())), 1, idx, d2);
    const double d = std::sqrt(double(d2[0]));
    mx = std::max(mx, d);
    sum += d;
  }
  return {mx, samples.empty() ? 0.0 : sum / double(samples.size())};
}

//! GP3 parameters (docs/benchmarks.md): search radius = radius_factor x mean spacing.
struct Gp3Parameters {
  double radius_factor = 6.0, mu = 2.5;
};

//! GP3 on the points with the given normals; the mesh's vertices are the input points.
inline Mesh pcl_gp3(const std::vector<Eigen::Vector3d>& pts,
                    const std::vector<Eigen::Vector3d>& normals, double spacing,
                    const Gp3Parameters& param = {}) {
  auto cloud = pcl::make_shared<pcl::PointCloud<pcl::PointNormal>>();
  cloud->reserve(pts.size());
  for (std::size_t i = 0; i < pts.size(); ++i) {
    pcl::PointNormal p;
    p.x = float(pts[i].x());
    p.y = float(pts[i].y());
    p.z = float(pts[i].z());
    p.normal_x = float(normals[i].x());
    p.normal_y = float(normals[i].y());
    p.normal_z = float(normals[i].z());
    cloud->push_back(p);
  }
  auto tree = pcl::make_shared<pcl::search::KdTree<pcl::PointNormal>>();
  tree->setInputCloud(cloud);
  pcl::GreedyProjectionTriangulation<pcl::PointNormal> gp3;
  gp3.setSearchRadius(param.radius_factor * spacing);
  gp3.setMu(param.mu);
  gp3.setMaximumNearestNeighbors(100);
  gp3.setMaximumSurfaceAngle(M_PI / 4);
  gp3.setMinimumAngle(M_PI / 18);
  gp3.setMaximumAngle(2 * M_PI / 3);
  gp3.setNormalConsistency(true);
  gp3.setConsistentVertexOrdering(true);
  gp3.setInputCloud(cloud);
  gp3.setSearchMethod(tree);
  std::vector<pcl::Vertices> polys;
  gp3.reconstruct(polys);
  Mesh m;
  m.positions = pts;
  for (const auto& v : polys)
    if (v.vertices.size() == 3)
      m.triangles.push_back({int(v.vertices[0]), int(v.vertices[1]), int(v.vertices[2])});
  return m;
}

//! PCL's per-point estimate: unit normal and the principal curvatures (unsigned, pc1 >= pc2).
struct PclCurvature {
  bool ok = false;
  double pc1 = 0, pc2 = 0;
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
};

//! NormalEstimationOMP (`normal_threads`) + PrincipalCurvaturesEstimation (serial), both over
//! the same radius.
inline std::vector<PclCurvature> pcl_principal_curvatures(const std::vector<Eigen::Vector3d>& pts,
                                                          double radius, int normal_threads) {
  const auto cloud = to_pcl_xyz(pts);
  auto tree = pcl::make_shared<pcl::search::KdTree<pcl::PointXYZ>>();
  auto normals = pcl::make_shared<pcl::PointCloud<pcl::Normal>>();
  pcl::NormalEstimationOMP<pcl::PointXYZ, pcl::Normal> ne(normal_threads);
  ne.setInputCloud(cloud);
  ne.setSearchMethod(tree);
  ne.setRadiusSearch(radius);
  ne.compute(*normals);
  pcl::PrincipalCurvaturesEstimation<pcl::PointXYZ, pcl::Normal, pcl::PrincipalCurvatures> pce;
  pce.setInputCloud(cloud);
  pce.setInputNormals(normals);
  pce.setSearchMethod(tree);
  pce.setRadiusSearch(radius);
  pcl::PointCloud<pcl::PrincipalCurvatures> curv;
  pce.compute(curv);
  std::vector<PclCurvature> out(pts.size());
  for (std::size_t p = 0; p < pts.size(); ++p) {
    const auto& n = (*normals)[p];
    const auto& c = curv[p];
    if (!std::isfinite(n.normal_x) || !std::isfinite(c.pc1)) continue;
    out[p] = {true, c.pc1, c.pc2, Eigen::Vector3d(n.normal_x, n.normal_y, n.normal_z).normalized()};
  }
  return out;
}

}  // namespace scanmesh::bench
