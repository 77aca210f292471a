// Importing other scanners' data into a RangeGrid (docs/acquisition.md, "Importing scans"):
// unorganised clouds are binned into cylindrical cells around the turntable axis (robust radius
// of the outermost layer per cell, confidence from the sample count, colour kept); meshes and
// organised clouds are ray-cast from the axis (the outermost hit, as a turntable scanner sees
// it). Cells without data stay invalid, and a scan covering part of the turn keeps its columns.
#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "scanmesh/core/image.h"
#include "scanmesh/core/mesh.h"
#include "scanmesh/core/point_cloud_io.h"
#include "scanmesh/core/range_grid.h"

namespace scanmesh {

//! The rotation axis of the grid, in the input file's frame.
struct CylinderAxis {
  Eigen::Vector3d point = Eigen::Vector3d::Zero();
  Eigen::Vector3d direction = Eigen::Vector3d::UnitZ();  //!< unit length
};

enum class AxisDirection {
  Z,         //!< +z (turntable files: Horus, FabScan, and the scanmesh grids)
  Given,     //!< ImportOptions::axis_direction
  Estimate,  //!< the principal direction of largest extent of the points (PCA)
};

struct ImportOptions {
  AxisDirection direction = AxisDirection::Z;
  Eigen::Vector3d axis_direction = Eigen::Vector3d::UnitZ();  //!< for AxisDirection::Given
  //! A point on the axis; nullopt: the centroid of the data (right for a full turn; a partial
  //! turn needs the turntable's own axis, e.g. the origin of a Horus file).
  std::optional<Eigen::Vector3d> axis_point;
  int n_phi = 0;    //!< columns; 0 = from the data's sample spacing
  int n_h = 0;      //!< rows; 0 = from dh
  double dh = 0;    //!< row spacing (mm); 0 = the cell size derived from the sample spacing
  //! Clouds: samples of one cell further apart in radius than this many cell sizes are
  //! different layers (an arm in front of the body); the outermost layer with a quarter of the
  //! cell's samples gives the radius.
  double layer_gap_cells = 3.0;
  //! Organised clouds: lattice neighbours further apart than this many times the median
  //! neighbour distance are not joined (a depth jump, not a surface).
  double max_lattice_jump = 5.0;
};

//! Which part of the turn the grid's valid columns cover.
struct TurnCoverage {
  int columns = 0, covered_columns = 0;
  bool full_turn = false;
  //! Covered arcs [start, end) in radians (start in [phi0, phi0 + 2 pi), end > start),
  //! longest first. One arc spanning the whole turn when full_turn.
  std::vector<std::pair<double, double>> arcs;
  double covered_fraction() const { return columns ? double(covered_columns) / columns : 0.0; }
};

TurnCoverage turn_coverage(const RangeGrid& grid);

struct ImportReport {
  std::string input_kind;  //!< "point cloud", "organised point cloud", "mesh"
  std::string method;      //!< "binned (outermost-layer median)" or "ray cast (outermost hit)"
  std::size_t input_points = 0, input_triangles = 0;
  std::size_t samples_used = 0;  //!< cloud points that set a cell / ray hits
  bool colors = false, textured = false;
  CylinderAxis axis;
  double sample_spacing_mm = 0;  //!< median neighbour distance / edge length of the input
  double cell_mm = 0;            //!< cell size the resolution was derived from
  TurnCoverage coverage;
  std::vector<std::string> warnings;  //!< e.g. a texture image that could not be read
};

struct ImportResult {
  RangeGrid grid;
  ImportReport report;
  //! Input frame -> grid frame (x = r cos phi, y = r sin phi, z = h).
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  Eigen::Vector3d to_grid_frame(const Eigen::Vector3d& p) const {
    return rotation * (p - origin);
  }
};

//! Any supported file, by extension: clouds .ply (no faces) .pcd .xyz .txt .pts; meshes .ply
//! .off .obj (with its MTL texture) .stl .vtk (legacy) .vtp (XML); organised .pcd. Throws
//! FileFormatError naming the file for content that cannot be a scan (no points, every point on
//! the axis, non-finite values), InvalidInputError for impossible options or extensions.
ImportResult import_scan(const std::filesystem::path& input, const ImportOptions& options = {});

//! An unorganised cloud, binned. `source` names the input in errors.
ImportResult grid_from_cloud(const PointCloud& cloud, const ImportOptions& options,
                             const std::filesystem::path& source);
//! A mesh, ray-cast; colours from its vertex colours, or from `texture` through its texture
//! coordinates (when both are given).
ImportResult grid_from_mesh(const Mesh& mesh, const Image8* texture, const ImportOptions& options,
                            const std::filesystem::path& source);
//! An organised cloud: its lattice joined into triangles (no joins across depth jumps), then
//! ray-cast like a mesh with the points' colours.
ImportResult grid_from_organised_cloud(const PointCloud& cloud, const ImportOptions& options,
                                       const std::filesystem::path& source);

//! The organised cloud's lattice as a mesh (used by grid_from_organised_cloud; exposed for tests).
Mesh lattice_mesh(const PointCloud& cloud, double max_jump_factor);

//! VTK legacy (.vtk) or XML (.vtp) polydata through VTK's own readers: points, triangulated
//! polygons and triangle strips, point colours (3- or 4-component unsigned char scalars).
//! A file with points and no cells gives a mesh without triangles (a cloud).
Mesh read_vtk_polydata(const std::filesystem::path& path);

}  // namespace scanmesh
