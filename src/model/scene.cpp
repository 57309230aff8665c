// Scene files: one table of parameter definitions, used to load, check, print and
// document every key.
#include "wetcloth/scene.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <optional>
#include <sstream>
#include <string_view>

#include "wetcloth/caches.hpp"
#define TOML_HEADER_ONLY 1
#include <toml++/toml.h>

#include <tuple>
#include <type_traits>
#include <utility>

#include "detail.hpp"
#include "geometry/mesh_obstacle.hpp"
#include "wetcloth/motion.hpp"

namespace wetcloth {

namespace {

constexpr double kNoLimit = 1e300;

// A member as the loader holds it: an enum by its name in the scene file
// (ChoiceNames), anything else as it is.
template <class T>
ParamValue to_value(const T& v) {
  if constexpr (std::is_enum_v<T>)
    return to_string(v);
  else
    return v;
}
template <class T>
T from_value(const ParamValue& v) {
  if constexpr (std::is_enum_v<T>) {
    const auto& names = ChoiceNames<T>::names;
    const auto it = std::find(names.begin(), names.end(), std::get<std::string>(v));
    if (it == names.end()) throw std::invalid_argument("not a choice: " + std::get<std::string>(v));
    return static_cast<T>(it - names.begin());
  } else {
    return std::get<T>(v);
  }
}
template <class T>
std::vector<std::string> choices_of(std::vector<std::string> given) {
  if constexpr (std::is_enum_v<T>)
    return {ChoiceNames<T>::names.begin(), ChoiceNames<T>::names.end()};
  else
    return given;
}

// A definition's name, unit, range and meaning.
ParamDef describe(std::string key, std::string unit, double lo, double hi, std::string meaning) {
  ParamDef d;
  d.key = std::move(key);
  d.unit = std::move(unit);
  d.meaning = std::move(meaning);
  d.min = lo;
  d.max = hi;
  return d;
}

template <class F>
ParamDef field(std::string key, std::string unit, double lo, double hi, std::string meaning, F acc,
               std::vector<std::string> choices = {}) {
  using T = std::remove_cvref_t<decltype(acc(std::declval<Params&>()))>;
  ParamDef d = describe(std::move(key), std::move(unit), lo, hi, std::move(meaning));
  d.choices = choices_of<T>(std::move(choices));
  Params defaults;
  d.default_value = to_value(acc(defaults));
  d.get = [acc](const Params& p, const std::string&) {
    return to_value(acc(const_cast<Params&>(p)));
  };
  d.set = [acc](Params& p, const std::string&, const ParamValue& v) { acc(p) = from_value<T>(v); };
  return d;
}

// A key of the tables a scene names, [handle.NAME] (Params::handles) or
// [obstacle.NAME] (Params::obstacles): `KIND.*.KEY`; get and set take the name.
template <auto Tables, class F>
ParamDef named_field(const std::string& kind, std::string key, std::string unit, double lo,
                     double hi, std::string meaning, F acc, std::vector<std::string> choices = {}) {
  using Table =
      typename std::remove_cvref_t<decltype(std::declval<Params&>().*Tables)>::mapped_type;
  using T = std::remove_cvref_t<decltype(acc(std::declval<Table&>()))>;
  ParamDef d = describe(kind + ".*." + key, std::move(unit), lo, hi, std::move(meaning));
  d.choices = choices_of<T>(std::move(choices));
  Table defaults;
  d.default_value = to_value(acc(defaults));
  d.get = [acc](const Params& p, const std::string& name) {
    return to_value(acc(const_cast<Table&>((p.*Tables).at(name))));
  };
  d.set = [acc](Params& p, const std::string& name, const ParamValue& v) {
    acc((p.*Tables)[name]) = from_value<T>(v);
  };
  return d;
}

template <class... A>
ParamDef handle_field(A&&... a) {
  return named_field<&Params::handles>("handle", std::forward<A>(a)...);
}
template <class... A>
ParamDef obstacle_field(A&&... a) {
  return named_field<&Params::obstacles>("obstacle", std::forward<A>(a)...);
}
template <class... A>
ParamDef wet_field(A&&... a) {
  return named_field<&Params::wet>("wet", std::forward<A>(a)...);
}

// A number that may be left unset (std::optional<double>): get gives NaN then.
template <class F>
ParamDef optional_field(std::string key, std::string unit, double lo, double hi,
                        std::string meaning, F acc) {
  ParamDef d = describe(std::move(key), std::move(unit), lo, hi, std::move(meaning));
  d.optional = true;
  d.default_value = std::numeric_limits<double>::quiet_NaN();
  d.get = [acc](const Params& p, const std::string&) {
    return ParamValue(
        acc(const_cast<Params&>(p)).value_or(std::numeric_limits<double>::quiet_NaN()));
  };
  d.set = [acc](Params& p, const std::string&, const ParamValue& v) {
    acc(p) = std::get<double>(v);
  };
  return d;
}

// A motion's keyframes as a flat list, 7 numbers a key (time, translate, rotate).
NumberList flatten(const Motion& m) {
  NumberList v;
  for (const Keyframe& k : m.keys) {
    v.push_back(k.time);
    v.insert(v.end(), k.translate.begin(), k.translate.end());
    v.insert(v.end(), k.rotate.begin(), k.rotate.end());
  }
  return v;
}
std::vector<Keyframe> unflatten(const NumberList& v) {
  std::vector<Keyframe> keys(v.size() / 7);
  for (std::size_t k = 0; k < keys.size(); ++k) {
    const double* a = v.data() + 7 * k;
    keys[k] = {a[0], {a[1], a[2], a[3]}, {a[4], a[5], a[6]}};
  }
  return keys;
}

// A moving body's keyframes (ball.motion, obstacle.*.motion): motion(p, name)
// is its Motion, made where it is new.
template <class F>
ParamDef motion_field(std::string key, std::string meaning, F motion) {
  ParamDef d = describe(std::move(key), "s, m, °", 1, 0, std::move(meaning));
  d.list = ParamDef::List::Keyframes;
  d.default_value = NumberList{};
  d.get = [motion](const Params& p, const std::string& name) -> ParamValue {
    return flatten(motion(const_cast<Params&>(p), name));
  };
  d.set = [motion](Params& p, const std::string& name, const ParamValue& v) {
    motion(p, name).keys = unflatten(std::get<NumberList>(v));
  };
  return d;
}

// handle.*.vertices: a list of particle indices, or a file of them.
ParamDef vertices_field(std::string meaning) {
  ParamDef d = describe("handle.*.vertices", "", 1, 0, std::move(meaning));
  d.list = ParamDef::List::Indices;
  d.default_value = NumberList{};
  d.get = [](const Params& p, const std::string& name) -> ParamValue {
    const VertexList& v = p.handles.at(name).vertices;
    if (!v.file.empty()) return v.file;
    return NumberList(v.indices.begin(), v.indices.end());
  };
  d.set = [](Params& p, const std::string& name, const ParamValue& v) {
    VertexList& list = p.handles[name].vertices;
    list = VertexList{};
    if (const auto* file = std::get_if<std::string>(&v)) {
      list.file = *file;
      return;
    }
    for (const double i : std::get<NumberList>(v)) list.indices.push_back(std::llround(i));
  };
  return d;
}

#define P(path) \
  [](Params & p) -> auto& { return p.path; }
#define H(path) \
  [](HandleParams & h) -> auto& { return h.path; }
#define O(path) \
  [](ObstacleParams & o) -> auto& { return o.path; }
#define W(path) \
  [](WetRegionParams & r) -> auto& { return r.path; }

// Positions: at 1e14 m a double's step is 0.02 m, and metrics.csv got inf.
constexpr double kFar = 1e4;

// material.preset's choices: "" (none) and every preset's name.
std::vector<std::string> preset_choices() {
  std::vector<std::string> names{""};
  for (const FabricPreset& f : fabric_presets()) names.push_back(f.name);
  return names;
}

// The definitions of the scene's name, the cloth, its material and springs.
std::vector<ParamDef> cloth_defs() {
  return {
      field("name", "", 1, 0, "scene name (default output folder out/NAME)", P(name)),
      field("description", "", 1, 0, "one line about the scene", P(description)),
      field("cloth.mesh", "", 1, 0,
            "an OBJ triangle (or quad) mesh to make the cloth of, relative to the scene file "
            "(\"\": the grid of cloth.resolution and cloth.size); its bounding box's centre is "
            "placed at cloth.center, then cloth.orientation and cloth.tilt turn it as the grid",
            P(cloth.mesh)),
      field("cloth.mesh_scale", "m", 1e-6, 1e6,
            "cloth.mesh: the length of one unit of the file (0.01: the file is in centimetres)",
            P(cloth.mesh_scale)),
      field("cloth.resolution", "particles", 2, 2001, "grid nu × nv", P(cloth.resolution)),
      field("cloth.size", "m", 1e-4, 100, "width (u) and height (v) of the cloth", P(cloth.size)),
      field("cloth.center", "m", -kFar, kFar,
            "centre of the cloth at t = 0 (within 10 km: farther, positions lose the precision "
            "the springs need)",
            P(cloth.center)),
      field("cloth.orientation", "", 1, 0,
            "horizontal: in the xy plane; vertical: in the xz plane, v down", P(cloth.orientation)),
      field("cloth.tilt", "°", -90, 90,
            "then turned about the x axis through its centre: tilted by 20, a falling cloth "
            "lands edge first (with air.model = \"exchange\" the wedge of air under it leaks "
            "only through the cloth and holds it up; \"vented\" lets it out at the sides)",
            P(cloth.tilt)),
      field("cloth.up", "", 1, 0,
            "cloth.mesh: the file's up axis; y (Blender's and most tools' OBJ export) turns it "
            "z-up first. With cloth.up, cloth.translate, cloth.rotate or cloth.scale the mesh is "
            "placed as obstacles are, from the file's own origin (not by cloth.center, "
            "cloth.orientation and cloth.tilt): a garment made around a body keeps its place on it",
            P(cloth.up)),
      field("cloth.translate", "m", -kFar, kFar,
            "cloth.mesh: its points p become R (S p) + translate, as obstacle.*.translate",
            P(cloth.translate)),
      field("cloth.rotate", "°", -360, 360,
            "cloth.mesh: turns it about the x, then y, then z axis (fixed axes), as "
            "obstacle.*.rotate",
            P(cloth.rotate)),
      field("cloth.scale", "1", 1e-6, 1e6,
            "cloth.mesh: scales it along x, y, z (times cloth.mesh_scale) before turning it",
            P(cloth.scale)),
      field("cloth.humidity", "1", 0, 1,
            "water saturation by weight ω = (w − w0)/(w100 − w0), the same everywhere at the "
            "start (then each particle's own: wicking, drying and uptake change it)",
            P(cloth.humidity)),
      field("cloth.humidity_map", "", 1, 0,
            "a grayscale image (PNG, JPEG, BMP, TGA, PGM; relative to the scene file) over the "
            "cloth's (u, v): ω at the start is its value, black 0 to white 1, instead of "
            "cloth.humidity (u along the image's rows, v up; \"\": none)",
            P(cloth.humidity_map)),
      field("cloth.areal_density", "kg/m²", 1e-6, 100, "dry areal density ρ_A",
            P(cloth.areal_density)),
      field("cloth.water_ratio", "1", 0, 100, "water held at ω = 1, per unit dry mass (r_w)",
            P(cloth.water_ratio)),
      field("material.preset", "", 1, 0,
            "a real fabric (\"\": none): sets cloth.areal_density, cloth.water_ratio, "
            "material.stretch_stiffness, material.shear_stiffness, material.bending_rigidity, "
            "friction.mu, air.d_delta and air.k_delta, but for those the scene or --set gives "
            "(wetcloth params --preset NAME: its values and their sources)",
            P(material.preset), preset_choices()),
      field("material.stretch_stiffness", "N/m", 0, 1e7,
            "membrane stiffness per unit width in stretch: the structural springs' constant on a "
            "square grid of any spacing",
            P(material.stretch_stiffness)),
      field("material.stretch_damping", "N·s/m", 0, 1e3,
            "damping of stretch (eq. 1): the structural springs' on a square grid of any spacing",
            P(material.stretch_damping)),
      field("material.shear_stiffness", "N/m", 0, 1e7,
            "membrane stiffness per unit width in shear: the shear springs' constant on a square "
            "grid of any spacing",
            P(material.shear_stiffness)),
      field("material.shear_damping", "N·s/m", 0, 1e3,
            "damping of shear: the shear springs' on a square grid of any spacing",
            P(material.shear_damping)),
      field("material.bending", "", 1, 0,
            "bending model: quadratic (a curvature energy, Bergou et al. 2006: the same fabric at "
            "any grid) or provot (the paper's chord springs across two grid steps, which soften "
            "on a finer grid)",
            P(material.bending)),
      field("material.bending_rigidity", "N·m", 0, 1e3,
            "bending rigidity B (Kawabata's B): a bend of curvature κ stores B κ²/2 per unit "
            "area; with material.bending = \"provot\" the bending springs get B / l² at spacing l "
            "(7.2e-4 gives the paper's 20 N/m at 6 mm)",
            P(material.bending_rigidity)),
      field("material.bending_damping", "N·s·m", 0, 1,
            "damping of Provot's bending springs: they get it / l² (0.01 N·s/m at 6 mm); the "
            "quadratic bending is undamped",
            P(material.bending_damping)),
      field("material.wicking_diffusivity", "m²/s", 0, 1,
            "wicking: water spreads through the fabric by diffusion of its water content, "
            "∂c/∂t = D ∇²c, taken implicitly once a step (0: none; 5e-6, a cotton woven's "
            "in-plane wicking, docs/model.md \"Humidity field\")",
            P(material.wicking_diffusivity)),
      field(
          "material.drying_rate", "1/s", 0, 1e3,
          "drying: dω/dt = −k_e (1 − air.relative_humidity) ω where the cloth is lifted (0: none; "
          "5e-4 dries a wet cotton cloth in room air in about 2 h)",
          P(material.drying_rate)),
      field("material.drying_contact_factor", "1", 0, 1,
            "drying where the cloth lies on the contact surface, times material.drying_rate (one "
            "face of two open to the air)",
            P(material.drying_contact_factor)),
      field("material.uptake_rate", "1/s", 0, 1e6,
            "uptake from a wet surface (table.water_film, ball.water_film, "
            "obstacle.*.water_film): a particle in contact takes up water as dω/dt = k_u (1 − ω) "
            "while the film under it lasts",
            P(material.uptake_rate)),
      optional_field("springs.structural_k", "N/m", 0, 1e7,
                     "every structural spring's constant at any grid, set directly (the blog's "
                     "way); unset, from material.stretch_stiffness",
                     P(springs.structural_k)),
      optional_field("springs.structural_damping", "N·s/m", 0, 1e3,
                     "every structural spring's damping (eq. 1); unset, from "
                     "material.stretch_damping",
                     P(springs.structural_damping)),
      optional_field("springs.shear_k", "N/m", 0, 1e7,
                     "every shear spring's constant; unset, from material.shear_stiffness",
                     P(springs.shear_k)),
      optional_field("springs.shear_damping", "N·s/m", 0, 1e3,
                     "every shear spring's damping; unset, from material.shear_damping",
                     P(springs.shear_damping)),
      optional_field("springs.bending_k", "N/m", 0, 1e7,
                     "every bending spring's constant; unset, from material.bending_rigidity",
                     P(springs.bending_k)),
      optional_field("springs.bending_damping", "N·s/m", 0, 1e3,
                     "every bending spring's damping; unset, from material.bending_damping",
                     P(springs.bending_damping)),
  };
}

// The definitions of the forces, strain limiting and the surfaces.
std::vector<ParamDef> force_defs() {
  return {
      field("forces.gravity", "m/s²", -1e3, 1e3, "gravitational acceleration", P(forces.gravity)),
      field("forces.viscous_damping", "N·s/m³", 0, 1e4, "viscous damping −c A_i v_i, per unit area",
            P(forces.viscous_damping)),
      field("wind.velocity", "m/s", -1e3, 1e3, "wind velocity", P(wind.velocity)),
      field("wind.k", "N·s/m³", 0, 1e4, "normal drag per unit area k_w (acts in still air too)",
            P(wind.k)),
      field("wind.region_min", "1", 0, 1, "(u, v) corner of the region the wind blows on",
            P(wind.region_min)),
      field("wind.region_max", "1", 0, 1, "opposite (u, v) corner of that region",
            P(wind.region_max)),
      field("strain_limit.enabled", "", 0, 0, "shorten over-stretched springs (Provot)",
            P(strain_limit.enabled)),
      field("strain_limit.tau", "1", 0, 10, "allowed stretch τ_c", P(strain_limit.tau)),
      field("strain_limit.passes", "", 0, 100, "passes over the springs per step",
            P(strain_limit.passes)),
      field("table.enabled", "", 0, 0, "the table: the plane z = table.height", P(table.enabled)),
      field("table.height", "m", -kFar, kFar, "height of the table", P(table.height)),
      field("table.water_film", "m", 0, 1,
            "water standing on the table, as a depth: a cloth on it (the contact surface) takes "
            "it up (material.uptake_rate), each particle from the film under it, ρ_w h A_i",
            P(table.water_film)),
      field("ball.enabled", "", 0, 0, "a ball (fixed, or moving by ball.motion)", P(ball.enabled)),
      field("ball.center", "m", -kFar, kFar, "centre of the ball", P(ball.center)),
      field("ball.radius", "m", 1e-4, 100, "radius of the ball", P(ball.radius)),
      field("ball.water_film", "m", 0, 1,
            "water on the ball as a depth, as table.water_film (when it is the contact surface)",
            P(ball.water_film)),
      motion_field("ball.motion",
                   "keyframes [[t, [x, y, z], [rx, ry, rz]], ...]: at time t (s) the ball is "
                   "moved by [x, y, z] (m) from ball.center and turned by rx, ry, rz degrees "
                   "about x, then y, then z through its centre (a rolling ball turns: its "
                   "surface's velocity drives friction); times increasing; held before the first "
                   "and after the last ([]: fixed)",
                   [](Params& p, const std::string&) -> Motion& { return p.ball.motion; }),
      field("ball.motion_interpolation", "", 1, 0,
            "between keyframes: linear, or smooth (a cubic Hermite spline with Catmull-Rom "
            "tangents, starting and stopping at rest)",
            P(ball.motion.interpolation)),
      field("contact.surface", "", 1, 0, "the surface the cloth sticks to and traps air against",
            P(contact.surface)),
      field("contact.bridge_height", "m", 0, 1,
            "liquid-bridge threshold h_th: closer is in contact", P(contact.bridge_height)),
      field("adhesion.enabled", "", 0, 0, "liquid-bridge adhesion (eq. 13)", P(adhesion.enabled)),
      field("adhesion.surface_tension", "N/m", 0, 1, "surface tension γ of the liquid",
            P(adhesion.surface_tension)),
      field("adhesion.theta_a_deg", "°", 0, 90, "contact angle θa of the liquid on the cloth",
            P(adhesion.theta_a_deg)),
      field("adhesion.theta_b_deg", "°", 0, 90, "contact angle θb on the surface (glass 14)",
            P(adhesion.theta_b_deg)),
      field("adhesion.film_height", "m", 1e-7, 1, "liquid-bridge height h",
            P(adhesion.film_height)),
      field("friction.mu", "1", 0, 10, "Coulomb friction coefficient μ", P(friction.mu)),
      field("friction.normal", "", 1, 0,
            "normal force for friction: contact (adhesion + load) or adhesion (the paper's)",
            P(friction.normal)),
  };
}

// The definitions of the air, self-collision, the integrator and the run.
std::vector<ParamDef> solver_defs() {
  return {
      field("air.model", "", 1, 0, "trapped air: exchange (paper), sealed (Yamada), vented, off",
            P(air.model)),
      field("air.p_atm", "Pa", 1, 1e7, "atmospheric pressure", P(air.p_atm)),
      field("air.d_delta", "m/(s·Pa)", 0, 1, "dry permeability D_δ (eq. 5)", P(air.d_delta)),
      field("air.k_delta", "m/(s·Pa)", 0, 1, "permeability lost per unit humidity K_δ (eq. 5)",
            P(air.k_delta)),
      field("air.breakthrough_pressure", "Pa", 0, 1e7,
            "deficit at which air breaks through the wet pores P_b", P(air.breakthrough_pressure)),
      field("air.band", "m", 0, 10, "ball: air counted within this distance of it", P(air.band)),
      field("air.film", "m", 0, 0.01,
            "air film a resting cloth keeps in its weave (sets sealed air)", P(air.film)),
      field(
          "air.force_direction", "", 1, 0,
          "direction of the pressure force (eq. 3): surface normal (conservative) or cloth normal",
          P(air.force_direction)),
      field("air.paper_update_rule", "", 0, 0, "update the air only when its volume grew (paper)",
            P(air.paper_update_rule)),
      field("air.paper_threshold", "m³", 0, 1, "growth per step that triggers that update",
            P(air.paper_threshold)),
      field("air.relative_humidity", "1", 0, 1,
            "the room air's relative humidity RH, for drying (material.drying_rate); at 1 "
            "nothing dries",
            P(air.relative_humidity)),
      field("self_collision.enabled", "", 0, 0,
            "repulsion between non-neighbouring particles (eq. 15)", P(self_collision.enabled)),
      field("self_collision.distance", "m", 1e-6, 1, "repulsion distance d_t",
            P(self_collision.distance)),
      field("self_collision.k", "N/m", 0, 1e7, "repulsion stiffness k_t", P(self_collision.k)),
      field("self_collision.damping", "N·s/m", 0, 1e3, "damping k_f of colliding particles",
            P(self_collision.damping)),
      field("self_collision.spacing", "m", 0, 1,
            "the particle spacing k and damping are given for (the paper's 30 cm cloth on 51 x "
            "51): on a finer cloth a pair's k scales as the square of the particles' area and a "
            "particle's damping as its area, the same layers' pressure at every grid (0: as "
            "given at any spacing)",
            P(self_collision.spacing)),
      field("integrator.tier", "", 1, 0,
            "the integrator's settings by name: accurate (symplectic Euler at 1e-4 s on the "
            "default cloth, median error 0.7 % against the reference on the paper's scenes) or "
            "live (xpbd at 1/240 s, 4 times cheaper, the viewer's; median error 26 %; "
            "docs/performance.md); sets "
            "integrator.type, dt, substeps and max_step_strain, and any of them the scene or a "
            "later --set gives overrides it (--live sets live)",
            P(integrator.tier)),
      field("integrator.type", "", 1, 0,
            "time integrator: symplectic-euler (small steps, the reference), xpbd (large steps "
            "in substeps: dt 1/240 s, integrator.substeps), implicit-euler (backward Euler), "
            "explicit-euler (the blog's forward Euler: it gains energy every step, for comparison)",
            P(integrator.type)),
      field("integrator.dt", "s", 1e-9, 1,
            "time step (not given: 1/240 s for xpbd and implicit-euler; for the small-step "
            "integrators 1e-4 s on the default fabric at 51 x 51 and on another grid cloth the "
            "same fraction of its explicit limit, dry)",
            P(integrator.dt)),
      field("integrator.substeps", "", 0, 10000,
            "xpbd: substeps a step, each one sweep of the constraints (0: 10, and one per 10 "
            "particles past 101 along the cloth's longer side; a mesh cloth has its longest "
            "side over its mean edge, plus one; a set count runs as set at any --grid; "
            "`wetcloth check` prints the count)",
            P(integrator.substeps)),
      field("integrator.threads", "", 0, 1024,
            "threads of the step (0: all cores, or one where that is faster, timed as it runs; "
            "the CLI's --threads, default 0, sets it)",
            P(integrator.threads)),
      field("integrator.cg_tolerance", "m/s", 1e-12, 1,
            "implicit-euler: conjugate gradients stop when no velocity is off by more",
            P(integrator.cg_tolerance)),
      field("integrator.cg_max_iterations", "", 1, 100000,
            "implicit-euler: most conjugate-gradient iterations per solve",
            P(integrator.cg_max_iterations)),
      field(
          "integrator.max_step_strain", "1", 1e-3, 10,
          "implicit-euler: a step is halved when a spring changes by more than this times its rest "
          "length in it, and doubled only when none changed by half as much",
          P(integrator.max_step_strain)),
      field("integrator.landing_dt", "s", 0, 1,
            "symplectic-euler: the longest substep while a cloth lands on its contact surface, "
            "from two steps before its first contact to two periods of the cushion of air it "
            "traps after (the cushion's first ringing decides where the cloth settles; 0: no "
            "substeps)",
            P(integrator.landing_dt)),
      field("integrator.max_speed", "m/s", 1e-3, 1e6, "speed taken as a blow-up",
            P(integrator.max_speed)),
      field("run.duration", "s", 0, 1e6, "simulated time", P(run.duration)),
      field("run.fps", "1/s", 1e-3, 1e5, "output frames per simulated second", P(run.fps)),
      field("run.meshes", "", 0, 0, "write frames/frame_NNNNN.obj", P(run.meshes)),
      field("run.export", "", 1, 0,
            "animation caches to write, any of usd, pc2, vtk (comma-separated): cloth.usda; "
            "cloth.pc2 with cloth_rest.obj; vtk/cloth_NNNNN.vtp with cloth.pvd",
            P(run.exports)),
      field("run.up", "", 1, 0, "up axis of the files written: z (the simulation's) or y",
            P(run.up)),
      field("run.checkpoint_every", "s", 0, 1e6,
            "simulated time between checkpoints (checkpoint.state, for `wetcloth run --resume`; "
            "0: none, but a run stopped by a signal writes one)",
            P(run.checkpoint_every)),
  };
}

// The definitions of the keys of [handle.NAME] and [obstacle.NAME].
std::vector<ParamDef> named_defs() {
  return {
      handle_field("type", "", 1, 0, "force: constant force; move: driven at a velocity; pin: held",
                   H(type)),
      handle_field("at", "1", 0, 1,
                   "(u, v) of the handle on the cloth: its centre, or with span one end", H(at)),
      handle_field("span", "1", -1, 1,
                   "the handle takes every particle from at to at + span, e.g. [1, 0] from a "
                   "corner along an edge (each widened by patch)",
                   H(span)),
      handle_field("patch", "grid steps", 0, 1000, "half-width of the handle's patch", H(patch)),
      handle_field("force", "N", -1e6, 1e6, "force: total force on the patch", H(force)),
      handle_field("velocity", "m/s", -1e3, 1e3, "move: velocity of the patch", H(velocity)),
      handle_field("max_height", "m", 0, 1e3, "force: stop pulling up above this height (0: never)",
                   H(max_height)),
      handle_field("max_travel", "m", 0, 1e3,
                   "force, move: stop and hold once the patch has moved this far (0: never)",
                   H(max_travel)),
      handle_field("start", "s", 0, 1e6,
                   "time the handle starts acting (a pin or move handle leaves its particles free "
                   "until then, then holds or drives them from where they are)",
                   H(start)),
      vertices_field(
          "the handle's particles by index instead of at, span and patch: a list [i, j, ...] or a "
          "file of whitespace-separated indices (relative to the scene file; # starts a "
          "comment), 0-based: a grid's particle (i, j) is j nu + i, a mesh cloth's are its "
          "file's vertices in order (a vertex group exported from Blender)"),
      obstacle_field("mesh", "", 1, 0,
                     "[obstacle.NAME]: an obstacle (fixed, or moving by obstacle.*.motion), an OBJ "
                     "triangle mesh (path relative to the scene file, inside its folder)",
                     O(mesh)),
      obstacle_field("up", "", 1, 0,
                     "the file's up axis: y (Blender's OBJ export) turns it z-up before scale, "
                     "rotate and translate",
                     O(up)),
      obstacle_field("translate", "m", -kFar, kFar,
                     "moves the mesh: its points p become R (S p) + translate", O(translate)),
      obstacle_field("rotate", "°", -360, 360,
                     "turns the mesh about the x, then y, then z axis (fixed axes), degrees; "
                     "[90, 0, 0] stands a y-up file's mesh up in wetcloth's z-up world",
                     O(rotate)),
      obstacle_field("scale", "1", 1e-6, 1e6,
                     "scales the mesh along x, y, z (before turning it); the same three: uniform",
                     O(scale)),
      obstacle_field("thickness", "m", 0, 10,
                     "an open mesh (edges on one triangle only) is a shell this thick about its "
                     "surface; a closed mesh's inside is the obstacle (0)",
                     O(thickness)),
      obstacle_field("contact", "", 0, 0,
                     "this obstacle is the contact surface (with contact.surface = "
                     "\"obstacle\"): adhesion, friction's wet load and trapped air act on it",
                     O(contact)),
      obstacle_field("water_film", "m", 0, 1,
                     "water on the obstacle as a depth, as table.water_film (when it is the "
                     "contact surface)",
                     O(water_film)),
      motion_field(
          "obstacle.*.motion",
          "keyframes [[t, [x, y, z], [rx, ry, rz]], ...]: at time t (s) the placed mesh "
          "is turned by rx, ry, rz degrees (about x, then y, then z) about its pivot and "
          "moved by [x, y, z] (m); times increasing; held before the first and after "
          "the last ([]: fixed). Contact, friction and the trapped air follow its "
          "surface and its velocity",
          [](Params& p, const std::string& name) -> Motion& { return p.obstacles[name].motion; }),
      obstacle_field("motion_interpolation", "", 1, 0,
                     "between keyframes: linear, or smooth (a cubic Hermite spline with "
                     "Catmull-Rom tangents, starting and stopping at rest)",
                     O(motion.interpolation)),
      obstacle_field("pivot", "file units", -kFar, kFar,
                     "the point the motion turns the mesh about, in the file's coordinates "
                     "(placed with the mesh): a shoulder, a hinge",
                     O(pivot)),
      obstacle_field("cache", "", 1, 0,
                     "a deforming obstacle: its vertices per frame, an OBJ sequence "
                     "(\"arm_####.obj\", # the zero-padded frame number, the first file found "
                     "frame 0) or a PC2 file over obstacle.*.mesh (relative to the scene file), "
                     "the same vertices in the same order as the mesh; placed as the mesh, then "
                     "moved by the motion; linear between frames, held outside them (\"\": none)",
                     O(cache)),
      obstacle_field("cache_fps", "1/s", 1e-3, 1e6, "frames per second of obstacle.*.cache",
                     O(cache_fps)),
      obstacle_field("cache_start", "s", -1e6, 1e6, "the time of obstacle.*.cache's first frame",
                     O(cache_start)),
      wet_field("at", "1", 0, 1,
                "[wet.NAME]: a wet region at the start, its centre the particle nearest this "
                "(u, v), as a handle's at",
                W(at)),
      wet_field("radius", "m", 1e-6, 100,
                "its particles: those within this distance of the centre, in metres in the rest "
                "shape",
                W(radius)),
      wet_field("humidity", "1", 0, 1,
                "their ω at the start (over cloth.humidity and cloth.humidity_map; regions in "
                "name order, a later one over an earlier)",
                W(humidity)),
  };
}

std::vector<ParamDef> make_defs() {
  std::vector<ParamDef> defs;
  for (auto part : {cloth_defs, force_defs, solver_defs, named_defs})
    for (ParamDef& d : part()) defs.push_back(std::move(d));
  return defs;
}

#undef P
#undef H
#undef O
#undef W

// Bounds on a scene's text (guard_toml_text).
constexpr std::size_t kMaxSceneBytes = 1 << 20;
constexpr int kMaxNesting = 32;

// Scene text is untrusted input: toml++ 3.3 recurses once per level of
// nesting (a 32 KB file of `[a.a.a...]` overflows the stack) and reaches
// undefined behaviour on a non-ASCII byte outside a string or comment. So,
// before toml++ sees it: a bounded size, valid UTF-8, no non-ASCII byte
// outside strings and comments (TOML's bare keys are ASCII), and nesting
// (brackets, braces and the parts of one dotted key) at most kMaxNesting.
// A scene needs three levels.
// toml++ 3.3's is_non_ascii_horizontal_whitespace is undefined (it reaches
// __builtin_unreachable) for U+00A1-U+0499 and U+FB66-U+FEFE, and toml++
// asks it of characters it reads ahead of a value, wherever they are (the
// fuzzer found one past a quote that began no string): so no such character
// reaches toml++. In a basic string it becomes its \uXXXX escape (the same
// value), in a comment '?'; in a literal string it is refused. Returns the
// text to parse (the same lines).
// guard_toml_text's passes over one text.
class TomlGuard {
 public:
  TomlGuard(const std::string& text, const std::string& source)
      : text_(text),
        source_(source),
        s_(reinterpret_cast<const unsigned char*>(text.data())),
        n_(text.size()) {}

