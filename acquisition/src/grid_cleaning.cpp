#include "scanmesh/acquisition/grid_cleaning.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "scanmesh/core/errors.h"

namespace scanmesh {

namespace {

void check_options(const CleaningOptions& o) {
  if (!(o.spike_threshold_mm >= 0.0) || !(o.spike_spread_factor >= 0.0))
    throw InvalidInputError("cleaning: spike thresholds must be >= 0");
  if (o.spike_min_neighbours < 1 || o.spike_min_neighbours > 8)
    throw InvalidInputError("cleaning: spike_min_neighbours must be in 1..8, got " +
                            std::to_string(o.spike_min_neighbours));
  if (o.min_component_cells < 1)
    throw InvalidInputError("cleaning: min_component_cells must be >= 1, got " +
                            std::to_string(o.min_component_cells));
}

double median_in_place(std::vector<float>& v) {
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  double m = *mid;
  if (v.size() % 2 == 0) m = 0.5 * (m + *std::max_element(v.begin(), mid));
  return m;
}

// Predicts r at (i, j) from the four pairs of opposite neighbours (left-right, down-up and the
// two diagonals): on any smooth surface, sloped or not, each pair's mean is the centre value up
// to curvature terms, and a second spike nearby spoils only one pair. Falls back to the median
// of all valid neighbours where fewer than two pairs are complete (edges of holes and rims).
struct Prediction {
  double value = 0.0;
  double spread = 0.0;  // how much the individual predictions disagree
  bool ok = false;
};

Prediction predict_from_pairs(const RangeGrid& grid, int i, int j, std::vector<float>& scratch) {
  static constexpr std::array<std::array<int, 2>, 4> kDirections = {
      {{1, 0}, {0, 1}, {1, 1}, {1, -1}}};
  scratch.clear();
  for (const auto& [di, dj] : kDirections) {
    const int ja = j - dj, jb = j + dj;
    if (ja < 0 || jb < 0 || ja >= grid.n_h() || jb >= grid.n_h()) continue;
    const int ia = grid.wrap_phi(i - di), ib = grid.wrap_phi(i + di);
    if (grid.valid(ia, ja) && grid.valid(ib, jb))
      scratch.push_back(0.5f * (grid.radius(ia, ja) + grid.radius(ib, jb)));
  }
  Prediction p;
  if (scratch.size() < 2) return p;
  p.value = median_in_place(scratch);
  for (float& r : scratch) r = static_cast<float>(std::abs(r - p.value));
  p.spread = median_in_place(scratch);
  p.ok = true;
  return p;
}

Prediction predict_from_median(const RangeGrid& grid, int i, int j, int min_neighbours,
                               std::vector<float>& scratch) {
  scratch.clear();
  for (int dj = -1; dj <= 1; ++dj) {
    const int jj = j + dj;
    if (jj < 0 || jj >= grid.n_h()) continue;
    for (int di = -1; di <= 1; ++di) {
      if (di == 0 && dj == 0) continue;
      const int ii = grid.wrap_phi(i + di);
      if (grid.valid(ii, jj)) scratch.push_back(grid.radius(ii, jj));
    }
  }
  Prediction p;
  if (static_cast<int>(scratch.size()) < min_neighbours) return p;
  p.value = median_in_place(scratch);
  for (float& r : scratch) r = static_cast<float>(std::abs(r - p.value));
  p.spread = median_in_place(scratch);
  p.ok = true;
  return p;
}

bool is_spike(const RangeGrid& grid, int i, int j, const CleaningOptions& o,
              std::vector<float>& scratch) {
  Prediction p = predict_from_pairs(grid, i, j, scratch);
  if (!p.ok) p = predict_from_median(grid, i, j, o.spike_min_neighbours, scratch);
  if (!p.ok) return false;  // too few neighbours to judge; fragment removal decides
  return std::abs(grid.radius(i, j) - p.value) >
         o.spike_threshold_mm + o.spike_spread_factor * p.spread;
}

std::size_t remove_spikes(RangeGrid& grid, const CleaningOptions& o) {
  std::vector<std::size_t> spikes;
  std::vector<float> scratch;
  for (int j = 0; j < grid.n_h(); ++j)
    for (int i = 0; i < grid.n_phi(); ++i)
      if (grid.valid(i, j) && is_spike(grid, i, j, o, scratch)) spikes.push_back(grid.index(i, j));
  for (std::size_t k : spikes)
    grid.invalidate(static_cast<int>(k % grid.n_phi()), static_cast<int>(k / grid.n_phi()));
  return spikes.size();
}

// Labels 4-connected components of valid cells (phi wraps) and removes the small ones.
void remove_fragments(RangeGrid& grid, const CleaningOptions& o, CleaningReport& report) {
  std::vector<int> label(grid.cell_count(), -1);
  std::vector<std::size_t> stack, members;
  int next_label = 0;
  for (std::size_t seed = 0; seed < grid.cell_count(); ++seed) {
    if (!grid.validity()[seed] || label[seed] >= 0) continue;
    members.clear();
    stack.assign(1, seed);
    label[seed] = next_label;
    while (!stack.empty()) {
      const std::size_t k = stack.back();
      stack.pop_back();
      members.push_back(k);
      const int i = static_cast<int>(k % grid.n_phi()), j = static_cast<int>(k / grid.n_phi());
      const std::array<std::array<int, 2>, 4> nbrs = {
          {{grid.wrap_phi(i - 1), j}, {grid.wrap_phi(i + 1), j}, {i, j - 1}, {i, j + 1}}};
      for (const auto& [ni, nj] : nbrs) {
        if (nj < 0 || nj >= grid.n_h()) continue;
        const std::size_t n = grid.index(ni, nj);
        if (grid.validity()[n] && label[n] < 0) {
          label[n] = next_label;
          stack.push_back(n);
        }
      }
    }
    ++next_label;
    if (static_cast<int>(members.size()) >= o.min_component_cells) {
      ++report.components_kept;
      continue;
    }
    ++report.fragments_removed;
    report.fragment_cells_removed += members.size();
    for (std::size_t k : members)
      grid.invalidate(static_cast<int>(k % grid.n_phi()), static_cast<int>(k / grid.n_phi()));
  }
}

}  // namespace

CleaningReport clean_grid(RangeGrid& grid, const CleaningOptions& options) {
  check_options(options);
  CleaningReport report;
  report.valid_before = grid.valid_count();
  report.spikes_removed = remove_spikes(grid, options);
  remove_fragments(grid, options, report);
  report.valid_after = grid.valid_count();
  return report;
}

}  // namespace scanmesh
