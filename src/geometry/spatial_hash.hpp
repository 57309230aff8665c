// A spatial hash over particles (Teschner et al. 2003), built by counting sort so
// that the order of pairs, and so the sums, are deterministic.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>

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

// Sorts particles into buckets of cubic cells of side `cell`; the cells are
// found on `threads` threads, the counting sort is in particle order. Points
// x are a Vec3Array or a std::vector<Vec3>.
template <class Points>
void build_hash(const Points& x, double cell, Workspace& w, int threads = 1) {
  const int n = static_cast<int>(x.size());
  std::size_t size = 1;
  while (size < 2 * std::size_t(n)) size <<= 1;
  const auto mask = static_cast<std::uint32_t>(size - 1);
  w.hash_cell = cell;
  w.cell_start.assign(size + 1, 0);
  w.cell_entries.resize(n);
  w.particle_cell.resize(n);
#pragma omp parallel for schedule(static) num_threads(threads) if (threads > 1)
  for (int i = 0; i < n; ++i)
    w.particle_cell[i] = static_cast<int>(hash_cell(
        std::llround(std::floor(x[i].x() / cell)), std::llround(std::floor(x[i].y() / cell)),
        std::llround(std::floor(x[i].z() / cell)), mask));
  for (int i = 0; i < n; ++i) ++w.cell_start[w.particle_cell[i] + 1];
  for (std::size_t c = 0; c < size; ++c) w.cell_start[c + 1] += w.cell_start[c];
  std::vector<int>& fill = w.queue;  // reuse as a cursor per bucket
  fill.assign(w.cell_start.begin(), w.cell_start.end() - 1);
  for (int i = 0; i < n; ++i) w.cell_entries[fill[w.particle_cell[i]]++] = i;
}

// Calls fn(j, d, |d|²) for every particle j > after of the hash, but self,
// with d = y - x[j] shorter than `radius`: the buckets of the cells the ball
// of that radius around y meets, in order of z, y, x, each bucket once. A
// particle within the radius is in one of those cells, so in one of those
// buckets, found once; one of another cell that shares a bucket is beyond
// the radius. The hash's cells are at least the radius: 2 or 3 a side (4 where
// a rounding crosses a face). Around a cloth, a surface, cells of the radius
// hold about half the particles of cells of twice it, and the buckets need no
// cell's coordinates (docs/performance.md, seventeenth stop).
template <class Points, class Fn>
void for_each_near(const Points& x, double radius, const Workspace& w, const Vec3& y, int self,
                   int after, Fn fn) {
  const auto mask = static_cast<std::uint32_t>(w.cell_start.size() - 2);
  const double r2 = radius * radius, cell = w.hash_cell;
  if (!(cell >= radius)) throw std::logic_error("spatial hash: cells smaller than the radius");
  const auto first = [&](double c) { return std::llround(std::floor((c - radius) / cell)); };
  // At most 3 past the first: past 2^53 cells (a blown-up cloth at 1e14 m,
  // stopped after the step) doubles skip whole cells, and the last had
  // fallen 4 past the first, overrunning `seen`. (Unsigned: no overflow.)
  const auto last = [&](double c, long long from) {
    const long long to = std::llround(std::floor((c + radius) / cell));
    return static_cast<unsigned long long>(to) - static_cast<unsigned long long>(from) > 3
               ? from + 3
               : to;
  };
  const long long x0 = first(y.x()), y0 = first(y.y()), z0 = first(y.z());
  const long long x1 = last(y.x(), x0), y1 = last(y.y(), y0), z1 = last(y.z(), z0);
  std::uint32_t seen[64];
  int buckets = 0;
  for (long long oz = z0; oz <= z1; ++oz)
    for (long long oy = y0; oy <= y1; ++oy)
      for (long long ox = x0; ox <= x1; ++ox) {
        const std::uint32_t c = hash_cell(ox, oy, oz, mask);
        if (std::find(seen, seen + buckets, c) != seen + buckets) continue;
        seen[buckets++] = c;
        for (int e = w.cell_start[c]; e < w.cell_start[c + 1]; ++e) {
          const int j = w.cell_entries[e];
          if (j <= after || j == self) continue;
          const Vec3 d = y - x[j];
          const double len2 = d.squaredNorm();
          if (len2 < r2) fn(j, d, len2);
        }
      }
}

// Calls fn(i, j, d_ij, |d_ij|) once for every pair i < j closer than `radius`
// that `skip(i, j)` does not exclude, with i in [first, last) (all particles by
// default), in order of i.
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