  // Valid UTF-8: no overlong forms, no surrogates, nothing past U+10FFFF.
  void check_utf8() const {
    long line = 1;
    for (std::size_t i = 0; i < n_;) {
      const unsigned char c = s_[i];
      if (c == '\n') ++line;
      if (c < 0x80) {
        ++i;
        continue;
      }
      int len = 0;
      unsigned cp = 0, min = 0;
      if ((c & 0xE0) == 0xC0)
        len = 2, cp = c & 0x1F, min = 0x80;
      else if ((c & 0xF0) == 0xE0)
        len = 3, cp = c & 0x0F, min = 0x800;
      else if ((c & 0xF8) == 0xF0)
        len = 4, cp = c & 0x07, min = 0x10000;
      bool ok = len > 0 && i + static_cast<std::size_t>(len) <= n_;
      for (int k = 1; ok && k < len; ++k) {
        ok = (s_[i + k] & 0xC0) == 0x80;
        cp = (cp << 6) | (s_[i + k] & 0x3F);
      }
      if (!ok || cp < min || cp > 0x10FFFF || (cp >= 0xD800 && cp <= 0xDFFF))
        throw SceneError(at(line) + ": not valid UTF-8 (byte " + std::to_string(i + 1) + ")");
      i += static_cast<std::size_t>(len);
    }
  }

