// What the step's kernels derive from the cloth's springs and triangles: the
// grid's stencil, a mesh cloth's neighbour lists. Built once with the Model
// (build_model) and shared by its copies; private to the library, so that the
// public Model holds what a user reads, not how the solvers walk it.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

namespace wetcloth {

// A spring of the grid's stencil, as a forward offset: particle (i, j) is tied
// to (i + di, j + dj). Eight offsets and their mirror images are all the springs.
struct StencilEdge {
  int di = 0, dj = 0;
  double k = 0, damping = 0, rest = 0;
};

// The quadratic bending's Q (forces/bending.cpp), N/m: E = ½ xᵀ Q x per
// component. Its off-diagonal entries by row, sorted (row i's are
// [start[i], start[i + 1])), exactly symmetric; the diagonal, each row's sum
// zero; bound, each row's Σ_j |Q_ij| (Gershgorin's bound on its stiffness).
// Empty with material.bending = "provot".
struct BendingMatrix {
  std::vector<int> start, column;
  std::vector<double> value, diagonal, bound;
  // A grid's rows away from its border are all one stencil: offset[e] from
  // the row's particle, with value[e] (ascending offsets, as the rows'
  // columns). Grid row j's particles [first[j], last[j]) use it, in loops
  // that vectorise; the others their row of the matrix. Empty for a mesh.
  // Those rows are not stored in start, column and value (their ranges are
  // empty): for_each_in_row gives any row's entries.
  struct Stencil {
    int nu = 0;  // the grid's row length
    std::vector<int> offset, first, last;
    std::vector<double> value;
    // A 5 x 5 stencil the same under di → -di and dj → -dj (a grid of
    // rectangular cells): the value of each group of mirror images, (di, dj)
    // = (1,0), (0,1), (2,0), (0,2), (1,1), (1,2), (2,1), (2,2); empty otherwise.
    std::vector<double> mirror;
  } stencil;
  // The stored rows (those not in the stencil), ascending, and as many as
  // can be in groups of kLanes rows of one length: group g's rows are
  // row[kLanes g ...] (ascending), its entries from entry[g] interleaved
  // (entry e of lane l at e kLanes + l), so that a group sums in one vector
  // loop, each row in its own order: the bits of a row at a time.
  // group_of[k]: the group of row stored[k], or -1 (summed alone).
  static constexpr int kLanes = 4;
  struct Groups {
    std::vector<int> stored, group_of, row, entry, length, column;
    std::vector<double> value;
    std::vector<std::uint8_t> side_by_side;  // rows r, r + 1, ..., the same offsets
  } groups;

  bool in_stencil(int i) const {
    if (stencil.first.empty()) return false;
    const int j = i / stencil.nu, k = i % stencil.nu;
    return k >= stencil.first[j] && k < stencil.last[j];
  }
  // f(j, Q_ij) for each j ≠ i of row i, in ascending j.
  template <class F>
  void for_each_in_row(int i, F&& f) const {
    if (in_stencil(i)) {
      for (std::size_t e = 0; e < stencil.offset.size(); ++e)
        f(i + stencil.offset[e], stencil.value[e]);
      return;
    }
    for (int e = start[i]; e < start[i + 1]; ++e) f(column[e], value[e]);
  }
};

struct Topology {
  // The grid's springs by offset (the SpringSets hold them one by one): the
  // stencil kernels (forces/springs.cpp and the integrators) run on these.
  std::array<StencilEdge, 8> stencil;
  // The cloth's edges (its structural springs) per particle, as lists:
  // particle k's neighbours are edge_neighbour[edge_start[k] .. edge_start[k + 1]).
  // A mesh cloth only, as the three lists after it.
  std::vector<int> edge_start, edge_neighbour;
  // Each particle's structural and shear springs (their index in structural,
  // then shear + structural.size()).
  std::vector<int> strain_start, strain_spring;
  // The particles that never collide with k (within self-collision's reach
  // along the springs), sorted.
  std::vector<int> ring_start, ring;
  // A mesh cloth's particles along its longer side, as a grid's (the file's
  // bounding box's longest side over the mean edge, plus one): xpbd_substeps.
  int along = 0;
  std::vector<std::array<int, 2>> triangle_pairs;  // triangles sharing an edge
  BendingMatrix bending;
  // The wicking's Laplacian (water/humidity.cpp): edge e joins wick_a[e] and
  // wick_b[e] with weight wick_w[e] (its dual edge over its length: the
  // grid's 5-point stencil with the Voronoi areas, a mesh's cotangent weights,
  // negative ones taken as zero), in increasing (a, b).
  std::vector<int> wick_a, wick_b;
  std::vector<double> wick_w;
};

}  // namespace wetcloth
