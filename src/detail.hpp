// Internal: the stages of one step (docs/model.md section 8), one file each.
#pragma once

#include <omp.h>

#include <algorithm>
#include <array>
#include <limits>
#include <type_traits>

#include "geometry/mesh_obstacle.hpp"
#include "model/topology.hpp"
#include "wetcloth/simulation.hpp"
#include "workspace.hpp"

namespace wetcloth {

struct TriangleMesh;
// model/mesh_cloth.cpp: a cloth from cloth.mesh (Model::grid false): particles,
// areas, springs, neighbour lists (into t); where its vertices start (the file's
// bounding box's centre at cloth.center, then orientation and tilt); a
// handle's particles, placed by the texture coordinates.
void build_mesh_cloth(Model& m, Topology& t, const Params& p);
std::vector<Vec3> mesh_cloth_positions(const Params& p, const TriangleMesh& mesh);
std::vector<int> mesh_handle_particles(const Model& m, const HandleParams& h);
// handle.NAME.vertices read (its list, or its file) and checked against the
// cloth's n particles: sorted, each once. Throws SceneError naming the key,
// and a file's name and line.
std::vector<int> handle_vertex_indices(const Params& p, const std::string& name, int n);
// The same for every handle of a loaded scene (source: the scene file).
void check_handle_vertices(const Params& p, const std::string& source);
// A scene's cloth.mesh read and placed: throws SceneError naming the scene
// file (source), the mesh file and what is wrong with it.
void check_cloth_mesh(const Params& p, const std::string& source);

}  // namespace wetcloth