  // The nesting, the dotted keys, and the characters toml++ must not see.
  void scan() {
    for (std::size_t i = 0; i < n_;) {
      const unsigned char c = s_[i];
      if (c == '\n') {
        ++line_, ++i;
        other();
      } else if (c == '#') {
        while (i < n_ && s_[i] != '\n') i += inside(i, '#');
        other();
      } else if (c == '"' || c == '\'') {
        i = skip_string(i);
        part();
      } else if (c >= 0x80) {
        throw SceneError(at(line_) +
                         ": a non-ASCII character outside a string or comment (keys "
                         "are ASCII: letters, digits, _ and -)");
      } else if (c == '[' || c == '{') {
        if (++depth_ > kMaxNesting)
          throw SceneError(at(line_) + ": tables or arrays nested more than " +
                           std::to_string(kMaxNesting) + " deep: not a scene file");
        ++i;
        other();
      } else if (c == ']' || c == '}') {
        depth_ = std::max(0, depth_ - 1);
        ++i;
        other();
      } else if (c == '.') {
        if (after_part_)
          after_part_ = false, after_dot_ = true;
        else
          other();
        ++i;
      } else if (c == ' ' || c == '\t') {
        ++i;
      } else if (bare(c)) {
        while (i < n_ && bare(s_[i])) ++i;
        part();
      } else {
        ++i;
        other();
      }
    }
  }

