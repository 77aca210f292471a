// Feature skeleton on the input mesh (seed 001 §4.1, §4.4 kink rule) and the feature-lines file.
#include "scanmesh/meshing/remeshing/feature_skeleton.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <set>
#include <sstream>

#include "scanmesh/core/atomic_file.h"
#include "scanmesh/core/errors.h"

namespace scanmesh::remeshing {

namespace {

int parse_index(const std::string& token, const std::string& name, int line_no) {
  if (token.empty() || token.size() > 10 ||
      !std::all_of(token.begin(), token.end(), [](char c) { return c >= '0' && c <= '9'; }))
    throw FileFormatError(name, "line " + std::to_string(line_no) + ": '" + token.substr(0, 20) +
                                    "' is not a vertex index");
  const long long v = std::stoll(token);
  if (v > 2147483647LL)
    throw FileFormatError(name, "line " + std::to_string(line_no) + ": vertex index too large");
  return static_cast<int>(v);
}

// Faces around v grouped into fans connected across manifold non-skeleton edges.
int count_fans(const TriangleMesh& m, int v,
               const std::unordered_map<std::uint64_t, int>& skel_edges,
               const std::set<std::uint64_t>& skel_set) {
  const auto& fs = m.vfaces[v];
  std::vector<int> parent(fs.size());
  for (std::size_t i = 0; i < fs.size(); ++i) parent[i] = static_cast<int>(i);
  auto find = [&](int i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  for (std::size_t i = 0; i < fs.size(); ++i)
    for (int c : m.tri[fs[i]]) {
      if (c == v) continue;
      const auto k = edge_key(v, c);
      if (skel_edges.count(k) || skel_set.count(k)) continue;
      for (std::size_t j = i + 1; j < fs.size(); ++j) {
        const auto& t = m.tri[fs[j]];
        if (t[0] == c || t[1] == c || t[2] == c)
          parent[find(static_cast<int>(i))] = find(static_cast<int>(j));
      }
    }
  int n = 0;
  for (std::size_t i = 0; i < fs.size(); ++i) n += find(static_cast<int>(i)) == static_cast<int>(i);
  return n;
}

}  // namespace

FeatureLines parse_feature_lines(const std::string& text, const std::string& name) {
  FeatureLines out;
  std::istringstream in(text);
  std::string line;
  int line_no = 0;
  bool header = false;
  while (std::getline(in, line)) {
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    const auto hash = line.find('#');
    if (hash != std::string::npos) line.resize(hash);
    std::istringstream ls(line);
    std::string word;
    if (!(ls >> word)) continue;
    if (!header) {
      std::string version;
      if (word != "scanmesh_feature_lines" || !(ls >> version) || version != "1")
        throw FileFormatError(name, "line " + std::to_string(line_no) +
                                        ": expected header 'scanmesh_feature_lines 1'");
      header = true;
      continue;
    }
    std::vector<int> ids;
    std::string tok;
    while (ls >> tok) ids.push_back(parse_index(tok, name, line_no));
    if (word == "line") {
      if (ids.size() < 2)
        throw FileFormatError(name, "line " + std::to_string(line_no) +
                                        ": a feature line needs at least two vertices");
      out.lines.push_back(std::move(ids));
    } else if (word == "fixed") {
      if (ids.empty())
        throw FileFormatError(name,
                              "line " + std::to_string(line_no) + ": 'fixed' without vertices");
      out.fixed.insert(out.fixed.end(), ids.begin(), ids.end());
    } else {
      throw FileFormatError(name, "line " + std::to_string(line_no) + ": unknown keyword '" +
                                      word.substr(0, 20) + "' (expected line or fixed)");
    }
  }
  if (!header) throw FileFormatError(name, "empty file (expected 'scanmesh_feature_lines 1')");
  return out;
}

FeatureLines read_feature_lines(const std::filesystem::path& path) {
  const std::vector<std::uint8_t> bytes = read_file_bytes(path, kMaxTextInputBytes);
  return parse_feature_lines(std::string(bytes.begin(), bytes.end()), path.string());
}

std::string format_feature_lines(const FeatureLines& lines) {
  std::ostringstream out;
  out << "scanmesh_feature_lines 1\n";
  for (const auto& l : lines.lines) {
    out << "line";
    for (int v : l) out << ' ' << v;
    out << '\n';
  }
  if (!lines.fixed.empty()) {
    out << "fixed";
    for (int v : lines.fixed) out << ' ' << v;
    out << '\n';
  }
  return out.str();
}

std::size_t FeatureSkeleton::branch_vertex_count() const {
  return static_cast<std::size_t>(std::count(kind.begin(), kind.end(), VertexKind::Branch));
}

Eigen::Vector3d FeatureSkeleton::point(const std::vector<Eigen::Vector3d>& positions, int seg,
                                       double s, int* edge, double* t) const {
  const SkeletonSegment& sg = segments[seg];
  s = std::clamp(s, 0.0, sg.length());
  auto it = std::upper_bound(sg.arc.begin(), sg.arc.end(), s);
  int i = static_cast<int>(it - sg.arc.begin()) - 1;
  i = std::clamp(i, 0, static_cast<int>(sg.arc.size()) - 2);
  const double len = sg.arc[i + 1] - sg.arc[i];
  const double u = len > 0 ? std::clamp((s - sg.arc[i]) / len, 0.0, 1.0) : 0.0;
  if (edge) *edge = i;
  if (t) *t = u;
  return (1 - u) * positions[sg.vertices[i]] + u * positions[sg.vertices[i + 1]];
}

namespace {

using SkeletonEdges = std::set<std::uint64_t>;
using SkeletonAdjacency = std::vector<std::vector<int>>;

// Step 1: the edges of M0 that are skeleton by themselves: boundary and non-manifold edges,
// label borders, sharp edges. (The radial face lists are TriangleMesh's, in face order: a hash
// map of vectors here was a third of the skeleton's time on the demo head.)
SkeletonEdges classify_edges(const TriangleMesh& m, const std::vector<std::uint64_t>& edges,
                             const SkeletonOptions& options, FeatureSkeleton& sk) {
  SkeletonEdges skel;
  const double cos_sharp =
      options.sharp_angle_deg > 0 ? std::cos(options.sharp_angle_deg * std::numbers::pi / 180) : 2;
  for (const auto k : edges) {
    const auto fs = m.edge_faces(edge_key_first(k), edge_key_second(k));
    if (fs.size() != 2) {
      skel.insert(k);
      (fs.size() == 1 ? sk.boundary_edges : sk.nonmanifold_edges)++;
      continue;
    }
    if (options.label_borders && m.label[fs[0]] != m.label[fs[1]]) {
      skel.insert(k);
      ++sk.label_edges;
      continue;
    }
    if (cos_sharp < 1.5) {
      // Consistent orientation: the shared edge runs opposite in the two faces.
      const double c = m.face_normal(fs[0]).dot(m.face_normal(fs[1]));
      if (c < cos_sharp) {
        skel.insert(k);
        ++sk.sharp_edges;
      }
    }
  }
  return skel;
}

// Step 2: the user's feature lines join the skeleton; lines and fixed vertices are checked
// against the mesh.
void add_feature_lines(const TriangleMesh& m, const FeatureLines& lines, SkeletonEdges& skel,
                       FeatureSkeleton& sk) {
  const int nv = static_cast<int>(m.pos.size());
  for (const auto& l : lines.lines)
    for (std::size_t i = 0; i < l.size(); ++i) {
      if (l[i] >= nv)
        throw InvalidInputError("feature line vertex " + std::to_string(l[i]) +
                                " is out of range (mesh has " + std::to_string(nv) + " vertices)");
      if (i + 1 < l.size()) {
        const auto k = edge_key(l[i], std::min(l[i + 1], nv - 1));
        if (l[i + 1] >= nv || m.edge_face_count(l[i], l[i + 1]) == 0)
          throw InvalidInputError("feature line: vertices " + std::to_string(l[i]) + " and " +
                                  std::to_string(l[i + 1]) + " are not joined by an edge");
        if (skel.insert(k).second) ++sk.user_edges;
      }
    }
  for (int v : lines.fixed)
    if (v >= nv) throw InvalidInputError("fixed vertex " + std::to_string(v) + " is out of range");
}

SkeletonAdjacency skeleton_adjacency(int nv, const SkeletonEdges& skel) {
  SkeletonAdjacency sadj(nv);
  for (auto k : skel) {
    sadj[edge_key_first(k)].push_back(edge_key_second(k));
    sadj[edge_key_second(k)].push_back(edge_key_first(k));
  }
  return sadj;
}

// Step 3: free, skeleton (on a chain of degree 2 whose sides agree) or branch vertices; a
// kink (a turn of at least the kink angle, the sharpest within the reach) and a fixed vertex
// are branch vertices too.
void classify_vertices(const TriangleMesh& m, const std::vector<std::uint64_t>& edges,
                       const SkeletonEdges& skel, const SkeletonAdjacency& sadj,
                       const FeatureLines& lines, const SkeletonOptions& options,
                       FeatureSkeleton& sk) {
  const int nv = static_cast<int>(m.pos.size());
  sk.kind.assign(nv, VertexKind::Free);
  const double cos_kink = std::cos(options.kink_angle_deg * std::numbers::pi / 180);
  const std::unordered_map<std::uint64_t, int> no_map;
  const SkeletonEdges no_set;
  double mean_edge = 0;
  for (const auto k : edges)
    mean_edge += (m.pos[edge_key_first(k)] - m.pos[edge_key_second(k)]).norm();
  mean_edge /= std::max<double>(1, static_cast<double>(edges.size()));
  const double reach =
      options.kink_reach_mm > 0 ? options.kink_reach_mm : options.kink_window * mean_edge;
  // End of the walk from v through n along degree-2 skeleton vertices for arc length `reach`.
  auto walk = [&](int v, int n) {
    int prev = v, cur = n;
    double arc = (m.pos[n] - m.pos[v]).norm();
    while (arc < reach && sadj[cur].size() == 2 && cur != v) {
      const int nxt = sadj[cur][0] == prev ? sadj[cur][1] : sadj[cur][0];
      arc += (m.pos[nxt] - m.pos[cur]).norm();
      prev = cur;
      cur = nxt;
    }
    return cur;
  };
  std::vector<double> turn(nv, 1.0);  // cosine of the turn at degree-2 skeleton vertices
  for (int v = 0; v < nv; ++v) {
    if (m.vfaces[v].empty()) continue;
    const auto& a = sadj[v];
    if (a.empty()) {  // no skeleton edge at v: none to look up
      if (count_fans(m, v, no_map, no_set) != 1) sk.kind[v] = VertexKind::Branch;
      continue;
    }
    if (a.size() != 2) {
      sk.kind[v] = VertexKind::Branch;
      continue;
    }
    const int k0 = m.edge_face_count(v, a[0]), k1 = m.edge_face_count(v, a[1]);
    const bool book = k0 == k1 && count_fans(m, v, no_map, skel) == k0;
    sk.kind[v] = book ? VertexKind::Skeleton : VertexKind::Branch;
    const Eigen::Vector3d d0 = (m.pos[v] - m.pos[walk(v, a[0])]).normalized();
    const Eigen::Vector3d d1 = (m.pos[walk(v, a[1])] - m.pos[v]).normalized();
    turn[v] = d0.dot(d1);
  }
  // Kinks: turn >= kink angle and the sharpest turn within the reach (non-maximum suppression).
  for (int v = 0; v < nv; ++v) {
    if (sk.kind[v] != VertexKind::Skeleton || turn[v] > cos_kink) continue;
    bool is_max = true;
    for (int n : sadj[v]) {
      int prev = v, cur = n;
      double arc = (m.pos[n] - m.pos[v]).norm();
      while (is_max && arc <= reach && sadj[cur].size() == 2 && cur != v) {
        if (turn[cur] < turn[v] || (turn[cur] == turn[v] && cur < v)) is_max = false;
        const int nxt = sadj[cur][0] == prev ? sadj[cur][1] : sadj[cur][0];
        arc += (m.pos[nxt] - m.pos[cur]).norm();
        prev = cur;
        cur = nxt;
      }
    }
    if (is_max) sk.kind[v] = VertexKind::Branch;
  }
  for (int v : lines.fixed) sk.kind[v] = VertexKind::Branch;
}

// Step 4: segments are the chains between branch vertices; a closed loop without one gets one.
void trace_segments(const TriangleMesh& m, const SkeletonAdjacency& sadj, FeatureSkeleton& sk) {
  const int nv = static_cast<int>(m.pos.size());
  sk.vertex_segment.assign(nv, -1);
  sk.vertex_arc.assign(nv, 0.0);
  std::set<std::uint64_t> used;
  auto trace = [&](int start, int next) {
    SkeletonSegment sg;
    sg.vertices = {start};
    sg.arc = {0.0};
    sg.sides = m.edge_face_count(start, next);
    int prev = start, cur = next;
    const int id = static_cast<int>(sk.segments.size());
    while (true) {
      const auto k = edge_key(prev, cur);
      used.insert(k);
      sk.edge_segment[k] = id;
      sg.arc.push_back(sg.arc.back() + (m.pos[cur] - m.pos[prev]).norm());
      sg.vertices.push_back(cur);
      if (sk.kind[cur] == VertexKind::Branch) break;
      sk.vertex_segment[cur] = id;
      sk.vertex_arc[cur] = sg.arc.back();
      const int nxt = sadj[cur][0] == prev ? sadj[cur][1] : sadj[cur][0];
      prev = cur;
      cur = nxt;
    }
    sk.segments.push_back(std::move(sg));
  };
  for (int v = 0; v < nv; ++v) {
    if (sk.kind[v] != VertexKind::Branch) continue;
    std::vector<int> nb = sadj[v];
    std::sort(nb.begin(), nb.end());
    for (int w : nb)
      if (!used.count(edge_key(v, w))) trace(v, w);
  }
  for (int v = 0; v < nv; ++v) {
    if (sk.kind[v] != VertexKind::Skeleton || sk.vertex_segment[v] >= 0) continue;
    sk.kind[v] = VertexKind::Branch;  // closed loop without a branch vertex
    trace(v, std::min(sadj[v][0], sadj[v][1]));
  }
}

// Step 5: patches are the faces connected across non-skeleton edges.
void find_patches(const TriangleMesh& m, const SkeletonEdges& skel, const SkeletonAdjacency& sadj,
                  FeatureSkeleton& sk) {
  const int nf = static_cast<int>(m.tri.size());
  sk.face_patch.assign(nf, -1);
  for (int f0 = 0; f0 < nf; ++f0) {
    if (!m.face_alive[f0] || sk.face_patch[f0] >= 0) continue;
    const int id = sk.patch_count++;
    std::vector<int> stack = {f0};
    sk.face_patch[f0] = id;
    while (!stack.empty()) {
      const int f = stack.back();
      stack.pop_back();
      for (int i = 0; i < 3; ++i) {
        const int a = m.tri[f][i], b = m.tri[f][(i + 1) % 3];
        // A skeleton edge joins two vertices with skeleton edges (most edges answer here).
        if (!sadj[a].empty() && !sadj[b].empty() && skel.count(edge_key(a, b))) continue;
        for (int g : m.edge_faces(a, b))
          if (sk.face_patch[g] < 0) {
            sk.face_patch[g] = id;
            stack.push_back(g);
          }
      }
    }
  }
}

}  // namespace

FeatureSkeleton build_feature_skeleton(const TriangleMesh& m, const FeatureLines& lines,
                                       const SkeletonOptions& options) {
  FeatureSkeleton sk;
  const std::vector<std::uint64_t> edges = m.edges();
  SkeletonEdges skel = classify_edges(m, edges, options, sk);
  add_feature_lines(m, lines, skel, sk);
  const SkeletonAdjacency sadj = skeleton_adjacency(static_cast<int>(m.pos.size()), skel);
  classify_vertices(m, edges, skel, sadj, lines, options, sk);
  trace_segments(m, sadj, sk);
  find_patches(m, skel, sadj, sk);
  return sk;
}

}  // namespace scanmesh::remeshing
