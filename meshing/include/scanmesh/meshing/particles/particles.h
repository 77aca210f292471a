// Particle-based triangulation of implicit surfaces by a spring network (seed 003 §4, after
// Rodrian, Schueller, Moock, "Partikelgestuetzte Triangulierung skelettbasierter impliziter
// Flaechen", Univ. Kaiserslautern report 280/96). Particles are the vertices, springs are the
// edges; each iteration moves the particles with the Witkin-Heckbert constraint velocity (eq. 8)
// driven by spring forces (eq. 13), then collapses (eq. 14) and splits (eq. 15) springs with
// the one-step marks and the "still moving" rule (16), optionally flips edges towards valence
// 6, adapts rest lengths to curvature (eq. 17-23) and cuts the mesh where the surface tears
// apart (§4.4, eq. 24-25). Every decision where the report has a gap is in docs/particles.md.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <vector>

#include "scanmesh/core/mesh.h"
#include "scanmesh/meshing/particles/implicit_surface.h"

namespace scanmesh::particles {

//! All parameters; the defaults are the ones documented in docs/particles.md. Lengths that
//! are not `edge_length` are given as fractions of it.
struct ParticleOptions {
  double edge_length = 1.0;  //!< R, the base rest length (mm)
  bool adaptive = false;     //!< curvature-adaptive rest lengths (§4.3)
  //! Adaptive mode: average the eq. (21) rest lengths over each particle's springs and then
  //! over each spring's two particles (an addition; keeps neighbouring triangles alike).
  bool adaptive_smoothing = true;
  double rho = 1.0;  //!< spring constant rho of eq. (12); sets the time unit
  //! Stiffening k of eq. (12) for moderate strains: S = rho x (1 + min(k x^2, 1/3)) with
  //! x = (R_e - |r|)/R_e (an addition; 0 gives eq. 12 as printed).
  double spring_stiffening = 10.0;
  //! Euler step (eq. 11) as a fraction of the non-oscillation bound 1 / (rho * max valence).
  double time_step_factor = 1.0;
  double d_min = 0.55;              //!< eq. (14): collapse below d_min * R_e
  double d_max = 1.45;              //!< eq. (15): split above d_max * R_e
  double moving_epsilon = 0.02;     //!< eq. (16): remesh only if ||r|_alt - |r|| <= eps R_e
  bool flips = true;                //!< edge flips towards valence 6 (not in the report)
  double theta = 0.25;              //!< damping of the curvature update, eq. (22)
  double lambda = 0.5;              //!< clamp half-width, eq. (23), fraction of R
  bool topology_change = true;      //!< §4.4 marking, constriction, ring cut
  double gap_angle_deg = 15.0;      //!< §4.4 Step 1 "eps": spring-to-gradient angle
  double special_factor = 0.2;      //!< §4.4 Step 2: rest length of special springs, times R_e
  double special_min_length = 0.5;  //!< §4.4 Step 2: special springs shorter are removed
  double epsilon1 = 0.05;           //!< eq. (25.2): shared-edge midpoint at least eps1 * R outside
  double epsilon2 = 0.0;            //!< eq. (25.3): cosine between end-point gradients below this
  //! §4.4 Step 3: steps a band of ring candidates may persist without forming a clean ring
  //! before the fallback removes it wholesale (gap decision 26); also the steps a particle
  //! may stay lost (far from F = 0; in scan mode also where F is undefined) before it is
  //! removed (decisions 25 and 43).
  int ring_patience = 10;
  double max_step = 0.5;  //!< displacement cap per step, fraction of R (stability guard)
  //! relax(): converged after 10 consecutive steps with no collapse, split, flip or cut in
  //! which no particle moved farther than 10 x this x R in total (§4.4 is off in relax()).
  double convergence_tolerance = 1e-3;
  int max_iterations = 3000;    //!< relax(): iteration limit
  double start_spacing = 1.25;  //!< start triangulation grid spacing, fraction of R
  //! Multilevel start: relax first at up to 2^max_levels R, then subdivide 1:4 (0: off).
  int max_levels = 3;
  //! Subdivided start (closed surfaces, uniform mode; docs/particles.md, decision 37): the
  //! largest 1:n subdivision of an evenly spread coarse mesh tried (< 2: off) ...
  int max_subdivision = 8;
  //! ... the largest coarse particle count per component it spreads ...
  int max_spread_particles = 100;
  //! ... how many of the best-scored coarse candidates are subdivided and relaxed ...
  int subdivision_trials = 3;
  //! ... and the fraction of edges within +-15 % of R that spares the layered start.
  double subdivision_accept = 0.99;
  //! relax(): isotropic remeshing rounds (split/collapse/flip/tangential relaxation) before
  //! the spring iterations.
  int remesh_rounds = 10;
  //! relax(): after convergence, a mean stretch farther than this from 1 is corrected by
  //! collapsing or splitting springs (docs/particles.md, decision 13).
  double density_tolerance = 0.03;
  //! relax(): after convergence, valence-5/7 pairs (dislocations) are glided by flips up to
  //! this many steps to cancel against other defects (docs/particles.md, decision 33; 0: off).
  int max_glide = 0;
  //! relax(): flips stop after this many spring iterations so flip/collapse cycles cannot
  //! keep it from converging (docs/particles.md, decision 34; 0: never). In scan mode moves
  //! that still cycle are calmed from then on, and Rules 1-2 stop at twice this (decision 44).
  int flip_freeze = 500;
  std::uint64_t seed = 1;  //!< reserved (CLI --seed); the spring network uses no randomness
  //! Progress display (optional): every full-resolution relax() calls it every 10 iterations
  //! with (iterations, max_iterations) -- relaxed_network() may run a few in turn (decision
  //! 37), coarse levels stay silent -- and animate() once per frame with (frame, frames).
  std::function<void(int done, int total)> progress;
};

//! What one iteration did.
struct StepReport {
  int collapses = 0, splits = 0, flips = 0, special_collapses = 0;
  int cuts = 0;           //!< §4.4 ring cuts (eq. 25, two closing fans)
  int fallback_cuts = 0;  //!< removals of lost particles / spanning bands (gap decisions 25-26;
                          //!< in scan mode the holes opened at lost particles, decision 43)
  int new_topology_marks = 0;
  double max_tangential_move = 0.0;  //!< largest |dt * tangential velocity| (mm)
  double max_constraint = 0.0;       //!< largest |F|/|grad F| before the step (mm)
  double time_step = 0.0;
  bool changed() const {
    return collapses + splits + flips + special_collapses + cuts + fallback_cuts > 0;
  }
};

//! The spring network: a closed (or, on scans, bounded) manifold triangle mesh whose vertices
//! carry stable identities. Vertices keep their id for as long as they exist; vertices
//! created by a split, a collapse (the merged vertex) or a cut get fresh ids, never reused.
class SpringNetwork {
 public:
  //! Takes over a manifold triangle mesh (e.g. the start triangulation). Throws
  //! InvalidInputError for a non-manifold or inconsistently oriented input or bad options.
  SpringNetwork(const Mesh& start, const ParticleOptions& options);
  ~SpringNetwork();
  SpringNetwork(SpringNetwork&&) noexcept;
  SpringNetwork& operator=(SpringNetwork&&) noexcept;