  // The text with each hidden character as its \uXXXX escape (in a basic
  // string) or '?' (in a comment).
  std::string safe_text() const {
    if (hidden_.empty()) return text_;
    std::string safe;
    safe.reserve(text_.size() + 4 * hidden_.size());
    std::size_t from = 0;
    for (const Hidden& h : hidden_) {
      safe.append(text_, from, h.at - from);
      char u[16];
      std::snprintf(u, sizeof u, "\\u%04X", h.cp);
      safe += h.in == '"' ? u : "?";
      from = h.at + static_cast<std::size_t>(h.len);
    }
    safe.append(text_, from, std::string::npos);
    return safe;
  }

 private:
  // Where toml++ must not see a character: (offset, length, code point, '"'
  // basic string, '\'' literal string, '#' comment).
  struct Hidden {
    std::size_t at;
    int len;
    unsigned cp;
    char in;
  };
  const std::string& text_;
  const std::string& source_;
  const unsigned char* s_;
  std::size_t n_;
  std::vector<Hidden> hidden_;
  long line_ = 1;
  int depth_ = 0;  // open [ and {
  int parts_ = 0;  // parts of the dotted key (or number) being read
  bool after_part_ = false, after_dot_ = false;

  std::string at(long line) const {
    return source_.rfind("--set", 0) == 0 ? source_ : source_ + ":" + std::to_string(line);
  }
  static bool bare(unsigned char c) { return std::isalnum(c) || c == '_' || c == '-' || c == '+'; }

  // At a byte inside a string or comment: its length, noting a character
  // toml++ must not see.
  std::size_t inside(std::size_t i, char in) {
    if (s_[i] < 0x80) return 1;
    const int len = s_[i] >= 0xF0 ? 4 : s_[i] >= 0xE0 ? 3 : 2;  // valid: checked before
    unsigned cp = s_[i] & (len == 4 ? 0x07 : len == 3 ? 0x0F : 0x1F);
    for (int k = 1; k < len; ++k) cp = (cp << 6) | (s_[i + k] & 0x3F);
    if ((cp >= 0xA1 && cp <= 0x499) || (cp >= 0xFB66 && cp <= 0xFEFE)) {
      if (in == '\'') {
        char u[16];
        std::snprintf(u, sizeof u, "U+%04X", cp);
        throw SceneError(at(line_) + ": " + u +
                         " in a literal string ('...'): the TOML library mishandles it; write "
                         "the string in double quotes");
      }
      hidden_.push_back({i, len, cp, in});
    }
    return static_cast<std::size_t>(len);
  }

  // A string that opens at i (its quote, once or three times): where it ends.
  std::size_t skip_string(std::size_t i) {
    const unsigned char c = s_[i];
    const bool multi = i + 2 < n_ && s_[i + 1] == c && s_[i + 2] == c;
    i += multi ? 3 : 1;
    for (;;) {
      if (i >= n_) break;                  // unterminated: toml++ says so
      if (s_[i] == '\n' && !multi) break;  // toml++ says so
      if (s_[i] == '\n') ++line_;
      if (c == '"' && s_[i] == '\\') {  // the escaped character is the string's
        if (++i >= n_) break;
        if (s_[i] == '\n') ++line_;
        i += inside(i, '"');
        continue;
      }
      if (s_[i] == c && (!multi || (i + 2 < n_ && s_[i + 1] == c && s_[i + 2] == c))) {
        i += multi ? 3 : 1;
        break;
      }
      i += inside(i, c == '"' ? '"' : '\'');
    }
    return i;
  }

  void part() {
    parts_ = after_dot_ ? parts_ + 1 : 1;
    after_part_ = true;
    after_dot_ = false;
    if (parts_ > kMaxNesting)
      throw SceneError(at(line_) + ": a dotted key of more than " + std::to_string(kMaxNesting) +
                       " parts: not a scene key");
  }
  void other() { parts_ = 0, after_part_ = after_dot_ = false; }
};

std::string guard_toml_text(const std::string& text, const std::string& source) {
  if (text.size() > kMaxSceneBytes)
    throw SceneError(source + ": " + std::to_string(text.size()) + " bytes, more than a scene's " +
                     std::to_string(kMaxSceneBytes) + ": not a scene file");
  TomlGuard guard(text, source);
  guard.check_utf8();
  guard.scan();
  return guard.safe_text();
}

// The source name of Params made in code (validate).
const std::string kInCode = "Params";

// Where a node came from: "file:line" for scene files, the --set text for overrides.
std::string where(const toml::node& n) {
  const auto& src = n.source();
  const std::string path = src.path ? *src.path : std::string("<scene>");
  if (path.rfind("--set", 0) == 0 || path == kInCode) return path;  // no line to name
  return path + ":" + std::to_string(src.begin.line);
}

[[noreturn]] void fail(const toml::node& n, const std::string& key, const std::string& msg) {
  throw SceneError(where(n) + ": " + key + ": " + msg);
}

std::string shortest(double v) {
  char buf[64];
  auto r = std::to_chars(buf, buf + sizeof buf, v);
  std::string s(buf, r.ptr);
  if (s.find_first_of(".eEn") == std::string::npos) s += ".0";  // keep it a TOML float
  return s;
}

double number(const toml::node& n, const ParamDef& d, const std::string& key) {
  double v;
  if (auto i = n.as_integer())
    v = static_cast<double>(i->get());
  else if (auto f = n.as_floating_point())
    v = f->get();
  else
    fail(n, key, "expected a number");
  if (d.min <= d.max && (v < d.min || v > d.max))
    fail(n, key, "value " + shortest(v) + " is out of range " + d.range_text());
  if (!std::isfinite(v)) fail(n, key, "value is not finite");
  return v;
}

template <std::size_t N, class T>
std::array<T, N> array_of(const toml::node& n, const ParamDef& d, const std::string& key) {
  const auto* a = n.as_array();
  if (!a || a->size() != N) fail(n, key, "expected an array of " + std::to_string(N) + " numbers");
  std::array<T, N> out{};
  for (std::size_t i = 0; i < N; ++i) {
    const toml::node& e = *a->get(i);
    if constexpr (std::is_integral_v<T>) {
      if (!e.is_integer()) fail(n, key, "expected an array of " + std::to_string(N) + " integers");
    }
    out[i] = static_cast<T>(number(e, d, key));
  }
  return out;
}

// Levenshtein's distance: a typo's from what was meant.
std::size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diagonal = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] != b[j - 1])});
      diagonal = up;
    }
  }
  return row[b.size()];
}

// A string that is none of a key's choices: the choices, and the nearest one
// where one is close ("did you mean denim?").
std::string not_a_choice(const ParamDef& d, const std::string& s) {
  std::string best;
  std::size_t best_distance = std::max<std::size_t>(2, s.size() / 4) + 1;
  for (const std::string& c : d.choices)
    if (const std::size_t dist = edit_distance(s, c); !c.empty() && dist < best_distance)
      best_distance = dist, best = c;
  return "'" + s + "' is not one of " + d.range_text() +
         (best.empty() ? std::string() : " (did you mean " + best + "?)");
}

// A number within [lo, hi], for the parts of a list.
double number_in(const toml::node& n, double lo, double hi, const std::string& key,
                 const std::string& what) {
  double v;
  if (auto i = n.as_integer())
    v = static_cast<double>(i->get());
  else if (auto f = n.as_floating_point())
    v = f->get();
  else
    fail(n, key, what + ": expected a number");
  if (!std::isfinite(v)) fail(n, key, what + ": value is not finite");
  if (v < lo || v > hi)
    fail(n, key,
         what + ": value " + shortest(v) + " is out of range [" + shortest(lo) + ", " +
             shortest(hi) + "]");
  return v;
}

// Keyframes [[t, [x, y, z], [rx, ry, rz]], ...], times increasing: flattened.
// An error names the line of the keyframe at fault.
NumberList keyframes(const toml::node& n, const std::string& key) {
  const char* form = "[[t, [x, y, z], [rx, ry, rz]], ...] (seconds, metres, degrees)";
  const auto* a = n.as_array();
  if (!a) fail(n, key, std::string("expected keyframes ") + form);
  NumberList out;
  for (std::size_t i = 0; i < a->size(); ++i) {
    const toml::node& e = *a->get(i);
    const std::string what = "keyframe " + std::to_string(i + 1);
    const auto* k = e.as_array();
    if (!k || k->size() != 3 || !k->get(1)->is_array() || !k->get(2)->is_array() ||
        k->get(1)->as_array()->size() != 3 || k->get(2)->as_array()->size() != 3)
      fail(e, key, what + ": expected [t, [x, y, z], [rx, ry, rz]], as in " + form);
    const double t = number_in(*k->get(0), 0, 1e6, key, what + "'s time");
    if (i > 0 && !(t > out[out.size() - 7]))
      fail(e, key,
           what + "'s time " + shortest(t) + " s is not after keyframe " + std::to_string(i) +
               "'s, " + shortest(out[out.size() - 7]) + " s: the times must increase");
    out.push_back(t);
    for (int c = 0; c < 3; ++c)
      out.push_back(
          number_in(*k->get(1)->as_array()->get(c), -kFar, kFar, key, what + "'s translation"));
    for (int c = 0; c < 3; ++c)
      out.push_back(
          number_in(*k->get(2)->as_array()->get(c), -1e6, 1e6, key, what + "'s rotation"));
  }
  return out;
}

