// Cleaning of laser-scan grids (docs/acquisition.md, "Cleaning").
#include "scanmesh/acquisition/scan_cleaning.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "scanmesh/core/errors.h"

namespace scanmesh {

namespace {

// Membrane fill of one hole: every cell becomes the mean of its valid and already estimated
// 4-neighbours, 200 Jacobi sweeps (enough for the hole sizes filled here: they are small).
void fill_component(RangeGrid& g, const std::vector<int>& comp, const std::vector<int>& label) {
  const int np = g.n_phi();
  const int hole = label[comp.front()];
  std::vector<double> r(comp.size(), 0.0), nr(comp.size());
  std::vector<int> sorted = comp;
  std::sort(sorted.begin(), sorted.end());
  std::vector<std::array<int, 4>> nbr(comp.size());  // slot of an in-hole neighbour, or -1
  std::vector<std::array<float, 4>> fixed(comp.size());  // radius of a valid neighbour, or 0
  for (std::size_t q = 0; q < sorted.size(); ++q) {
    const int ci = sorted[q] % np, cj = sorted[q] / np;
    const int nb[4][2] = {{ci - 1, cj}, {ci + 1, cj}, {ci, cj - 1}, {ci, cj + 1}};
    for (int k = 0; k < 4; ++k) {
      nbr[q][k] = -1;
      fixed[q][k] = 0.0f;
      const int qi = g.wrap_phi(nb[k][0]), qj = nb[k][1];
      if (g.valid(qi, qj))
        fixed[q][k] = g.radius(qi, qj);
      else if (label[g.index(qi, qj)] == hole)
        nbr[q][k] = static_cast<int>(std::lower_bound(sorted.begin(), sorted.end(),
                                                      static_cast<int>(g.index(qi, qj))) -
                                     sorted.begin());
    }
  }
  for (int it = 0; it < 200; ++it) {
    for (std::size_t q = 0; q < sorted.size(); ++q) {
      double s = 0;
      int n = 0;
      for (int k = 0; k < 4; ++k) {
        if (fixed[q][k] > 0.0f) {
          s += fixed[q][k];
          ++n;
        } else if (nbr[q][k] >= 0 && r[nbr[q][k]] > 0) {
          s += r[nbr[q][k]];
          ++n;
        }
      }
      nr[q] = n ? s / n : 0.0;
    }
    r.swap(nr);
  }
  for (std::size_t q = 0; q < sorted.size(); ++q)
    if (r[q] > 0) g.set_sample(sorted[q] % np, sorted[q] / np, static_cast<float>(r[q]), 0.0f);
}

}  // namespace

HoleFillReport fill_small_holes(RangeGrid& g, int max_cells) {
  if (max_cells < 0) throw InvalidInputError("hole filling: the cell limit must not be negative");
  HoleFillReport rep;
  const int np = g.n_phi(), nh = g.n_h();
  // 4-connected components of invalid cells (phi wraps); small ones not touching the top or
  // bottom row are filled by repeated averaging of valid neighbours (a discrete membrane).
  std::vector<int> label(g.cell_count(), -1);
  std::vector<int> stack, comp;
  int next = 0;
  for (int j = 0; j < nh; ++j)
    for (int i = 0; i < np; ++i) {
      if (g.valid(i, j) || label[g.index(i, j)] >= 0) continue;
      comp.clear();
      bool border = false, too_big = false;
      stack.assign(1, static_cast<int>(g.index(i, j)));
      label[g.index(i, j)] = next;
      while (!stack.empty()) {
        const int c = stack.back();
        stack.pop_back();
        if (!too_big) comp.push_back(c);
        if (static_cast<int>(comp.size()) > max_cells) too_big = true;
        const int ci = c % np, cj = c / np;
        if (cj == 0 || cj == nh - 1) border = true;
        const int nb[4][2] = {{ci - 1, cj}, {ci + 1, cj}, {ci, cj - 1}, {ci, cj + 1}};
        for (auto& q : nb) {
          if (q[1] < 0 || q[1] >= nh) continue;
          const int qi = g.wrap_phi(q[0]);
          const std::size_t k = g.index(qi, q[1]);
          if (g.valid(qi, q[1]) || label[k] >= 0) continue;
          label[k] = next;
          stack.push_back(static_cast<int>(k));
        }
      }
      ++next;
      if (border || too_big) continue;
      fill_component(g, comp, label);
      for (int c : comp)
        if (g.valid(c % np, c / np)) ++rep.cells;
      ++rep.holes;
    }
  return rep;
}

ScanCleaningReport clean_scan_grid(RangeGrid& g, const ScanCleaningOptions& o) {
  if (o.min_confidence < 0 || !(o.hair_threshold_mm > 0) || o.platter_margin_mm < 0 ||
      o.max_hole_cells < 0 || o.hair_min_neighbours < 1)
    throw InvalidInputError("scan cleaning: thresholds must be positive");
  ScanCleaningReport rep;
  rep.valid_before = g.valid_count();
  const int np = g.n_phi(), nh = g.n_h();
  if (o.low_confidence)
    for (int j = 0; j < nh; ++j)
      for (int i = 0; i < np; ++i)
        if (g.valid(i, j) && g.confidence(i, j) < o.min_confidence) {
          g.invalidate(i, j);
          ++rep.low_confidence_removed;
        }
  if (o.platter)
    for (int j = 0; j < nh; ++j) {
      if (g.h(j) >= o.platter_height_mm + o.platter_margin_mm) continue;
      for (int i = 0; i < np; ++i)
        if (g.valid(i, j)) {
          g.invalidate(i, j);
          ++rep.platter_removed;
        }
    }
  if (o.hair) {
    std::vector<std::pair<int, int>> remove;
    std::vector<float> window;
    for (int j = 0; j < nh; ++j)
      for (int i = 0; i < np; ++i) {
        if (!g.valid(i, j)) continue;
        // Predictions from opposite pairs at distances 1 and 2 along 4 directions: exact on
        // linear surfaces, and a strand spoils only the pairs along its own direction.
        window.clear();
        const int dirs[4][2] = {{1, 0}, {0, 1}, {1, 1}, {1, -1}};
        for (const auto& d : dirs)
          for (int k = 1; k <= 2; ++k) {
            const int ja = j - k * d[1], jb = j + k * d[1];
            if (ja < 0 || jb < 0 || ja >= nh || jb >= nh) continue;
            const int ia = g.wrap_phi(i - k * d[0]), ib = g.wrap_phi(i + k * d[0]);
            if (g.valid(ia, ja) && g.valid(ib, jb))
              window.push_back(0.5f * (g.radius(ia, ja) + g.radius(ib, jb)));
          }
        if (static_cast<int>(window.size()) < o.hair_min_neighbours) continue;
        auto mid = window.begin() + window.size() / 2;
        std::nth_element(window.begin(), mid, window.end());
        if (std::abs(g.radius(i, j) - *mid) > o.hair_threshold_mm) remove.emplace_back(i, j);
      }
    for (auto [i, j] : remove) g.invalidate(i, j);
    rep.hair_removed = remove.size();
  }
  if (o.spikes_and_fragments) rep.spikes = clean_grid(g, o.spikes);
  if (o.fill_holes && o.max_hole_cells > 0) {
    const HoleFillReport filled = fill_small_holes(g, o.max_hole_cells);
    rep.holes_filled = filled.holes;
    rep.cells_filled = filled.cells;
    g.metadata["filled_cells"] = std::to_string(rep.cells_filled);
  }
  rep.valid_after = g.valid_count();
  return rep;
}

}  // namespace scanmesh
