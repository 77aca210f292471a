// Closing a scan hole with a patch the remesher can work on (internal to prepare_input).
#pragma once

#include <Eigen/Core>
#include <array>
#include <functional>
#include <vector>

namespace scanmesh::remeshing::detail {

//! A hole patch: vertex k < loop size is loop vertex k, vertex loop size + i is new_points[i].
struct HolePatch {
  std::vector<Eigen::Vector3d> new_points;
  std::vector<std::array<int, 3>> triangles;
};

//! Closes the boundary loop `loop` (vertices in the order of the boundary edges of their
//! faces, a -> b). In the loop's least-squares plane: a minimum-area triangulation over the
//! loop's diagonals (dynamic programming), refined until no inner edge is longer than 4/3 of the
//! loop's mean edge (midpoint splits, max-min-angle flips across convex quads), inner vertices
//! smoothed (height: a membrane over the fixed loop; in the plane: only where no face turns
//! over), so the patch is a graph over its plane and cannot cut itself. A loop that is not
//! simple in its plane gets the centroid fan that this replaced: the fan left one vertex of
//! valence up to 100 with folded faces whose normals made the remesher refuse every operation
//! there (docs/remeshing.md). The triangles are oriented like the faces around the hole.
//! `joined(i, j)` says whether loop vertices i and j are already joined by an edge of the mesh
//! outside the hole: such a chord would get a third face, so it is never used (when every
//! triangulation needs one, the patch starts from a centroid fan instead).
HolePatch fill_hole(const std::vector<Eigen::Vector3d>& loop,
                    const std::function<bool(int, int)>& joined);

}  // namespace scanmesh::remeshing::detail
