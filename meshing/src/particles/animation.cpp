// Animated meshing (seed 003 §1: the mesh follows the moving skeleton) and the per-frame PLY
// with stable vertex ids (docs/formats.md, "Particle frames").
#include <charconv>
#include <sstream>

#include "scanmesh/core/atomic_file.h"
#include "scanmesh/core/binary_io.h"
#include "scanmesh/core/errors.h"
#include "scanmesh/meshing/particles/particles.h"

namespace scanmesh::particles {

std::vector<AnimationFrame> animate(const SurfaceAtTime& surface_at, double t0, double t1,
                                    int frames, const ParticleOptions& options,
                                    int steps_per_frame) {
  if (frames < 1 || steps_per_frame < 1)
    throw InvalidInputError("particles: need frames >= 1 and steps_per_frame >= 1");
  std::vector<AnimationFrame> out;
  const auto first = surface_at(t0);
  SpringNetwork net = relaxed_network(*first, options);
  out.push_back({t0, net.mesh(), net.vertex_ids(), 0, 0});
  for (int f = 1; f < frames; ++f) {
    if (options.progress) options.progress(f, frames);
    const double ta = t0 + (t1 - t0) * (f - 1) / (frames - 1);
    const double tb = t0 + (t1 - t0) * f / (frames - 1);
    const double tau = (tb - ta) / steps_per_frame;
    int cuts = 0, fallback = 0;
    std::shared_ptr<const ImplicitSurface> s;
    for (int k = 0; k < steps_per_frame; ++k) {
      // The surface at the start of the sub-step, advancing by tau during it (dF/dt in eq. 8).
      s = surface_at(ta + k * tau);
      const StepReport r = net.step(*s, tau);
      cuts += r.cuts;
      fallback += r.fallback_cuts;
    }
    s = surface_at(tb);
    net.project(*s);
    out.push_back({tb, net.mesh(), net.vertex_ids(), cuts, fallback});
  }
  if (options.progress) options.progress(frames, frames);
  return out;
}

void write_ply_with_ids(const std::filesystem::path& path, const Mesh& mesh,
                        const std::vector<std::uint64_t>& ids) {
  if (ids.size() != mesh.positions.size())
    throw InvalidInputError("write_ply_with_ids: one id per vertex needed");
  std::ostringstream h;
  h << "ply\nformat binary_little_endian 1.0\ncomment scanmesh particles frame\n"
    << "element vertex " << mesh.positions.size()
    << "\nproperty float x\nproperty float y\nproperty float z\nproperty uint id\n"
    << "element face " << mesh.triangles.size()
    << "\nproperty list uchar int vertex_indices\nend_header\n";
  const std::string header = h.str();
  std::vector<std::uint8_t> b(header.begin(), header.end());
  ByteWriter out(b);
  for (std::size_t i = 0; i < mesh.positions.size(); ++i) {
    for (int a = 0; a < 3; ++a) out.f32(static_cast<float>(mesh.positions[i][a]));
    if (ids[i] > 0xffffffffULL) throw InvalidInputError("write_ply_with_ids: id beyond 32 bits");
    out.u32(static_cast<std::uint32_t>(ids[i]));
  }
  for (const auto& t : mesh.triangles) {
    out.u8(3);
    for (int v : t) out.u32(static_cast<std::uint32_t>(v));
  }
  write_file_atomically(path, std::span<const std::uint8_t>(b));
}

std::vector<std::uint64_t> read_ply_ids(const std::filesystem::path& path) {
  const std::vector<std::uint8_t> bytes = read_file_bytes(path);
  const std::string text(bytes.begin(), bytes.end());
  const std::string expect =
      "property float x\nproperty float y\nproperty float z\nproperty uint id\n";
  const auto end = text.find("end_header\n");
  const auto vpos = text.find("element vertex ");
  if (end == std::string::npos || vpos == std::string::npos ||
      text.find(expect) == std::string::npos ||
      text.find("format binary_little_endian 1.0") == std::string::npos)
    throw FileFormatError(path, "not a scanmesh particle frame (x y z float + uint id)");
  // The count is checked against the bytes present before anything is allocated (a hostile
  // count must neither throw from std::stoull nor wrap the size check).
  std::size_t n = 0;
  const char* count_begin = text.data() + vpos + 15;
  const char* count_end = text.data() + text.size();
  const auto [count_stop, count_error] = std::from_chars(count_begin, count_end, n);
  if (count_error != std::errc() || count_stop == count_begin ||
      (*count_stop != '\n' && *count_stop != '\r'))
    throw FileFormatError(path, "vertex count is not a non-negative integer");
  const std::size_t data = end + 11;
  if (n > (bytes.size() - data) / 16)
    throw FileFormatError(path, "truncated vertex data: " + std::to_string(n) +
                                    " vertices of 16 bytes declared, " +
                                    std::to_string(bytes.size() - data) + " bytes present");
  std::vector<std::uint64_t> ids(n);
  for (std::size_t i = 0; i < n; ++i) ids[i] = read_le_u32(bytes.data() + data + 16 * i + 12);
  return ids;
}

}  // namespace scanmesh::particles