// Particle indices [i, ...] (0-based integers), or a string: a file of them.
ParamValue index_list(const toml::node& n, const std::string& key) {
  if (const auto* file = n.as_string()) {
    if (file->get().empty())
      fail(n, key, "is empty: name a file of particle indices, or list them");
    return file->get();
  }
  const auto* a = n.as_array();
  if (!a) fail(n, key, "expected a list of particle indices [i, j, ...] (0-based) or a file name");
  NumberList out;
  for (std::size_t i = 0; i < a->size(); ++i) {
    const auto* v = a->get(i)->as_integer();
    if (!v || v->get() < 0 || v->get() > (1LL << 31))
      fail(*a->get(i), key,
           "entry " + std::to_string(i + 1) + ": a particle index is an integer from 0");
    out.push_back(static_cast<double>(v->get()));
  }
  return out;
}

ParamValue convert(const toml::node& n, const ParamDef& d, const std::string& key) {
  return std::visit(
      [&](const auto& def) -> ParamValue {
        using T = std::decay_t<decltype(def)>;
        if constexpr (std::is_same_v<T, bool>) {
          if (!n.is_boolean()) fail(n, key, "expected true or false");
          return n.as_boolean()->get();
        } else if constexpr (std::is_same_v<T, long long>) {
          if (!n.is_integer()) fail(n, key, "expected an integer");
          return static_cast<long long>(number(n, d, key));
        } else if constexpr (std::is_same_v<T, double>) {
          return number(n, d, key);
        } else if constexpr (std::is_same_v<T, std::string>) {
          if (!n.is_string()) fail(n, key, "expected a string");
          std::string s = n.as_string()->get();
          if (!d.choices.empty() &&
              std::find(d.choices.begin(), d.choices.end(), s) == d.choices.end())
            fail(n, key, not_a_choice(d, s));
          return s;
        } else if constexpr (std::is_same_v<T, Vec2i>) {
          return array_of<2, long long>(n, d, key);
        } else if constexpr (std::is_same_v<T, Vec2d>) {
          return array_of<2, double>(n, d, key);
        } else if constexpr (std::is_same_v<T, Vec3d>) {
          return array_of<3, double>(n, d, key);
        } else if (d.list == ParamDef::List::Indices) {
          return index_list(n, key);
        } else {
          return keyframes(n, key);
        }
      },
      d.default_value);
}

// The tables a scene names: [handle.NAME] and [obstacle.NAME].
constexpr std::array<std::string_view, 3> kNamedKinds = {"handle", "obstacle", "wet"};

// The kind of a key `KIND.*.LEAF` ("" for any other key).
std::string named_kind(const std::string& key) {
  for (const std::string_view kind : kNamedKinds)
    if (key.rfind(std::string(kind) + ".*.", 0) == 0) return std::string(kind);
  return "";
}

// The names of a scene's tables of one kind, in order.
std::vector<std::string> table_names(const Params& p, const std::string& kind) {
  std::vector<std::string> names;
  if (kind == "handle")
    for (const auto& [name, unused] : p.handles) names.push_back(name);
  else if (kind == "wet")
    for (const auto& [name, unused] : p.wet) names.push_back(name);
  else
    for (const auto& [name, unused] : p.obstacles) names.push_back(name);
  return names;
}

const ParamDef* find_def(const std::string& key) {
  for (const auto& d : param_defs())
    if (d.key == key) return &d;
  return nullptr;
}

// "unknown key", with the nearest key by edit distance where one is close: a
// typo names what was meant ("did you mean cloth.humidity?").
std::string unknown_key(const std::string& key) {
  // A handle's or obstacle's keys compare by their part after its name.
  std::string kind;  // "handle." or "obstacle.", or none
  for (const std::string k : {"handle.", "obstacle.", "wet."})
    if (key.rfind(k, 0) == 0 && key.find('.', k.size()) != std::string::npos) kind = k;
  const bool in_handle = !kind.empty();
  const std::string prefix = in_handle ? key.substr(0, key.find('.', kind.size()) + 1) : "";
  const std::string leaf = in_handle ? key.substr(prefix.size()) : key;
  std::string best;
  std::size_t best_distance = std::max<std::size_t>(2, leaf.size() / 4) + 1;
  for (const ParamDef& d : param_defs()) {
    const bool named_key = !named_kind(d.key).empty();
    if (named_key != in_handle || (in_handle && d.key.rfind(kind + "*.", 0) != 0)) continue;
    const std::string candidate = named_key ? d.key.substr(kind.size() + 2) : d.key;
    if (const std::size_t dist = edit_distance(leaf, candidate); dist < best_distance)
      best_distance = dist, best = prefix + candidate;
  }
  return "unknown key" + (best.empty() ? std::string() : " (did you mean " + best + "?)") +
         " (wetcloth params lists the keys)";
}

// new_handles: whether the table may add handles (a scene file may; an
// override may only change the scene's own, so that a misspelt name is an
// error, not a second handle).
void apply_table(const toml::table& t, const std::string& prefix, Params& p, bool new_handles) {
  for (const auto& [k, node] : t) {
    const std::string key =
        prefix.empty() ? std::string(k.str()) : prefix + "." + std::string(k.str());
    if (prefix.empty() && (k.str() == "handle" || k.str() == "obstacle" || k.str() == "wet")) {
      // [handle.NAME] and [obstacle.NAME]: tables of keys `handle.*.KEY`, `obstacle.*.KEY`.
      const std::string kind(k.str());
      const auto* tables = node.as_table();
      if (!tables) fail(node, key, "expected a table of " + kind + "s, [" + kind + ".NAME]");
      for (const auto& [name, h] : *tables) {
        const std::string hkey = kind + "." + std::string(name.str());
        const auto* ht = h.as_table();
        if (!ht) fail(h, hkey, "expected a table");
        // The name is part of keys (handle.NAME.force, --set, scene.toml): a bare key.
        const std::string_view nm = name.str();
        if (nm.empty() || !std::all_of(nm.begin(), nm.end(), [](unsigned char c) {
              return std::isalnum(c) || c == '_' || c == '-';
            }))
          fail(h, hkey,
               "a " + kind + "'s name is letters, digits, _ and - (it is part of keys such as " +
                   kind + ".NAME." +
                   (kind == "handle" ? "force"
                    : kind == "wet"  ? "radius"
                                     : "mesh") +
                   ")");
        const bool is_handle = kind == "handle";
        const std::vector<std::string> known = table_names(p, kind);
        if (!new_handles && std::find(known.begin(), known.end(), nm) == known.end()) {
          std::string names;
          for (const auto& n : known) names += (names.empty() ? "" : ", ") + n;
          fail(h, hkey,
               "the scene has no such " + kind + " (" +
                   (names.empty() ? "it has none" : "its " + kind + "s: " + names) + "); add " +
                   (is_handle       ? "a handle"
                    : kind == "wet" ? "a wet region"
                                    : "an obstacle") +
                   " in a scene file");
        }
        // A table with every key at its default, where it is new.
        if (is_handle)
          p.handles[std::string(nm)];
        else if (kind == "wet")
          p.wet[std::string(nm)];
        else
          p.obstacles[std::string(nm)];
        for (const auto& [hk, hv] : *ht) {
          const std::string full = hkey + "." + std::string(hk.str());
          const ParamDef* d = find_def(kind + ".*." + std::string(hk.str()));
          if (!d) fail(hv, full, unknown_key(full));
          d->set(p, std::string(nm), convert(hv, *d, full));
        }
      }
      continue;
    }
    const ParamDef* d = find_def(key);
    bool section = false;  // some key is under this one: [cloth]
    for (const auto& def : param_defs()) section = section || def.key.rfind(key + ".", 0) == 0;
    if (const auto* sub = node.as_table(); sub && !d) {
      // Only into a known section: the recursion is as deep as the keys are.
      if (!section) fail(node, key, "unknown table (wetcloth params lists the keys)");
      apply_table(*sub, key, p, new_handles);
      continue;
    }
    if (!d) {
      if (section) fail(node, key, "expected a table, [" + key + "]");
      fail(node, key, unknown_key(key));
    }
    d->set(p, "", convert(node, *d, key));
  }
}

// The values a parsed `KEY = VALUE` holds: one, unless VALUE went on to set
// more keys (a newline, then `name = "x"`). An inline table is one value.
int count_values(const toml::table& t) {
  int n = 0;
  for (const auto& [k, v] : t)
    n += v.is_table() && !v.as_table()->is_inline() ? count_values(*v.as_table()) : 1;
  return n;
}

// One KEY=VALUE: VALUE is one TOML value and sets KEY alone.
toml::table one_value(toml::table t, const std::string& source, const std::string& key) {
  if (count_values(t) != 1)
    throw SceneError(source + ": " + key +
                     ": the value goes on past one TOML value (a newline, then another key?): "
                     "a --set sets one key; give another --set for another");
  return t;
}

toml::table parse_override(const std::string& text) {
  const auto eq = text.find('=');
  if (eq == std::string::npos || eq == 0)
    throw SceneError("--set '" + text + "': expected KEY=VALUE, e.g. cloth.humidity=0.5");
  const std::string key = text.substr(0, eq), value = text.substr(eq + 1);
  // A long override (a fuzzer's 30 000-part key) is named by its start.
  const std::string source =
      "--set '" +
      (text.size() <= 160
           ? text
           : text.substr(0, 120) + "...' (" + std::to_string(text.size()) + " characters)") +
      (text.size() <= 160 ? "'" : "");
  // Let a bare word stand for a string: --set air.model=sealed.
  const bool bare_word =
      !value.empty() && std::all_of(value.begin(), value.end(), [](unsigned char c) {
        return std::isalnum(c) || c == '_' || c == '-' || c == ',';
      });
  const std::string text_safe = guard_toml_text(key + " = " + value, source);
  try {
    return one_value(toml::parse(text_safe, source), source, key);
  } catch (const toml::parse_error& e) {
    if (!bare_word) throw SceneError(source + ": " + key + ": " + std::string(e.description()));
  }
  try {
    return one_value(toml::parse(guard_toml_text(key + " = \"" + value + "\"", source), source),
                     source, key);
  } catch (const toml::parse_error& e) {
    throw SceneError(source + ": " + key + ": " + std::string(e.description()));
  }
}

