// The wet cloth: a read-only Model (grid, springs, areas, parameters), a
// copyable State (positions, velocities, trapped air, contact flags), and a
// Workspace of scratch arrays. Simulation ties them together and runs the
// step of docs/model.md section 8.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cstdint>
#include <functional>
#include <initializer_list>
#include <memory>
#include <string>
#include <vector>

#include "wetcloth/params.hpp"

namespace wetcloth {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;

inline Vec3 to_vec(const Vec3d& a) { return {a[0], a[1], a[2]}; }

// n 3-vectors held by component: every x, then every y, then every z. A loop
// over particles then reads each component contiguously and the compiler
// vectorises it, which it cannot do over an array of Vec3 (three interleaved
// doubles). a[i] is particle i's vector as a strided view that reads and
// writes like a Vec3; column(k) is component k of all of them. (Eigen sums a
// view's dot product as x + (y + z), a Vec3's as (x + y) + z; the loops over
// columns sum as a Vec3 does.)
class Vec3Array {
 public:
  using Ref = Eigen::Map<Vec3, Eigen::Unaligned, Eigen::InnerStride<>>;
  using ConstRef = Eigen::Map<const Vec3, Eigen::Unaligned, Eigen::InnerStride<>>;

  Vec3Array() = default;
  explicit Vec3Array(std::size_t n, const Vec3& value = Vec3::Zero()) { assign(n, value); }
  explicit Vec3Array(const std::vector<Vec3>& v) : Vec3Array(v.size()) {
    for (std::size_t i = 0; i < v.size(); ++i) (*this)[i] = v[i];
  }
  Vec3Array(std::initializer_list<Vec3> v) : Vec3Array(std::vector<Vec3>(v)) {}
  void assign(std::size_t n, const Vec3& value) {
    n_ = n;
    data_.resize(3 * n);
    for (int k = 0; k < 3; ++k) std::fill_n(data_.begin() + k * n, n, value[k]);
  }
  std::size_t size() const { return n_; }
  bool empty() const { return n_ == 0; }
  Ref operator[](std::size_t i) { return Ref(data_.data() + i, Eigen::InnerStride<>(n_)); }
  ConstRef operator[](std::size_t i) const {
    return ConstRef(data_.data() + i, Eigen::InnerStride<>(n_));
  }
  // Range-for yields the views: for (const Vec3& x : a) copies each one.
  template <class Array, class View>
  struct Iterator {
    Array* array;
    std::size_t i;
    View operator*() const { return (*array)[i]; }
    Iterator& operator++() {
      ++i;
      return *this;
    }
    bool operator==(const Iterator& o) const { return i == o.i; }
  };
  Iterator<Vec3Array, Ref> begin() { return {this, 0}; }
  Iterator<Vec3Array, Ref> end() { return {this, n_}; }
  Iterator<const Vec3Array, ConstRef> begin() const { return {this, 0}; }
  Iterator<const Vec3Array, ConstRef> end() const { return {this, n_}; }
  double* column(int k) { return data_.data() + k * n_; }
  const double* column(int k) const { return data_.data() + k * n_; }
  bool operator==(const Vec3Array&) const = default;

