// Quadratic bending (docs/model.md section 1; after Bergou, Wardetzky, Harmon,
// Zorin & Grinspun 2006, "A Quadratic Bending Model for Inextensible
// Surfaces"). For a cloth whose rest shape is flat and whose stretch stays
// small, the bending energy is ½ B ∫ |∇∇x|² dA = ½ B ∫ (κ₁² + κ₂²) dA: each
// particle's Hessian of the positions is linear in them, with weights from
// the rest shape alone, so E = ½ xᵀ Q x with Q constant and the force -Q x
// linear. The symplectic step adds it, implicit Euler adds Q to its matrix
// once, xpbd adds it with the mass a substep needs to take it stably.
//
// Choices (docs/model.md section 1, with the measurements):
// - The squared Hessian (a plate of Poisson's ratio 0), not Bergou's squared
//   mean curvature (κ₁ + κ₂)²: the two agree on every bend a cloth can make
//   without stretching, but a saddle (κ₂ = -κ₁) costs nothing in the second,
//   and a strip bent along its length then curls across it as far as its
//   soft membrane lets it: Peirce's cantilever gave back 0.75 B at every
//   grid. Its per-edge stencils, on a grid of right triangles, also store a
//   cylinder bend at 45° to the rows at twice the energy of one along them.
// - Each inner particle's Hessian is the least-squares quadratic through its
//   neighbours in the rest shape's tangent plane (exact for any quadratic,
//   zero for an affine map: a flat or rigidly moved cloth feels nothing),
//   weighted by its mixed Voronoi area (Meyer et al. 2003).
// - A border particle's own fit would be one-sided: its area goes in equal
//   shares to its inner neighbours, whose curvature stands for it. A uniform
//   bend then stores B κ²/2 over the whole cloth.
// - The rest shape's own angles and lengths: a mesh cloth's rest is its flat
//   pattern. A grid is split both ways and the two averaged (its areas and
//   neighbours do not depend on the split).
#include <Eigen/SVD>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <stdexcept>

#include "detail.hpp"

