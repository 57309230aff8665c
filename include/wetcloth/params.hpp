// Every scene parameter, with its default. Units are SI; see `wetcloth params`
// (generated from scene.cpp's definitions) for the unit, range and meaning of each.
#pragma once

#include <array>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace wetcloth {

using Vec3d = std::array<double, 3>;
using Vec2d = std::array<double, 2>;
using Vec2i = std::array<long long, 2>;

// The choices a scene makes, each with its names in the scene file (in the
// order of the enum's values). The loader parses them once.
template <class E>
struct ChoiceNames;
#define WETCLOTH_CHOICE(E, ...)                        \
  template <>                                          \
  struct ChoiceNames<E> {                              \
    static constexpr std::array names = {__VA_ARGS__}; \
  };
enum class HandleType { Force, Move, Pin };
WETCLOTH_CHOICE(HandleType, "force", "move", "pin")
enum class Orientation { Horizontal, Vertical };  // the xy plane, the xz plane
WETCLOTH_CHOICE(Orientation, "horizontal", "vertical")
// Obstacle: the [obstacle.NAME] whose `contact` is true (a triangle mesh).
enum class SurfaceChoice { Table, Ball, None, Obstacle };
WETCLOTH_CHOICE(SurfaceChoice, "table", "ball", "none", "obstacle")
enum class FrictionNormal { Contact, Adhesion };  // adhesion + load; the paper's adhesion alone
WETCLOTH_CHOICE(FrictionNormal, "contact", "adhesion")
enum class AirModel { Exchange, Sealed, Vented, Off };
WETCLOTH_CHOICE(AirModel, "exchange", "sealed", "vented", "off")
enum class AirForceDirection { Surface, Cloth };  // n_s; the cloth normal
WETCLOTH_CHOICE(AirForceDirection, "surface", "cloth")
enum class IntegratorType { SymplecticEuler, Xpbd, ImplicitEuler, ExplicitEuler };
WETCLOTH_CHOICE(IntegratorType, "symplectic-euler", "xpbd", "implicit-euler", "explicit-euler")
// Bending (docs/model.md section 1): the quadratic curvature energy (Bergou et al.
// 2006), the same fabric at any grid; Provot's chord springs (i±2), the
// paper's literal model, which soften on a finer grid.
enum class BendingModel { Quadratic, Provot };
WETCLOTH_CHOICE(BendingModel, "quadratic", "provot")
// The integrator settings by name, chosen by measurement (docs/performance.md,
// "Work against precision"): accurate, the cheapest setting near the
// reference on the paper's scenes (no cheaper one came within 5 %); live, the
// fastest, for the viewer.
enum class IntegratorTier { Accurate, Live };
WETCLOTH_CHOICE(IntegratorTier, "accurate", "live")
enum class UpAxis { Z, Y };  // of the files written (or read): the simulation's z, or y
WETCLOTH_CHOICE(UpAxis, "z", "y")
// Between a moving obstacle's keyframes: straight lines, or a cubic Hermite
// spline with Catmull-Rom tangents (docs/guide.md "Moving obstacles").
enum class Interpolation { Linear, Smooth };
WETCLOTH_CHOICE(Interpolation, "linear", "smooth")
#undef WETCLOTH_CHOICE

// A choice's name in the scene file ("?" for a value no name has: the loader
// then refuses it).
template <class E>
std::string to_string(E e) {
  const auto k = static_cast<std::size_t>(e);
  return k < ChoiceNames<E>::names.size() ? ChoiceNames<E>::names[k] : "?";
}

// One key of a moving obstacle's path: at `time` it is moved by `translate`
// and turned by `rotate` (degrees about x, then y, then z, fixed axes) from
// where its own keys place it.
struct Keyframe {
  double time = 0;  // s
  Vec3d translate{0, 0, 0};
  Vec3d rotate{0, 0, 0};
  bool operator==(const Keyframe&) const = default;
};

// A rigid motion by keyframes (none: the body stands still), held at the
// first key before it and at the last after it.
struct Motion {
  std::vector<Keyframe> keys;
  Interpolation interpolation = Interpolation::Linear;
  bool moves() const { return !keys.empty(); }
};

// Particles named by index (0-based: a grid's j nu + i, a mesh cloth's
// vertex in its file's order): a list in the scene, or a file of
// whitespace-separated indices (relative to the scene file). Empty: none.
struct VertexList {
  std::string file;
  std::vector<long long> indices;
  bool empty() const { return file.empty() && indices.empty(); }
};