 private:
  std::size_t n_ = 0;
  std::vector<double> data_;
};

// One kind of spring (structural, shear or bending), as flat arrays.
struct SpringSet {
  std::vector<int> a, b;
  std::vector<double> rest;
  // Each spring's stiffness (N/m) and damping (N·s/m): on the grid its
  // offset's, on a mesh cloth from the material and the local geometry.
  std::vector<double> k, damping;
  std::size_t size() const { return a.size(); }
};

struct Handle {
  std::string name;
  HandleType type = HandleType::Force;
  std::vector<int> particles;
  Vec3 force = Vec3::Zero();  // total; particle e gets share[e] of it
  std::vector<double> share;  // A_i / Σ A: the same acceleration over the patch
  Vec3 velocity = Vec3::Zero();
  double max_height = 0, max_travel = 0;
  double start = 0;
  std::vector<Vec3> anchor;  // positions at t = 0 (move, pin)
};

// Mesh: an [obstacle.NAME] (Model::obstacles). Where a byte names the
// surface a particle touched, obstacle k is kMeshCode + k.
enum class SurfaceKind { None, Table, Ball, Mesh };
constexpr int kMeshCode = 3;
constexpr int kMostObstacles = 250;  // codes up to 252 fit a byte
// A triangle-mesh obstacle, built (src/geometry/mesh_obstacle.hpp).
struct MeshObstacle;

// What the step's kernels derive from the cloth (the grid's stencil, a mesh
// cloth's neighbour lists): private to the library (src/model/topology.hpp).
struct Topology;

struct Model {
  Params params;
  // The rectangular grid (cloth.mesh unset): particle (i, j) is j nu + i, and
  // the step runs the grid's stencil kernels. A mesh cloth (cloth.mesh,
  // src/model/mesh_cloth.cpp) has grid = false, nu = n, nv = 1 (one row: the passes in
  // which each particle stands alone run unchanged) and runs the general
  // kernels, which follow the springs and the neighbour lists below, on one
  // thread.
  bool grid = true;
  int nu = 0, nv = 0, n = 0;
  // Texture coordinates per particle: (i, j) / (nu - 1, nv - 1) on the grid,
  // the file's on a mesh (handles and the wind region are placed by them).
  std::vector<std::array<double, 2>> uv;
  double spacing = 0;  // the grid's smaller step; a mesh's shortest mean edge, m
  std::vector<Vec3> rest_position;
  std::vector<double> area, mass, inv_mass;
  std::vector<std::uint8_t> on_border;  // on the cloth's border
  std::vector<std::uint8_t> driven;     // pinned or moved from t = 0: dynamics never moves it
  // ω of each particle at t = 0: cloth.humidity, or cloth.humidity_map's
  // value, then each [wet.NAME] region's (docs/model.md "Humidity field").
  // The field then lives in State::humidity; mass and inv_mass follow it.
  std::vector<double> initial_humidity;
  std::vector<std::uint8_t> in_wind;  // inside the wind region
  // A mesh cloth's springs. Empty on the grid, whose stencil is all of its
  // springs (128 B a particle kept out of a large grid's memory):
  // spring_set and for_each_spring give any cloth's.
  SpringSet structural, shear, bending;
  int threads =
      1;  // threads of the step (integrator.threads resolved; the bits do not depend on it)
  std::vector<std::array<int, 3>> triangles;
  std::shared_ptr<const Topology> topology;
  std::vector<Handle> handles;
  int measured_handle = -1;  // the one the metrics follow: the first that is not a pin, else the
                             // first pin (-1: no handle)
  SurfaceKind contact_surface = SurfaceKind::None;
  // The [obstacle.NAME] tables, in name order, transformed and ready to query;
  // contact_obstacle: the one that is the contact surface (-1: none).
  std::vector<std::shared_ptr<const MeshObstacle>> obstacles;
  int contact_obstacle = -1;
  // The byte that names the contact surface (SurfaceKind, or kMeshCode + k).
  std::uint8_t contact_code() const {
    return static_cast<std::uint8_t>(contact_surface == SurfaceKind::Mesh
                                         ? kMeshCode + contact_obstacle
                                         : static_cast<int>(contact_surface));
  }
  int index(int i, int j) const { return j * nu + i; }
  // Spring e of a set: its stiffness (N/m) and damping (N·s/m).
  SpringConstants constants(const SpringSet& set, std::size_t e) const {
    return {set.k[e], set.damping[e]};
  }
  // Whether the metrics follow a handle that pulls or drives (not a pin).
  bool measures_a_pull() const {
    return measured_handle >= 0 && handles[measured_handle].type != HandleType::Pin;
  }
};

Model build_model(const Params& p);

// The springs of a kind, of any cloth: a mesh cloth's set, or the grid's from
// its stencil in rows, particles, then offsets (the order a set of them was
// built in), the rest length the distance of the ends' rest positions.
enum class SpringKind { Structural, Shear, Bending };
void for_each_spring(
    const Model& m, SpringKind kind,
    const std::function<void(int a, int b, double rest, double k, double damping)>& f);
std::size_t spring_count(const Model& m, SpringKind kind);
// The same as a set (a copy: for tests and tools, not for a large grid's step).
SpringSet spring_set(const Model& m, SpringKind kind);
// XPBD's substeps a step: integrator.substeps, or when 0 10, and one more per
// 10 particles past 101 along the longer side (a stretch must cross the cloth
// in a step's sweeps).
int xpbd_substeps(const Params& p);
// The same for a built model, a mesh cloth's particles along its longer side
// counted as its topology's along (xpbd_substeps(Params) takes a mesh cloth's as the
// default grid's, 51).
int xpbd_substeps(const Model& m);
// explicit_step_limit for a built model: on a mesh cloth, from its stiffest
// spring of each kind and its lightest particle (on a grid, the same).
double explicit_step_limit(const Model& m);
// Where grid particle (i, j) starts: cloth.center, orientation and tilt.
Vec3 cloth_start_position(const Params& p, int i, int j);
// Humidity drives mass (section 1), permeability (eq. 5) and adhesion (eq. 13).
// A uniform ω: the start's field and every particle's mass.
void set_humidity(Model& m, double omega);
// Each particle's mass (and inverse) from its own ω, m_i = ρ_A (1 + r_w ω_i) A_i.
void set_masses(Model& m, const std::vector<double>& omega);

// How a pocket's deficit answers a change of V_sum over a step of Δt (src/air/air.cpp):
// dΔP/dV_sum = gas + spring (1 - e^(-Δt/τ)) τ/Δt, with 1/τ the seep rate.
struct PocketAir {
  double gas = 0, spring = 0, seep_rate = 0;  // Pa/m³, Pa/m³, 1/s
};

// Everything a run carries from one step to the next: a copy restored into a
// Simulation of the same scene (Simulation::restore) continues with the same bits.
struct State {
  double time = 0;
  long long steps = 0;
  Vec3Array x, v;
  std::vector<std::uint8_t> contact;    // 1: within h_th of the contact surface
  std::vector<std::uint8_t> held;       // 1: held by its handle: where a capped force handle
                                        // stopped, on a late pin's or move handle's path
  std::vector<Vec3> held_at;            // where it was taken (a late handle's path starts there)
  double air_atm_volume = 0;            // trapped air at atmospheric pressure V_atm, m³
  double air_volume = 0;                // V_sum, m³
  double inner_pressure = 0;            // P_in, Pa (mean over pockets for `vented`)
  double peak_deficit = 0;              // max over time of P_atm - P_in, Pa
  std::vector<double> air_share;        // vented: V_atm carried by each particle, m³
  std::vector<double> air_gap;          // vented: each particle's part of V_sum, m³
  std::vector<double> pocket_pressure;  // P_in under each particle, Pa
  // Strain limiting's adaptive order (docs/model.md section 2).
  std::vector<int> source_distance;  // grid steps from the first-moving particles
  bool sources_found = false;
  // What a step hands to the next beside the particles. The air: each
  // particle's pocket (-1 none) and how each pocket's deficit answers a change
  // of its volume over the last step (the implicit air correction uses them).
  std::vector<int> pocket;
  std::vector<PocketAir> pocket_air;
  // Implicit Euler: the halvings of dt the next substep tries, and the last
  // substep's solved change of velocity per second (the next solve starts
  // from v + h times it; empty: from v).
  int halvings = 0;
  Vec3Array acceleration;
  // The symplectic step: until when it runs in substeps of at most
  // integrator.landing_dt, the cushion of air a landing cloth trapped ringing
  // (two of its periods from the first contact).
  double landing_until = 0;
  // The humidity field (docs/model.md "Humidity field"): ω of each particle,
  // moved by wicking, drying and uptake from a wet surface once a step; the
  // water (kg) left in the contact surface's film under each particle (empty
  // with no film); the water (kg) evaporated since the start.
  std::vector<double> humidity;
  std::vector<double> film;
  double water_evaporated = 0;
};

// The step's scratch arrays (src/workspace.hpp): private to the library.
struct Workspace;

// What the last steps did, for benchmarks and summaries.
struct StepStats {
  Vec3 handle_force = Vec3::Zero();  // the measured handle's force on the cloth, N
  long long substeps = 0;            // since reset: one a step, more where a step was split
  long long solves = 0;              // implicit Euler's linear solves since reset
  int cg_iterations = 0;             // of the last solve
  long long cg_iterations_total = 0;
  // integrator.threads = 0: the step's threads are chosen as it runs, one or
  // the most the grid takes (most_threads), whichever was faster in the last
  // trial; the steps taken on each.
  bool threads_chosen = false;
  int most_threads = 1;
  long long steps_on_one = 0, steps_on_most = 0;
};

// One row of metrics.csv (docs/model.md section 10).
struct Metrics {
  double time_s = 0, handle_height_m = 0, handle_force_n = 0, max_height_m = 0;
  double contact_area_m2 = 0, lifted_area_m2 = 0, base_diagonal_m = 0, outer_diagonal_m = 0;
  double inner_pressure_pa = 0, trapped_air_m3 = 0, air_volume_m3 = 0;
  double kinetic_energy_j = 0, max_strain = 0, wrinkle_rad = 0, centroid_x_m = 0, centroid_y_m = 0;
  // The lifted cloth's pull on the cloth in contact, away from the surface: its
  // springs' elastic forces on the contact particles (at a peel front, what
  // their adhesion holds; negative where the lifted cloth presses them down).
  double front_pull_n = 0;
  // The humidity field: ω's area-weighted mean, least and greatest; the water
  // the cloth holds, Σ ρ_A r_w ω_i A_i; the water left in the contact
  // surface's film under it; the water evaporated since the start.
  double humidity_mean = 0, humidity_min = 0, humidity_max = 0;
  double water_kg = 0, film_water_kg = 0, evaporated_kg = 0;
};
std::vector<std::string> metrics_columns();
std::vector<double> metrics_values(const Metrics& m);

class Simulation {
 public:
  // Throws SceneError on parameters a scene file could not give (validate).
  explicit Simulation(const Params& p);
  Simulation(const Simulation& other);
  Simulation& operator=(const Simulation& other);
  Simulation(Simulation&&) noexcept;
  Simulation& operator=(Simulation&&) noexcept;
  ~Simulation();