namespace wetcloth::detail {

namespace {

// Per row, (column, value) pairs being summed.
using Row = std::vector<std::pair<int, double>>;

// Each row's diagonal, which makes it sum to zero, and its Gershgorin bound
// Σ_j |Q_ij| (the diagonal included).
void set_diagonal_and_bound(BendingMatrix& b) {
  const int n = static_cast<int>(b.start.size()) - 1;
  b.diagonal.assign(n, 0.0);
  b.bound.assign(n, 0.0);
  for (int j = 0; j < n; ++j) {
    b.for_each_in_row(j, [&](int, double q) {
      b.diagonal[j] -= q;
      b.bound[j] += std::abs(q);
    });
    b.bound[j] += std::abs(b.diagonal[j]);
  }
}

// The stored rows in groups of kLanes of one length (BendingMatrix::Groups):
// rows taken in ascending order, each into its length's open group, so that a
// group's rows are near one another (a border's rows, or the same place on
// kLanes grid rows). What no group fills is summed a row at a time.
void group_rows(BendingMatrix& b) {
  constexpr int L = BendingMatrix::kLanes;
  BendingMatrix::Groups& g = b.groups;
  const int n = static_cast<int>(b.start.size()) - 1;
  g = {};
  std::vector<std::vector<int>> open;  // by length, the places in stored waiting for a group
  for (int i = 0; i < n; ++i) {
    if (b.in_stencil(i)) continue;
    g.stored.push_back(i);
    g.group_of.push_back(-1);
    const int length = b.start[i + 1] - b.start[i];
    if (length == 0) continue;
    if (static_cast<int>(open.size()) <= length) open.resize(length + 1);
    std::vector<int>& waiting = open[length];
    waiting.push_back(static_cast<int>(g.stored.size()) - 1);
    if (static_cast<int>(waiting.size()) < L) continue;
    const int k = static_cast<int>(g.length.size());
    g.length.push_back(length);
    g.entry.push_back(static_cast<int>(g.column.size()));
    const int r0 = g.stored[waiting[0]];
    for (int e = 0; e < length; ++e)
      for (const int place : waiting) {
        g.column.push_back(b.column[b.start[g.stored[place]] + e]);
        g.value.push_back(b.value[b.start[g.stored[place]] + e]);
      }
    bool side_by_side = true;
    for (int l = 0; l < L; ++l) {
      const int r = g.stored[waiting[l]];
      side_by_side &= r == r0 + l;
      for (int e = 0; e < length; ++e)
        side_by_side &= b.column[b.start[r] + e] - r == b.column[b.start[r0] + e] - r0;
      g.row.push_back(r);
      g.group_of[waiting[l]] = k;
    }
    g.side_by_side.push_back(side_by_side);
    waiting.clear();
  }
}

// The rows' diagonals, bounds and groups, from their final entries.
void finish_rows(BendingMatrix& b) {
  set_diagonal_and_bound(b);
  group_rows(b);
}

void add_to(Row& row, int column, double value) {
  for (auto& [c, v] : row)
    if (c == column) {
      v += value;
      return;
    }
  row.push_back({column, value});
}

// Each particle's neighbours along the triangles' edges, sorted; and its
// mixed Voronoi area (Meyer et al. 2003), each split's triangles counted
// 1 / splits.
struct Rings {
  std::vector<std::vector<int>> around;
  std::vector<double> area;
  std::vector<Vec3> normal;  // area-weighted, of the rest triangles at it
};

Rings rings_of(const std::vector<Vec3>& x,
               const std::vector<std::vector<std::array<int, 3>>>& splits) {
  const std::size_t n = x.size();
  Rings r{std::vector<std::vector<int>>(n), std::vector<double>(n, 0.0),
          std::vector<Vec3>(n, Vec3::Zero())};
  const double weight = 1.0 / static_cast<double>(splits.size());
  for (const auto& triangles : splits)
    for (const auto& t : triangles) {
      const Vec3 e[3] = {x[t[2]] - x[t[1]], x[t[0]] - x[t[2]], x[t[1]] - x[t[0]]};  // opposite k
      const Vec3 cross = e[1].cross(e[2]);
      const double twice_area = cross.norm();
      if (!(twice_area > 0)) continue;  // a degenerate triangle holds nothing
      double cot[3];
      for (int k = 0; k < 3; ++k) cot[k] = -e[(k + 1) % 3].dot(e[(k + 2) % 3]) / twice_area;
      const int obtuse = cot[0] < 0 ? 0 : cot[1] < 0 ? 1 : cot[2] < 0 ? 2 : -1;
      for (int k = 0; k < 3; ++k) {
        // Voronoi: |e|² cot / 8 over the two sides at k; at an obtuse
        // triangle half its area to the obtuse corner, a quarter to the others.
        const double a = obtuse < 0 ? (e[(k + 1) % 3].squaredNorm() * cot[(k + 1) % 3] +
                                       e[(k + 2) % 3].squaredNorm() * cot[(k + 2) % 3]) /
                                          8
                                    : twice_area / (obtuse == k ? 4 : 8);
        r.area[t[k]] += weight * a;
        r.normal[t[k]] += weight * cross;
        for (const int other : {t[(k + 1) % 3], t[(k + 2) % 3]}) r.around[t[k]].push_back(other);
      }
    }
  for (auto& a : r.around) {
    std::sort(a.begin(), a.end());
    a.erase(std::unique(a.begin(), a.end()), a.end());
  }
  return r;
}

// The stencil of particle i's Hessian: fitted by least squares over its
// neighbours in the rest shape's tangent plane, x_j - x_i ≈ g·d + ½ dᵀ H d
// (d their rest offsets there), which is exact for any quadratic field and
// so zero for an affine one. Returns the particles and, for each, its
// coefficients in H_uu, H_uv, H_vv; empty where the fit is not determined.
struct HessianStencil {
  std::vector<int> particle;
  std::vector<std::array<double, 3>> c;
};

HessianStencil hessian_stencil(const std::vector<Vec3>& x, const Rings& r, int i) {
  std::vector<int> near = r.around[i];
  if (near.size() < 6) {  // too few for five unknowns, well posed: the next ring too
    for (const int j : r.around[i]) near.insert(near.end(), r.around[j].begin(), r.around[j].end());
    std::sort(near.begin(), near.end());
    near.erase(std::unique(near.begin(), near.end()), near.end());
    near.erase(std::remove(near.begin(), near.end(), i), near.end());
  }
  const Vec3 n = r.normal[i].normalized();
  const Vec3 t1 = n.unitOrthogonal(), t2 = n.cross(t1);
  const int k = static_cast<int>(near.size());
  Eigen::MatrixXd a(k, 5);
  double scale = 0;
  for (int q = 0; q < k; ++q) scale = std::max(scale, (x[near[q]] - x[i]).norm());
  for (int q = 0; q < k; ++q) {  // in units of the farthest neighbour: well scaled
    const Vec3 d = (x[near[q]] - x[i]) / scale;
    const double u = d.dot(t1), v = d.dot(t2);
    a.row(q) << u, v, 0.5 * u * u, u * v, 0.5 * v * v;
  }
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(a, Eigen::ComputeThinU | Eigen::ComputeThinV);
  const auto& sv = svd.singularValues();
  if (k < 5 || !(sv(4) > 1e-6 * sv(0))) return {};
  const Eigen::MatrixXd fit = svd.solve(Eigen::MatrixXd::Identity(k, k));  // 5 x k
  HessianStencil h;
  h.particle = near;
  h.particle.push_back(i);
  std::array<double, 3> self{};
  for (int q = 0; q < k; ++q) {
    std::array<double, 3> c;
    for (int e = 0; e < 3; ++e) {
      c[e] = fit(2 + e, q) / (scale * scale);
      self[e] -= c[e];
    }
    h.c.push_back(c);
  }
  h.c.push_back(self);
  return h;
}

}  // namespace

namespace {

// Q's rows where `needed` says (all when it is empty; the others left empty),
// in its columns' order. E = ½ B Σ_i A_i (H_uu² + 2 H_uv² + H_vv²): row j of
// Q gets, from each inner particle i whose stencil holds j, B A_i Σ_e w_e
// c_je c_i·e, summed in the order of i (a row's bits do not depend on which
// others are built). Exactly symmetric where both rows are built (Q_jk and
// Q_kj summed the same terms in other orders), so that the forces' pairs
// cancel: momentum is kept to the last bit of each pair.
BendingMatrix build_rows(const std::vector<Vec3>& rest,
                         const std::vector<std::vector<std::array<int, 3>>>& splits,
                         const std::vector<std::uint8_t>& on_border, double rigidity,
                         const std::vector<std::uint8_t>& needed) {
  const int n = static_cast<int>(rest.size());
  const Rings r = rings_of(rest, splits);
  const auto is_needed = [&](int j) { return needed.empty() || needed[j] != 0; };
  // Each inner particle's area and its share of its border neighbours'.
  std::vector<double> carried(r.area);
  for (int k = 0; k < n; ++k) {
    if (!on_border[k]) continue;
    carried[k] = 0;
    int inner = 0;
    for (const int j : r.around[k]) inner += !on_border[j];
    for (const int j : r.around[k])
      if (!on_border[j]) carried[j] += r.area[k] / inner;
  }
  // The particles whose stencil can reach a needed row: within two rings.
  std::vector<std::uint8_t> reaches(n, needed.empty());
  if (!needed.empty())
    for (int i = 0; i < n; ++i)
      for (const int j : r.around[i])
        for (const int k : r.around[j]) reaches[i] |= needed[i] | needed[j] | needed[k];
  std::vector<Row> q(n);
  for (int i = 0; i < n; ++i) {
    if (on_border[i] || !(carried[i] > 0) || !reaches[i]) continue;
    const HessianStencil h = hessian_stencil(rest, r, i);
    const double w = rigidity * carried[i];
    for (std::size_t a = 0; a < h.particle.size(); ++a) {
      if (!is_needed(h.particle[a])) continue;
      for (std::size_t b = 0; b < h.particle.size(); ++b) {
        const auto &ca = h.c[a], &cb = h.c[b];
        add_to(q[h.particle[a]], h.particle[b],
               w * (ca[0] * cb[0] + 2 * ca[1] * cb[1] + ca[2] * cb[2]));
      }
    }
  }
  BendingMatrix b;
  b.start.push_back(0);
  for (int j = 0; j < n; ++j) {
    std::sort(q[j].begin(), q[j].end());
    for (const auto& [k, v] : q[j]) {
      if (k == j || v == 0) continue;
      b.column.push_back(k);
      b.value.push_back(v);
    }
    b.start.push_back(static_cast<int>(b.column.size()));
    Row().swap(q[j]);  // freed as it goes: the build's peak memory
  }
  for (int j = 0; j < n; ++j)
    for (int e = b.start[j]; e < b.start[j + 1]; ++e) {
      const int k = b.column[e];
      if (k < j && is_needed(k)) {
        const auto first = b.column.begin() + b.start[k], last = b.column.begin() + b.start[k + 1];
        b.value[e] = b.value[std::lower_bound(first, last, j) - b.column.begin()];
      }
    }
  return b;
}

}  // namespace

BendingMatrix build_bending_matrix(const std::vector<Vec3>& rest,
                                   const std::vector<std::vector<std::array<int, 3>>>& splits,
                                   const std::vector<std::uint8_t>& on_border, double rigidity) {
  BendingMatrix b = build_rows(rest, splits, on_border, rigidity, {});
  finish_rows(b);  // each row sums to zero
  return b;
}

namespace {

// A grid's rows: those within kBand of its border, and the centre's, from the
// rest shape; the others, whose fits differ from the centre's only in the
// rest positions' last bits, are its stencil without being built (a build of
// every row held some 500 bytes a particle at its peak).
constexpr int kBand = 4;

// The grid's 5 x 5 stencil (offsets as dj nu + di, |di|, |dj| <= 2, but
// itself) has kGridStencil of them.
constexpr int kGridStencil = 24;

// The mirror groups of Stencil::mirror, by (|di|, |dj|).
constexpr int kMirrorGroups = 8;
constexpr int kMirror[kMirrorGroups][2] = {{1, 0}, {0, 1}, {2, 0}, {0, 2},
                                           {1, 1}, {1, 2}, {2, 1}, {2, 2}};

// A grid of rectangular cells has a stencil the same under di → -di and
// dj → -dj, but for the fits' rounding: where each group of mirror images
// agrees within 1e-9, each takes the group's mean and the group is noted,
// so that bending_rows sums it once (mirrored_rows). The mean changes the
// row by rounding, as making opposite offsets equal did.
void make_mirrored(int nu, BendingMatrix::Stencil& st) {
  if (st.offset.size() != static_cast<std::size_t>(kGridStencil)) return;
  std::array<std::vector<std::size_t>, kMirrorGroups> members;
  for (std::size_t e = 0; e < st.offset.size(); ++e) {
    const int dj = (st.offset[e] + 2 * nu + 2) / nu - 2, di = st.offset[e] - dj * nu;
    const int g =
        static_cast<int>(std::find_if(std::begin(kMirror), std::end(kMirror),
                                      [&](const int(&k)[2]) {
                                        return k[0] == std::abs(di) && k[1] == std::abs(dj);
                                      }) -
                         std::begin(kMirror));
    if (g == kMirrorGroups) return;
    members[g].push_back(e);
  }
  std::vector<double> mean(kMirrorGroups, 0.0);
  for (int g = 0; g < kMirrorGroups; ++g) {
    if (members[g].size() != (g < 4 ? 2u : 4u)) return;
    for (const std::size_t e : members[g]) mean[g] += st.value[e];
    mean[g] /= static_cast<double>(members[g].size());
    for (const std::size_t e : members[g])
      if (std::abs(st.value[e] - mean[g]) > 1e-9 * std::abs(mean[g])) return;
  }
  for (int g = 0; g < kMirrorGroups; ++g)
    for (const std::size_t e : members[g]) st.value[e] = mean[g];
  st.mirror = std::move(mean);
}

// The rows of a grid's matrix that are its centre row's stencil, within
// rounding, made that stencil exactly, in their columns and their
// transposes; each row's diagonal and bound from its final values. Symmetry
// and zero row sums stay exact. `built` marks the rows build_rows made; the
// others are the stencil's.
void find_stencil(const Model& m, BendingMatrix& b, const std::vector<std::uint8_t>& built) {
  const int centre = m.index(m.nu / 2, m.nv / 2);
  BendingMatrix::Stencil& st = b.stencil;
  for (int e = b.start[centre]; e < b.start[centre + 1]; ++e) {
    st.offset.push_back(b.column[e] - centre);
    st.value.push_back(b.value[e]);
  }
  const std::size_t size = st.offset.size();
  // Each offset's value as the mean of the offset's and its opposite's, so
  // that the stencil is symmetric to the bit.
  for (std::size_t e = 0; e < size; ++e) {
    const std::size_t opposite = size - 1 - e;
    if (e < opposite) st.value[e] = st.value[opposite] = 0.5 * (st.value[e] + st.value[opposite]);
  }
  make_mirrored(m.nu, st);
  const auto same = [&](int a) {
    if (!built[a]) return true;
    if (static_cast<std::size_t>(b.start[a + 1] - b.start[a]) != size) return false;
    for (std::size_t e = 0; e < size; ++e) {
      const int c = b.start[a] + static_cast<int>(e);
      if (b.column[c] - a != st.offset[e] ||
          std::abs(b.value[c] - st.value[e]) > 1e-9 * std::abs(st.value[e]))
        return false;
    }
    return true;
  };
  st.nu = m.nu;
  st.first.assign(m.nv, 0);
  st.last.assign(m.nv, 0);
  for (int j = 0; j < m.nv; ++j) {
    // The run of stencil rows about the row's middle.
    int lo = m.nu / 2, hi = m.nu / 2;
    if (!same(m.index(lo, j))) continue;
    while (lo > 0 && same(m.index(lo - 1, j))) --lo;
    while (hi < m.nu && same(m.index(hi, j))) ++hi;
    st.first[j] = lo;
    st.last[j] = hi;
  }
  for (int a = 0; a < m.n; ++a)
    if (!built[a] && !b.in_stencil(a))
      throw std::logic_error("build_bending_matrix: a row left out is not the grid's stencil");
  // The other rows keep their entries, those in a stencil row's column as
  // the stencil's (its transpose); the stencil's rows leave the stored matrix.
  std::vector<int> start{0}, column;
  std::vector<double> value;
  for (int j = 0; j < m.n; ++j) {
    if (!b.in_stencil(j))
      for (int e = b.start[j]; e < b.start[j + 1]; ++e) {
        const int k = b.column[e];
        column.push_back(k);
        value.push_back(b.in_stencil(k)
                            ? st.value[std::lower_bound(st.offset.begin(), st.offset.end(), j - k) -
                                       st.offset.begin()]
                            : b.value[e]);
      }
    start.push_back(static_cast<int>(column.size()));
  }
  b.start = std::move(start);
  b.column = std::move(column);
  b.value = std::move(value);
  finish_rows(b);
}

}  // namespace

BendingMatrix build_bending_matrix(const Model& m, double rigidity) {
  if (!m.grid) return build_bending_matrix(m.rest_position, {m.triangles}, m.on_border, rigidity);
  std::vector<std::array<int, 3>> one, other;  // each quad split along one diagonal, then the other
  for (int j = 0; j + 1 < m.nv; ++j)
    for (int i = 0; i + 1 < m.nu; ++i) {
      const int a = m.index(i, j), b = m.index(i + 1, j), c = m.index(i + 1, j + 1),
                d = m.index(i, j + 1);
      one.push_back({a, b, c});
      one.push_back({a, c, d});
      other.push_back({a, b, d});
      other.push_back({b, c, d});
    }
  if (m.nu < 5 || m.nv < 5) {
    BendingMatrix b = build_rows(m.rest_position, {one, other}, m.on_border, rigidity, {});
    finish_rows(b);
    return b;
  }
  std::vector<std::uint8_t> built(m.n, 0);
  for (int j = 0; j < m.nv; ++j)
    for (int i = 0; i < m.nu; ++i)
      built[m.index(i, j)] = std::min({i, j, m.nu - 1 - i, m.nv - 1 - j}) <= kBand;
  built[m.index(m.nu / 2, m.nv / 2)] = 1;
  BendingMatrix b = build_rows(m.rest_position, {one, other}, m.on_border, rigidity, built);
  find_stencil(m, b, built);
  return b;
}

// Q x on differences at the particles [i0, i1) of grid row j, from a
// mirrored stencil (Stencil::mirror): Σ_g c_g Σ_{(di,dj) in g} (x_{i+di+dj nu} -
// x_i), each group's sum made from the second differences along rows,
// a1 = (x_{i-1} - x_i) + (x_{i+1} - x_i) and a2 the same two apart, which
// the particles of five rows share, and those across them, b1 and b2:
//   (±1, 0): a1(i)   (0, ±1): b1(i)   (±2, 0): a2(i)   (0, ±2): b2(i)
//   (±1, ±1): a1(i - nu) + a1(i + nu) + 2 b1(i)
//   (±1, ±2): a1(i - 2 nu) + a1(i + 2 nu) + 2 b2(i)
//   (±2, ±1): a2(i - nu) + a2(i + nu) + 2 b1(i)
//   (±2, ±2): a2(i - 2 nu) + a2(i + 2 nu) + 2 b2(i)
// Every term is a difference of near particles, so a cloth far from the origin
// loses no precision; some 40 operations a particle and component where
// the offsets one by one took 72. `ring` holds a1 and a2 of rows
// [next - 5, next), slot r % 5 for row r, and is filled as j advances.
template <bool Assign>
void mirrored_rows(const Model& m, const double* __restrict x, double* __restrict out, double scale,
                   int j, int i0, int i1, double* __restrict ring, int& next) {
  const int nu = m.nu;
  const auto a1 = [&](int r) { return ring + (r % 5) * 2 * nu; };
  const auto a2 = [&](int r) { return ring + (r % 5) * 2 * nu + nu; };
  for (int r = std::max(next, j - 2); r <= j + 2; ++r) {
    const double* __restrict row = x + r * nu;
    double* __restrict to1 = a1(r), * __restrict to2 = a2(r);
#pragma omp simd
    for (int i = 1; i < nu - 1; ++i) to1[i] = (row[i - 1] - row[i]) + (row[i + 1] - row[i]);
#pragma omp simd
    for (int i = 2; i < nu - 2; ++i) to2[i] = (row[i - 2] - row[i]) + (row[i + 2] - row[i]);
  }
  next = j + 3;
  const std::vector<double>& c = m.topology->bending.stencil.mirror;
  const double c10 = c[0], c01 = c[1], c20 = c[2], c02 = c[3], c11 = c[4], c12 = c[5], c21 = c[6],
               c22 = c[7];
  const double* __restrict a1m2 = a1(j - 2), * __restrict a1m1 = a1(j - 1), * __restrict a10 = a1(j), * __restrict a1p1 = a1(j + 1), * __restrict a1p2 = a1(j + 2);
  const double* __restrict a2m2 = a2(j - 2), * __restrict a2m1 = a2(j - 1), * __restrict a20 = a2(j), * __restrict a2p1 = a2(j + 1), * __restrict a2p2 = a2(j + 2);
  const double* __restrict y = x + j * nu;
  double* __restrict o = out + j * nu;
#pragma omp simd
  for (int i = i0; i < i1; ++i) {
    const double b1 = (y[i - nu] - y[i]) + (y[i + nu] - y[i]);
    const double b2 = (y[i - 2 * nu] - y[i]) + (y[i + 2 * nu] - y[i]);
    const double sum = c10 * a10[i] + c01 * b1 + c20 * a20[i] + c02 * b2 +
                       c11 * ((a1m1[i] + a1p1[i]) + 2 * b1) + c12 * ((a1m2[i] + a1p2[i]) + 2 * b2) +
                       c21 * ((a2m1[i] + a2p1[i]) + 2 * b1) + c22 * ((a2m2[i] + a2p2[i]) + 2 * b2);
    if constexpr (Assign)
      o[i] = scale * sum;
    else
      o[i] += scale * sum;
  }
}

// The stored rows (BendingMatrix::Groups) among [a0, a1): a group whose rows
// all lie there in one vector loop, its lanes its rows, each summing its
// entries in their order; any other row alone, in the same order.
template <bool Difference, bool Assign, int C>
void stored_rows(const BendingMatrix& b, const std::array<const double*, C>& x,
                 const std::array<double*, C>& out, double scale, int a0, int a1) {
  constexpr int L = BendingMatrix::kLanes;
  const BendingMatrix::Groups& g = b.groups;
  const auto put = [&](int k, int i, double sum) {
    if constexpr (Assign)
      out[k][i] = scale * sum;
    else
      out[k][i] += scale * sum;
  };
  const auto one_row = [&](int i) {
    double sum[C] = {};
    for (int e = b.start[i]; e < b.start[i + 1]; ++e)
      for (int k = 0; k < C; ++k)
        sum[k] += b.value[e] * (Difference ? x[k][b.column[e]] - x[k][i] : x[k][b.column[e]]);
    for (int k = 0; k < C; ++k) put(k, i, sum[k]);
  };
  // A group's lanes in one vector (GCC's vector extension, which Clang has
  // too), each component's sum a chain of its own.
  using Lanes = double __attribute__((vector_size(L * sizeof(double))));
  // A group's rows side by side (a border's own rows, each entry's columns
  // consecutive) load a vector at once.
  const auto group = [&]<bool SideBySide>(int q) {
    const int* const row = g.row.data() + q * L;
    const int* __restrict column = g.column.data() + g.entry[q];
    const double* __restrict value = g.value.data() + g.entry[q];
    Lanes own[C], sum[C];
    for (int k = 0; k < C; ++k) {
      if constexpr (SideBySide)
        std::memcpy(&own[k], x[k] + row[0], sizeof(Lanes));
      else
        for (int l = 0; l < L; ++l) own[k][l] = x[k][row[l]];
      sum[k] = Lanes{};
    }
    for (int e = 0; e < g.length[q]; ++e, column += L, value += L) {
      Lanes v;
      std::memcpy(&v, value, sizeof v);
      for (int k = 0; k < C; ++k) {
        Lanes y;
        if constexpr (SideBySide)
          std::memcpy(&y, x[k] + column[0], sizeof y);
        else
          for (int l = 0; l < L; ++l) y[l] = x[k][column[l]];
        sum[k] += v * (Difference ? y - own[k] : y);
      }
    }
    for (int k = 0; k < C; ++k)
      for (int l = 0; l < L; ++l) put(k, row[l], sum[k][l]);
  };
  for (auto it = std::lower_bound(g.stored.begin(), g.stored.end(), a0);
       it != g.stored.end() && *it < a1; ++it) {
    const int i = *it, q = g.group_of[it - g.stored.begin()];
    if (q < 0 || g.row[q * L] < a0 || g.row[q * L + L - 1] >= a1)
      one_row(i);
    else if (i == g.row[q * L] && g.side_by_side[q])
      group.template operator()<true>(q);
    else if (i == g.row[q * L])
      group.template operator()<false>(q);
  }
}

// out_i += scale Σ_j Q_ij (x_j - x_i) (Difference) or scale Σ_j Q_ij x_j over
// j ≠ i, for the particles [a0, a1), each of the C components: each particle
// sums its own row in a fixed order, so that any thread count gives the same
// bits. The stored rows go by stored_rows; the stencil's runs of a row a chunk
// of particles at a time, in loops that vectorise: by mirror groups
// (mirrored_rows), or offset by offset.
template <bool Difference, bool Assign, int C>
void bending_rows(const Model& m, const std::array<const double*, C>& x,
                  const std::array<double*, C>& out, double scale, int a0, int a1) {
  const BendingMatrix& b = m.topology->bending;
  stored_rows<Difference, Assign, C>(b, x, out, scale, a0, a1);
  const BendingMatrix::Stencil& st = b.stencil;
  if (st.first.empty()) return;
  const int size = static_cast<int>(st.offset.size());
  const int* const offset = st.offset.data();
  const double* const coefficient = st.value.data();
  // The mirrored stencil's second differences, five rows of them per
  // component, this thread's.
  static thread_local std::vector<double> ring;
  const bool mirrored = Difference && !st.mirror.empty();
  const std::size_t per_component = std::size_t(10) * m.nu;
  if (mirrored && ring.size() < C * per_component) ring.resize(C * per_component);
  int next[C] = {};  // per component, the first row not in its ring
  for (int a = a0; a < a1;) {
    const int j = a / m.nu, row = j * m.nu, lo = row + st.first[j], hi = row + st.last[j];
    const int end = std::min(a1, row + m.nu);
    if (a < lo || a >= hi) {  // stored rows (above) up to the row's stencil run, or to its end
      a = a < lo ? std::min(lo, end) : end;
      continue;
    }
    const int to = std::min(hi, end);
    for (int k = 0; k < C; ++k) {
      const double* __restrict y = x[k];
      double* __restrict f = out[k];
      if (size != kGridStencil) {  // not a grid's 5 x 5 (none is met): a particle at a time
        for (int i = a; i < to; ++i) {
          double sum = 0;
          for (int e = 0; e < size; ++e)
            sum += coefficient[e] * (Difference ? y[i + offset[e]] - y[i] : y[i + offset[e]]);
          if constexpr (Assign)
            f[i] = scale * sum;
          else
            f[i] += scale * sum;
        }
        continue;
      }
      if (mirrored) {
        mirrored_rows<Assign>(m, y, f, scale, j, a - row, to - row, ring.data() + k * per_component,
                              next[k]);
        continue;
      }
      // Vectorised across the particles, each one's sum held in a register
      // over the stencil's 24 offsets (unrolled: its size is known here).
      int o[kGridStencil];
      double c[kGridStencil];
      std::copy_n(offset, kGridStencil, o);
      std::copy_n(coefficient, kGridStencil, c);
#pragma omp simd
      for (int i = a; i < to; ++i) {
        double sum = 0;
#pragma GCC unroll 24
        for (int e = 0; e < kGridStencil; ++e)
          sum += c[e] * (Difference ? y[i + o[e]] - y[i] : y[i + o[e]]);
        if constexpr (Assign)
          f[i] = scale * sum;
        else
          f[i] += scale * sum;
      }
    }
    a = to;
  }
}

template <bool Assign>
void bending_rows_xyz(const Model& m, const State& s, Vec3Array& f, int first, int end) {
  bending_rows<true, Assign, 3>(m, {s.x.column(0), s.x.column(1), s.x.column(2)},
                                {f.column(0), f.column(1), f.column(2)}, -1.0, first, end);
}

// f -= Q x on differences, so that a cloth far from the origin loses no precision.
void add_bending_forces(const Model& m, const State& s, Vec3Array& f, int first, int end) {
  if (!m.topology->bending.start.empty()) bending_rows_xyz<false>(m, s, f, first, end);
}
void add_bending_forces(const Model& m, const State& s, Vec3Array& f) {
  if (m.topology->bending.start.empty()) return;
  for_each_particle_block(
      m, [&](int first, int end) { bending_rows_xyz<false>(m, s, f, first, end); });
}

// f = -Q x, every particle's row written: xpbd's own array, no zeroing pass.
void bending_forces(const Model& m, const State& s, Vec3Array& f) {
  for_each_particle_block(m,
                          [&](int first, int end) { bending_rows_xyz<true>(m, s, f, first, end); });
}

void add_bending_off_diagonal(const Model& m, const double* x, double* y, double scale, int a0,
                              int a1) {
  bending_rows<false, false, 1>(m, {x}, {y}, scale, a0, a1);
}

// ½ xᵀ Q x = -¼ Σ_i Σ_j≠i Q_ij |x_j - x_i|² (the rows sum to zero).
double bending_energy(const Model& m, const Vec3Array& x) {
  const BendingMatrix& b = m.topology->bending;
  double e = 0;
  for (int i = 0; i + 1 < static_cast<int>(b.start.size()); ++i)
    b.for_each_in_row(i, [&](int j, double q) { e -= 0.25 * q * (x[j] - x[i]).squaredNorm(); });
  return e;
}

}  // namespace wetcloth::detail
