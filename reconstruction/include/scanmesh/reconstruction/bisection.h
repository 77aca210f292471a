// Bisection on a bracketed sign change, shared by the scan surface's ray/circle intersections
// and the advancing-front mesher's rotation construction (which must find the same roots, bit
// for bit, docs/animation-meshes.md).
#pragma once

namespace scanmesh {

//! Halves [a, b] while it is wider than `tolerance` (200 times at most), keeping the half whose
//! ends differ in "f < 0"; f(a) = fa is given and f returns an optional value. Stops early at a
//! midpoint where f is undefined. Returns the midpoint of the last bracket.
template <typename F>
double bisect_sign_change(const F& f, double a, double fa, double b, double tolerance) {
  for (int it = 0; it < 200 && b - a > tolerance; ++it) {
    const double m = 0.5 * (a + b);
    const auto fm = f(m);
    if (!fm) break;
    if ((*fm < 0) == (fa < 0)) {
      a = m;
      fa = *fm;
    } else {
      b = m;
    }
  }
  return 0.5 * (a + b);
}

}  // namespace scanmesh