  // One time step of docs/model.md section 8. XPBD takes it in substeps
  // (xpbd_substeps); implicit Euler may take it in substeps of dt / 2^k
  // (Baraff & Witkin's step control).
  void step();
  // Advances to time t; returns false (and stops) if the run blew up.
  bool advance_to(double t);
  void reset();
  // Continues from a state of this scene (a copy of state() taken earlier, in
  // this or another Simulation of the same parameters): the same bits as the
  // run it was copied from. Throws std::invalid_argument on a state of
  // another grid.
  void restore(const State& s);
  // The particles moved, or their velocities set, between steps (the next
  // step starts from them). Throws std::invalid_argument on another count.
  void set_positions(const Vec3Array& x);
  void set_velocities(const Vec3Array& v);
  // Live: the whole field uniform at ω; mass, permeability and adhesion
  // follow. Throws SceneError outside [0, 1].
  void set_humidity(double omega);
  // Live: each particle's ω (a value per particle, each in [0, 1]); throws
  // std::invalid_argument on another count or a value outside [0, 1].
  void set_humidity_field(const std::vector<double>& omega);
  // Wets (or dries) the particles within `radius` (m) of x to at least
  // (most) ω: the viewer's brush. Returns how many it changed.
  int wet_near(const Vec3& x, double radius, double omega);
  // New parameters, live: the state is kept when the grid is the same size.
  // Throws SceneError on parameters a scene file could not give (validate).
  void set_params(const Params& p);

  // Non-empty when the state holds NaN or a runaway speed; names what to look at.
  std::string blow_up_reason() const;

  Metrics metrics() const;
  StepStats stats() const;
  // |F_adh| on each particle at the last step, N (eq. 13).
  const std::vector<double>& adhesion() const;

  // The viewer's hand: a critically damped spring of `stiffness` pulling
  // `particle` toward `target`.
  void grab(int particle, const Vec3& target, double stiffness);
  void release();

  const Model& model() const { return model_; }
  const State& state() const { return state_; }

 private:
  Model model_;
  State state_;
  std::unique_ptr<Workspace> ws_;
  int grab_particle_ = -1;
  Vec3 grab_target_ = Vec3::Zero();
  double grab_k_ = 0;

  friend Workspace& detail_workspace(const Simulation& sim);
  friend State& detail_state(Simulation& sim);

  void start_thread_choice();
};

// Particle normals, area-weighted over the adjacent triangles.
void compute_normals(const Model& m, const Vec3Array& x, Vec3Array& normal);

}  // namespace wetcloth
