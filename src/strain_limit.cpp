// Strain limiting (MODEL.md section 2; Provot 1995, adaptive order after Dochev &
// Vassilev 2003): over-stretched structural and shear springs are shortened back
// to (1 + τ_c) l0, starting from the particles that move first.
#include <algorithm>
#include <numeric>

#include "detail.hpp"

namespace wetcloth::detail {

namespace {

// Breadth-first grid distance (8-neighbourhood) from the source particles.
void distances_from(const Model& m, const std::vector<int>& sources, State& s, Workspace& w) {
  s.source_distance.assign(m.n, -1);
  w.queue.clear();
  for (int k : sources) {
    if (s.source_distance[k] == 0) continue;
    s.source_distance[k] = 0;
    w.queue.push_back(k);
  }
  for (std::size_t q = 0; q < w.queue.size(); ++q) {
    const int k = w.queue[q], i = k % m.nu, j = k / m.nu;
    for (int dj = -1; dj <= 1; ++dj)
      for (int di = -1; di <= 1; ++di) {
        const int ii = i + di, jj = j + dj;
        if (ii < 0 || jj < 0 || ii >= m.nu || jj >= m.nv) continue;
        const int kk = m.index(ii, jj);
        if (s.source_distance[kk] >= 0) continue;
        s.source_distance[kk] = s.source_distance[k] + 1;
        w.queue.push_back(kk);
      }
  }
}

}  // namespace

// Sources: the handles' particles; in a scene without handles, the first
// particles to touch an obstacle. Until there are any, every spring is split
// evenly, in grid order.
void update_strain_order(const Model& m, State& s, Workspace& w) {
  const std::size_t ns = m.structural.size(), nsh = m.shear.size();
  if (w.strain_order.size() != ns + nsh) {
    w.strain_order.resize(ns + nsh);
    std::iota(w.strain_order.begin(), w.strain_order.end(), 0);
  }
  if (s.sources_found) return;
  std::vector<int> sources;
  for (const Handle& h : m.handles) sources.insert(sources.end(), h.particles.begin(), h.particles.end());
  if (sources.empty()) {
    const double h_th = m.params.contact.bridge_height;
    for (int i = 0; i < m.n; ++i) {
      const bool near = (m.params.table.enabled &&
                         query_surface(m.params, SurfaceKind::Table, s.x[i]).distance < h_th) ||
                        (m.params.ball.enabled &&
                         query_surface(m.params, SurfaceKind::Ball, s.x[i]).distance < h_th);
      if (near) sources.push_back(i);
    }
  }
  if (sources.empty()) {
    s.source_distance.assign(m.n, 0);
    return;
  }
  s.sources_found = true;
  distances_from(m, sources, s, w);
  auto spring_key = [&](int e) {
    const SpringSet& set = e < static_cast<int>(ns) ? m.structural : m.shear;
    const int k = e < static_cast<int>(ns) ? e : e - static_cast<int>(ns);
    return std::min(s.source_distance[set.a[k]], s.source_distance[set.b[k]]);
  };
  std::iota(w.strain_order.begin(), w.strain_order.end(), 0);
  std::stable_sort(w.strain_order.begin(), w.strain_order.end(),
                   [&](int a, int b) { return spring_key(a) < spring_key(b); });
}

// Springs are corrected level by level in the adaptive order; within a level
// (springs at the same distance from the source) every correction is computed
// from the same positions and averaged per particle, so that the result does
// not depend on the order of springs within a level, and a symmetric cloth
// stays symmetric.
void limit_strain(const Model& m, State& s, Workspace& w, double dt) {
  const auto& p = m.params.strain_limit;
  if (!p.enabled) return;
  update_strain_order(m, s, w);
  w.x_before = s.x;
  w.strain_delta.assign(m.n, Vec3::Zero());
  w.strain_count.assign(m.n, 0);
  const double stretch = 1.0 + p.tau;
  const int ns = static_cast<int>(m.structural.size());
  auto ends = [&](int e, int& a, int& b) -> const SpringSet& {
    const SpringSet& set = e < ns ? m.structural : m.shear;
    const int k = e < ns ? e : e - ns;
    a = set.a[k];
    b = set.b[k];
    return set;
  };
  auto level = [&](int e) {
    int a, b;
    ends(e, a, b);
    return std::min(s.source_distance[a], s.source_distance[b]);
  };
  const std::size_t count = w.strain_order.size();
  bool moved = false;
  for (int pass = 0; pass < p.passes; ++pass) {
    bool corrected = false;  // a pass that corrects nothing ends the passes
    for (std::size_t first = 0; first < count;) {
      const int key = level(w.strain_order[first]);
      std::size_t last = first;
      for (; last < count && level(w.strain_order[last]) == key; ++last) {
        int a, b;
        const SpringSet& set = ends(w.strain_order[last], a, b);
        const Vec3 d = s.x[b] - s.x[a];
        const double len = d.norm();
        const double max_len = stretch * set.rest[w.strain_order[last] < ns ? w.strain_order[last]
                                                                            : w.strain_order[last] - ns];
        if (len <= max_len) continue;
        corrected = true;
        // The end farther from the source moves; both halves when neither is
        // nearer; pinned and driven particles never move.
        double wa = 0.5, wb = 0.5;
        const int da = s.source_distance[a], db = s.source_distance[b];
        if (da != db) {
          wa = da < db ? 0.0 : 1.0;
          wb = 1.0 - wa;
        }
        const bool fixed_a = m.driven[a] || s.held[a], fixed_b = m.driven[b] || s.held[b];
        if (fixed_a) {
          wa = 0;
          wb = fixed_b ? 0 : 1;
        }
        if (fixed_b) {
          wb = 0;
          wa = fixed_a ? 0 : 1;
        }
        const Vec3 corr = d * ((len - max_len) / len);
        if (wa > 0) {
          w.strain_delta[a] += wa * corr;
          ++w.strain_count[a];
        }
        if (wb > 0) {
          w.strain_delta[b] -= wb * corr;
          ++w.strain_count[b];
        }
      }
      for (std::size_t e = first; e < last; ++e) {
        int ab[2];
        ends(w.strain_order[e], ab[0], ab[1]);
        for (int k : ab) {
          if (w.strain_count[k] == 0) continue;
          s.x[k] += w.strain_delta[k] / w.strain_count[k];
          w.strain_delta[k].setZero();
          w.strain_count[k] = 0;
        }
      }
      first = last;
    }
    moved = moved || corrected;
    if (!corrected) break;
  }
  if (!moved) return;
  // Velocities follow the corrected positions.
  const double inv_dt = 1.0 / dt;
  for (int i = 0; i < m.n; ++i) s.v[i] += (s.x[i] - w.x_before[i]) * inv_dt;
}

}  // namespace wetcloth::detail
