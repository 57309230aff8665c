// The step's scratch arrays, reused every step so that a step allocates
// nothing. Private to the library (and to its tests and micro-benchmarks,
// which reach it through detail::workspace).
#pragma once

#include <algorithm>
#include <array>
#include <compare>
#include <cstdint>
#include <vector>

#include "geometry/mesh_obstacle.hpp"
#include "wetcloth/motion.hpp"
#include "wetcloth/simulation.hpp"

namespace wetcloth {

// A symmetric 3x3 block as its six entries xx, yy, zz, xy, xz, yz.
using Sym = std::array<double, 6>;

// Two particles closer than the self-collision distance; u points from j to i.
struct CollisionPair {
  int i = 0, j = 0;
  Vec3 u = Vec3::Zero();
  Sym block{};  // implicit Euler: its h² k_t u uᵀ
};

// compute_normals' scratch: each thread's quads' two triangle normals (a
// chunk of rows at a time), and 1 where
// i + j is even (its quad splits along a-cc; see Model::triangles), else 0,
// as a column, so that it runs over whole blocks of rows.
struct NormalsScratch {
  std::vector<double> quad_normals, chequer;
  int chequer_nu = 0;
};

// A search of the spatial hash (geometry/spatial_hash.hpp): the cells it
// visits, from lo to lo + span on each axis (span at most 3), and the
// particle it searches around (32 B). Sorted, searches that visit the same
// cells are side by side.
struct NearSearch {
  std::array<long long, 3> lo;
  std::array<std::uint8_t, 3> span;
  int query;
  bool same_cells(const NearSearch& o) const { return lo == o.lo && span == o.span; }
  auto operator<=>(const NearSearch&) const = default;
};

// A thread's scratch for its searches: the points (x, y, z) and particles of
// the cells a search visits, gathered in runs, each one's squared distance
// and whether it is kept.
struct NearScratch {
  std::vector<double> x, y, z, len2;
  std::vector<int> index;
  std::vector<std::uint8_t> keep;  // 8 longer: read eight at a time
  void make_room(int count) {
    const auto n = static_cast<std::size_t>(count);
    if (n <= x.size()) return;
    const std::size_t size = std::max(n, 2 * x.size());
    for (auto* v : {&x, &y, &z, &len2}) v->resize(size);
    index.resize(size);
    keep.resize(size + 8);
  }
};

// integrator.threads = 0: the step's threads are chosen as it runs. Now and
// then a few milliseconds of steps are timed on one thread and on all the
// grid takes, and the faster is kept until the next trial: another busy
// process makes every barrier wait for a descheduled thread, and two threads
// then took 3 × as long as one (51 × 51). The count never changes the
// result, so neither does the choice.
struct ThreadChoice {
  bool automatic = false;
  int most = 1;  // the threads the grid takes (Model::threads as built)
  long long steps_on_one = 0, steps_on_most = 0;
  // The trial: 0, 1 timing one thread, then `most`; 2 keeping the faster.
  int phase = 0;
  double seconds = 0;
  long long substeps = 0;
  double per_substep[2] = {};
};

// Where the moving surfaces are at `time` (detail::place_surfaces): the ball's
// and each mesh obstacle's pose (docs/model.md section 3, "Moving surfaces").
// Nothing moves: every pose the identity, and the step runs as it did before
// surfaces could move, bit for bit.
struct SurfacePoses {
  double time = 0;
  bool any = false;  // some surface moves
  RigidPose ball;
  std::vector<RigidPose> obstacles;  // as Model::obstacles
  // A deforming obstacle's shape now (obstacle.NAME.cache; its pose is
  // `moving`, the identity without a motion), null for a rigid one: its own
  // copy, made again where a copied workspace shares it (copy on write).
  std::vector<std::shared_ptr<MeshObstacle>> shapes;
};

// Scratch arrays, reused every step: nothing is allocated per step.
// The humidity field's scratch (water/humidity.cpp): the wicking solve's
// vectors, and whether the field is uniform (then wicking has nothing to do).
struct HumidityScratch {
  std::vector<double> delta, r, z, p, q, diagonal, flux;
  bool uniform = true;
  int cg_iterations = 0;  // the last wicking solve's
};

struct Workspace {
  SurfacePoses surfaces;
  HumidityScratch humidity;
  Vec3Array force, normal, surface_normal;
  Vec3Array bending_force;     // xpbd: the quadratic bending's, apart (add_external_velocity)
  std::vector<Vec3> x_before;  // limit_strain: where each of strain_changed started
  NormalsScratch normals_scratch;
  std::vector<double> distance;       // signed distance to the contact surface
  std::vector<std::uint8_t> touched;  // the surface each particle was pushed out of this step
  // Per mesh obstacle, each particle's last query (bounds the next search only).
  std::vector<MeshQueryCache> mesh_cache;
  std::vector<double> adhesion;      // |adhesion force| per particle, N
  std::vector<std::uint8_t> border;  // border of the contact region
  std::vector<double> pocket_sums;   // scratch for the implicit air correction
  Vec3Array air_direction;           // A_i n_i of eq. 3 (zero where no air force)
  // Springs (forces/springs.cpp): a zero row, then per thread its ring of
  // edge rows.
  std::vector<double> spring_rows;
  std::vector<float> damping_columns;    // apply_spring_damping's columns and scratch
  std::vector<double> damping_impulses;  // and its impulses
  std::vector<int> queue;
  // Strain limiting: structural and shear springs in adaptive order (their
  // slots; a mesh cloth's springs by slot in strain_springs, a grid's from
  // the slot, detail::strain_spring), the first spring of each level (and the
  // end); within a level, the corrections found
  // (each spring's shortening and its ends' shares, by inverse mass), how many
  // move each particle, and their sums.
  struct StrainSpring {
    int a = 0, b = 0;
    double max_len = 0;  // (1 + τ_c) l0
    int slot = 0;        // 4 × lower end + stencil offset: its strain_stretched flag
  };
  struct StrainCorrection {
    int a = 0, b = 0;
    double wa = 0, wb = 0;     // a moves by wa corr, b by -wb corr (before the relaxation)
    Vec3 corr = Vec3::Zero();  // (x_b - x_a)(1 - max_len / |x_b - x_a|)
  };
  std::vector<StrainSpring> strain_springs;  // a mesh cloth's, by slot
  std::vector<int> strain_slots, strain_levels;
  std::vector<StrainCorrection> strain_corrections;
  std::vector<Vec3> strain_delta;
  std::vector<int> strain_count;
  // The force the last limit_strain's corrections exerted on each pinned,
  // driven or held particle (minus the momentum they gave the free ends, over
  // dt²; zero elsewhere), and those particles: part of a handle's reaction.
  std::vector<Vec3> strain_reaction;
  std::vector<int> strain_reacting;
  std::vector<int> strain_index;               // slot -> its place in strain_slots
  std::vector<std::uint8_t> strain_stretched;  // per stencil slot, at the start of a pass
  std::vector<std::uint64_t> strain_queue;     // a bit per spring of the order: queued
  std::vector<int> strain_touched;
  std::vector<int> strain_moved, strain_over;  // particles moved, springs stretched in a pass
  std::vector<std::uint8_t> strain_saved;      // x_before holds where it started this call
  std::vector<int> strain_changed;             // particles moved in this call
  Vec3 handle_force = Vec3::Zero();            // force the first pulling handle exerts, N
  // Self-collision spatial hash (counting sort by cell), its searches and
  // their scratch on each thread.
  std::vector<int> cell_start, cell_entries, particle_cell;
  double hash_cell = 0;               // the side of the hash's cells
  std::vector<NearSearch> near_plan;  // the searches, in order of their cells
  std::vector<NearScratch> near_scratch;
  std::vector<std::uint8_t> colliding;  // in a pair within d_t (the pairs' ends, listed once)
  std::vector<int> colliding_particles;
  std::vector<CollisionPair> collision_pairs;
  // Self-collision candidates: pairs (i < j, sorted) whose anchors are within
  // candidates_radius; the particles searched again this step, and their flags
  // (zero between steps).
  std::vector<std::array<int, 2>> candidates;
  std::vector<std::array<int, 2>> candidates_merged;  // the movers' new pairs, merged in
  std::vector<int> candidate_movers;
  std::vector<std::uint8_t> candidate_moved;
  // Particles anchored again since the hash was built (its entries for them
  // are out of date), and their flags.
  std::vector<int> hash_stale;
  std::vector<std::uint8_t> hash_stale_flag;
  std::vector<std::vector<std::array<int, 2>>>
      thread_candidates;                      // each thread's share of the search
  std::vector<std::uint8_t> candidate_close;  // candidate within d_t this step
  // Where each particle was last searched from, taken back through the
  // cloth's rigid motion then; the rigid motion at the last refresh, x ≈ R a
  // + c (each particle is within margin / 2 of its anchor moved by it).
  Vec3Array candidates_anchor;
  Eigen::Matrix3d candidates_rotation = Eigen::Matrix3d::Identity();
  Vec3 candidates_motion = Vec3::Zero();
  double candidates_radius = 0;
  // Implicit Euler, in columns (see integrators/implicit_euler.cpp): in float, the
  // blocks of the matrix's forward stencil edges that have a constant, the
  // block-Jacobi preconditioner and the flags of the particles held on the
  // surface; in double, the conjugate-gradient vectors and the
  // matrix's diagonal blocks; per-row sums; the particles whose velocity the
  // solve keeps (pinned, driven, held).
  std::vector<float> float_columns;
  std::vector<float> mesh_blocks;  // a mesh cloth: each spring's block (s_x, s_y, s_z, β)
  std::vector<double> cg_columns;
  std::vector<int> fixed_particles;
  std::vector<double> row_sums, row_max;
  double bending_h2 = 0;              // implicit Euler: the substep's h², Q's factor in its matrix
  int cg_iterations = 0;              // of the last implicit solve
  long long cg_iterations_total = 0;  // of every implicit solve since reset
  // Implicit Euler's step control: velocities at the start of a try; substeps
  // taken since reset (one a step for the other integrators), and solves (the
  // tries thrown away included).
  Vec3Array v_start;
  long long substeps = 0, solves = 0;
  // XPBD (integrators/xpbd.cpp): positions at the start of the substep, before contact;
  // the inverse masses the constraints see; a mesh cloth's flags of the
  // particles the measured handle holds; those particles and the
  // constraints' impulse on them over the substep.
  Vec3Array x_prev, x_before_collide;
  Vec3Array surface_velocity;  // moving surfaces: the one each particle touches, m/s
  std::vector<double> free_inv_mass, reaction_flag;
  std::vector<int> reaction_particles;
  Vec3 reaction_impulse = Vec3::Zero();
  // The choice of the step's threads, kept by reset (Simulation::step).
  ThreadChoice threads;
  // The viewer's hand (Simulation::grab), copied in from the Simulation.
  int grab_particle = -1;
  Vec3 grab_target = Vec3::Zero();
  double grab_k = 0;
};

}  // namespace wetcloth