// How a scene pulls on the cloth (docs/model.md section 9).
struct HandleParams {
  HandleType type = HandleType::Force;
  Vec2d at{0.5, 0.5};       // position on the cloth, (u, v) in [0, 1]
  Vec2d span{0, 0};         // the handle runs from `at` to `at + span`: an edge, a band
  long long patch = 0;      // half-width of the patch, in grid steps
  Vec3d force{0, 0, 0};     // force: total force on the patch, N
  Vec3d velocity{0, 0, 0};  // move: driving velocity, m/s
  double max_height = 0;    // force: height cap above the table, m (0: none)
  double max_travel = 0;    // force, move: distance the hand travels before it stops, m (0: none)
  double start = 0;         // time the handle starts acting, s (a late pin holds where it is then)
  VertexList vertices;      // the particles by index, instead of at, span and patch
};

// An obstacle made of a triangle mesh ([obstacle.NAME], docs/guide.md
// "Obstacles"): the file's points p (turned z-up first when `up` is y) become
// R (S p) + translate, S the per-axis scale, R the rotation about x, then y,
// then z (fixed axes). With a motion, that placement is then turned by the
// motion's rotation about `pivot` and moved by its translation.
struct ObstacleParams {
  std::string mesh;          // OBJ file, relative to the scene file's folder
  UpAxis up = UpAxis::Z;     // the file's up axis
  Vec3d translate{0, 0, 0};  // m
  Vec3d rotate{0, 0, 0};     // degrees about x, y, z, applied in that order
  Vec3d scale{1, 1, 1};      // per axis (the same three: uniform)
  double thickness = 0;      // open meshes: a shell this thick about the surface, m
  bool contact = false;      // the contact surface (with contact.surface = "obstacle")
  double water_film = 0;     // depth of water on it under the cloth, m (when the contact surface)
  Motion motion;
  Vec3d pivot{0, 0, 0};  // the point the motion turns about, in the file's coordinates
  // A deforming obstacle (docs/guide.md "Deforming obstacles"): its vertices
  // per frame, an OBJ sequence ("arm_####.obj": # the zero-padded frame
  // number) or a PC2 file over `mesh`, in the file's coordinates (placed by
  // the keys above, then moved by the motion); "" for none. Frame k is at
  // cache_start + k / cache_fps, linear between frames, held outside them.
  std::string cache;
  double cache_fps = 24;   // frames per second of the cache
  double cache_start = 0;  // s: the time of the cache's first frame
};

// A wet region of the cloth at the start ([wet.NAME], docs/model.md "Humidity
// field"): the particles within `radius` (m, in the rest shape) of the one
// nearest to `at` (u, v), as a handle's, start at ω = humidity.
struct WetRegionParams {
  Vec2d at{0.5, 0.5};    // (u, v) of its centre
  double radius = 0.05;  // m
  double humidity = 1;   // ω inside it
};

struct Params {
  std::string name = "scene";
  std::string description;
  // Not a key: the folder the scene file is in, where the paths it names
  // start ("." for a scene given as text; "builtin:" for a built-in scene,
  // whose meshes are built into the program). load_scene sets it.
  std::string scene_dir = ".";

  struct Cloth {
    // A triangle mesh (OBJ, relative to the scene file) to make the cloth of;
    // empty: the rectangular grid of resolution and size (docs/guide.md).
    std::string mesh;
    double mesh_scale = 1;     // the mesh file's units, in metres
    Vec2i resolution{51, 51};  // particles along u and v
    Vec2d size{0.3, 0.3};      // width (u) and height (v), m
    Vec3d center{0, 0, 0};     // centre of the cloth at t = 0, m
    Orientation orientation = Orientation::Horizontal;
    double tilt = 0;  // then turned about the x axis, degrees
    // A mesh placed as obstacles are (instead of center, orientation, tilt):
    // the file's points, turned z-up when `up` is y, become R (S p) + translate.
    UpAxis up = UpAxis::Z;
    Vec3d translate{0, 0, 0};  // m
    Vec3d rotate{0, 0, 0};     // degrees about x, then y, then z
    Vec3d scale{1, 1, 1};      // per axis, times mesh_scale
    bool placed() const {      // by these keys rather than by center
      return up != UpAxis::Z || translate != Vec3d{0, 0, 0} || rotate != Vec3d{0, 0, 0} ||
             scale != Vec3d{1, 1, 1};
    }
    double humidity = 0.0;  // water saturation by weight ω, 0..1 (the uniform start)
    // A grayscale image over the cloth's (u, v): ω = its value (black 0, white
    // 1) at the start, instead of `humidity` ("": none). Relative to the scene file.
    std::string humidity_map;
    double areal_density = 0.12;  // dry ρ_A, kg/m²
    double water_ratio = 1.0;     // water held at ω = 1 per unit dry mass r_w
  } cloth;

