// Timing helpers shared by the benchmarks that are plain programs (not Google Benchmark).
#pragma once

#include <algorithm>
#include <chrono>
#include <functional>
#include <vector>

namespace scanmesh::bench {

//! Seconds on the steady clock.
inline double now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

//! Median wall time of `runs` calls of f, in seconds.
inline double time_median(int runs, const std::function<void()>& f) {
  std::vector<double> t;
  for (int k = 0; k < runs; ++k) {
    const double start = now();
    f();
    t.push_back(now() - start);
  }
  std::nth_element(t.begin(), t.begin() + t.size() / 2, t.end());
  return t[t.size() / 2];
}

}  // namespace scanmesh::bench
