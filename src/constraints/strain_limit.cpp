// Strain limiting (docs/model.md section 2; Provot 1995, adaptive order after Dochev &
// Vassilev 2003): over-stretched structural and shear springs are shortened back
// to (1 + τ_c) l0, visited outwards from the particles that move first. Each
// correction is an internal force: it is split between the spring's ends in
// inverse proportion to their masses, so it conserves momentum.
#include <algorithm>
#include <bit>
#include <cstring>

#include "detail.hpp"

namespace wetcloth::detail {

namespace {

// Structural and shear springs are the first four offsets of Topology::stencil.
constexpr int kStrainOffsets = 4;

// A mesh cloth's structural or shear spring e (structural first), its end
// that is not k.
int other_end(const Model& m, int e, int k) {
  const auto ns = static_cast<int>(m.structural.size());
  const SpringSet& set = e < ns ? m.structural : m.shear;
  const int i = e < ns ? e : e - ns;
  return set.a[i] == k ? set.b[i] : set.a[i];
}

// Breadth-first grid distance (8-neighbourhood) from the source particles.
void distances_from(const Model& m, const std::vector<int>& sources, State& s, Workspace& w) {
  s.source_distance.assign(m.n, -1);
  w.queue.clear();
  for (int k : sources) {
    if (s.source_distance[k] == 0) continue;
    s.source_distance[k] = 0;
    w.queue.push_back(k);
  }
  if (!m.grid) {  // a mesh cloth: along the structural and shear springs
    for (std::size_t q = 0; q < w.queue.size(); ++q) {
      const int k = w.queue[q];
      for (int e = m.topology->strain_start[k]; e < m.topology->strain_start[k + 1]; ++e) {
        const int kk = other_end(m, m.topology->strain_spring[e], k);
        if (s.source_distance[kk] >= 0) continue;
        s.source_distance[kk] = s.source_distance[k] + 1;
        w.queue.push_back(kk);
      }
    }
    return;
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

// The structural and shear springs' slots, sorted by level (the smaller
// distance of their ends), stable so that a level keeps grid order. A mesh
// cloth's springs are listed once, by slot (their index, structural then
// shear); a grid's are its stencil slots.
void order_springs(const Model& m, const State& s, Workspace& w) {
  w.strain_slots.clear();
  const std::size_t count =
      spring_count(m, SpringKind::Structural) + spring_count(m, SpringKind::Shear);
  w.strain_slots.reserve(count);
  if (!m.grid && w.strain_springs.empty()) {
    w.strain_springs.reserve(count);
    const double stretch = 1.0 + m.params.strain_limit.tau;
    for (const SpringKind kind : {SpringKind::Structural, SpringKind::Shear})
      for_each_spring(m, kind, [&](int a, int b, double rest, double, double) {
        const int slot = static_cast<int>(w.strain_springs.size());
        w.strain_springs.push_back({a, b, stretch * rest, slot});
      });
  }
  if (!m.grid)
    for (std::size_t e = 0; e < w.strain_springs.size(); ++e)
      w.strain_slots.push_back(static_cast<int>(e));
  else
    for (const SpringKind kind : {SpringKind::Structural, SpringKind::Shear})
      for_each_spring(m, kind, [&](int a, int b, double, double, double) {
        // Its stencil slot: the lower end and the forward offset, one of the first four.
        int di = b % m.nu - a % m.nu, dj = b / m.nu - a / m.nu, lower = a;
        if (dj < 0 || (dj == 0 && di < 0)) {
          di = -di;
          dj = -dj;
          lower = b;
        }
        int e = 0;
        while (m.topology->stencil[e].di != di || m.topology->stencil[e].dj != dj) ++e;
        w.strain_slots.push_back(kStrainOffsets * lower + e);
      });
  auto level = [&](int slot) {
    int a, b;
    if (m.grid) {
      const StencilEdge& st = m.topology->stencil[slot % kStrainOffsets];
      a = slot / kStrainOffsets;
      b = a + st.di + st.dj * m.nu;
    } else {
      a = w.strain_springs[slot].a;
      b = w.strain_springs[slot].b;
    }
    return std::min(s.source_distance[a], s.source_distance[b]);
  };
  std::stable_sort(w.strain_slots.begin(), w.strain_slots.end(),
                   [&](int x, int y) { return level(x) < level(y); });
  w.strain_index.assign(m.grid ? kStrainOffsets * std::size_t(m.n) : w.strain_slots.size(), -1);
  for (std::size_t e = 0; e < w.strain_slots.size(); ++e)
    w.strain_index[w.strain_slots[e]] = static_cast<int>(e);
  w.strain_levels.clear();
  for (std::size_t e = 0; e < w.strain_slots.size(); ++e)
    if (e == 0 || level(w.strain_slots[e]) != level(w.strain_slots[e - 1]))
      w.strain_levels.push_back(static_cast<int>(e));
  w.strain_levels.push_back(static_cast<int>(w.strain_slots.size()));
}

}  // namespace

// Sources: the handles' particles; in a scene without handles, the first
// particles to touch an obstacle. Until there are any, every spring is split
// evenly, in grid order.
void update_strain_order(const Model& m, State& s, Workspace& w) {
  if (s.sources_found && !w.strain_slots.empty()) return;
  std::vector<int> sources;
  for (const Handle& h : m.handles)
    sources.insert(sources.end(), h.particles.begin(), h.particles.end());
  if (sources.empty()) {
    const double h_th = m.params.contact.bridge_height;
    for (int i = 0; i < m.n; ++i) {
      const SurfacePoses& at = w.surfaces;  // where the surfaces are now
      const bool near = (m.params.table.enabled &&
                         query_surface(m.params, SurfaceKind::Table, s.x[i]).distance < h_th) ||
                        (m.params.ball.enabled &&
                         query_surface(m.params, at, SurfaceKind::Ball, s.x[i]).distance < h_th) ||
                        std::any_of(m.obstacles.begin(), m.obstacles.end(), [&](const auto& o) {
                          const int k = static_cast<int>(&o - m.obstacles.data());
                          const RigidPose* pose = pose_of(at, kMeshCode + k);
                          const Vec3 x = pose ? pose->to_body(s.x[i]) : Vec3(s.x[i]);
                          // (a search within the bridge alone: the cloth is outside)
                          const MeshObstacle& shape = mesh_of(m, at, k);
                          return shape.query_within(x, h_th + shape.half_thickness).distance < h_th;
                        });
      if (near) sources.push_back(i);
    }
  }
  if (sources.empty()) {
    s.source_distance.assign(m.n, 0);
    if (w.strain_slots.empty()) order_springs(m, s, w);
    return;
  }
  s.sources_found = true;
  distances_from(m, sources, s, w);
  order_springs(m, s, w);
}

// Springs are corrected level by level in the adaptive order; within a level
// (springs at the same distance from the source) every correction is computed
// from the same positions and applied at the end of the level, so that the
// result does not depend on the order of springs within a level, and a
// symmetric cloth stays symmetric.
//
// A correction moves the spring's ends by wa corr and -wb corr, with wa, wb =
// 1/m_a, 1/m_b over their sum: Σ m Δx = 0. Pinned, driven and held particles
// weigh infinitely (the other end takes it all), and the force the correction
// would take to hold them is recorded for their handle (w.strain_reaction).
// Where several springs of a level move one particle, each of them is scaled
// by 1 / (the most springs moving either of its ends), computed before any is
// applied: a relaxation both ends share, so that momentum stays conserved (an
// average per particle would scale each end of a spring differently).
namespace {

// The springs a pass is to look at, a bit each by their order (w.strain_queue,
// zero between passes), taken least first. Every spring queued while a pass
// is taking them comes after the one it took last (it is of a later level,
// though maybe before the least queued), so the search for the least starts
// at the last one taken. (A min-heap of some 400 springs a step, on the pull
// at 51 x 51, had been 2 % of its step, of the limiter's 7.7 %.)
class SpringQueue {
 public:
  explicit SpringQueue(std::vector<std::uint64_t>& bits) : bits_(bits) {}
  void push(int e) {
    std::uint64_t& word = bits_[std::size_t(e) >> 6];
    const std::uint64_t bit = std::uint64_t{1} << (e & 63);
    count_ += (word & bit) == 0;
    word |= bit;
  }
  bool empty() const { return count_ == 0; }
  void restart() { taken_ = 0; }  // a pass's first springs may come before the last one taken
  int front() const {             // the least queued; not empty
    std::size_t word = taken_;
    while (bits_[word] == 0) ++word;
    return static_cast<int>(word * 64) + std::countr_zero(bits_[word]);
  }
  void pop(int e) {
    taken_ = std::size_t(e) >> 6;
    bits_[taken_] &= ~(std::uint64_t{1} << (e & 63));
    --count_;
  }

 private:
  std::vector<std::uint64_t>& bits_;
  int count_ = 0;
  std::size_t taken_ = 0;  // the word of the last spring taken
};

// One call of limit_strain: its passes' queue of springs, the corrections of
// a level and their relaxation.
class StrainLimiter {
 public:
  StrainLimiter(const Model& m, State& s, Workspace& w, double dt)
      : m_(m),
        s_(s),
        w_(w),
        queue_(w.strain_queue),
        touched_(w.strain_touched),
        inv_dt2_(1.0 / (dt * dt)) {
    for (int e = 0; e < kStrainOffsets; ++e) {
      const double l = (1.0 + m.params.strain_limit.tau) * m.topology->stencil[e].rest;
      max_len2_[e] = l * l;
    }
  }

  // The springs a pass looks at: those stretched at its start, and the springs
  // of particles moved since. The first pass finds them in grid order, on
  // every thread (a mesh cloth: in the springs' order); a later one takes
  // those of the pass before and the springs of the particles it moved.
  void queue_pass(int pass) {
    queue_.restart();
    if (pass > 0) {
      for (const int k : w_.strain_moved) queue_springs_of(k, -1);
      for (const int e : w_.strain_over) queue_.push(e);
    } else if (!m_.grid) {
      queue_stretched_mesh();
    } else {
      flag_stretched_grid();
      queue_flagged();
    }
  }
  bool queued() const { return !queue_.empty(); }

  // The queued springs level by level: returns whether any was corrected.
  bool correct_queued() {
    w_.strain_moved.clear();
    w_.strain_over.clear();
    bool corrected = false;  // a pass that corrects nothing ends the passes
    for (int l = 0;;) {
      if (queue_.empty()) {  // the last level's corrections may queue more springs
        if (touched_.empty()) break;
        finish_level(l);
        continue;
      }
      const int e = queue_.front();
      if (e >= level_end(l)) {
        if (!touched_.empty()) {
          finish_level(l);  // may queue springs of the levels before e's
          continue;
        }
        while (e >= level_end(l)) ++l;
      }
      queue_.pop(e);
      corrected = correct(e) || corrected;
    }
    return corrected;
  }

 private:
  const Model& m_;
  State& s_;
  Workspace& w_;
  SpringQueue queue_;          // springs to look at
  std::vector<int>& touched_;  // particles with a correction in this level
  const double inv_dt2_;
  double max_len2_[kStrainOffsets];

  bool fixed(int i) const { return m_.driven[i] || s_.held[i]; }
  int level_end(int l) const { return w_.strain_levels[l + 1]; }

  // Particle k moved: its springs in later levels than l may now be stretched.
  void queue_springs_of(int k, int l) {
    const Model& m = m_;
    if (!m.grid) {
      for (int e = m.topology->strain_start[k]; e < m.topology->strain_start[k + 1]; ++e)
        if (const int order = w_.strain_index[m.topology->strain_spring[e]]; order >= level_end(l))
          queue_.push(order);
      return;
    }
    const int i = k % m.nu, j = k / m.nu;
    for (int e = 0; e < kStrainOffsets; ++e)
      for (const int sign : {1, -1}) {
        const int b = grid_neighbour(m, i, j, sign * m.topology->stencil[e].di,
                                     sign * m.topology->stencil[e].dj);
        if (b < 0) continue;
        const int order = w_.strain_index[kStrainOffsets * (sign > 0 ? k : b) + e];
        if (order >= level_end(l)) queue_.push(order);
      }
  }

  // A mesh cloth's first pass: every stretched spring, in the springs' order.
  void queue_stretched_mesh() {
    for (std::size_t e = 0; e < w_.strain_slots.size(); ++e) {
      const auto& sp = w_.strain_springs[w_.strain_slots[e]];
      if ((s_.x[sp.b] - s_.x[sp.a]).squaredNorm() > sp.max_len * sp.max_len)
        queue_.push(static_cast<int>(e));
    }
  }

  // The grid's first pass: each stencil slot's strain_stretched flag, each
  // thread through its block of rows. Per offset, the block's springs in one
  // run of particles, kRun at a time: the squared lengths in a loop that
  // vectorises, the springs that would run past a row's end (di = ±1, at
  // its last or first column) set to zero, then their largest, and flags
  // only where it is over the limit. (By rows, the largest's reduction
  // after each row of 51 took a fifth of the pass; this pass went from 5.1 %
  // to 3.7 % of the pull's step at 51 x 51.)
  void flag_stretched_grid() {
    const Model& m = m_;
    const State& s = s_;
    Workspace& w = w_;
    const double* max_len2 = max_len2_;
    for_each_row_block(m, [&](int j0, int j1, int) {
      constexpr int kRun = 512;
      // Locals: a byte store could alias the vectors, the model and the bounds.
      const double *X = s.x.column(0), *Y = s.x.column(1), *Z = s.x.column(2);
      const int nu = m.nu, n = m.n;
      std::uint8_t* const flag = w.strain_stretched.data();
      std::fill(flag + kStrainOffsets * std::size_t(j0) * nu,
                flag + kStrainOffsets * std::size_t(j1) * nu, 0);
      for (int e = 0; e < kStrainOffsets; ++e) {
        const StencilEdge& st = m.topology->stencil[e];
        const int off = st.di + st.dj * nu;
        // Springs from rows [j0, j1) that end on the grid; a last one past
        // the grid's end (the last row's, di = 1) left out.
        const int first = j0 * nu, end = std::min(std::min(j1, m.nv - st.dj) * nu, n - off);
        const int wrapped = st.di > 0 ? nu - 1 : 0;  // the column whose spring runs off its row
        const double limit = max_len2[e];
        for (int a0 = first; a0 < end; a0 += kRun) {
          const int count = std::min(kRun, end - a0);
          double len2[kRun], most = 0;
#pragma omp simd
          for (int k = 0; k < count; ++k) {
            const int a = a0 + k;
            const double dx = X[a + off] - X[a], dy = Y[a + off] - Y[a], dz = Z[a + off] - Z[a];
            len2[k] = dx * dx + dy * dy + dz * dz;
          }
          if (st.di != 0)
            for (int k = (wrapped - a0 % nu + nu) % nu; k < count; k += nu) len2[k] = 0;
#pragma omp simd reduction(max : most)
          for (int k = 0; k < count; ++k) most = most > len2[k] ? most : len2[k];
          if (!(most > limit)) continue;  // the flags stay zero: most runs
          for (int k = 0; k < count; ++k) flag[kStrainOffsets * (a0 + k) + e] = len2[k] > limit;
        }
      }
    });
  }

  // The flagged springs in grid order, eight flags at a time: most are zero
  // (a serial pass over four bytes a particle).
  void queue_flagged() {
    const std::uint8_t* const flags = w_.strain_stretched.data();
    const std::size_t slots = w_.strain_stretched.size();
    std::size_t slot = 0;
    for (; slot + 8 <= slots; slot += 8) {
      std::uint64_t eight;
      std::memcpy(&eight, flags + slot, 8);
      if (eight == 0) continue;
      for (std::size_t k = slot; k < slot + 8; ++k)
        if (flags[k]) queue_.push(w_.strain_index[k]);
    }
    for (; slot < slots; ++slot)
      if (flags[slot]) queue_.push(w_.strain_index[slot]);
  }

  // Spring e's correction, if it is stretched and an end can move; returns
  // whether it made one.
  bool correct(int e) {
    const Workspace::StrainSpring sp = strain_spring(m_, w_, e);
    const Vec3 d = s_.x[sp.b] - s_.x[sp.a];
    const double len2 = d.squaredNorm();
    if (len2 <= sp.max_len * sp.max_len) return false;
    // Shares by inverse mass; a pinned, driven or held end weighs infinitely.
    const double inv_a = fixed(sp.a) ? 0.0 : m_.inv_mass[sp.a];
    const double inv_b = fixed(sp.b) ? 0.0 : m_.inv_mass[sp.b];
    if (inv_a + inv_b == 0) return false;  // both held: nothing can move
    w_.strain_over.push_back(e);
    const double wa = inv_a / (inv_a + inv_b), wb = inv_b / (inv_a + inv_b);
    const double len = std::sqrt(len2);
    w_.strain_corrections.push_back({sp.a, sp.b, wa, wb, d * ((len - sp.max_len) / len)});
    if (wa > 0 && w_.strain_count[sp.a]++ == 0) touched_.push_back(sp.a);
    if (wb > 0 && w_.strain_count[sp.b]++ == 0) touched_.push_back(sp.b);
    return true;
  }

  // The force on a pinned, driven or held particle k from holding it against a
  // correction: f, minus the momentum the free end gained over dt².
  void react(int k, const Vec3& f) {
    if (w_.strain_reaction[k] == Vec3::Zero()) w_.strain_reacting.push_back(k);
    add(w_.strain_reaction[k], f);
  }

  // End of level l: each correction, relaxed by the most corrections that move
  // either of its ends, then every moved particle by the sum of its shares.
  void finish_level(int l) {
    Workspace& w = w_;
    for (const auto& c : w.strain_corrections) {
      const int most =
          std::max(c.wa > 0 ? w.strain_count[c.a] : 0, c.wb > 0 ? w.strain_count[c.b] : 0);
      const Vec3 step = c.corr / static_cast<double>(most);
      if (c.wa > 0) add(w.strain_delta[c.a], c.wa * step);
      if (c.wb > 0) sub(w.strain_delta[c.b], c.wb * step);
      // One end held: it takes minus the momentum the other gained.
      if (c.wa == 0) react(c.a, (m_.mass[c.b] * inv_dt2_) * step);
      if (c.wb == 0) react(c.b, -(m_.mass[c.a] * inv_dt2_) * step);
    }
    w.strain_corrections.clear();
    for (const int k : touched_) {
      if (!w.strain_saved[k]) {
        w.strain_saved[k] = 1;
        w.strain_changed.push_back(k);
        w.x_before.push_back(s_.x[k]);
      }
      add(s_.x[k], w.strain_delta[k]);
      put(w.strain_delta[k], Vec3::Zero());
      w.strain_count[k] = 0;
    }
    for (const int k : touched_) queue_springs_of(k, l);
    w.strain_moved.insert(w.strain_moved.end(), touched_.begin(), touched_.end());
    touched_.clear();
  }
};

}  // namespace

void limit_strain(const Model& m, State& s, Workspace& w, double dt) {
  const auto& p = m.params.strain_limit;
  for (const int k : w.strain_reacting) put(w.strain_reaction[k], Vec3::Zero());
  w.strain_reacting.clear();
  if (!p.enabled) return;
  update_strain_order(m, s, w);
  // Where each particle the limiter moves started (in strain_changed's order,
  // not n of them): its velocity follows at the end.
  w.x_before.clear();
  w.strain_saved.resize(m.n, 0);  // zero between calls
  w.strain_changed.clear();
  w.strain_delta.resize(m.n, Vec3::Zero());  // zero between levels
  w.strain_count.resize(m.n, 0);
  w.strain_reaction.resize(m.n, Vec3::Zero());  // zero but for strain_reacting
  w.strain_corrections.clear();
  w.strain_stretched.resize(m.grid ? kStrainOffsets * std::size_t(m.n) : w.strain_slots.size());
  w.strain_queue.resize((w.strain_slots.size() + 63) / 64, 0);  // zero between passes
  // The levels run in order, one after the other, but most springs are not
  // stretched: each pass looks at those that can be, in the order of the levels.
  StrainLimiter limiter(m, s, w, dt);
  for (int pass = 0; pass < p.passes; ++pass) {
    limiter.queue_pass(pass);
    if (!limiter.queued() || !limiter.correct_queued()) break;
  }
  // Velocities follow the corrected positions (only moved particles' change).
  const double inv_dt = 1.0 / dt;
  for (std::size_t q = 0; q < w.strain_changed.size(); ++q) {
    const int k = w.strain_changed[q];
    add(s.v[k], (s.x[k] - w.x_before[q]) * inv_dt);
    w.strain_saved[k] = 0;
  }
}

}  // namespace wetcloth::detail
