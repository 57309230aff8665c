// Strain limiting (MODEL.md section 2; Provot 1995, adaptive order after Dochev &
// Vassilev 2003): over-stretched structural and shear springs are shortened back
// to (1 + τ_c) l0, starting from the particles that move first.
#include <algorithm>

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

// The structural and shear springs, sorted by level (the smaller distance of
// their ends), stable so that a level keeps grid order.
void order_springs(const Model& m, const State& s, Workspace& w) {
  w.strain_springs.clear();
  const double stretch = 1.0 + m.params.strain_limit.tau;
  for (const SpringSet* set : {&m.structural, &m.shear})
    for (std::size_t k = 0; k < set->size(); ++k) {
      const int a = set->a[k], b = set->b[k];
      const int da = s.source_distance[a], db = s.source_distance[b];
      w.strain_springs.push_back({a, b, stretch * set->rest[k], da == db ? 0 : (da < db ? -1 : 1)});
    }
  auto level = [&](const Workspace::StrainSpring& e) {
    return std::min(s.source_distance[e.a], s.source_distance[e.b]);
  };
  std::stable_sort(w.strain_springs.begin(), w.strain_springs.end(),
                   [&](const auto& x, const auto& y) { return level(x) < level(y); });
  w.strain_levels.clear();
  for (std::size_t e = 0; e < w.strain_springs.size(); ++e)
    if (e == 0 || level(w.strain_springs[e]) != level(w.strain_springs[e - 1]))
      w.strain_levels.push_back(static_cast<int>(e));
  w.strain_levels.push_back(static_cast<int>(w.strain_springs.size()));
}

}  // namespace

// Sources: the handles' particles; in a scene without handles, the first
// particles to touch an obstacle. Until there are any, every spring is split
// evenly, in grid order.
void update_strain_order(const Model& m, State& s, Workspace& w) {
  if (s.sources_found && !w.strain_springs.empty()) return;
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
    if (w.strain_springs.empty()) order_springs(m, s, w);
    return;
  }
  s.sources_found = true;
  distances_from(m, sources, s, w);
  order_springs(m, s, w);
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
  w.x_before.resize(m.n);
  for_each_particle(m, [&](int i) { w.x_before[i] = s.x[i]; });
  w.strain_delta.resize(m.n, Vec3::Zero());  // zero between levels
  w.strain_count.resize(m.n, 0);
  const auto& springs = w.strain_springs;
  auto fixed = [&](int i) { return m.driven[i] || s.held[i]; };
  bool moved = false;
  for (int pass = 0; pass < p.passes; ++pass) {
    bool corrected = false;  // a pass that corrects nothing ends the passes
    for (std::size_t l = 0; l + 1 < w.strain_levels.size(); ++l) {
      const int first = w.strain_levels[l], last = w.strain_levels[l + 1];
      bool level_corrected = false;
      for (int e = first; e < last; ++e) {
        const auto& sp = springs[e];
        const Vec3 d = s.x[sp.b] - s.x[sp.a];
        const double len2 = d.squaredNorm();
        if (len2 <= sp.max_len * sp.max_len) continue;
        level_corrected = true;
        // The end farther from the source moves; both halves when neither is
        // nearer; pinned and driven particles never move.
        double wa = sp.nearer == 0 ? 0.5 : (sp.nearer < 0 ? 0.0 : 1.0);
        double wb = 1.0 - wa;
        const bool fixed_a = fixed(sp.a), fixed_b = fixed(sp.b);
        if (fixed_a) {
          wa = 0;
          wb = fixed_b ? 0 : 1;
        }
        if (fixed_b) {
          wb = 0;
          wa = fixed_a ? 0 : 1;
        }
        const double len = std::sqrt(len2);
        const Vec3 corr = d * ((len - sp.max_len) / len);
        if (wa > 0) {
          w.strain_delta[sp.a] += wa * corr;
          ++w.strain_count[sp.a];
        }
        if (wb > 0) {
          w.strain_delta[sp.b] -= wb * corr;
          ++w.strain_count[sp.b];
        }
      }
      if (!level_corrected) continue;
      corrected = true;
      for (int e = first; e < last; ++e)
        for (const int k : {springs[e].a, springs[e].b}) {
          if (w.strain_count[k] == 0) continue;
          s.x[k] += w.strain_delta[k] / w.strain_count[k];
          w.strain_delta[k].setZero();
          w.strain_count[k] = 0;
        }
    }
    moved = moved || corrected;
    if (!corrected) break;
  }
  if (!moved) return;
  // Velocities follow the corrected positions.
  const double inv_dt = 1.0 / dt;
  for_each_particle(m, [&](int i) { s.v[i] += (s.x[i] - w.x_before[i]) * inv_dt; });
}

}  // namespace wetcloth::detail
