// A spatial hash over particles (Teschner et al. 2003), built by counting sort so
// that the order of pairs, and so the sums, are deterministic.
#pragma once

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <vector>

#include "wetcloth/simulation.hpp"

namespace wetcloth::detail {

// In unsigned arithmetic: the products of a blown-up cloth's cells (1e16)
// wrap, where signed ones overflowed (undefined; the sanitizer build's find).
inline std::uint32_t hash_cell(long long ix, long long iy, long long iz, std::uint32_t mask) {
  const std::uint64_t h = static_cast<std::uint64_t>(ix) * 73856093ULL ^
                          static_cast<std::uint64_t>(iy) * 19349663ULL ^
                          static_cast<std::uint64_t>(iz) * 83492791ULL;
  return static_cast<std::uint32_t>(h) & mask;
}

// The cell of a coordinate (in cells): floor, as a whole number. Beyond
// ±2^63 (a blown-up cloth) and for NaN, llround's answer, as before; the
// cast within it is the same number and is inlined.
inline long long cell_of(double v) {
  const double f = std::floor(v);
  return std::abs(f) < 9.2e18 ? static_cast<long long>(f) : std::llround(f);
}

// Sorts particles into buckets of cubic cells of side `cell`; the cells are
// found on `threads` threads, the counting sort is in particle order. Points
// x are a Vec3Array or a std::vector<Vec3>. The buckets are twice the cells
// expected to hold a particle (`cells`, at most one a particle): a table of
// two a particle was most of a build, and missed the cache in each search
// (each bucket holds a cloth's patch of cell² area).
template <class Points>
void build_hash(const Points& x, double cell, Workspace& w, int threads = 1,
                std::size_t cells = 0) {
  const int n = static_cast<int>(x.size());
  if (cells == 0 || cells > std::size_t(n)) cells = n;
  std::size_t size = 1;
  while (size < 2 * cells) size <<= 1;
  const auto mask = static_cast<std::uint32_t>(size - 1);
  w.hash_cell = cell;
  w.cell_start.assign(size + 1, 0);
  w.cell_entries.resize(n);
  w.particle_cell.resize(n);
  const auto bucket = [&](int i) {
    return static_cast<int>(hash_cell(cell_of(x[i].x() / cell), cell_of(x[i].y() / cell),
                                      cell_of(x[i].z() / cell), mask));
  };
  if (threads > 1) {
#pragma omp parallel for schedule(static) num_threads(threads)
    for (int i = 0; i < n; ++i) w.particle_cell[i] = bucket(i);
  } else {
    for (int i = 0; i < n; ++i) w.particle_cell[i] = bucket(i);
  }
  for (int i = 0; i < n; ++i) ++w.cell_start[w.particle_cell[i] + 1];
  for (std::size_t c = 0; c < size; ++c) w.cell_start[c + 1] += w.cell_start[c];
  std::vector<int>& fill = w.queue;  // reuse as a cursor per bucket
  fill.assign(w.cell_start.begin(), w.cell_start.end() - 1);
  for (int i = 0; i < n; ++i) w.cell_entries[fill[w.particle_cell[i]]++] = i;
}

// Points as three columns of doubles, `stride` apart from point to point: a
// gather loop over them vectorises.
struct PointColumns {
  const double *x, *y, *z;
  int stride;
};
inline PointColumns columns_of(const Vec3Array& p) {
  return {p.column(0), p.column(1), p.column(2), 1};
}
inline PointColumns columns_of(const std::vector<Vec3>& p) {
  const double* d = p.empty() ? nullptr : p.data()->data();
  return {d, d + 1, d + 2, 3};
}

// The cells a search of `radius` around y visits, lo to lo + span on each axis:
// those the ball meets. The hash's cells are at least the radius: 2 or 3 a
// side (4 where a rounding crosses a face). At most 3 past the first: past
// 2^53 cells (a blown-up cloth at 1e14 m, stopped after the step) doubles
// skip whole cells, and the last had fallen 4 past the first, overrunning
// the search's list of buckets. (Unsigned: no overflow.)
inline NearSearch cells_around(const Vec3& y, double radius, double cell, int query) {
  NearSearch search{};
  for (int k = 0; k < 3; ++k) {
    const long long from = cell_of((y[k] - radius) / cell);
    const long long to = cell_of((y[k] + radius) / cell);
    search.lo[k] = from;
    const unsigned long long span =
        static_cast<unsigned long long>(to) - static_cast<unsigned long long>(from);
    search.span[k] = static_cast<std::uint8_t>(std::min(span, 3ULL));
  }
  search.query = query;
  return search;
}

// Grid neighbours a search leaves out in its vectorised pass: particles
// within `reach` rows and columns of each other on a grid of nu columns
// (reach < 0: none). A row is found by a multiplication, not a division (two
// a pair were a fifth of a search): (i + 1/2) / nu lies at least 1 / (2 nu)
// from a whole number, which the product's rounding, below 1e-11 for any
// cloth that fits in memory, cannot cross.
struct GridNear {
  int nu = 1, reach = -1;
  double inv_nu = 1.0;
  GridNear() = default;
  GridNear(int columns, int steps) : nu(columns), reach(steps), inv_nu(1.0 / columns) {}
  int row(int i) const { return static_cast<int>((i + 0.5) * inv_nu); }
  bool operator()(int i, int j) const {
    const int vi = row(i), vj = row(j);
    return std::abs(vi - vj) <= reach && std::abs((i - vi * nu) - (j - vj * nu)) <= reach;
  }
};

// The searches of the points y[i], i in `queries`, with the cells each
// visits, sorted by those cells: searches that visit the same share one
// gather of their entries (for_each_near).
template <class Points, class Queries>
void plan_searches(const Points& y, const Queries& queries, double radius, const Workspace& w,
                   std::vector<NearSearch>& plan) {
  plan.clear();
  for (const int i : queries) plan.push_back(cells_around(y[i], radius, w.hash_cell, i));
  std::sort(plan.begin(), plan.end());
}

// Calls fn(i, j, |d|²) with d = y - x_j for each of the `count` points x_j
// (particles j) gathered in s with 0 < |d|² < r2, j > after, and not near(i,
// j), in their order. One vectorised pass with no branch (& for &&) finds
// them; the few it keeps are then given.
template <class Fn>
void test_gathered(NearScratch& s, int count, const Vec3& y, int i, double r2, int after,
                   const GridNear& near, Fn& fn) {
  const double yx = y.x(), yy = y.y(), yz = y.z();
  const double *gx = s.x.data(), *gy = s.y.data(), *gz = s.z.data();
  const int* gj = s.index.data();
  double* len2 = s.len2.data();
  std::uint8_t* keep = s.keep.data();
  const int nu = near.nu, reach = near.reach, vi = near.row(i), ui = i - vi * nu;
  const double inv_nu = near.inv_nu;
#pragma omp simd
  for (int e = 0; e < count; ++e) {
    const double dx = yx - gx[e], dy = yy - gy[e], dz = yz - gz[e];
    const double l2 = dx * dx + dy * dy + dz * dz;
    const int j = gj[e], vj = static_cast<int>((j + 0.5) * inv_nu), uj = j - vj * nu;
    const bool grid_near = (std::abs(vj - vi) <= reach) & (std::abs(uj - ui) <= reach);
    len2[e] = l2;
    keep[e] = (l2 < r2) & (l2 != 0) & (j > after) & !grid_near;
  }
  for (int e = count; e % 8 != 0; ++e) keep[e] = 0;
  for (int e = 0; e < count; e += 8) {  // eight flags a word: most are all zero
    std::uint64_t flags;
    std::memcpy(&flags, keep + e, 8);
    for (; flags != 0; flags &= flags - 1) {  // a flag is a byte's lowest bit
      const int k = e + std::countr_zero(flags) / 8;
      fn(i, gj[k], len2[k]);
    }
  }
}

// Calls fn(i, j, |d|²) with d = y[i] - x[j], for the searches plan[first,
// last) (plan_searches) and every particle j of the hash with 0 < |d| <
// radius, j > i if only_after, and not near(i, j): j = i and points that
// coincide are never given. A particle within the radius is in a cell the
// search visits, so in one of those cells' buckets, each gathered once; one
// of another cell that shares a bucket is beyond the radius. The gathered
// points are tested in one vectorised pass a search (test_gathered; the
// searches' costs: docs/performance.md, nineteenth stop). Around a cloth, a
// surface, cells of the radius hold about half the particles of cells of
// twice it, and the buckets need no cell's coordinates (seventeenth stop).
template <class Points, class Fn>
void for_each_near(const Points& y, double radius, const Workspace& w, NearScratch& s,
                   const std::vector<NearSearch>& plan, std::size_t first, std::size_t last,
                   bool only_after, const GridNear& near, Fn fn) {
  const auto mask = static_cast<std::uint32_t>(w.cell_start.size() - 2);
  const double r2 = radius * radius;
  if (!(w.hash_cell >= radius))
    throw std::logic_error("spatial hash: cells smaller than the radius");
  const PointColumns p = columns_of(y);
  const NearSearch* gathered = nullptr;
  int count = 0;
  for (std::size_t q = first; q < last; ++q) {
    const NearSearch& search = plan[q];
    if (!gathered || !search.same_cells(*gathered)) {  // gather the cells' entries
      std::uint32_t seen[64];
      std::uint64_t seen_bits = 0;
      int buckets = 0;
      count = 0;
      const auto& lo = search.lo;
      const auto& span = search.span;
      for (long long oz = lo[2]; oz <= lo[2] + span[2]; ++oz)
        for (long long oy = lo[1]; oy <= lo[1] + span[1]; ++oy)
          for (long long ox = lo[0]; ox <= lo[0] + span[0]; ++ox) {
            const std::uint32_t c = hash_cell(ox, oy, oz, mask);
            // A bucket's bit among 64: only one whose bit is set may have
            // been seen (27 buckets: most are not looked for in the list).
            const std::uint64_t bit = std::uint64_t{1} << (c & 63);
            if ((seen_bits & bit) && std::find(seen, seen + buckets, c) != seen + buckets) continue;
            seen_bits |= bit;
            seen[buckets++] = c;
            const int from = w.cell_start[c], to = w.cell_start[c + 1];
            if (from == to) continue;  // most cells around a surface are empty
            s.make_room(count + (to - from));
            const int* entries = w.cell_entries.data() + from;
            int* index = s.index.data() + count;
            double *gx = s.x.data() + count, *gy = s.y.data() + count, *gz = s.z.data() + count;
            const int stride = p.stride;
#pragma omp simd
            for (int k = 0; k < to - from; ++k) {
              const int j = entries[k];
              index[k] = j;
              gx[k] = p.x[j * stride];
              gy[k] = p.y[j * stride];
              gz[k] = p.z[j * stride];
            }
            count += to - from;
          }
      gathered = &search;
    }
    const int i = search.query;
    test_gathered(s, count, y[i], i, r2, only_after ? i : -1, near, fn);
  }
}

// Calls fn(i, j, |d|²) once for every pair i < j closer than `radius` that
// near(i, j) does not exclude (and whose points do not coincide).
template <class Points, class Fn>
void for_each_close_pair(const Points& x, double radius, const Workspace& w, NearScratch& s,
                         const GridNear& near, Fn fn) {
  std::vector<NearSearch> plan;
  plan_searches(x, w.cell_entries, radius, w, plan);
  for_each_near(x, radius, w, s, plan, 0, plan.size(), true, near, fn);
}

}  // namespace wetcloth::detail
