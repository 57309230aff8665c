// A spatial hash over particles (Teschner et al. 2003), built by counting sort so
// that the order of pairs, and so the sums, are deterministic.
#pragma once

#include <cmath>
#include <cstdint>

#include "wetcloth/simulation.hpp"

namespace wetcloth::detail {

inline std::uint32_t hash_cell(long long ix, long long iy, long long iz, std::uint32_t mask) {
  const auto h = static_cast<std::uint64_t>(ix * 73856093LL) ^
                 static_cast<std::uint64_t>(iy * 19349663LL) ^
                 static_cast<std::uint64_t>(iz * 83492791LL);
  return static_cast<std::uint32_t>(h) & mask;
}

// Sorts particles into buckets of cubic cells of side `cell`; the cells are
// found on `threads` threads, the counting sort is in particle order. Points
// x are a Vec3Array or a std::vector<Vec3>.
template <class Points>
void build_hash(const Points& x, double cell, Workspace& w, int threads = 1) {
  const int n = static_cast<int>(x.size());
  std::size_t size = 1;
  while (size < 2 * std::size_t(n)) size <<= 1;
  const auto mask = static_cast<std::uint32_t>(size - 1);
  w.cell_start.assign(size + 1, 0);
  w.cell_entries.resize(n);
  w.particle_cell.resize(n);
  w.cell_coord.resize(n);
#pragma omp parallel for schedule(static) num_threads(threads) if (threads > 1)
  for (int i = 0; i < n; ++i) {
    auto& cc = w.cell_coord[i];
    cc = {std::llround(std::floor(x[i].x() / cell)), std::llround(std::floor(x[i].y() / cell)),
          std::llround(std::floor(x[i].z() / cell))};
    w.particle_cell[i] = static_cast<int>(hash_cell(cc[0], cc[1], cc[2], mask));
  }
  for (int i = 0; i < n; ++i) ++w.cell_start[w.particle_cell[i] + 1];
  for (std::size_t c = 0; c < size; ++c) w.cell_start[c + 1] += w.cell_start[c];
  std::vector<int>& fill = w.queue;  // reuse as a cursor per bucket
  fill.assign(w.cell_start.begin(), w.cell_start.end() - 1);
  for (int i = 0; i < n; ++i) w.cell_entries[fill[w.particle_cell[i]]++] = i;
}

// Calls fn(j, d, |d|²) for every particle j > after of the hash, but self,
// with d = y - x[j] shorter than `radius`, bucket by bucket. The hash must
// have been built with cell = 2 radius: the ball of radius r around y then
// meets at most 2 x 2 x 2 cells.
template <class Points, class Fn>
void for_each_near(const Points& x, double radius, const Workspace& w, const Vec3& y, int self,
                   int after, Fn fn) {
  const auto mask = static_cast<std::uint32_t>(w.cell_start.size() - 2);
  const double r2 = radius * radius, cell = 2 * radius;
  const long long cx = std::llround(std::floor((y.x() - radius) / cell));
  const long long cy = std::llround(std::floor((y.y() - radius) / cell));
  const long long cz = std::llround(std::floor((y.z() - radius) / cell));
  for (int dz = 0; dz <= 1; ++dz)
    for (int dy = 0; dy <= 1; ++dy)
      for (int dx = 0; dx <= 1; ++dx) {
        const long long ox = cx + dx, oy = cy + dy, oz = cz + dz;
        const std::uint32_t c = hash_cell(ox, oy, oz, mask);
        for (int e = w.cell_start[c]; e < w.cell_start[c + 1]; ++e) {
          const int j = w.cell_entries[e];
          if (j <= after || j == self) continue;
          // A bucket may hold other cells too: take j only in the cell visited,
          // so that none is found twice.
          const auto& cj = w.cell_coord[j];
          if (cj[0] != ox || cj[1] != oy || cj[2] != oz) continue;
          const Vec3 d = y - x[j];
          const double len2 = d.squaredNorm();
          if (len2 < r2) fn(j, d, len2);
        }
      }
}

// Calls fn(i, j, d_ij, |d_ij|) once for every pair i < j closer than `radius`
// that `skip(i, j)` does not exclude, with i in [first, last) (all particles by
// default), in order of i. The hash must have been built with cell = 2 radius.
template <class Points, class Skip, class Fn>
void for_each_close_pair(const Points& x, double radius, const Workspace& w, Skip skip, Fn fn,
                         int first = 0, int last = -1) {
  if (last < 0) last = static_cast<int>(x.size());
  for (int i = first; i < last; ++i)
    for_each_near(x, radius, w, x[i], i, i, [&](int j, const Vec3& d, double len2) {
      if (len2 == 0 || skip(i, j)) return;  // skip last: it may cost most
      fn(i, j, d, std::sqrt(len2));
    });
}

}  // namespace wetcloth::detail