namespace wetcloth::detail {

// water/humidity.cpp: the humidity field (docs/model.md "Humidity field").
// ω at t = 0 per particle (cloth.humidity, cloth.humidity_map, [wet.NAME]);
// the wicking's Laplacian into t; cloth.humidity_map read to check it
// (throws SceneError naming source, the file and the key).
std::vector<double> initial_humidity(const Model& m, const Params& p);
void build_wicking(const Model& m, Topology& t);
void check_humidity_map(const Params& p, const std::string& source);
// Wicking runs every wicking_steps(dt) steps (a step of at least
// kWickingInterval, 1 ms, measured within 1e-4 of wicking every step).
constexpr double kWickingInterval = 1e-3;
long long wicking_steps(double dt);
// One backward-Euler step of wicking over τ = D Δt on the field c (ω), in place.
void wick(const Model& m, std::vector<double>& c, HumidityScratch& h, double tau);
// The contact surface's film depth, m (table.water_film, ball.water_film).
double film_depth(const Model& m);
// The field and the film at the start; the scratch's note of a uniform field
// (after the field is set from outside).
void start_humidity(const Model& m, State& s, Workspace& w);
// The film alone: ρ_w h A_i of water under each particle (none with h = 0).
void start_film(const Model& m, State& s);
void note_humidity_changed(const State& s, Workspace& w);
// Once a step of dt: uptake from the film, drying, wicking; the masses follow.
// Returns whether the field changed.
bool update_humidity(Model& m, State& s, Workspace& w, double dt);

// A simulation's scratch, for the library's stages, its tests and benchmarks.
inline Workspace& workspace(const Simulation& sim) { return detail_workspace(sim); }
// Its state, to change (the public API reads it; tests set up cases in it).
inline State& state(Simulation& sim) { return detail_state(sim); }

constexpr double kInf = std::numeric_limits<double>::infinity();

// Signed distance and outward normal of the table and the ball (inline: the
// stages that touch a surface ask it once per particle).
struct SurfaceHit {
  double distance = kInf;
  Vec3 normal = Vec3::UnitZ();
};
inline SurfaceHit query_surface(const Params& p, SurfaceKind kind, const Vec3& x) {
  SurfaceHit h;
  if (kind == SurfaceKind::Table) {
    h.distance = x.z() - p.table.height;
    h.normal = Vec3::UnitZ();
  } else if (kind == SurfaceKind::Ball) {
    const Vec3 r = x - to_vec(p.ball.center);
    const double len = r.norm();
    h.distance = len - p.ball.radius;
    h.normal = len > 0 ? Vec3(r / len) : Vec3::UnitZ();
  }
  return h;
}

// contact/surfaces.cpp: collide's projection out of the mesh obstacles alone, after
// friction moved particles along a curved mesh (a chord of it dips inside).
void collide_with_meshes(const Model& m, State& s, Workspace& w);

// Moving surfaces (docs/model.md section 3): the poses of the ball and the mesh
// obstacles at time t, into w.surfaces. Every stage that asks a surface
// asks it where it is at the time the state has reached: the step places
// them at its end (a substep's, in xpbd) before it collides.
void place_surfaces(const Model& m, Workspace& w, double t);

// The pose of the surface a byte names (SurfaceKind, or kMeshCode + k), or
// null for one that stands still.
inline const RigidPose* pose_of(const SurfacePoses& poses, int code) {
  const RigidPose* pose = nullptr;
  if (code == static_cast<int>(SurfaceKind::Ball)) pose = &poses.ball;
  if (code >= kMeshCode && code - kMeshCode < static_cast<int>(poses.obstacles.size()))
    pose = &poses.obstacles[code - kMeshCode];
  return pose && pose->moving ? pose : nullptr;
}

// Mesh obstacle k's shape now: a deforming one's, or the model's.
inline const MeshObstacle& mesh_of(const Model& m, const SurfacePoses& poses, int k) {
  const auto u = static_cast<std::size_t>(k);
  return u < poses.shapes.size() && poses.shapes[u] ? *poses.shapes[u] : *m.obstacles[u];
}

// The table and the ball where they are now: the ball's centre moved by its
// motion (it turns about its centre: its distances do not change with it).
inline SurfaceHit query_surface(const Params& p, const SurfacePoses& poses, SurfaceKind kind,
                                const Vec3& x) {
  if (kind != SurfaceKind::Ball || !poses.ball.moving) return query_surface(p, kind, x);
  return query_surface(p, kind, Vec3(x - poses.ball.shift));
}

// A mesh obstacle's hit where it is now: the query in its body frame (the
// tree built once, where its keys place it; a rigid motion moves the
// particle instead, which costs a 3 x 3 product where a rebuild costs the
// whole tree), the normal turned back. The cache holds body-frame positions,
// so its bounds hold as the obstacle moves.
inline MeshObstacle::Hit query_mesh(const MeshObstacle& o, const RigidPose* pose, const Vec3& x,
                                    double reach, MeshQueryCache* cache, int i) {
  if (!pose) return query_mesh(o, x, reach, cache, i);
  MeshObstacle::Hit h = query_mesh(o, pose->to_body(x), reach, cache, i);
  h.normal = pose->rotation * h.normal;
  return h;
}

// Any surface by its byte (SurfaceKind, or kMeshCode + k for obstacle k),
// exactly (a whole search of a mesh): for what is asked once in a while.
inline SurfaceHit query_code(const Model& m, int code, const Vec3& x) {
  if (code < kMeshCode) return query_surface(m.params, static_cast<SurfaceKind>(code), x);
  const MeshObstacle::Hit h = m.obstacles[code - kMeshCode]->query(x);
  return {h.distance, h.normal};
}
// The same where the surfaces are now.
inline SurfaceHit query_code(const Model& m, const SurfacePoses& poses, int code, const Vec3& x) {
  const RigidPose* pose = pose_of(poses, code);
  if (!pose) return query_code(m, code, x);
  if (code < kMeshCode) return query_surface(m.params, poses, static_cast<SurfaceKind>(code), x);
  const MeshObstacle::Hit h = mesh_of(m, poses, code - kMeshCode).query(pose->to_body(x));
  return {h.distance, pose->rotation * h.normal};
}

// The velocity of the surface a byte names at x (zero where it stands
// still): friction (eq. 14) and the inelastic contact act on the cloth's
// velocity relative to it. A deforming mesh's adds its vertices' velocity at
// the point of it nearest x (a search of its tree), turned by its pose.
inline Vec3 surface_velocity(const SurfacePoses& poses, int code, const Vec3& x) {
  const RigidPose* pose = pose_of(poses, code);
  if (!pose) return Vec3::Zero();
  Vec3 v = pose->velocity_at(x);
  const auto k = static_cast<std::size_t>(code - kMeshCode);
  if (code >= kMeshCode && k < poses.shapes.size() && poses.shapes[k]) {
    // Asked of particles on or near the surface: a search within 1 cm of it
    // first (the same answer, but for ties), the whole tree past that.
    const MeshObstacle& o = *poses.shapes[k];
    const Vec3 xb = pose->to_body(x);
    MeshObstacle::Hit h = o.query_within(xb, o.half_thickness + 0.01);
    if (h.triangle < 0) h = o.query(xb);
    v += pose->rotation * surface_velocity_at(o, h);
  }
  return v;
}

// contact/surfaces.cpp: projects particles out of every obstacle and removes inward normal
// velocity. touched[i] is the obstacle it was pushed out of (SurfaceKind, or kMeshCode
// + k for mesh obstacle k), or None.
// With `only`, just those particles (the others are known to be outside).
// With a workspace, mesh obstacles' searches are bounded by its cache.
void collide(const Model& m, State& s, std::vector<std::uint8_t>* touched,
             const std::vector<int>* only = nullptr, Workspace* w = nullptr);
// The same over particles [first, end), for a region of for_each_row_block
// (prepare_contact before it, with a workspace).
void collide(const Model& m, State& s, std::vector<std::uint8_t>* touched, Workspace* w, int first,
             int end);
// forces/normals.cpp: compute_normals from positions by component (x, y, z
// columns of n), with a scratch array for the triangles' normals (the step's:
// no allocation).
void compute_normals(const Model& m, const double* x_columns, Vec3Array& normal,
                     NormalsScratch& scratch);
// A grid's, in two parts, as the springs'.
void prepare_normals(const Model& m, NormalsScratch& scratch);
void compute_normal_rows(const Model& m, const double* x_columns, Vec3Array& normal,
                         NormalsScratch& scratch, int j0, int j1, int thread);
// Distances to the contact surface, contact flags and the contact border.
void update_contact(const Model& m, State& s, Workspace& w);
// In parts, for a region of for_each_row_block: the mesh caches made ready
// (before it), the distances and flags of particles [first, end), and the
// border of rows [j0, j1) (once every row's flags are in).
void prepare_contact(const Model& m, Workspace& w);
void update_contact(const Model& m, State& s, Workspace& w, int first, int end);
void mark_contact_border(const Model& m, const State& s, Workspace& w, int j0, int j1);

// Runs body(r) for r in [0, count) on the step's threads, in fixed static
// chunks. Bodies write only their own rows, so the result never depends on
// the number of threads.
// On one thread, no region: libgomp makes (and allocates) a team even for a
// region its `if` turns off, about 2 000 instructions with the malloc and
// free, and an xpbd step ran some 350 regions, most of them these. The loop is called, not inlined,
// as the region's outlined function is: inlined into the stage, some loops vectorised worse.
template <class Body>
[[gnu::noinline]] void serial_for(int count, Body& body) {
  for (int r = 0; r < count; ++r) body(r);
}

template <class Body>
void parallel_for(const Model& m, int count, Body&& body) {
  if (m.threads <= 1) return serial_for(count, body);
#pragma omp parallel for schedule(static) num_threads(m.threads)
  for (int r = 0; r < count; ++r) body(r);
}

// Runs body(j0, j1, thread) on each of the step's threads, for its own block
// of rows [j0, j1): for passes that carry something from row to row.
// On one thread, called as serial_for calls its body: inlined into the stage,
// the wind's loop took four times the instructions; and a region, even one
// its `if` turns off, cost a futex call (17 a symplectic step at 51 x 51,
// about a sixth of its CPU time).
template <class Body>
[[gnu::noinline]] void serial_block(int rows, Body& body) {
  body(0, rows, 0);
}

template <class Body>
void for_each_row_block(const Model& m, Body&& body) {
  if (m.threads <= 1) return serial_block(m.nv, body);
#pragma omp parallel num_threads(m.threads)
  {
    const int t = omp_get_thread_num(), count = omp_get_num_threads();
    body(m.nv * t / count, m.nv * (t + 1) / count, t);
  }
}

// Inside for_each_row_block's body: each thread waits until every thread has
// got here, so that the rows the others wrote before it can be read. None on
// one thread, which runs no region: a barrier there would bind to a caller's
// own parallel region.
inline void wait_for_all_rows(const Model& m) {
  if (m.threads > 1) {
#pragma omp barrier
  }
}

// Runs body(first, end) on each thread's own particles, whole rows: for a
// pass in which each particle stands alone, one loop across the rows (a loop
// per row of 51 ends in a scalar tail).
template <class Body>
void for_each_particle_block(const Model& m, Body&& body) {
  for_each_row_block(m, [&](int j0, int j1, int) {
    if (j0 < j1) body(j0 * m.nu, j1 * m.nu);
  });
}

// Runs body(first, end) on each thread's own particles, in chunks of 1024:
// for passes that run several loops over the same particles, each loop
// finding the chunk's columns (8 KB each) in cache from the one before.
constexpr int kCachedParticles = 1024;
template <class Body>
void for_each_particle_chunk(const Model& m, Body&& body) {
  for_each_particle_block(m, [&](int first, int end) {
    for (int a = first; a < end; a += kCachedParticles)
      body(a, std::min(end, a + kCachedParticles));
  });
}

// Runs body(i) for every particle, whole rows to each thread.
template <class Body>
void for_each_particle(const Model& m, Body&& body) {
  parallel_for(m, m.nv, [&](int j) {
    for (int i = j * m.nu; i < (j + 1) * m.nu; ++i) body(i);
  });
}

// One particle's Vec3 written component by component: to = v, to += v,
// to -= v. Eigen stores a Vec3 through its packet type, which may alias
// anything, so after each such store the compiler reloads every pointer and
// bound of the loop and does not vectorise it (BM_gravity shows the
// difference). Each component is the same arithmetic, so the same bits.
// (A strided view of a Vec3Array takes the same path.)
template <class To, class E>
void put(To&& to, const Eigen::MatrixBase<E>& v) {
  for (int k = 0; k < 3; ++k) to.coeffRef(k) = v.coeff(k);
}
template <class To, class E>
void add(To&& to, const Eigen::MatrixBase<E>& v) {
  for (int k = 0; k < 3; ++k) to.coeffRef(k) += v.coeff(k);
}
template <class To, class E>
void sub(To&& to, const Eigen::MatrixBase<E>& v) {
  for (int k = 0; k < 3; ++k) to.coeffRef(k) -= v.coeff(k);
}

// A loop that reads byte flags along with doubles is vectorised a vector of
// bytes (64 particles) at a time, so a row of 51 would run in its scalar tail.
// Such loops take particles [begin, end) in chunks of at most kChunk:
// value(i) (a double made from the flags, in a scalar loop) into
// chunk_values[i - i0], then body(i0, count, chunk_values), whose loop over
// doubles alone vectorises 8 at a time.
constexpr int kChunk = 64;
template <class Value, class Body>
void for_each_chunk(int begin, int end, Value&& value, Body&& body) {
  for (int i0 = begin; i0 < end; i0 += kChunk) {
    const int count = std::min(kChunk, end - i0);
    double chunk_values[kChunk];
    for (int k = 0; k < count; ++k) chunk_values[k] = value(i0 + k);
    body(i0, count, chunk_values);
  }
}

// The largest value(i) over the particles: a maximum, so the same for any
// split between threads.
template <class Value>
double max_over_particles(const Model& m, Value&& value) {
  double worst = -std::numeric_limits<double>::infinity();
  if (m.threads <= 1) {
    for (int i = 0; i < m.n; ++i) worst = std::max(worst, value(i));
    return worst;
  }
#pragma omp parallel for reduction(max : worst) num_threads(m.threads)
  for (int i = 0; i < m.n; ++i) worst = std::max(worst, value(i));
  return worst;
}

// Σ over rows of row(j), K sums at once (row(j) returns std::array<double, K>):
// the rows' sums added in order, so the same bits for any number of threads.
// Uses w.row_sums.
template <std::size_t K, class Row>
std::array<double, K> ordered_sums(const Model& m, Workspace& w, Row row) {
  w.row_sums.resize(K * std::size_t(m.nv));
  parallel_for(m, m.nv, [&](int j) {
    const std::array<double, K> sums = row(j);
    std::copy(sums.begin(), sums.end(), w.row_sums.begin() + K * std::size_t(j));
  });
  std::array<double, K> total{};
  for (int j = 0; j < m.nv; ++j)
    for (std::size_t k = 0; k < K; ++k) total[k] += w.row_sums[K * std::size_t(j) + k];
  return total;
}

// ordered_sums inside for_each_row_block's body, for its rows [j0, j1):
// each thread's rows into w.row_sums (sized K nv before the region), a wait,
// then every thread adds all the rows in order. Each gets the same total, with
// the bits of ordered_sums; w.row_sums must not be written again in the region.
template <std::size_t K, class Row>
std::array<double, K> ordered_sums_in_rows(const Model& m, Workspace& w, int j0, int j1, Row row) {
  for (int j = j0; j < j1; ++j) {
    const std::array<double, K> sums = row(j);
    std::copy(sums.begin(), sums.end(), w.row_sums.begin() + K * std::size_t(j));
  }
  wait_for_all_rows(m);
  std::array<double, K> total{};
  for (int j = 0; j < m.nv; ++j)
    for (std::size_t k = 0; k < K; ++k) total[k] += w.row_sums[K * std::size_t(j) + k];
  return total;
}

template <class Row>
double ordered_sum(const Model& m, Workspace& w, Row row) {
  return ordered_sums<1>(m, w, [&](int j) { return std::array<double, 1>{row(j)}; })[0];
}

// The particle at grid cell (i + di, j + dj), or -1 off the grid.
inline int grid_neighbour(const Model& m, int i, int j, int di, int dj) {
  const int a = i + di, b = j + dj;
  return a >= 0 && b >= 0 && a < m.nu && b < m.nv ? m.index(a, b) : -1;
}

// forces/*.cpp: each adds its force into w.force.
// Springs: with_damping adds eq. 1's damping too (explicit Euler); without it,
// only the elastic part. Implicit Euler takes the damping into its matrix, the
// symplectic step takes it with apply_spring_damping, after its velocity
// update and before the move.
// The springs explicit_step_limit looks at, for a blow-up message:
// "structural 200 N/m, shear 20 N/m, bending 20 N/m".
std::string step_limit_springs_text(const Params& p);
// The springs set w.force: they are the step's first force.
void set_spring_forces(const Model& m, const State& s, Workspace& w, bool with_damping);
// A grid's, in two parts: its scratch made ready (before the region), then a
// thread's block of rows [j0, j1) (inside for_each_row_block's body).
void prepare_spring_rows(const Model& m, Workspace& w);
void set_spring_force_rows(const Model& m, const State& s, Workspace& w, bool with_damping, int j0,
                           int j1, int thread);
// The general kernels of a mesh cloth (model/mesh_cloth.cpp), where the grid has its stencil's.
void add_spring_forces_mesh(const Model& m, const State& s, Workspace& w, bool damped);
void apply_spring_damping_mesh(const Model& m, State& s, double h);
void compute_normals_mesh(const Model& m, const double* X, Vec3Array& normal);
void contact_border_mesh(const Model& m, const State& s, Workspace& w);
// A reference to the caller's body(first, end), which outlives the call:
// std::function would allocate, inside the step, for a lambda of more than
// two captures.
class ParticleChunks {
 public:
  ParticleChunks() = default;
  template <class Body>
  requires(!std::is_same_v<std::decay_t<Body>, ParticleChunks>)
      ParticleChunks(Body&& body)  // implicit, as std::function's
      : body_(const_cast<void*>(static_cast<const void*>(&body))),
        call_([](void* b, int first, int end) {
          (*static_cast<std::remove_reference_t<Body>*>(b))(first, end);
        }) {}
  explicit operator bool() const { return call_ != nullptr; }
  void operator()(int first, int end) const { call_(body_, first, end); }

