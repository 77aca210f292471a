// Scan clean-up before remeshing: tiny components removed, small holes closed by a fan.
#include <algorithm>
#include <map>
#include <unordered_map>

#include "scanmesh/meshing/remeshing/remesh.h"

namespace scanmesh::remeshing {

Mesh prepare_input(const Mesh& in, const PrepareOptions& o, PrepareStats* stats) {
  PrepareStats st;
  const int nv = static_cast<int>(in.positions.size());
  const int nf = static_cast<int>(in.triangles.size());
  std::vector<char> keep(nf, 1);
  if (o.min_component_faces > 0) {
    // Components by shared vertices (union-find).
    std::vector<int> parent(nv);
    for (int i = 0; i < nv; ++i) parent[i] = i;
    auto find = [&](int i) {
      while (parent[i] != i) i = parent[i] = parent[parent[i]];
      return i;
    };
    for (const auto& t : in.triangles) {
      parent[find(t[1])] = find(t[0]);
      parent[find(t[2])] = find(t[0]);
    }
    std::unordered_map<int, int> size;
    for (const auto& t : in.triangles) ++size[find(t[0])];
    std::unordered_map<int, char> counted;
    for (int f = 0; f < nf; ++f) {
      const int r = find(in.triangles[f][0]);
      if (size[r] < o.min_component_faces) {
        keep[f] = 0;
        ++st.faces_removed;
        if (!counted[r]) {
          counted[r] = 1;
          ++st.components_removed;
        }
      }
    }
  }
  Mesh out;
  std::vector<int> map(nv, -1);
  for (int f = 0; f < nf; ++f) {
    if (!keep[f]) continue;
    std::array<int, 3> t{};
    for (int i = 0; i < 3; ++i) {
      int& m = map[in.triangles[f][i]];
      if (m < 0) {
        m = static_cast<int>(out.positions.size());
        out.positions.push_back(in.positions[in.triangles[f][i]]);
      }
      t[i] = m;
    }
    out.triangles.push_back(t);
    out.face_labels.push_back(in.has_face_labels() ? in.face_labels[f] : 0);
  }
  if (o.max_hole_edges > 0) {
    // Directed boundary edges a -> b (as in their face) with the face label.
    std::map<std::pair<int, int>, int> count;
    for (const auto& t : out.triangles)
      for (int i = 0; i < 3; ++i) {
        const int a = t[i], b = t[(i + 1) % 3];
        ++count[{std::min(a, b), std::max(a, b)}];
      }
    std::unordered_map<int, std::vector<std::pair<int, int>>> out_edges;  // a -> (b, label)
    for (std::size_t f = 0; f < out.triangles.size(); ++f) {
      const auto& t = out.triangles[f];
      for (int i = 0; i < 3; ++i) {
        const int a = t[i], b = t[(i + 1) % 3];
        if (count[{std::min(a, b), std::max(a, b)}] == 1)
          out_edges[a].push_back({b, out.face_labels[f]});
      }
    }
    std::vector<int> starts;
    for (const auto& [a, e] : out_edges) starts.push_back(a);
    std::sort(starts.begin(), starts.end());
    std::unordered_map<int, char> used;
    for (int a0 : starts) {
      if (used[a0] || out_edges[a0].size() != 1) continue;
      std::vector<int> loop = {a0};
      int lab = out_edges[a0][0].second;
      int cur = out_edges[a0][0].first;
      bool ok = true;
      while (cur != a0) {
        auto it = out_edges.find(cur);
        if (it == out_edges.end() || it->second.size() != 1 || used[cur] ||
            static_cast<int>(loop.size()) > o.max_hole_edges) {
          ok = false;
          break;
        }
        loop.push_back(cur);
        cur = it->second[0].first;
      }
      for (int v : loop) used[v] = 1;
      if (!ok || loop.size() < 3 || static_cast<int>(loop.size()) > o.max_hole_edges) continue;
      Eigen::Vector3d c = Eigen::Vector3d::Zero();
      for (int v : loop) c += out.positions[v];
      const int cv = static_cast<int>(out.positions.size());
      out.positions.push_back(c / static_cast<double>(loop.size()));
      for (std::size_t i = 0; i < loop.size(); ++i) {
        // Boundary edge a -> b belongs to a face; the hole face runs b -> a.
        const int a = loop[i], b = loop[(i + 1) % loop.size()];
        out.triangles.push_back({b, a, cv});
        out.face_labels.push_back(lab);
        ++st.faces_added;
      }
      ++st.holes_filled;
    }
  }
  if (stats) *stats = st;
  return out;
}

}  // namespace scanmesh::remeshing