  // The fabric (docs/model.md section 1): constants of the material, the same at
  // any grid. Each spring's constants follow from them and the spacing
  // (resolve_springs); a 0.3 m cloth of 51 x 51 (l = 6 mm) gets 200/20/20 N/m.
  struct Material {
    // A fabric preset's name (material.preset, docs/model.md "Fabric
    // presets"), "" for none. The loader sets the preset's values under the
    // scene's own keys; here it is only the name (apply_preset sets values).
    std::string preset;
    double stretch_stiffness = 200;  // membrane stiffness per unit width, N/m
    double stretch_damping = 0.01;   // N·s/m
    double shear_stiffness = 20;     // N/m
    double shear_damping = 0.01;     // N·s/m
    BendingModel bending = BendingModel::Quadratic;
    // B, N·m: a cylindrical bend of curvature κ stores B κ²/2 per unit area
    // (quadratic); Provot's bending springs get B / l².
    double bending_rigidity = 2e-5;
    double bending_damping = 3.6e-7;  // N·s·m: Provot's bending springs get it / l²
    // The humidity field (docs/model.md "Humidity field").
    double wicking_diffusivity = 5e-6;  // D, m²/s: water spreading in the fabric's plane (0: none)
    double drying_rate = 0;             // k_e, 1/s: dω/dt = -k_e (1 - RH) ω (0: no drying)
    double drying_contact_factor = 0.5;  // the rate on the contact surface, times k_e
    double uptake_rate = 1;  // k_u, 1/s: from a wet surface's film, dω/dt = k_u (1 - ω)
  } material;

  // Spring constants set directly (the blog's way): the same at every grid.
  // Unset (the default), each follows from the material.
  struct Springs {
    std::optional<double> structural_k, structural_damping;
    std::optional<double> shear_k, shear_damping;
    std::optional<double> bending_k, bending_damping;
  } springs;

  struct Forces {
    Vec3d gravity{0, 0, -9.81};
    double viscous_damping = 0.2;  // per unit cloth area, N·s/m³
  } forces;

  struct Wind {
    Vec3d velocity{0, 0, 0};  // m/s
    double k = 1.0;           // normal drag coefficient per unit area, N·s/m³
    Vec2d region_min{0, 0};   // (u, v) box the wind acts in
    Vec2d region_max{1, 1};
  } wind;

  struct StrainLimit {
    bool enabled = true;
    double tau = 0.10;  // allowed stretch τ_c
    long long passes = 2;
  } strain_limit;

  struct Table {
    bool enabled = true;
    double height = 0.0;    // z of the plane, m
    double water_film = 0;  // depth of water on it under the cloth, m (wets what touches it)
  } table;

  struct Ball {
    bool enabled = false;
    Vec3d center{0, 0, 0.1};
    double radius = 0.1;
    Motion motion;          // about its centre
    double water_film = 0;  // depth of water on it under the cloth, m
  } ball;

  struct Contact {
    SurfaceChoice surface = SurfaceChoice::Table;
    double bridge_height = 1e-3;  // liquid-bridge threshold h_th, m
  } contact;

  struct Adhesion {
    bool enabled = true;
    double surface_tension = 0.0728;  // γ, N/m
    double theta_a_deg = 80;          // contact angle on the cloth
    double theta_b_deg = 58;          // contact angle on the surface
    double film_height = 1e-3;        // liquid-bridge height h, m
  } adhesion;

  struct Friction {
    double mu = 0.3;
    FrictionNormal normal = FrictionNormal::Contact;
  } friction;

  struct Air {
    AirModel model = AirModel::Exchange;
    double p_atm = 101325;                // Pa
    double d_delta = 1.0e-3;              // D_δ, m/(s·Pa)
    double k_delta = 0.9e-3;              // K_δ, m/(s·Pa)
    double breakthrough_pressure = 1000;  // P_b, Pa
    double band = 0.05;                   // ball: air counted within this distance, m
    double film = 1e-4;                   // air film a resting cloth keeps under it, m
    AirForceDirection force_direction = AirForceDirection::Surface;
    bool paper_update_rule = false;
    double paper_threshold = 0.0;    // m³ of growth per step that triggers an update
    double relative_humidity = 0.5;  // RH of the room's air, 0..1 (drying stops at 1)
  } air;

  struct SelfCollision {
    bool enabled = true;
    double distance = 5e-3;  // d_t, m
    double k = 200;          // k_t, N/m
    double damping = 5e-3;   // k_f, N·s/m
    double spacing = 6e-3;   // the particle spacing k and damping are given for, m (0: any)
  } self_collision;