// material.preset first, so that every key the scene or --set gives, in any
// order, overrides the preset's: the last --set's, else the scene's.
void apply_named_preset(const toml::table& root, const std::vector<toml::table>& sets, Params& p) {
  const std::string key = "material.preset";
  const toml::node* named = root.at_path(key).node();
  for (const auto& t : sets)
    if (const toml::node* n = t.at_path(key).node()) named = n;
  if (named) apply_preset(p, std::get<std::string>(convert(*named, *find_def(key), key)));
}

// The integrator's keys come from the scene, then from the overrides (each
// --set in order): a source's integrator.tier sets the tier's keys before the
// keys given after it, and a source that names an integrator.type of the
// other kind (small or large steps) and no integrator.dt gets that kind's
// step, not the one before.
void apply_tier_key(const toml::table& t, Params& p) {
  const std::string key = "integrator.tier";
  if (const toml::node* n = t.at_path(key).node())
    apply_tier(p, from_value<IntegratorTier>(convert(*n, *find_def(key), key)));
}
// A step nobody gave is default_step's, for the cloth and fabric as read.
void apply_sources(const toml::table& root, const std::vector<toml::table>& sets, Params& p) {
  bool given = false;  // integrator.dt comes from a source, not from the defaults
  const auto source = [&p, &given](const std::vector<const toml::table*>& tables, bool scene) {
    std::optional<bool> large_before;  // the kind before the first type named
    bool dt = false;                   // this source gives a step
    for (const toml::table* t : tables) {
      apply_tier_key(*t, p);
      if (t->at_path("integrator.tier").node())
        given = false;  // the tier's, unless a key gives one
      if (!large_before && t->at_path("integrator.type").node())
        large_before = takes_large_steps(p.integrator.type);
      if (t->at_path("integrator.dt").node()) dt = given = true;
      apply_table(*t, "", p, scene);
    }
    if (large_before && !dt && *large_before != takes_large_steps(p.integrator.type)) given = false;
  };
  source({&root}, true);
  std::vector<const toml::table*> overrides;
  for (const auto& t : sets) overrides.push_back(&t);
  source(overrides, false);
  if (!given) p.integrator.dt = default_step(p);
}

// Checks that combine keys. An error names the scene, with the line of the
// key it reports where the scene sets it, and the overrides that may have set
// what it says: those of the key's section (cloth, handle, ...) and those of
// any key the message names.
// How check_consistency complains: key and message (throws SceneError).
using Complain = std::function<void(const std::string& key, const std::string& msg)>;

// The contact surface and the obstacles agree.
void check_surfaces(const Params& p, const Complain& bad) {
  if (p.contact.surface == SurfaceChoice::Ball && !p.ball.enabled)
    bad("contact.surface", "is 'ball' but ball.enabled is false");
  if (p.contact.surface == SurfaceChoice::Table && !p.table.enabled)
    bad("contact.surface", "is 'table' but table.enabled is false");
  // Obstacles: at most one is the contact surface, and then contact.surface says so.
  if (p.obstacles.size() > static_cast<std::size_t>(kMostObstacles))
    bad("obstacle", "more than " + std::to_string(kMostObstacles) + " obstacles");
  std::string contact_obstacles;
  for (const auto& [name, o] : p.obstacles) {
    if (o.mesh.empty())
      bad("obstacle." + name + ".mesh", "is missing: name the obstacle's OBJ file");
    if (o.contact) contact_obstacles += (contact_obstacles.empty() ? "" : ", ") + name;
    // Uptake follows the contact state, which only the contact surface has.
    if (o.water_film > 0 && !o.contact)
      bad("obstacle." + name + ".water_film",
          "is set but the obstacle is not the contact surface: water is taken up only from "
          "it (set obstacle." +
              name + ".contact = true and contact.surface = \"obstacle\")");
  }
  if (contact_obstacles.find(',') != std::string::npos)
    bad("contact.surface", "one obstacle at most can be the contact surface, and " +
                               contact_obstacles + " all say contact = true");
  if (p.contact.surface == SurfaceChoice::Obstacle && contact_obstacles.empty())
    bad("contact.surface",
        "is 'obstacle' but no [obstacle.NAME] says contact = true (mark the one the cloth "
        "sticks to)");
  if (p.contact.surface != SurfaceChoice::Obstacle && !contact_obstacles.empty())
    bad("obstacle." + contact_obstacles + ".contact",
        "is true but contact.surface is '" + to_string(p.contact.surface) +
            "' (set contact.surface = \"obstacle\" to make it the contact surface)");
}

// A cloth that starts inside the table or the ball would be flung out of it
// at the first step (a tilted or lowered cloth makes that easy to do).
void check_cloth_start(const Params& p, const Complain& bad) {
  for (const auto& [kind, name, on] : {std::tuple{SurfaceKind::Table, "table", p.table.enabled},
                                       std::tuple{SurfaceKind::Ball, "ball", p.ball.enabled}}) {
    if (!on) continue;
    double deepest = 0;
    SurfacePoses at_start;  // a moving ball where it is at t = 0
    if (p.ball.enabled) at_start.ball = ball_pose(p, 0.0);
    // (A mesh cloth's: check_cloth_mesh, once its file is found.)
    if (p.cloth.mesh.empty())
      for (int j = 0; j < p.cloth.resolution[1]; ++j)
        for (int i = 0; i < p.cloth.resolution[0]; ++i) {
          const Vec3 x = cloth_start_position(p, i, j);
          deepest = std::min(deepest, detail::query_surface(p, at_start, kind, x).distance);
        }
    if (deepest < -1e-9) {
      char mm[32];
      std::snprintf(mm, sizeof mm, "%.3g", -deepest * 1000);
      const char* keys = kind == SurfaceKind::Table ? "table.height" : "ball.center, ball.radius";
      bad("cloth.center", std::string("the cloth starts ") + mm + " mm inside the " + name +
                              " (cloth.center, cloth.tilt, " + keys + ")");
    }
  }
}

// A run that would take no step, or write frames between steps.
void check_run_timing(const Params& p, const Complain& bad) {
  if (p.run.duration > 0 && p.integrator.dt > p.run.duration * (1 + 1e-9))
    bad("integrator.dt", "= " + shortest(p.integrator.dt) +
                             " s is longer than run.duration = " + shortest(p.run.duration) +
                             " s: the run would take no step (lower integrator.dt; "
                             "run.duration = 0 writes the start alone)");
  if (p.run.fps * p.integrator.dt > 1 + 1e-9)
    bad("run.fps", "= " + shortest(p.run.fps) + " frames/s is above the step rate, 1 / " +
                       "integrator.dt = " + shortest(1 / p.integrator.dt) +
                       " steps/s: frames would repeat steps (lower run.fps, or integrator.dt)");
}

// A key that does nothing for a handle's type is a mistake, not a default.
void check_handles(const Params& p, const Complain& bad) {
  const auto nonzero = [](const Vec3d& v) { return v[0] != 0 || v[1] != 0 || v[2] != 0; };
  for (const auto& [name, h] : p.handles) {
    const std::string key = "handle." + name + ".";
    const std::string is = " (this one is " + to_string(h.type) + ")";
    if (h.type != HandleType::Force && nonzero(h.force))
      bad(key + "force", "applies to force handles only" + is);
    if (h.type != HandleType::Force && h.max_height > 0)
      bad(key + "max_height", "applies to force handles only" + is);
    for (int i = 0; i < 2; ++i)
      if (h.at[i] + h.span[i] < 0 || h.at[i] + h.span[i] > 1)
        bad(key + "span", "at + span must stay on the cloth, in [0, 1]");
    if (h.type == HandleType::Pin && h.max_travel > 0)
      bad(key + "max_travel", "applies to force and move handles only" + is);
    if (h.type != HandleType::Move && nonzero(h.velocity))
      bad(key + "velocity", "applies to move handles only" + is);
    if (!h.vertices.empty() && (h.span[0] != 0 || h.span[1] != 0 || h.patch != 0))
      bad(key + "vertices",
          "names the handle's particles: span and patch place one by (u, v) instead; give "
          "one or the other");
    // A grid's particles are known here; a mesh cloth's once its file is read
    // (check_handle_vertices), as are a file's indices.
    if (p.cloth.mesh.empty()) {
      const long long n = p.cloth.resolution[0] * p.cloth.resolution[1];
      for (const long long i : h.vertices.indices)
        if (i >= n)
          bad(key + "vertices", "index " + std::to_string(i) + " is out of range: the cloth has " +
                                    std::to_string(n) + " particles (0 to " +
                                    std::to_string(n - 1) + ")");
    }
  }
}

// Keyframes in time order (a scene file's are checked as they are read, with
// their line; Params made in code here), each number finite.
void check_motions(const Params& p, const Complain& bad) {
  const auto check = [&](const Motion& m, const std::string& key) {
    for (std::size_t k = 0; k < m.keys.size(); ++k) {
      const Keyframe& f = m.keys[k];
      bool finite = std::isfinite(f.time);
      for (int c = 0; c < 3; ++c)
        finite = finite && std::isfinite(f.translate[c]) && std::isfinite(f.rotate[c]);
      if (!finite)
        bad(key, "keyframe " + std::to_string(k + 1) + " holds a value that is not finite");
      if (k > 0 && !(f.time > m.keys[k - 1].time))
        bad(key, "keyframe " + std::to_string(k + 1) + "'s time " + shortest(f.time) +
                     " s is not after keyframe " + std::to_string(k) + "'s, " +
                     shortest(m.keys[k - 1].time) + " s: the times must increase");
    }
  };
  check(p.ball.motion, "ball.motion");
  if (p.ball.motion.moves() && !p.ball.enabled)
    bad("ball.motion", "moves a ball that is not there (ball.enabled = false)");
  for (const auto& [name, o] : p.obstacles) check(o.motion, "obstacle." + name + ".motion");
  // A cache: a PC2 file, or an OBJ sequence with one run of # in its file's
  // name (its files are read with the mesh, check_obstacle_meshes).
  for (const auto& [name, o] : p.obstacles) {
    if (o.cache.empty()) continue;
    const std::string file = std::filesystem::path(o.cache).filename().string();
    const auto ends = [&](const std::string& e) {
      std::string tail = file.size() >= e.size() ? file.substr(file.size() - e.size()) : "";
      for (char& c : tail) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
      return tail == e;
    };
    const std::size_t hash = file.find('#');
    const bool sequence = hash != std::string::npos && ends(".obj") &&
                          file.find('#', file.find_first_not_of('#', hash)) == std::string::npos;
    if (o.cache.find('#') != std::string::npos && hash == std::string::npos)
      bad("obstacle." + name + ".cache", "\"" + o.cache +
                                             "\": the # of an OBJ sequence's frame number goes "
                                             "in the file's name, not its folder's");
    if (!sequence && !(hash == std::string::npos && ends(".pc2")))
      bad("obstacle." + name + ".cache",
          "\"" + o.cache +
              "\" is neither a PC2 file (.pc2) nor an OBJ sequence (one run of # in the file's "
              "name for the zero-padded frame number, e.g. \"arm_####.obj\")");
  }
}

