// Self-collision (docs/model.md section 7, eq. 15): repulsion springs between particles
// closer than d_t that are not within two grid steps, found with a spatial hash.
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <cstdlib>

#include "detail.hpp"
#include "geometry/spatial_hash.hpp"

namespace wetcloth::detail {

namespace {

// The cloth's rigid motion since its anchors, x ≈ R a + c.
struct RigidMotion {
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Vec3 shift = Vec3::Zero();
};

// Squared distance of particle i from its anchor moved by the cloth's rigid
// motion (by columns, pointers taken once, so that a loop over i vectorises).
struct AnchorGap {
  const double *x, *y, *z, *ax, *ay, *az;
  double r[3][3], c[3];
  AnchorGap(const Vec3Array& p, const Vec3Array& anchor, const RigidMotion& motion)
      : x(p.column(0)),
        y(p.column(1)),
        z(p.column(2)),
        ax(anchor.column(0)),
        ay(anchor.column(1)),
        az(anchor.column(2)) {
    for (int k = 0; k < 3; ++k) {
      for (int l = 0; l < 3; ++l) r[k][l] = motion.rotation(k, l);
      c[k] = motion.shift[k];
    }
  }
  double operator()(int i) const {
    const double dx = x[i] - (r[0][0] * ax[i] + r[0][1] * ay[i] + r[0][2] * az[i] + c[0]);
    const double dy = y[i] - (r[1][0] * ax[i] + r[1][1] * ay[i] + r[1][2] * az[i] + c[1]);
    const double dz = z[i] - (r[2][0] * ax[i] + r[2][1] * ay[i] + r[2][2] * az[i] + c[2]);
    return dx * dx + dy * dy + dz * dz;
  }
};

// The cloth's rigid motion since its anchors, fitted by least squares
// (Kabsch's rotation of the centred points) on a fixed sample of some 256
// particles, in a fixed order: the same on any number of threads. A pair's
// distance is kept by any rigid motion, so the list stays exact whatever the
// fit; a good one follows a cloth that swings about its pins or tumbles as it
// falls, where the mean translation alone left a hundred particles to be
// searched again every substep (hang, 51 x 51).
// The last refresh's motion is kept while it carries the sample's anchors'
// mean to within `keep` of the sample's mean now (a cloth lying on its
// surface: no fit a step); the list is exact with any motion, and the pairs
// the step uses, those within d_t in the list's order, are the same bits.
RigidMotion rigid_motion(const Model& m, const Vec3Array& p, const Vec3Array& anchor,
                         const RigidMotion& last, double keep) {
  const int stride = std::max(1, m.n / 256);
  Vec3 mean_a = Vec3::Zero(), mean_x = Vec3::Zero();
  int count = 0;
  for (int i = 0; i < m.n; i += stride, ++count) {
    mean_a += anchor[i];
    mean_x += p[i];
  }
  mean_a /= count;
  mean_x /= count;
  if ((last.rotation * mean_a + last.shift - mean_x).squaredNorm() <= keep * keep) return last;
  Eigen::Matrix3d h = Eigen::Matrix3d::Zero();
  for (int i = 0; i < m.n; i += stride) h += (anchor[i] - mean_a) * (p[i] - mean_x).transpose();
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(h, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
  if ((svd.matrixV() * svd.matrixU().transpose()).determinant() < 0) d(2, 2) = -1;  // no mirror
  RigidMotion motion{svd.matrixV() * d * svd.matrixU().transpose(), Vec3::Zero()};
  motion.shift = mean_x - motion.rotation * mean_a;
  if (!motion.rotation.allFinite() || !motion.shift.allFinite()) return {};  // blowing up
  return motion;
}

// The largest of them in row j: a maximum over columns, which vectorises
// (and is the same in any order).
double row_most(const Model& m, const AnchorGap& gap, int j) {
  const AnchorGap local = gap;  // a copy: through the reference GCC gathered
  double row = 0;
#pragma omp simd reduction(max : row)
  for (int i = j * m.nu; i < (j + 1) * m.nu; ++i) row = std::max(row, local(i));
  return row;
}

// The particles farther than far2 (squared) from their anchors moved by c,
// in their order: looked for in the rows whose largest gap is, alone,
// where every particle was scanned one by one.
void find_movers(const Model& m, const AnchorGap& gap, double far2, std::vector<int>& movers) {
  for (int j = 0; j < m.nv; ++j)
    if (row_most(m, gap, j) > far2)
      for (int i = j * m.nu; i < (j + 1) * m.nu; ++i)
        if (gap(i) > far2) movers.push_back(i);
}

// The largest of them over the cloth, by rows on the step's threads.
double farthest(const Model& m, const AnchorGap& gap) {
  const auto row_most = [&](int j) { return detail::row_most(m, gap, j); };
  double most = 0;
  if (m.threads <= 1) {  // no region: even one its `if` turns off costs a futex call
    for (int j = 0; j < m.nv; ++j) most = std::max(most, row_most(j));
    return most;
  }
#pragma omp parallel for reduction(max : most) num_threads(m.threads)
  for (int j = 0; j < m.nv; ++j) most = std::max(most, row_most(j));
  return most;
}

// Grid neighbours never collide: within `reach` grid steps, which the
// search leaves out itself (GridNear); a mesh cloth's particles, within its
// own reach along the springs (Topology::ring).
struct NearOnCloth {
  GridNear grid;    // reach -1 on a mesh cloth
  const int* ring;  // null on a grid
  const int* ring_start;
  bool operator()(int i, int j) const {
    if (ring) return std::binary_search(ring + ring_start[i], ring + ring_start[i + 1], j);
    return grid(i, j);
  }
};

// The cells of side `cell` a cloth's surface crosses, about: its area, n
// spacing², over a cell's, times up to √3 for a plane at a slant (2 here).
std::size_t crossed_cells(const Model& m, double cell) {
  const double per_particle = std::min(1.0, 2 * m.spacing * m.spacing / (cell * cell));
  return static_cast<std::size_t>(std::ceil(m.n * per_particle));
}

// Forgets which particles were anchored again since the hash was built.
void clear_stale(Workspace& w) {
  for (const int i : w.hash_stale) w.hash_stale_flag[i] = 0;
  w.hash_stale.clear();
}

// Every particle anchored where it is and the whole cloth searched, the
// searches shared between the step's threads.
void search_whole_cloth(const Model& m, const State& s, Workspace& w, double radius,
                        const NearOnCloth& near) {
  auto& anchor = w.candidates_anchor;
  w.candidates_radius = radius;
  anchor = s.x;
  w.candidates_rotation = Eigen::Matrix3d::Identity();
  w.candidates_motion = Vec3::Zero();
  build_hash(anchor, radius, w, m.threads, crossed_cells(m, radius));
  clear_stale(w);
  auto& plan = w.near_plan;
  plan_searches(anchor, w.cell_entries, radius, w, plan);
  w.near_scratch.resize(std::max(1, m.threads));
  const auto search = [&](std::size_t first, std::size_t last, int t, auto& list) {
    for_each_near(anchor, radius, w, w.near_scratch[t], plan, first, last, true, near.grid,
                  [&](int i, int j, double) {
                    if (!near(i, j)) list.push_back({i, j});
                  });
  };
  if (m.threads <= 1) {  // straight into the list: no second copy of the pairs
    w.candidates.clear();
    search(0, plan.size(), 0, w.candidates);
    std::sort(w.candidates.begin(), w.candidates.end());
    return;
  }
  w.thread_candidates.resize(m.threads);
  for (auto& list : w.thread_candidates) list.clear();  // the runtime may give fewer threads
  for_each_row_block(m, [&](int j0, int j1, int t) {
    const std::size_t count = plan.size();
    search(count * j0 / m.nv, count * j1 / m.nv, t, w.thread_candidates[t]);
  });
  w.candidates.clear();
  for (const auto& list : w.thread_candidates)
    w.candidates.insert(w.candidates.end(), list.begin(), list.end());
  std::sort(w.candidates.begin(), w.candidates.end());
}

// The hash is not built again for a few movers (a pulled handle moves a few
// particles every other step, and a build costs a pass over the cloth): a
// mover finds through it the particles it holds where they are, and the
// stale ones (anchored again since) and the other movers in a list of their
// own. Once those are many, it is built again. The pairs are the same either
// way (but for a pair at the radius itself, which the rounding of a sum may
// tip: one that is never within d_t). take(i, j, len2) is given each pair
// within the radius, the grid's neighbours left out.
template <class Take>
void find_mover_pairs(const Model& m, Workspace& w, double radius, const GridNear& grid,
                      Take&& take) {
  const auto& anchor = w.candidates_anchor;
  const auto& movers = w.candidate_movers;
  const auto& moved = w.candidate_moved;
  auto& stale = w.hash_stale;
  auto& is_stale = w.hash_stale_flag;
  constexpr std::size_t kMostStale = 256;
  const bool build = stale.size() + movers.size() > kMostStale;
  if (build) {
    build_hash(anchor, radius, w, m.threads, crossed_cells(m, radius));
    clear_stale(w);
  }
  // A pair of movers is found from both: taken from the first.
  const auto take_once = [&](int i, int j, double len2) {
    if (!(moved[j] && j < i)) take(i, j, len2);
  };
  plan_searches(anchor, movers, radius, w, w.near_plan);
  w.near_scratch.resize(std::max<std::size_t>(1, w.near_scratch.size()));
  auto& scratch = w.near_scratch[0];
  for_each_near(anchor, radius, w, scratch, w.near_plan, 0, w.near_plan.size(), false, grid,
                [&](int i, int j, double len2) {
                  if (build)
                    take_once(i, j, len2);
                  else if (!moved[j] && !is_stale[j])  // where the hash has them
                    take(i, j, len2);
                });
  if (build) return;
  // The stale particles and the movers, where they are now: gathered once,
  // tested against each mover.
  int count = 0;
  scratch.make_room(static_cast<int>(stale.size() + movers.size()));
  const auto gather = [&](int j) {
    scratch.index[count] = j;
    scratch.x[count] = anchor[j].x();
    scratch.y[count] = anchor[j].y();
    scratch.z[count] = anchor[j].z();
    ++count;
  };
  for (const int j : stale)
    if (!moved[j]) gather(j);
  for (const int j : movers) gather(j);
  for (const int i : movers)
    test_gathered(scratch, count, anchor[i], i, radius * radius, -1, grid, take_once);
  stale.reserve(kMostStale);  // never more: no allocation once warm
  for (const int i : movers)
    if (!is_stale[i]) {
      is_stale[i] = 1;
      stale.push_back(i);
    }
}

// The movers' pairs, dropped and searched again from their new anchors.
// Their flags are set here and cleared at the end: no pass over the cloth.
void search_movers_again(const Model& m, const State& s, Workspace& w, double radius,
                         const NearOnCloth& near, const RigidMotion& motion) {
  auto& anchor = w.candidates_anchor;
  const auto& movers = w.candidate_movers;
  auto& moved = w.candidate_moved;
  auto& list = w.candidates;
  moved.resize(m.n, 0);
  for (int i : movers) {
    moved[i] = 1;
    anchor[i] = motion.rotation.transpose() * (s.x[i] - motion.shift);
  }
  // The rest stays sorted; the new pairs are sorted alone and merged in:
  // a flat cloth at 401 x 401 lists a million pairs, too many to sort again.
  std::erase_if(list, [&](const auto& c) { return moved[c[0]] || moved[c[1]]; });
  const auto kept = static_cast<std::ptrdiff_t>(list.size());
  find_mover_pairs(m, w, radius, near.grid, [&](int i, int j, double len2) {
    if (len2 == 0 || near(i, j)) return;
    list.push_back({std::min(i, j), std::max(i, j)});
  });
  for (int i : movers) moved[i] = 0;
  std::sort(list.begin() + kept, list.end());
  // Merged in place from the back, the new pairs copied aside (they are few:
  // a second list of all of them would be 50 B a particle at 401 x 401).
  auto& added = w.candidates_merged;  // a scratch list: no allocation once warm
  added.assign(list.begin() + kept, list.end());
  auto out = list.end(), old = list.begin() + kept;
  for (auto fresh = added.end(); fresh != added.begin();) {
    --out;  // the larger of the two lists' last, a tie the new one's (as std::merge)
    if (old != list.begin() && fresh[-1] < old[-1])
      *out = *--old;
    else
      *out = *--fresh;
  }
}

}  // namespace

void refresh_collision_candidates(const Model& m, const State& s, Workspace& w) {
  const auto& p = m.params.self_collision;
  const double dt_dist = p.distance;
  // Candidate pairs (a Verlet list): every pair whose anchors, the positions
  // where each particle was last searched from, are within R = d_t + margin.
  // While no particle is farther than margin/2 from its anchor, no pair off
  // the list can have come within d_t. One that moves farther is searched
  // again from where it is, against the others' anchors; only when many have
  // moved is the whole cloth searched again. So a flat or slowly moving cloth
  // skips the hash for hundreds of steps, and a pulled handle costs a search
  // around the handle, not of the cloth. Sorted, the list depends on the
  // anchors alone, not on how or on how many threads it was made.
  const double step = m.spacing;
  // Grid neighbours never collide: within two grid steps (docs/model.md section 7), or more
  // on a grid fine enough that d_t spans more steps, else a flat cloth would
  // repel itself.
  const int reach = std::max(2, static_cast<int>(std::ceil(dt_dist / step)));
  // The margin: the larger it is, the less often a particle is searched
  // again (a swinging cloth's, every substep), and the more pairs the list
  // holds. Up to d_t, as long as a flat cloth lists no pair: its nearest
  // ones past the excluded ring are (reach + 1) steps apart (at 51 x 51, a
  // margin of d_t rather than d_t / 2 took hang in xpbd to 0.95 of its
  // time). Never below the old min(d_t / 2, 1.5 steps): on a fine grid that
  // lists the ring just past the excluded one (360 B a particle at 401 x 401).
  const double flat_room = 0.9 * ((reach + 1) * step - dt_dist);
  const double margin =
      std::max(std::min(0.5 * dt_dist, 1.5 * step), std::min({dt_dist, 1.5 * step, flat_room}));
  const double radius = dt_dist + margin;
  const NearOnCloth near{m.grid ? GridNear(m.nu, reach) : GridNear(),
                         m.grid ? nullptr : m.topology->ring.data(), m.topology->ring_start.data()};
  const auto& anchor = w.candidates_anchor;
  auto& movers = w.candidate_movers;
  movers.clear();
  bool search_all = w.candidates_radius != radius || anchor.size() != s.x.size();
  // A pair's distance does not change when both particles move by the same
  // rigid motion: each is measured from its anchor moved by the cloth's
  // (x_i = R a_i + c + g_i with every |g_i| <= margin / 2 keeps a pair off
  // the list at least d_t apart). A falling, sliding or swinging cloth then
  // keeps its list; the pairs, and so the results, are the same bits either way.
  const double far2 = 0.25 * margin * margin;
  const RigidMotion motion =
      search_all ? RigidMotion{}
                 : rigid_motion(m, s.x, anchor, {w.candidates_rotation, w.candidates_motion},
                                0.125 * margin);
  w.candidates_rotation = motion.rotation;
  w.candidates_motion = motion.shift;
  const AnchorGap gap(s.x, anchor, motion);
  // On one thread the rows' largest gaps are found once, the movers with
  // them; on more, the largest over the cloth first, on the threads.
  if (!search_all && (m.threads <= 1 || farthest(m, gap) > far2)) {
    find_movers(m, gap, far2, movers);
    search_all = 4 * movers.size() > std::size_t(m.n);
  }
  w.hash_stale_flag.resize(m.n, 0);
  if (search_all)
    search_whole_cloth(m, s, w, radius, near);
  else if (!movers.empty())
    search_movers_again(m, s, w, radius, near, motion);
}

void add_self_collision(const Model& m, const State& s, Workspace& w, bool with_damping) {
  const auto& p = m.params.self_collision;
  if (!p.enabled) return;
  const auto [k, damping] = collision_constants(m);
  const double dt_dist = p.distance;
  refresh_collision_candidates(m, s, w);
  // Flags of colliding particles: last step's cleared through last step's
  // pairs, not over the whole cloth.
  auto& colliding = w.colliding;
  for (const CollisionPair& c : w.collision_pairs) colliding[c.i] = colliding[c.j] = 0;
  w.collision_pairs.clear();
  w.colliding_particles.clear();
  // Which candidates are within d_t, in parallel; then the few that are, in
  // order. A parallel region costs about 1.25 µs and a candidate about 1 ns:
  // fewer than 4 096 (none, on a flat or tented cloth) on this thread.
  const int count = static_cast<int>(w.candidates.size());
  w.candidate_close.resize(count);
  const auto close = [&](int c) {
    const double len2 = (s.x[w.candidates[c][0]] - s.x[w.candidates[c][1]]).squaredNorm();
    w.candidate_close[c] = len2 < dt_dist * dt_dist && len2 != 0;
  };
  if (count >= 4096)
    parallel_for(m, count, close);
  else
    for (int c = 0; c < count; ++c) close(c);
  for (int c = 0; c < count; ++c) {
    if (!w.candidate_close[c]) continue;
    const auto [i, j] = w.candidates[c];
    const Vec3 d = s.x[i] - s.x[j];
    const double len = std::sqrt(d.squaredNorm());
    // eq. 15: F_i = k_t (d_t - |d_ij|) d_ij / |d_ij|, F_j = -F_i
    const Vec3 fi = (k * (dt_dist - len) / len) * d;
    w.force[i] += fi;
    w.force[j] -= fi;
    for (const int q : {i, j})
      if (!colliding[q]) {
        colliding[q] = 1;
        w.colliding_particles.push_back(q);
      }
    w.collision_pairs.push_back({i, j, d / len, {}});
  }
  if (!with_damping) return;  // implicit Euler takes it into its matrix
  // The paper's friction-like damping -k_f v on every colliding particle, once.
  for (const int q : w.colliding_particles) w.force[q] -= damping * s.v[q];
}

}  // namespace wetcloth::detail
