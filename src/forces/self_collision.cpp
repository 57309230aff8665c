// Self-collision (MODEL.md section 7, eq. 15): repulsion springs between particles
// closer than d_t that are not within two grid steps, found with a spatial hash.
#include <algorithm>
#include <cmath>
#include <cstdlib>

#include "../detail.hpp"
#include "../spatial_hash.hpp"

namespace wetcloth::detail {

void add_self_collision(const Model& m, const State& s, Workspace& w, bool with_damping) {
  const auto& p = m.params.self_collision;
  if (!p.enabled) return;
  const double dt_dist = p.distance, k = p.k;
  // Candidate pairs (a Verlet list): every pair within d_t + margin, rebuilt
  // with the hash only once some particle has moved margin/2 since the last
  // build. Until then no pair can have come within d_t unlisted, and a flat or
  // slowly moving cloth skips the hash for hundreds of steps.
  // The margin is at most 1.5 grid steps: on a fine grid half of d_t spans
  // many steps, and a flat cloth would list every particle's whole ring of
  // grid neighbours just past the excluded ones (360 B a particle at 401 x 401).
  const double step =
      std::min(m.params.cloth.size[0] / (m.nu - 1), m.params.cloth.size[1] / (m.nv - 1));
  const double margin = std::min(0.5 * dt_dist, 1.5 * step);
  bool rebuild =
      w.candidates_radius != dt_dist + margin || w.candidates_anchor.size() != s.x.size();
  if (!rebuild)
    rebuild = max_over_particles(m, [&](int i) {
                return (s.x[i] - w.candidates_anchor[i]).squaredNorm();
              }) > 0.25 * margin * margin;
  if (rebuild) {
    // Grid neighbours never collide: within two grid steps (MODEL.md), or more
    // on a grid fine enough that d_t spans more steps, else a flat cloth would
    // repel itself.
    const int nu = m.nu;
    const int reach = std::max(2, static_cast<int>(std::ceil(dt_dist / step)));
    auto near_in_grid = [nu, reach](int i, int j) {
      return std::abs(i % nu - j % nu) <= reach && std::abs(i / nu - j / nu) <= reach;
    };
    w.candidates_radius = dt_dist + margin;
    build_hash(s.x, 2 * w.candidates_radius, w);
    // The search, the costly part, by blocks of rows on the step's threads;
    // the blocks' lists joined in order are the list one thread would make.
    w.thread_candidates.resize(m.threads);
    for (auto& list : w.thread_candidates) list.clear();  // the runtime may give fewer threads
    for_each_row_block(m, [&](int j0, int j1, int t) {
      auto& list = w.thread_candidates[t];
      for_each_close_pair(
          s.x, w.candidates_radius, w, near_in_grid,
          [&](int i, int j, const Vec3&, double) {
            list.push_back({i, j});
          },
          j0 * nu, j1 * nu);
    });
    w.candidates.clear();
    for (const auto& list : w.thread_candidates)
      w.candidates.insert(w.candidates.end(), list.begin(), list.end());
    w.candidates_anchor = s.x;
  }
  auto& colliding = w.colliding;
  std::fill(colliding.begin(), colliding.end(), 0);
  w.collision_pairs.clear();
  // Which candidates are within d_t, in parallel; then the few that are, in order.
  const int count = static_cast<int>(w.candidates.size());
  w.candidate_close.resize(count);
  parallel_for(m, count, [&](int c) {
    const double len2 = (s.x[w.candidates[c][0]] - s.x[w.candidates[c][1]]).squaredNorm();
    w.candidate_close[c] = len2 < dt_dist * dt_dist && len2 != 0;
  });
  for (int c = 0; c < count; ++c) {
    if (!w.candidate_close[c]) continue;
    const auto [i, j] = w.candidates[c];
    const Vec3 d = s.x[i] - s.x[j];
    const double len = std::sqrt(d.squaredNorm());
    // eq. 15: F_i = k_t (d_t - |d_ij|) d_ij / |d_ij|, F_j = -F_i
    const Vec3 fi = (k * (dt_dist - len) / len) * d;
    w.force[i] += fi;
    w.force[j] -= fi;
    colliding[i] = colliding[j] = 1;
    w.collision_pairs.push_back({i, j, d / len, {}});
  }
  if (!with_damping) return;  // implicit Euler takes it into its matrix
  // The paper's friction-like damping -k_f v on every colliding particle.
  for_each_particle(m, [&](int i) {
    if (colliding[i]) w.force[i] -= p.damping * s.v[i];
  });
}

}  // namespace wetcloth::detail
