// The fair CGAL input for bench_aft: the animation lines traced on the grid band as
// simple polylines of band edges (end points snapped, a shortest path hugging each line, its
// vertices moved onto the line), constrained but free to be split and collapsed, and the check
// of which polylines survive CGAL's remeshing (docs/animation-meshes.md).
#pragma once

#include <cstddef>
#include <map>
#include <vector>

#include <Eigen/Core>

#include "aft_bench_rows.h"
#include "scanmesh/meshing/aft/regions.h"
#include "scanmesh/meshing/grid_mesh.h"

namespace scanmesh::bench_aft {

//! The "lines constrained, same count" row: the lines traced on the band, CGAL's target edge
//! tuned from the unconstrained same-count run (edge, count) in three rounds to the AFT's count.
void print_lines_constrained(const SM& band, const std::vector<Eigen::Vector2d>& pixel,
                             const aft::RegionGraph& g, const ScanSurface& surface, double edge,
                             std::size_t count, std::size_t target_count);

//! Each band vertex's pixel: its grid cell's centre.
std::vector<Eigen::Vector2d> band_pixels(const SM& band,
                                         const std::map<SM::Vertex_index, int>& back,
                                         const GridMesh& gm, int n_phi);

}  // namespace scanmesh::bench_aft
