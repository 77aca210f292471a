// Foundation benchmarks: the 512 x 512 head simulation, cleaning and the grid mesh, with the
// grid mesh measured against PCL's OrganizedFastMesh (the anchor for organised range meshing)
// on the same cleaned grid in the same run. Prints median times and the ratio.
#include <benchmark/benchmark.h>
#include <pcl/point_types.h>
#include <pcl/surface/organized_fast_mesh.h>

#include <cmath>
#include <iostream>
#include <map>
#include <string>

#include "scanmesh/acquisition/grid_cleaning.h"
#include "scanmesh/meshing/grid_mesh.h"
#include "scanmesh/sim/range_scanner.h"

namespace {

using namespace scanmesh;

const sim::SimulatedScan& head_scan() {
  static const sim::SimulatedScan scan =
      sim::simulate_scan(sim::builtin_head_scene(), sim::builtin_head_scanner());
  return scan;
}

const RangeGrid& clean_head_grid() {
  static const RangeGrid grid = [] {
    RangeGrid g = head_scan().grid;
    clean_grid(g);
    return g;
  }();
  return grid;
}

pcl::PointCloud<pcl::PointXYZ>::Ptr organised_cloud(const RangeGrid& grid) {
  auto cloud = pcl::make_shared<pcl::PointCloud<pcl::PointXYZ>>(grid.n_phi(), grid.n_h());
  cloud->is_dense = false;
  const float nan = std::nanf("");
  for (int j = 0; j < grid.n_h(); ++j)
    for (int i = 0; i < grid.n_phi(); ++i) {
      auto& p = cloud->at(i, j);
      if (!grid.valid(i, j)) {
        p.x = p.y = p.z = nan;
        continue;
      }
      const Eigen::Vector3d c = grid.cartesian(i, j);
      p.x = static_cast<float>(c.x());
      p.y = static_cast<float>(c.y());
      p.z = static_cast<float>(c.z());
    }
  return cloud;
}

void BM_SimulateHead512(benchmark::State& state) {
  const sim::Scene scene = sim::builtin_head_scene();
  const sim::ScannerConfig config = sim::builtin_head_scanner();
  for (auto _ : state) benchmark::DoNotOptimize(sim::simulate_scan(scene, config));
}
BENCHMARK(BM_SimulateHead512)->Unit(benchmark::kMillisecond)->Iterations(1)->Repetitions(3);

void BM_CleanHead512(benchmark::State& state) {
  for (auto _ : state) {
    RangeGrid g = head_scan().grid;
    benchmark::DoNotOptimize(clean_grid(g));
  }
}
BENCHMARK(BM_CleanHead512)->Unit(benchmark::kMillisecond)->Repetitions(5);

void BM_GridMeshHead512(benchmark::State& state) {
  const RangeGrid& grid = clean_head_grid();
  GridMeshOptions options;
  options.with_texcoords = false;  // the anchor makes no texture coordinates either
  options.with_colors = false;
  std::size_t faces = 0;
  for (auto _ : state) {
    const GridMesh gm = grid_mesh(grid, options);
    faces = gm.mesh.face_count();
  }
  state.counters["faces"] = static_cast<double>(faces);
}
BENCHMARK(BM_GridMeshHead512)->Unit(benchmark::kMillisecond)->Repetitions(5);

void BM_PclOrganizedFastMeshHead512(benchmark::State& state) {
  const auto cloud = organised_cloud(clean_head_grid());
  std::size_t faces = 0;
  for (auto _ : state) {
    pcl::OrganizedFastMesh<pcl::PointXYZ> ofm;
    ofm.setInputCloud(cloud);
    ofm.setTriangulationType(pcl::OrganizedFastMesh<pcl::PointXYZ>::TRIANGLE_ADAPTIVE_CUT);
    ofm.setMaxEdgeLength(8.0f);  // same absolute limit as our depth-jump threshold
    std::vector<pcl::Vertices> polygons;
    ofm.reconstruct(polygons);
    faces = polygons.size();
  }
  state.counters["faces"] = static_cast<double>(faces);
}
BENCHMARK(BM_PclOrganizedFastMeshHead512)->Unit(benchmark::kMillisecond)->Repetitions(5);

// Collects the median of each benchmark so main() can print the ratios to the anchors.
class MedianCollector : public benchmark::ConsoleReporter {
 public:
  void ReportRuns(const std::vector<Run>& runs) override {
    for (const Run& run : runs)
      if (run.run_type == Run::RT_Aggregate && run.aggregate_name == "median")
        medians[run.run_name.function_name] = run.GetAdjustedRealTime();
    ConsoleReporter::ReportRuns(runs);
  }
  std::map<std::string, double> medians;
};

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  MedianCollector reporter;
  benchmark::RunSpecifiedBenchmarks(&reporter);
  const auto& m = reporter.medians;
  if (m.count("BM_GridMeshHead512") && m.count("BM_PclOrganizedFastMeshHead512"))
    std::cout << "\nratio grid_mesh / PCL OrganizedFastMesh (median time, same grid): "
              << m.at("BM_GridMeshHead512") / m.at("BM_PclOrganizedFastMeshHead512")
              << "  (< 1 means scanmesh is faster)\n";
  benchmark::Shutdown();
  return 0;
}