  //! One iteration of seed 003 §5.2 on `surface`. `surface_time_step` is the time the
  //! surface advances during this step (multiplies dF/dt in eq. 8); 0 for a static surface.
  StepReport step(const ImplicitSurface& surface, double surface_time_step = 0.0);
  //! Steps until converged (see ParticleOptions::convergence_tolerance) or max_iterations,
  //! then projects every vertex onto the surface (Newton, eq. 8 with P = 0). Returns the
  //! number of iterations. `target_vertices` > 0 replaces the mean-stretch density correction
  //! (docs/particles.md, decision 13) by one towards that many particles (up to 8 rounds of
  //! collapses or splits; the count can end near it). On a mesh with borders (scan mode) it
  //! also removes particles that stay lost, leaving the holes open (decision 43), and drops
  //! triangles left turned over at a border (decision 38).
  int relax(const ImplicitSurface& surface, std::size_t target_vertices = 0);
  //! Newton projection of every vertex (no tangential motion).
  void project(const ImplicitSurface& surface);
  //! Spreads the particles evenly over the surface: `iterations` annealed steps of all-pairs
  //! Coulomb repulsion (tangential, Newton-projected), each followed by Delaunay flips (3D
  //! opposite angles). Particles repel only within their component; border particles stay.
  //! Quadratic in the particle count: meant for coarse meshes (the subdivided start,
  //! docs/particles.md decision 37).
  void spread_evenly(const ImplicitSurface& surface, int iterations);