// A mesh cloth placed as obstacles are, or by its centre: not both.
void check_cloth_placement(const Params& p, const Complain& bad) {
  if (!p.cloth.placed()) return;
  const char* keys = "cloth.up, cloth.translate, cloth.rotate and cloth.scale";
  if (p.cloth.mesh.empty())
    bad("cloth.translate", std::string(keys) +
                               " place a cloth.mesh; the grid is placed by cloth.center, "
                               "cloth.orientation and cloth.tilt");
  if (p.cloth.center != Vec3d{0, 0, 0} || p.cloth.tilt != 0 ||
      p.cloth.orientation != Orientation::Horizontal)
    bad("cloth.center", std::string("places the mesh's bounding box (with cloth.orientation and "
                                    "cloth.tilt), and ") +
                            keys + " place the file's own origin: give one or the other");
}

void check_consistency(const Params& p, const std::string& source,
                       const std::vector<std::string>& overrides, const toml::table& scene) {
  const Complain bad = [&](const std::string& key, const std::string& msg) {
    const std::string section = key.substr(0, key.find('.'));
    std::string sets;
    for (const auto& o : overrides) {
      std::string set_key = o.substr(0, o.find('='));  // `key = value` may have spaces
      set_key.erase(set_key.find_last_not_of(" \t") + 1);
      set_key.erase(0, set_key.find_first_not_of(" \t"));
      const bool named = !set_key.empty() && msg.find(set_key) != std::string::npos;
      if (o.substr(0, o.find('.')) == section || named)
        sets += (sets.empty() ? " with --set '" : "', '") + o;
    }
    std::string line;
    if (const toml::node* n = scene.at_path(key).node(); n && source != kInCode)
      line = ":" + std::to_string(n->source().begin.line);
    throw SceneError(source + line + (sets.empty() ? "" : sets + "'") + ": " + key + ": " + msg);
  };
  check_surfaces(p, bad);
  try {
    parse_export_formats(p.run.exports);
  } catch (const std::invalid_argument& e) {
    bad("run.export", e.what());
  }
  for (int i = 0; i < 2; ++i)
    if (p.wind.region_min[i] > p.wind.region_max[i])
      bad("wind.region_min", "must not exceed wind.region_max");
  if (p.material.bending == BendingModel::Quadratic &&
      (p.springs.bending_k || p.springs.bending_damping))
    bad(p.springs.bending_k ? "springs.bending_k" : "springs.bending_damping",
        "sets Provot's bending springs, which material.bending = \"quadratic\" (the default) "
        "does not have: set material.bending = \"provot\", or material.bending_rigidity");
  check_cloth_placement(p, bad);
  check_motions(p, bad);
  check_cloth_start(p, bad);
  // Params made in code (validate) may step to any time they like.
  if (source != kInCode) check_run_timing(p, bad);
  check_handles(p, bad);
}

// ":LINE" of a key a scene's text sets ("" where it does not: an override set it).
std::string line_of(const std::string& text, const std::string& source, const std::string& key) {
  try {
    const toml::table root = toml::parse(guard_toml_text(text, source), source);
    if (const toml::node* n = root.at_path(key).node())
      return ":" + std::to_string(n->source().begin.line);
  } catch (const toml::parse_error&) {
  }
  return "";
}

std::string read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw SceneError(path + ": cannot read the file");
  // No more than guard_toml_text takes, and one byte to say it was more.
  std::string text(kMaxSceneBytes + 1, '\0');
  in.read(text.data(), static_cast<std::streamsize>(text.size()));
  if (in.bad()) throw SceneError(path + ": cannot read the file");
  text.resize(static_cast<std::size_t>(in.gcount()));
  if (text.size() > kMaxSceneBytes)
    throw SceneError(path + ": more than a scene's " + std::to_string(kMaxSceneBytes) +
                     " bytes: not a scene file");
  return text;
}

}  // namespace

std::string ParamDef::type_name() const {
  const std::string name = std::visit(
      [](const auto& v) -> std::string {
        using T = std::decay_t<decltype(v)>;
        if constexpr (std::is_same_v<T, bool>) return "bool";
        if constexpr (std::is_same_v<T, long long>) return "integer";
        if constexpr (std::is_same_v<T, double>) return "number";
        if constexpr (std::is_same_v<T, std::string>) return "string";
        if constexpr (std::is_same_v<T, Vec2i>) return "[int, int]";
        if constexpr (std::is_same_v<T, Vec2d>) return "[num, num]";
        if constexpr (std::is_same_v<T, Vec3d>) return "[x, y, z]";
        return "";
      },
      default_value);
  if (list == List::Keyframes) return "[[t, [x, y, z], [rx, ry, rz]], ...]";
  if (list == List::Indices) return "[int, ...] or file";
  return name;
}

std::string ParamDef::default_text() const {
  if (optional && std::isnan(std::get<double>(default_value))) return "unset";
  return format_value(default_value);
}

std::string ParamDef::range_text() const {
  if (!choices.empty()) {
    std::string s;
    for (const auto& c : choices) s += (s.empty() ? "" : " | ") + (c.empty() ? "\"\"" : c);
    return s;
  }
  if (min > max) return "";
  auto num = [](double v) {
    if (v >= kNoLimit) return std::string("∞");
    if (v <= -kNoLimit) return std::string("−∞");
    char buf[32];
    auto r = std::to_chars(buf, buf + sizeof buf, v);
    return std::string(buf, r.ptr);
  };
  if (std::holds_alternative<bool>(default_value)) return "";
  return "[" + num(min) + ", " + num(max) + "]";
}

const std::vector<BuiltinScene>& builtin_scene_texts();  // builtin_scenes.cpp, generated

const std::vector<BuiltinScene>& builtin_scenes() {
  static const std::vector<BuiltinScene> scenes = [] {
    std::vector<BuiltinScene> v = builtin_scene_texts();
    for (auto& s : v) {
      try {
        s.description = toml::parse(s.text)["description"].value_or(std::string());
      } catch (const toml::parse_error&) {
      }
    }
    return v;
  }();
  return scenes;
}

const std::vector<ParamDef>& param_defs() {
  static const std::vector<ParamDef> defs = make_defs();
  return defs;
}

std::string format_value(const ParamValue& v) {
  return std::visit(
      [](const auto& x) -> std::string {
        using T = std::decay_t<decltype(x)>;
        if constexpr (std::is_same_v<T, bool>) return x ? "true" : "false";
        if constexpr (std::is_same_v<T, long long>) return std::to_string(x);
        if constexpr (std::is_same_v<T, double>) return shortest(x);
        if constexpr (std::is_same_v<T, std::string>) {
          // TOML's basic string: a control character (DEL too) only as an escape.
          std::string s = "\"";
          for (const char ch : x) {
            const auto c = static_cast<unsigned char>(ch);
            if (c == '"' || c == '\\') {
              s += '\\';
              s += ch;
            } else if (c == '\n') {
              s += "\\n";
            } else if (c == '\t') {
              s += "\\t";
            } else if (c < 0x20 || c == 0x7F) {
              char u[8];
              std::snprintf(u, sizeof u, "\\u%04X", c);
              s += u;
            } else {
              s += ch;
            }
          }
          return s + "\"";
        }
        if constexpr (std::is_same_v<T, Vec2i>)
          return "[" + std::to_string(x[0]) + ", " + std::to_string(x[1]) + "]";
        if constexpr (std::is_same_v<T, Vec2d>)
          return "[" + shortest(x[0]) + ", " + shortest(x[1]) + "]";
        if constexpr (std::is_same_v<T, Vec3d>)
          return "[" + shortest(x[0]) + ", " + shortest(x[1]) + ", " + shortest(x[2]) + "]";
        if constexpr (std::is_same_v<T, NumberList>) {
          std::string s = "[";
          for (const double e : x) s += (s.size() > 1 ? ", " : "") + shortest(e);
          return s + "]";
        }
      },
      v);
}

std::string format_value(const ParamDef& d, const ParamValue& v) {
  const auto* list = std::get_if<NumberList>(&v);
  if (!list || d.list == ParamDef::List::None) return format_value(v);
  std::string s = "[";
  if (d.list == ParamDef::List::Indices) {
    for (const double e : *list) s += (s.size() > 1 ? ", " : "") + std::to_string(std::llround(e));
    return s + "]";
  }
  for (std::size_t k = 0; k + 7 <= list->size(); k += 7) {
    const double* a = list->data() + k;
    s += std::string(s.size() > 1 ? ", " : "") + "[" + shortest(a[0]) + ", " +
         format_value(Vec3d{a[1], a[2], a[3]}) + ", " + format_value(Vec3d{a[4], a[5], a[6]}) + "]";
  }
  return s + "]";
}

Params parse_scene(const std::string& text, const std::string& source,
                   const std::vector<std::string>& overrides, IntegratorTier tier) {
  const std::string safe = guard_toml_text(text, source);
  toml::table root;
  try {
    root = toml::parse(safe, source);
  } catch (const toml::parse_error& e) {
    throw SceneError(source + ":" + std::to_string(e.source().begin.line) + ": " +
                     std::string(e.description()));
  }
  std::vector<toml::table> sets;
  for (const auto& o : overrides) sets.push_back(parse_override(o));
  Params p;
  apply_tier(p, tier);
  apply_named_preset(root, sets, p);
  // Overrides are applied on top, each keeping its own source for messages.
  apply_sources(root, sets, p);
  check_consistency(p, source, overrides, root);
  return p;
}

Params reparse_scene(const Params& base, const std::vector<std::string>& overrides) {
  Params p = parse_scene(to_toml(base), base.name, overrides);
  // to_toml wrote the scene's preset values out, and they would hide a new one's.
  if (p.material.preset != base.material.preset) {
    Params with = base;
    apply_preset(with, p.material.preset);
    p = parse_scene(to_toml(with), base.name, overrides);
  }
  p.scene_dir = base.scene_dir;
  return p;
}

Params load_scene(const std::string& scene, const std::vector<std::string>& overrides,
                  IntegratorTier tier) {
  // A file, not a folder: a run's output folder named after a built-in scene
  // (`--out hang`) opens as a stream too, and read as an empty scene.
  std::error_code ec;
  // Opening a FIFO waits for a writer: only a regular file is opened.
  const auto st = std::filesystem::status(scene, ec);
  if (std::filesystem::exists(st) && !std::filesystem::is_regular_file(st) &&
      !std::filesystem::is_directory(st))
    throw SceneError(scene +
                     ": not a regular file (a FIFO, device or socket): a scene is a TOML file");
  if (ec && ec != std::errc::no_such_file_or_directory)
    throw SceneError(scene + ": cannot read the file (" + ec.message() + ")");
  std::ifstream probe(std::filesystem::is_regular_file(st) ? scene : std::string());
  if (probe.good()) {
    const std::string text = read_file(scene);
    Params p = parse_scene(text, scene, overrides, tier);
    p.scene_dir = std::filesystem::absolute(scene).parent_path().lexically_normal().string();
    check_cloth_mesh(p, scene);
    check_obstacle_meshes(p, scene,
                          [&](const std::string& key) { return line_of(text, scene, key); });
    check_handle_vertices(p, scene);
    detail::check_humidity_map(p, scene + line_of(text, scene, "cloth.humidity_map"));
    return p;
  }
  for (const auto& b : builtin_scenes())
    if (b.name == scene) {
      Params p = parse_scene(b.text, "scenes/" + b.name + ".toml", overrides, tier);
      p.scene_dir = "builtin:";
      check_cloth_mesh(p, "scenes/" + b.name + ".toml");
      check_obstacle_meshes(p, "scenes/" + b.name + ".toml",
                            [&](const std::string& key) { return line_of(b.text, b.name, key); });
      check_handle_vertices(p, "scenes/" + b.name + ".toml");
      detail::check_humidity_map(
          p, "scenes/" + b.name + ".toml" + line_of(b.text, b.name, "cloth.humidity_map"));
      return p;
    }
  if (scene.find('/') != std::string::npos || scene.find(".toml") != std::string::npos)
    throw SceneError(scene + ": no such file");
  std::string names;
  for (const auto& b : builtin_scenes()) names += (names.empty() ? "" : ", ") + b.name;
  throw SceneError(scene + ": not a file and not a built-in scene (built-in: " + names + ")");
}