  struct Integrator {
    // The defaults below are the accurate tier's (apply_tier).
    IntegratorTier tier = IntegratorTier::Accurate;
    IntegratorType type = IntegratorType::SymplecticEuler;
    double dt = 1e-4;            // s (default_step; xpbd: 1/240 s in substeps)
    long long substeps = 0;      // xpbd: substeps a step (0: 10, and one per 10 particles past 101
                                 // along the longer side)
    double max_speed = 50;       // m/s; faster means the run has blown up
    long long threads = 1;       // threads of the step; 0: chosen as it runs (the CLI's default)
    double cg_tolerance = 1e-4;  // implicit-euler: largest velocity error, m/s
    long long cg_max_iterations = 300;  // implicit-euler
    double max_step_strain = 0.025;  // implicit-euler: a step is halved past this (Baraff & Witkin)
    double landing_dt = 2.5e-5;      // s; symplectic: the longest substep while the cloth lands
  } integrator;

  struct Run {
    double duration = 2.0;        // s
    double fps = 30;              // output frames per simulated second
    bool meshes = true;           // write frames/*.obj
    std::string exports;          // run.export: caches to write, "usd,pc2,vtk" or any of them
    UpAxis up = UpAxis::Z;        // the up axis of the files written
    double checkpoint_every = 0;  // s of simulated time between checkpoints; 0: none
  } run;

  std::map<std::string, HandleParams> handles;      // [handle.NAME]
  std::map<std::string, ObstacleParams> obstacles;  // [obstacle.NAME]
  std::map<std::string, WetRegionParams> wet;       // [wet.NAME]
};

// Humidity-dependent quantities (docs/model.md sections 1, 4, 6).
double particle_areal_mass(const Params& p);         // ρ_A (1 + r_w ω), kg/m²
double permeability(const Params& p);                // δ(ω), eq. 5, m/(s·Pa)
double permeability(const Params& p, double omega);  // δ at a given ω
double adhesion_pressure(const Params& p);  // ω γ (cos θa + cos θb) / h, Pa (eq. 13, area part)
double adhesion_edge_tension(const Params& p);  // ω γ sin θa, N/m (eq. 13, edge part per √S)
double adhesion_total(const Params& p, double contact_area);  // eq. 13, N
// Eq. 13's constants, for a particle's own ω: pressure_per_omega(ω) is
// adhesion_pressure at that ω, tension_per_omega(ω) adhesion_edge_tension,
// to the bit.
struct AdhesionConstants {
  bool enabled = false;
  double gamma = 0, cos_sum = 0, sin_a = 0, h = 1;
  double pressure_per_omega(double omega) const {
    return enabled ? omega * gamma * cos_sum / h : 0.0;
  }
  double tension_per_omega(double omega) const { return enabled ? omega * gamma * sin_a : 0.0; }
};
AdhesionConstants adhesion_constants(const Params& p);

// The constants of every spring of the grid (docs/model.md section 1), from the
// material and the spacing du x dv, or from [springs] where a scene sets them.
// On a square grid (l = du = dv): structural and shear springs get the
// membrane stiffnesses as they are, bending springs B / l², each damping as
// its stiffness. On a grid that is not square, the membrane keeps its
// stiffness per unit width in every direction: a structural spring along u
// gets k_s dv/du (along v, k_s du/dv), a shear spring k_shear 2 du dv /
// (du² + dv²); a bending spring along u B dv / du³ (along v, B du / dv³), a
// diagonal one 4 B du dv / (du² + dv²)².
struct SpringConstants {
  double k = 0, damping = 0;  // N/m, N·s/m
};
struct ResolvedSprings {
  double du = 0, dv = 0;  // spacing along u and v, m
  SpringConstants structural_u, structural_v, shear, bending_u, bending_v, bending_diagonal;
};
ResolvedSprings resolve_springs(const Params& p);

// About the largest stable explicit step, s: 2 / √(8 k / m) for the lightest
// particle (a corner's) and the stiffest chain of springs, k the structural
// constant or, where bending springs are stiffer than a quarter of it (fine
// grids), (2 k_s + 4 k_b + k_s² / (4 k_b)) / 4: a chain's highest mode.
double explicit_step_limit(const Params& p);

// xpbd and implicit Euler take a step of 1/240 s in substeps; the others
// (symplectic and explicit Euler) take small steps.
inline bool takes_large_steps(IntegratorType t) {
  return t == IntegratorType::Xpbd || t == IntegratorType::ImplicitEuler;
}

// The step a scene that gives no integrator.dt gets: 1/240 s for xpbd and
// implicit Euler, which take it in substeps; for the small-step ones
// (symplectic and explicit Euler) 1e-4 s on the default fabric at 51 x 51,
// and on another grid cloth the same fraction of its explicit limit, dry.
double default_step(const Params& p);

// Sets the integrator's keys (type, dt, substeps, max_step_strain) to the
// tier's; a key the scene or a --set gives after integrator.tier overrides it.
void apply_tier(Params& p, IntegratorTier tier);

}  // namespace wetcloth