  //! The current mesh (compact indices, counter-clockwise from outside) and the id of each of
  //! its vertices.
  Mesh mesh() const;
  std::vector<std::uint64_t> vertex_ids() const;
  std::size_t vertex_count() const;
  int iteration() const;
  //! True if the last relax() met its convergence test (not stopped by max_iterations).
  bool converged() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

//! The start triangulation (gap in seed 003 §4.2, "suitable"): marching tetrahedra (Kuhn
//! subdivision of a cubic grid) of F = 0 over surface.bounds() at grid `spacing`, vertices
//! welded per grid edge. Always manifold (possibly several components); open only where F is
//! undefined. Vertices are on the piecewise-linear interpolant, not yet on the surface.
Mesh marching_tetrahedra(const ImplicitSurface& surface, double spacing);

//! Start triangulation (multilevel: marching tetrahedra at a coarse level, relaxed, subdivided
//! 1:4, relaxed again, down to R; docs/particles.md) and relax(). `iterations` (optional)
//! receives the total spring iterations.
SpringNetwork relaxed_network(const ImplicitSurface& surface, const ParticleOptions& options,
                              int* iterations = nullptr);

//! Whole static pipeline: relaxed_network(), result.
struct ParticleMeshResult {
  Mesh mesh;
  std::vector<std::uint64_t> vertex_ids;
  int iterations = 0;
  bool converged = false;  //!< the final relax() met its convergence test
};
ParticleMeshResult particle_mesh(const ImplicitSurface& surface, const ParticleOptions& options);

//! A surface that changes with time (e.g. an animated skeleton); called once per step.
using SurfaceAtTime = std::function<std::shared_ptr<const ImplicitSurface>(double time)>;

struct AnimationFrame {
  double time = 0.0;
  Mesh mesh;
  std::vector<std::uint64_t> vertex_ids;
  int cuts = 0;           //!< §4.4 ring cuts (eq. 25) since the previous frame
  int fallback_cuts = 0;  //!< fallback separations (gap decisions 25-26) since then
};

//! Frame 0 is the relaxed mesh at t0; each later frame follows the surface with
//! `steps_per_frame` steps, the surface time advancing evenly (dF/dt enters eq. 8), and ends
//! with a Newton projection. frames >= 1; frames == 1 gives only t0.
std::vector<AnimationFrame> animate(const SurfaceAtTime& surface_at, double t0, double t1,
                                    int frames, const ParticleOptions& options,
                                    int steps_per_frame = 20);

//! Binary PLY with vertex x, y, z (float) and `uint id` (the stable identity) and triangle
//! faces (docs/formats.md, "Particle frames"). core's read_ply reads it (ignoring id).
void write_ply_with_ids(const std::filesystem::path& path, const Mesh& mesh,
                        const std::vector<std::uint64_t>& ids);
//! Reads back the id property written above (FileFormatError if absent or malformed).
std::vector<std::uint64_t> read_ply_ids(const std::filesystem::path& path);

}  // namespace scanmesh::particles