 private:
  void* body_ = nullptr;
  void (*call_)(void*, int, int) = nullptr;
};
// Eq. 1's damping over h, implicitly (forces/springs.cpp). `before` runs on
// each chunk of particles before the damping reads its velocities, `after`
// once the damping has changed them, each in the damping's own passes: the
// symplectic step's velocity update and move, which had cost two passes and
// two parallel regions of their own.
void apply_spring_damping(const Model& m, State& s, Workspace& w, double h,
                          const ParticleChunks& before = {}, const ParticleChunks& after = {});
// forces/bending.cpp: the quadratic bending's Q from the rest triangles (each
// split's triangles counted 1 / splits), rigidity B; for a model, its grid
// split both ways or its mesh's triangles. The force -Q x into f, and the
// energy ½ xᵀ Q x.
BendingMatrix build_bending_matrix(const std::vector<Vec3>& rest,
                                   const std::vector<std::vector<std::array<int, 3>>>& splits,
                                   const std::vector<std::uint8_t>& on_border, double rigidity);
BendingMatrix build_bending_matrix(const Model& m, double rigidity);
void add_bending_forces(const Model& m, const State& s, Vec3Array& f);
void add_bending_forces(const Model& m, const State& s, Vec3Array& f, int first, int end);
void bending_forces(const Model& m, const State& s, Vec3Array& f);  // f = -Q x
// y_i += scale Σ_j≠i Q_ij x_j for i in [a0, a1): implicit Euler's product.
void add_bending_off_diagonal(const Model& m, const double* x, double* y, double scale, int a0,
                              int a1);
double bending_energy(const Model& m, const Vec3Array& x);
// The forces each particle feels from its own state, over particles
// [first, end): gravity (forces/gravity.cpp), the viscous drag
// (viscous_damping.cpp), the wind and the still air's drag (wind.cpp).
void add_gravity(const Model& m, Vec3Array& f, int first, int end);
void set_gravity(const Model& m, Vec3Array& f, int first, int end);  // f = 0 + m g
void add_viscous_damping(const Model& m, const State& s, Vec3Array& f, int first, int end);
void add_wind(const Model& m, const State& s, const Workspace& w, Vec3Array& f, int first, int end);
// The three into w.force in one pass (the viscous drag with `viscous`), a
// chunk of kCachedParticles at a time: a pass and a parallel region each had
// cost 1-2 % of the step. With `zero_first`, gravity is w.force's first term
// (no pass to zero it: memset had been 2.6 % of xpbd's substep at 201 x 201,
// 0.7 % now, for 0.7 % more in gravity's pass). Over
// particles [first, end), or (the second) the whole cloth.
inline void add_own_forces(const Model& m, const State& s, Workspace& w, bool viscous,
                           bool zero_first, int first, int end) {
  for (int a = first; a < end; a += kCachedParticles) {
    const int b = std::min(end, a + kCachedParticles);
    if (zero_first)
      set_gravity(m, w.force, a, b);
    else
      add_gravity(m, w.force, a, b);
    if (viscous) add_viscous_damping(m, s, w.force, a, b);
    add_wind(m, s, w, w.force, a, b);
  }
}
inline void add_own_forces(const Model& m, const State& s, Workspace& w, bool viscous,
                           bool zero_first) {
  for_each_particle_block(
      m, [&](int first, int end) { add_own_forces(m, s, w, viscous, zero_first, first, end); });
}
// The trapped air's pressure (air/air.cpp) and the liquid bridges' adhesion
// (adhesion.cpp); the first over particles [first, end), the second over rows
// [j0, j1) inside for_each_row_block's body, w.row_sums sized 2 nv before it
// (it waits for every thread's rows: its ordered sums).
void add_air_pressure(const Model& m, const State& s, Workspace& w, int first, int end);
void add_air_pressure(const Model& m, const State& s, Workspace& w);
void add_adhesion_rows(const Model& m, const State& s, Workspace& w, int j0, int j1);
void add_adhesion(const Model& m, const State& s, Workspace& w);
// Self-collision records its pairs in w.collision_pairs; with_damping adds the
// -k_f v of colliding particles (implicit Euler takes it into its matrix).
void add_self_collision(const Model& m, const State& s, Workspace& w, bool with_damping);
// Eq. 15's k_t and k_f as a pair and a particle of this cloth feel them: on a
// grid finer than self_collision.spacing (the paper's 6 mm), a pair's
// stiffness scales as the product of the particles' areas and a particle's
// damping as its area, so that two layers press on and damp each other
// alike on every grid (docs/model.md section 7). A coarser cloth, or a
// spacing of 0, keeps them as given.
struct CollisionConstants {
  double k, damping;
};
inline CollisionConstants collision_constants(const Model& m) {
  const auto& p = m.params.self_collision;
  const double ref = p.spacing * p.spacing, area = m.spacing * m.spacing;
  const double scale = ref > 0 && area < ref ? area / ref : 1.0;
  return {p.k * scale * scale, p.damping * scale};
}
void add_handle_forces(const Model& m, const State& s, Workspace& w);

// air/air.cpp: the trapped air starts as the volume under the cloth at
// atmospheric pressure; update_air advances it over dt (eqs. 2, 4, 5).
void start_air(const Model& m, State& s, Workspace& w);
void update_air(const Model& m, State& s, Workspace& w, double dt);
// update_contact, then update_air (in one parallel region on a grid).
void update_contact_and_air(const Model& m, State& s, Workspace& w, double dt);
// The air term taken implicitly, after the explicit velocity update; with
// `move`, after the constraints, moving the free particles by Δt times the
// velocity it changes (the symplectic step's order). False: no air to take.
// `after` runs on each thread's particles once the air has changed them (not
// at all when there was no air to take).
bool correct_air_implicitly(const Model& m, State& s, Workspace& w, double dt, bool move = false,
                            const ParticleChunks& after = {});
// integrators/explicit_euler.cpp: forward Euler (x, then v) and symplectic
// Euler (v with the damping, then x) over dt, from the forces in w.force.
void integrate_explicit_euler(const Model& m, State& s, Workspace& w, double dt);
void integrate_symplectic_euler(const Model& m, State& s, Workspace& w, double dt);
// The air term taken implicitly on the new velocities, then x += h v.
void move_at_new_velocities(const Model& m, State& s, Workspace& w, double h);
// integrators/step_control.cpp: backward Euler over dt / 2^k, k raised while
// the springs change more than integrator.max_step_strain; returns the
// substep taken, and its springs' largest change in `strain`.
double implicit_euler_substep(const Model& m, State& s, Workspace& w, double dt, int& k,
                              double& strain);
// integrators/xpbd.cpp: one step of XPBD, in xpbd_substeps substeps.
void xpbd_step(const Model& m, State& s, Workspace& w);
// integrators/implicit_euler.cpp: the new velocities by backward Euler (s.v in, s.v out),
// from the forces in w.force without their damping.
void implicit_euler_velocities(const Model& m, State& s, Workspace& w, double h);
// A particle this close to the contact surface is on it, m, and the solve
// holds it there when the forces press it in: collide puts it at 0, and held
// on a ball it drifts off by (v h)² / 2R a substep, 1 µm at 0.1 m/s and
// 1/240 s on the 8 cm ball. A hundredth of the default liquid bridge.
constexpr double kOnSurface = 1e-5;
// The largest change of a structural or shear spring over a step of h at the
// velocities s.v, relative to its rest length: the step control's measure.
double step_strain(const Model& m, const State& s, double h);
// The most halvings of dt the step control makes: substeps of dt / 1024.
constexpr int kMostHalvings = 10;
// constraints/handles.cpp: pins, driven particles, height caps; records the rig's force.
void apply_handle_constraints(const Model& m, State& s, Workspace& w);
// After limit_strain: the force it took to hold the measured handle's particles
// against the limiter's corrections joins the handle's recorded force.
void add_strain_limit_reaction(const Model& m, const State& s, Workspace& w);
// Keeps held particles where their handle has them: a force handle's where it
// stopped, a late pin's or move handle's on its path.
void hold_stopped_handles(const Model& m, State& s);
// constraints/friction.cpp: eq. 14 on particles in contact.
void apply_friction(const Model& m, State& s, const Workspace& w,
                    const std::vector<std::uint8_t>& touched, double dt);
// The same over particles [first, end) (each stands alone).
void apply_friction(const Model& m, State& s, const Workspace& w,
                    const std::vector<std::uint8_t>& touched, double dt, int first, int end);
// The self-collision candidate pairs (a Verlet list in w.candidates), found again
// where particles moved from their anchors.
void refresh_collision_candidates(const Model& m, const State& s, Workspace& w);
// integrators/xpbd.cpp: one substep's constraint projections, contact and friction.
void xpbd_begin_substep(const Model& m, const State& s, Workspace& w);
// One sweep over the springs; limit_only: over the strain limit alone.
void project_springs(const Model& m, State& s, Workspace& w, double h, bool limit_only = false);
void project_self_collision(const Model& m, State& s, Workspace& w, double h);
void collide_with_friction(const Model& m, State& s, Workspace& w,
                           std::vector<std::uint8_t>& touched, double h);
// constraints/strain_limit.cpp: Provot's correction in adaptive order, split by inverse
// mass (it conserves momentum); the force it takes to hold pinned, driven and
// held particles against it in w.strain_reaction.
void update_strain_order(const Model& m, State& s, Workspace& w);
void limit_strain(const Model& m, State& s, Workspace& w, double dt);
// Spring e of the adaptive order (w.strain_slots): a mesh cloth's from its
// list, a grid's from its stencil slot, 4 × its lower end + its offset.
inline Workspace::StrainSpring strain_spring(const Model& m, const Workspace& w, int e) {
  const int slot = w.strain_slots[e];
  if (!m.grid) return w.strain_springs[slot];
  const int a = slot / 4;
  const StencilEdge& st = m.topology->stencil[slot % 4];
  return {a, a + st.di + st.dj * m.nu, (1.0 + m.params.strain_limit.tau) * st.rest, slot};
}

}  // namespace wetcloth::detail