namespace {

// A comment under `preset = "NAME"`: the keys whose values are not the
// preset's (the scene or --set gave them).
std::string preset_overrides_text(const Params& p) {
  const FabricPreset* preset = find_preset(p.material.preset);
  if (!preset) return "";
  std::string keys;
  for (const PresetValue& v : preset->values)
    if (std::get<double>(find_def(v.key)->get(p, "")) != v.value)
      keys += (keys.empty() ? "" : ", ") + v.key;
  return keys.empty() ? "" : "# set over the preset: " + keys + "\n";
}

}  // namespace

std::string to_toml(const Params& p) {
  std::ostringstream o;
  std::string section;
  for (const auto& d : param_defs()) {
    if (!named_kind(d.key).empty()) continue;
    const auto dot = d.key.rfind('.');
    const std::string sec = dot == std::string::npos ? "" : d.key.substr(0, dot);
    const std::string leaf = dot == std::string::npos ? d.key : d.key.substr(dot + 1);
    if (sec != section) {
      if (section == "springs") o << springs_text(p);
      o << "\n[" << sec << "]\n";
      section = sec;
    }
    const ParamValue v = d.get(p, "");
    if (d.optional && std::isnan(std::get<double>(v)))
      o << "# " << leaf << ": unset, from [material]\n";
    else
      o << leaf << " = " << format_value(d, v) << "\n";
    if (d.key == "material.preset") o << preset_overrides_text(p);
  }
  for (const std::string_view kind : kNamedKinds)
    for (const auto& name : table_names(p, std::string(kind))) {
      o << "\n[" << kind << "." << name << "]\n";
      for (const auto& d : param_defs()) {
        if (named_kind(d.key) != kind) continue;
        o << d.key.substr(kind.size() + 3) << " = " << format_value(d, d.get(p, name)) << "\n";
      }
    }
  return o.str();
}

std::string params_text() {
  // Columns padded by characters, not bytes: units and ranges hold °, ², −∞.
  const auto pad = [](const std::string& text, std::size_t width) {
    std::size_t chars = 0;
    for (const unsigned char c : text) chars += (c & 0xC0) != 0x80;
    return text + std::string(width > chars ? width - chars : 1, ' ');
  };
  std::ostringstream o;
  for (const auto& d : param_defs())
    o << pad(d.key, 29) << pad(d.unit, 11) << pad(d.default_text(), 23) << pad(d.range_text(), 23)
      << d.meaning << "\n";
  return o.str();
}

std::string params_markdown() {
  // A "|" inside a cell ("table | ball") would end it: GitHub's tables take "\|".
  const auto cell = [](const std::string& text) {
    std::string out;
    for (const char c : text) out += c == '|' ? std::string("\\|") : std::string(1, c);
    return out;
  };
  std::ostringstream o;
  o << "| key | unit | default | range | meaning |\n|---|---|---|---|---|\n";
  for (const auto& d : param_defs())
    o << "| `" << cell(d.key) << "` | " << cell(d.unit) << " | `" << cell(d.default_text())
      << "` | " << cell(d.range_text()) << " | " << cell(d.meaning) << " |\n";
  return o.str();
}

Params at_resolution(Params p, long long grid) {
  if (!p.cloth.mesh.empty())  // silently keeping the mesh would report a grid never run
    throw SceneError("a grid " + std::to_string(grid) +
                     " wide was asked of a cloth that is a mesh (" + "cloth.mesh = \"" +
                     p.cloth.mesh + "\"): its vertices are its particles and " +
                     "cloth.resolution is not used; remesh the file for another resolution");
  for (const auto& [name, h] : p.handles)  // j nu + i: other particles on another grid
    if (!h.vertices.empty())
      throw SceneError("a grid " + std::to_string(grid) +
                       " wide was asked of a scene whose handle." + name +
                       ".vertices names particles by index: on another grid they are "
                       "other particles (place the handle by at, span and patch to scale it)");
  const auto [nu, nv] = p.cloth.resolution;
  const double scale = static_cast<double>(grid - 1) / static_cast<double>(nu - 1);
  const long long height = std::llround(static_cast<double>(nv - 1) * scale) + 1;
  const ParamDef& d = *find_def("cloth.resolution");
  for (const long long size : {grid, height})
    if (static_cast<double>(size) < d.min || static_cast<double>(size) > d.max)
      throw SceneError(std::to_string(grid) + " gives a " + std::to_string(grid) + " x " +
                       std::to_string(height) + " cloth; each side must be " +
                       std::to_string(std::llround(d.min)) + " to " +
                       std::to_string(std::llround(d.max)) + " particles");
  for (auto& [name, h] : p.handles) h.patch = std::llround(static_cast<double>(h.patch) * scale);
  const double limit_before = explicit_step_limit(p);
  p.cloth.resolution = {grid, height};
  // xpbd's substeps: a set count is the count that runs; the default (0)
  // grows with the grid by itself (xpbd_substeps).
  // The particles get lighter as the spacing squared, the springs' limit
  // falls as the spacing, the bending's (quadratic, or Provot's B / l²) faster:
  // the step falls as the spacing, or as the limit where that falls faster.
  if (p.integrator.type != IntegratorType::ImplicitEuler &&
      p.integrator.type != IntegratorType::Xpbd && scale > 1)
    p.integrator.dt *= std::min(1.0 / scale, explicit_step_limit(p) / limit_before);
  return p;
}

std::string springs_text(const Params& p) {
  if (!p.cloth.mesh.empty())
    return "# The springs: per spring, from the material and the mesh's local sizes "
           "(docs/model.md section 1,\n#   \"a cloth from a mesh\"), or as [springs] sets "
           "them; cloth.resolution and cloth.size are not used.\n";
  const ResolvedSprings r = resolve_springs(p);
  const auto num = [](double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.4g", v);
    return std::string(buf);
  };
  // "200 N/m", or "250 N/m along u, 160 N/m along v" where they differ.
  const auto values = [&](std::initializer_list<std::pair<double, const char*>> vs,
                          const char* unit) {
    std::string s;
    const bool same = std::all_of(vs.begin(), vs.end(),
                                  [&](const auto& v) { return v.first == vs.begin()->first; });
    for (const auto& [v, where] : vs) {
      s += (s.empty() ? "" : ", ") + num(v) + " " + unit + (same ? "" : std::string(" ") + where);
      if (same) break;
    }
    return s;
  };
  const auto source = [](const std::optional<double>& set, const char* material) {
    return set ? std::string("set in [springs]") : std::string("from ") + material;
  };
  std::ostringstream o;
  o << "# The springs, resolved at a spacing of " << num(r.du * 1000) << " mm (u) x "
    << num(r.dv * 1000) << " mm (v):\n";
  o << "#   structural: k "
    << values({{r.structural_u.k, "along u"}, {r.structural_v.k, "along v"}}, "N/m") << " ("
    << source(p.springs.structural_k, "material.stretch_stiffness") << "); damping "
    << values({{r.structural_u.damping, "along u"}, {r.structural_v.damping, "along v"}}, "N·s/m")
    << " (" << source(p.springs.structural_damping, "material.stretch_damping") << ")\n";
  o << "#   shear: k " << num(r.shear.k) << " N/m ("
    << source(p.springs.shear_k, "material.shear_stiffness") << "); damping "
    << num(r.shear.damping) << " N·s/m ("
    << source(p.springs.shear_damping, "material.shear_damping") << ")\n";
  if (p.material.bending == BendingModel::Quadratic) {
    o << "#   bending: quadratic (a curvature energy, no springs), B "
      << num(p.material.bending_rigidity) << " N·m (material.bending_rigidity)\n";
    return o.str();
  }
  o << "#   bending: k "
    << values({{r.bending_u.k, "along u"},
               {r.bending_v.k, "along v"},
               {r.bending_diagonal.k, "diagonal"}},
              "N/m")
    << " (" << source(p.springs.bending_k, "material.bending_rigidity") << "); damping "
    << values({{r.bending_u.damping, "along u"},
               {r.bending_v.damping, "along v"},
               {r.bending_diagonal.damping, "diagonal"}},
              "N·s/m")
    << " (" << source(p.springs.bending_damping, "material.bending_damping") << ")\n";
  return o.str();
}

namespace {

// A value made in code, checked as convert() checks one read from a file.
void check_value(const ParamDef& d, const ParamValue& value, const std::string& key) {
  const auto bad = [&](const std::string& msg) {
    throw SceneError(kInCode + ": " + key + ": " + msg);
  };
  const auto in_range = [&](double v) {
    if (!std::isfinite(v)) bad("value is not finite");
    if (d.min <= d.max && (v < d.min || v > d.max))
      bad("value " + shortest(v) + " is out of range " + d.range_text());
  };
  std::visit(
      [&](const auto& v) {
        using T = std::decay_t<decltype(v)>;
        if constexpr (std::is_same_v<T, double>) {
          if (!(d.optional && std::isnan(v))) in_range(v);
        } else if constexpr (std::is_same_v<T, long long>) {
          in_range(static_cast<double>(v));
        } else if constexpr (std::is_same_v<T, std::string>) {
          if (!d.choices.empty() &&
              std::find(d.choices.begin(), d.choices.end(), v) == d.choices.end())
            bad(not_a_choice(d, v));
        } else if constexpr (!std::is_same_v<T, bool>) {
          for (const auto x : v) in_range(static_cast<double>(x));
        }
      },
      value);
}

}  // namespace

void validate(const Params& p) {
  for (const ParamDef& d : param_defs()) {
    // [handle.NAME] and [obstacle.NAME] keys, for each such table.
    const std::string kind = named_kind(d.key);
    if (kind.empty()) {
      check_value(d, d.get(p, ""), d.key);
      continue;
    }
    for (const auto& name : table_names(p, kind))
      check_value(d, d.get(p, name), kind + "." + name + d.key.substr(kind.size() + 2));
  }
  check_consistency(p, kInCode, {}, toml::table{});
}

}  // namespace wetcloth
