// Witkin-Heckbert particle sampling of an implicit surface (seed 003 §3.2, eq. 3-11, after
// Witkin & Heckbert, "Using particles to sample and control implicit surfaces", SIGGRAPH 94):
// particles held on F = 0 by the constraint velocity (8) with feedback phi, pushed apart by
// Gaussian repulsion (9)-(10) with per-particle adaptive radii sigma_i, and fission / death
// to reach the density the desired radius asks for.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "scanmesh/meshing/particles/implicit_surface.h"

namespace scanmesh::particles {

struct SamplerOptions {
  double sigma = 1.0;          //!< desired repulsion radius sigma_hat (mm); spacing is ~ 2 sigma
  double alpha = 6.0;          //!< energy amplitude alpha of eq. (9) (WH94)
  double energy_target = 0.8;  //!< desired energy E_hat, fraction of alpha (WH94: 0.8 alpha)
  double radius_rate = 15.0;   //!< WH94 rho: speed of the sigma_i adaptation
  double radius_beta = 10.0;   //!< WH94 beta: regulariser of d sigma_i / dt
  double time_step = 0.05;     //!< Euler step dt of eq. (11)
  int iterations = 400;
  int start_particles = 32;  //!< seeds placed by projecting jittered bounds-box points
  std::uint64_t seed = 1;
};

struct SampleResult {
  std::vector<Eigen::Vector3d> points;
  std::vector<double> sigma;  //!< final sigma_i per particle
  int fissions = 0, deaths = 0;
};

//! Samples the surface; every returned point is Newton-projected onto F = 0.
SampleResult witkin_heckbert_sample(const ImplicitSurface& surface, const SamplerOptions& o = {});

}  // namespace scanmesh::particles
