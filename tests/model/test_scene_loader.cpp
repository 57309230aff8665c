#include <gtest/gtest.h>

#include <cmath>

#include "model/topology.hpp"
#include "wetcloth/scene.hpp"
#include "wetcloth/simulation.hpp"

using namespace wetcloth;

namespace {
std::string error_of(const std::string& text, std::vector<std::string> sets = {}) {
  try {
    parse_scene(text, "bad.toml", sets);
  } catch (const SceneError& e) {
    return e.what();
  }
  return "";
}
}  // namespace

TEST(SceneLoader, ReadsValuesAndKeepsDefaults) {
  const Params p = parse_scene("[cloth]\nhumidity = 0.3\nresolution = [11, 21]\n", "s.toml");
  EXPECT_EQ(p.cloth.humidity, 0.3);
  EXPECT_EQ(p.cloth.resolution[1], 21);
  EXPECT_EQ(p.material.stretch_stiffness, 200);  // docs/model.md default
  EXPECT_FALSE(p.springs.structural_k);          // unset: from the material
}

// docs/model.md section 1: the springs follow from the material and the spacing,
// so that a 0.3 m cloth of 51 x 51 gets exactly 200/20/20 N/m; a spring
// constant set directly is that constant at every grid.
TEST(SceneLoader, SpringsFollowTheMaterialAndTheSpacing) {
  const auto stencil = [](const Params& p) { return build_model(p).topology->stencil; };
  // The quadratic bending (the default) has no springs: offsets 4-7 are empty.
  for (const auto& e : stencil(load_scene("pull-straight"))) {
    const bool structural = std::abs(e.di) + std::abs(e.dj) == 1;
    const bool shear = std::abs(e.di) == 1 && std::abs(e.dj) == 1;
    EXPECT_EQ(e.k, structural ? 200.0 : shear ? 20.0 : 0.0) << e.di << "," << e.dj;
    EXPECT_EQ(e.damping, structural || shear ? 0.01 : 0.0) << e.di << "," << e.dj;
  }
  // Provot's: the paper's 20 N/m at 6 mm from B = 7.2e-4 N·m.
  const std::vector<std::string> provot = {"material.bending=\"provot\"",
                                           "material.bending_rigidity=7.2e-4"};
  for (const auto& e : stencil(load_scene("pull-straight", provot)))
    if (std::abs(e.di) == 2 || std::abs(e.dj) == 2) EXPECT_EQ(e.k, 20.0) << e.di << "," << e.dj;
  // l = 12 mm and 3 mm: bending B / l² = 5 and 80 N/m, its damping alike;
  // structural and shear as given.
  for (const auto& [grid, bending] : {std::pair{26, 5.0}, std::pair{101, 80.0}}) {
    const auto s = stencil(at_resolution(load_scene("pull-straight", provot), grid));
    EXPECT_DOUBLE_EQ(s[0].k, 200) << grid;
    EXPECT_DOUBLE_EQ(s[2].k, 20) << grid;
    for (int e = 4; e < 8; ++e) {
      EXPECT_NEAR(s[e].k, bending, 1e-9 * bending) << grid;
      EXPECT_NEAR(s[e].damping, 0.01 * bending / 20, 1e-12) << grid;
    }
  }
  // Set directly: the same at every grid.
  const auto set = stencil(
      at_resolution(load_scene("pull-straight",
                               {"material.bending=\"provot\"", "material.bending_rigidity=7.2e-4",
                                "springs.bending_k=20", "springs.structural_damping=0.5"}),
                    101));
  EXPECT_EQ(set[4].k, 20);
  EXPECT_EQ(set[7].k, 20);
  EXPECT_EQ(set[0].damping, 0.5);
  EXPECT_NEAR(set[4].damping, 0.04, 1e-12);  // unset: from the material
  // A grid that is not square (du = 15 mm, dv = 30 mm): the membrane keeps
  // its stiffness per unit width in every direction.
  const auto r =
      resolve_springs(parse_scene("[cloth]\nresolution = [21, 11]\n[material]\nbending = "
                                  "\"provot\"\nbending_rigidity = 7.2e-4\n",
                                  "s.toml"));
  EXPECT_DOUBLE_EQ(r.structural_u.k, 400);
  EXPECT_DOUBLE_EQ(r.structural_v.k, 100);
  EXPECT_DOUBLE_EQ(r.shear.k, 16);
  EXPECT_DOUBLE_EQ(r.bending_u.k, 7.2e-4 * 0.03 / (0.015 * 0.015 * 0.015));
  EXPECT_DOUBLE_EQ(r.bending_v.k, 7.2e-4 * 0.015 / (0.03 * 0.03 * 0.03));
  EXPECT_DOUBLE_EQ(r.bending_diagonal.k,
                   4 * 7.2e-4 * 0.015 * 0.03 / std::pow(0.015 * 0.015 + 0.03 * 0.03, 2));
}

// Material keys and spring overrides are checked and named like any other;
// an unset override reads back unset, and the resolved springs are printed.
TEST(SceneLoader, MaterialAndSpringOverridesAreCheckedAndPrinted) {
  EXPECT_NE(error_of("[material]\n\nbending_rigidity = -1\n")
                .find("bad.toml:3: material.bending_rigidity: value -1.0 is out of range"),
            std::string::npos);
  EXPECT_NE(error_of("[springs]\nbending_k = \"stiff\"\n")
                .find("bad.toml:2: springs.bending_k: expected a number"),
            std::string::npos);
  const Params p = load_scene("pull-straight", {"springs.shear_k=30"});
  const std::string text = to_toml(p);
  EXPECT_NE(text.find("shear_k = 30.0\n"), std::string::npos) << text;
  EXPECT_NE(text.find("# structural_k: unset, from [material]\n"), std::string::npos) << text;
  EXPECT_NE(text.find("#   shear: k 30 N/m (set in [springs])"), std::string::npos) << text;
  EXPECT_NE(text.find("#   bending: quadratic (a curvature energy, no springs), B 2e-05 N·m "
                      "(material.bending_rigidity)"),
            std::string::npos)
      << text;
  EXPECT_NE(to_toml(load_scene("pull-straight", {"material.bending=\"provot\""}))
                .find("#   bending: k 0.5556 N/m (from material.bending_rigidity)"),
            std::string::npos);
  const Params q = parse_scene(text, "resolved.toml");
  EXPECT_EQ(q.springs.shear_k, 30.0);
  EXPECT_FALSE(q.springs.structural_k);
}

TEST(SceneLoader, IntegersAreAcceptedForNumbers) {
  EXPECT_EQ(parse_scene("[cloth]\nhumidity = 1\n", "s.toml").cloth.humidity, 1.0);
}

TEST(SceneLoader, SyntaxErrorNamesFileAndLine) {
  EXPECT_NE(error_of("[cloth]\nhumidity = = 2\n").find("bad.toml:2"), std::string::npos);
}

TEST(SceneLoader, UnknownKeyNamesFileLineAndKey) {
  const auto e = error_of("[cloth]\n\nhumidty = 0.5\n");
  EXPECT_NE(e.find("bad.toml:3"), std::string::npos) << e;
  EXPECT_NE(e.find("cloth.humidty"), std::string::npos) << e;
}

TEST(SceneLoader, WrongTypeNamesTheKey) {
  const auto e = error_of("[integrator]\ndt = \"fast\"\n");
  EXPECT_NE(e.find("bad.toml:2: integrator.dt"), std::string::npos) << e;
}

TEST(SceneLoader, OutOfRangeValuesAreRejected) {
  for (const char* text : {"[cloth]\nhumidity = 1.5\n", "[cloth]\nareal_density = -0.1\n",
                           "[cloth]\nresolution = [1, 10]\n", "[integrator]\ndt = 0.0\n",
                           "[integrator]\ndt = -1e-5\n"}) {
    const auto e = error_of(text);
    EXPECT_NE(e.find("bad.toml:2"), std::string::npos) << text << " -> " << e;
    EXPECT_NE(e.find("out of range"), std::string::npos) << text << " -> " << e;
  }
}

TEST(SceneLoader, ChoicesAreChecked) {
  const auto e = error_of("[air]\nmodel = \"leaky\"\n");
  EXPECT_NE(e.find("air.model"), std::string::npos) << e;
  EXPECT_NE(e.find("exchange"), std::string::npos) << e;
}

TEST(SceneLoader, HandleKeysAreChecked) {
  const Params p = parse_scene("[handle.pull]\nforce = [0, 0, 2]\npatch = 1\n", "s.toml");
  EXPECT_EQ(p.handles.at("pull").force[2], 2.0);
  EXPECT_EQ(p.handles.at("pull").type, HandleType::Force);
  const auto e = error_of("[handle.pull]\nforse = [0, 0, 2]\n");
  EXPECT_NE(e.find("handle.pull.forse"), std::string::npos) << e;
}

// A key that does nothing for its handle's type is an error, not ignored.
TEST(SceneLoader, HandleKeysMustFitTheType) {
  const auto expect = [](const std::string& text, const std::string& what) {
    const auto e = error_of(text);
    EXPECT_NE(e.find(what), std::string::npos) << text << " -> " << e;
  };
  expect("[handle.p]\ntype = \"pin\"\nforce = [0, 0, 1]\n",
         "bad.toml:3: handle.p.force: applies to force handles only (this one is pin)");
  expect("[handle.m]\ntype = \"move\"\nmax_height = 0.1\n",
         "handle.m.max_height: applies to force handles only");
  expect("[handle.p]\ntype = \"pin\"\nmax_travel = 0.1\n",
         "handle.p.max_travel: applies to force and move handles only");
  expect("[handle.f]\nvelocity = [1, 0, 0]\n",
         "handle.f.velocity: applies to move handles only (this one is force)");
  expect("[handle.e]\nat = [0.5, 0]\nspan = [0.6, 0]\n", "handle.e.span: at + span must stay");
  // What does fit: a late pin, a move that stops.
  EXPECT_NO_THROW(parse_scene("[handle.p]\ntype = \"pin\"\nstart = 0.1\n", "s.toml"));
  EXPECT_NO_THROW(parse_scene(
      "[handle.m]\ntype = \"move\"\nvelocity = [1, 0, 0]\nmax_travel = 0.1\n", "s.toml"));
}

TEST(SceneLoader, OverridesUseDottedKeysAndNameThemselves) {
  const Params p = parse_scene("", "s.toml", {"cloth.resolution=[5,7]", "air.model=sealed"});
  EXPECT_EQ(p.cloth.resolution[1], 7);
  EXPECT_EQ(p.air.model, AirModel::Sealed);
  const auto e = error_of("", {"cloth.humidity=2"});
  EXPECT_NE(e.find("--set 'cloth.humidity=2'"), std::string::npos) << e;
  EXPECT_NE(error_of("", {"nonsense"}).find("KEY=VALUE"), std::string::npos);
}

TEST(SceneLoader, ResolvedTomlReadsBackToTheSameParameters) {
  Params p =
      load_scene("pull-straight", {"cloth.humidity=0.1234567890123", "wind.velocity=[1e-7, 2, 3]"});
  const Params q = parse_scene(to_toml(p), "resolved.toml");
  EXPECT_EQ(to_toml(p), to_toml(q));
  EXPECT_EQ(q.cloth.humidity, 0.1234567890123);
  EXPECT_EQ(q.handles.size(), p.handles.size());
}

TEST(SceneLoader, UnknownSceneAndMissingFile) {
  try {
    load_scene("no-such-scene");
    FAIL();
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("built-in"), std::string::npos);
  }
  EXPECT_THROW(load_scene("/nonexistent/scene.toml"), SceneError);
}

TEST(SceneLoader, EveryBuiltinSceneLoads) {
  ASSERT_GE(builtin_scenes().size(), 4u);
  for (const auto& s : builtin_scenes()) {
    EXPECT_NO_THROW(load_scene(s.name)) << s.name;
    EXPECT_FALSE(s.description.empty()) << s.name;
  }
}

TEST(SceneLoader, EveryParameterIsDocumented) {
  for (const auto& d : param_defs()) {
    EXPECT_FALSE(d.meaning.empty()) << d.key;
    // Every number has a unit ("1" when dimensionless).
    if (std::holds_alternative<double>(d.default_value)) {
      EXPECT_FALSE(d.unit.empty()) << d.key;
    }
  }
}

// The same cloth on another grid: its height in particles scales with its
// width, a handle's patch keeps its size in metres, an explicit step shrinks
// with the spacing (an implicit one is left alone), and a side outside
// cloth.resolution's range, or a cloth that is a mesh, is refused.
TEST(SceneLoader, AtResolutionKeepsTheClothInMetres) {
  const std::string text =
      "[cloth]\nresolution = [21, 11]\n[handle.pull]\ntype = \"force\"\npatch = 2\n";
  const Params p = parse_scene(text, "s.toml");
  const Params fine = at_resolution(p, 41);
  EXPECT_EQ(fine.cloth.resolution, (Vec2i{41, 21}));
  EXPECT_EQ(fine.handles.at("pull").patch, 4);
  // The step falls as the spacing, or as the explicit limit where that falls
  // faster (the bending's falls as the spacing squared).
  EXPECT_DOUBLE_EQ(fine.integrator.dt, p.integrator.dt * std::min(0.5, explicit_step_limit(fine) /
                                                                           explicit_step_limit(p)));
  EXPECT_LT(fine.integrator.dt, p.integrator.dt / 2);
  const Params coarse = at_resolution(p, 11);
  EXPECT_EQ(coarse.cloth.resolution, (Vec2i{11, 6}));
  EXPECT_EQ(coarse.handles.at("pull").patch, 1);
  EXPECT_EQ(coarse.integrator.dt, p.integrator.dt);  // a coarser grid is stable at the same step
  const Params implicit = parse_scene(text + "[integrator]\ntype = \"implicit-euler\"\n", "s.toml");
  EXPECT_EQ(at_resolution(implicit, 41).integrator.dt, implicit.integrator.dt);
  // xpbd: a set count of substeps is the count that runs at any grid; the
  // default (0) grows with the grid by itself.
  const std::string xpbd = text + "[integrator]\ntype = \"xpbd\"\n";
  EXPECT_EQ(xpbd_substeps(at_resolution(parse_scene(xpbd + "substeps = 12\n", "s.toml"), 401)), 12);
  EXPECT_EQ(xpbd_substeps(at_resolution(parse_scene(xpbd, "s.toml"), 401)), 40);
  EXPECT_THROW(at_resolution(p, 1), SceneError);  // 1 x 1
  EXPECT_THROW(at_resolution(p, 2002), SceneError);
  // A mesh cloth's particles are its file's vertices: no grid to resize, and
  // the error says so rather than running the file's mesh under another name.
  try {
    at_resolution(load_scene("drape-disc"), 21);
    ADD_FAILURE() << "a mesh cloth took a grid";
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("cloth.mesh = \"meshes/cloth_disc.obj\""),
              std::string::npos)
        << e.what();
  }
}

// A scene that gives no step gets the same fraction of its cloth's explicit
// limit as the default cloth's 1e-4 s at 51 x 51: a finer grid or a lighter
// fabric a shorter step, the cloth taken dry (its lightest), a mesh cloth and
// the large-step integrators their fixed steps, and a step given is kept.
TEST(SceneLoader, AStepNotGivenFollowsTheClothsExplicitLimit) {
  const Params base = load_scene("drape-ball");
  EXPECT_EQ(base.integrator.dt, 1e-4);
  EXPECT_EQ(load_scene("drape-ball", {"cloth.humidity=1"}).integrator.dt, 1e-4);
  EXPECT_EQ(load_scene("drape-ball", {"cloth.resolution=[25,25]"}).integrator.dt, 1e-4);
  const Params fine = load_scene("drape-ball", {"cloth.resolution=[101,101]"});
  Params dry = fine;
  dry.cloth.humidity = 0;
  EXPECT_DOUBLE_EQ(fine.integrator.dt,
                   1e-4 * explicit_step_limit(dry) / explicit_step_limit(Params{}));
  EXPECT_NEAR(fine.integrator.dt, 4.93e-5, 0.01e-5);
  const Params light = load_scene("drape-ball", {"cloth.areal_density=0.03"});
  EXPECT_NEAR(light.integrator.dt, 5e-5, 1e-9);  // a quarter of the mass: half the limit
  EXPECT_EQ(
      load_scene("drape-ball", {"cloth.resolution=[101,101]", "integrator.dt=3e-5"}).integrator.dt,
      3e-5);
  EXPECT_EQ(load_scene("sleeve-pull", {"integrator.type=\"symplectic-euler\""}).integrator.dt,
            1e-4);
  EXPECT_EQ(load_scene("drape-ball", {"integrator.type=\"xpbd\""}).integrator.dt, 1.0 / 240);
  // A tier named after a step sets its own, and a step named with it is kept.
  const std::vector<std::string> fine_then_tier = {
      "cloth.resolution=[101,101]", "integrator.dt=3e-5", "integrator.tier=\"accurate\""};
  EXPECT_EQ(load_scene("drape-ball", fine_then_tier).integrator.dt, fine.integrator.dt);
  EXPECT_EQ(parse_scene("[integrator]\ntier = \"live\"\ndt = 3e-5\n", "s.toml").integrator.dt,
            3e-5);

  // The dry drape on 101 x 101 at its step runs; at the default cloth's step it
  // blows up within 2 ms.
  for (const bool given : {false, true}) {
    std::vector<std::string> sets = {"cloth.resolution=[101,101]", "cloth.humidity=0"};
    if (given) sets.push_back("integrator.dt=1e-4");
    Simulation sim(load_scene("drape-ball", sets));
    EXPECT_EQ(sim.advance_to(0.01), !given) << sim.blow_up_reason();
  }
}

// Params made in code get the checks a scene file gets: a Simulation is not
// built on values out of range (it used to run, and do nothing or blow up).
TEST(SceneLoader, ParamsMadeInCodeAreChecked) {
  const auto error_building = [](const Params& p) -> std::string {
    try {
      Simulation sim(p);
    } catch (const SceneError& e) {
      return e.what();
    }
    return "";
  };
  Params p = load_scene("drop-table");
  EXPECT_EQ(error_building(p), "");
  p.cloth.humidity = 3.0;
  EXPECT_EQ(error_building(p), "Params: cloth.humidity: value 3.0 is out of range [0, 1]");
  p = load_scene("drop-table");
  p.integrator.dt = -1e-3;
  EXPECT_NE(error_building(p).find("Params: integrator.dt: value -0.001 is out of range"),
            std::string::npos);
  p = load_scene("drop-table");
  p.contact.surface = SurfaceChoice::Ball;
  EXPECT_NE(error_building(p).find("contact.surface: is 'ball' but ball.enabled is false"),
            std::string::npos);
  Simulation sim(load_scene("drop-table"));
  p = sim.model().params;
  p.air.model = static_cast<AirModel>(7);  // no such model
  EXPECT_THROW(sim.set_params(p), SceneError);
  EXPECT_THROW(sim.set_humidity(1.5), SceneError);
  EXPECT_NO_THROW(sim.set_humidity(1.0));
}

// A step changed between steps (the viewer's integrator, Python's set) keeps
// the clock: the time goes on from where it was, not from the steps taken
// times the new step.
TEST(SceneLoader, ANewStepKeepsTheClock) {
  Simulation sim(load_scene("drag-corner", {"cloth.resolution=[21,21]"}));
  ASSERT_TRUE(sim.advance_to(0.05));
  Params p = sim.model().params;
  p.integrator.type = IntegratorType::Xpbd;
  p.integrator.dt = 1.0 / 240;
  sim.set_params(p);
  EXPECT_NEAR(sim.state().time, 0.05, 0.5 * p.integrator.dt);
  const long long steps = sim.state().steps;
  ASSERT_TRUE(sim.advance_to(0.1)) << sim.blow_up_reason();
  EXPECT_NEAR(sim.state().time, 0.1, 0.5 * p.integrator.dt);
  EXPECT_EQ(sim.state().steps - steps, 12);  // 0.05 s of 1/240 s
}

// A handle's name is part of its keys (and of scene.toml): a bare key.
TEST(SceneLoader, HandleNamesAreBareKeys) {
  EXPECT_NE(error_of("[handle.\"my pull\"]\ntype = \"pin\"\n")
                .find("bad.toml:1: handle.my pull: a handle's name is letters"),
            std::string::npos);
  EXPECT_EQ(error_of("[handle.pull-2]\ntype = \"pin\"\n"), "");
}

// Scene text is untrusted: what overflowed toml++'s stack (deep nesting) or
// reached its undefined behaviour (a non-ASCII byte outside a string) is bad
// input, named, before toml++ sees it.
TEST(SceneLoader, GuardsNestingAndBytesBeforeParsing) {
  std::string deep = "[a";
  for (int i = 0; i < 100000; ++i) deep += ".a";
  EXPECT_NE(error_of(deep + "]\n").find("bad.toml:1: a dotted key of more than 32 parts"),
            std::string::npos);
  EXPECT_NE(error_of("a = " + std::string(50000, '[') + std::string(50000, ']'))
                .find("nested more than 32"),
            std::string::npos);
  EXPECT_NE(error_of("b = 1\n\xc3\xa9 = 1\n").find("bad.toml:2: a non-ASCII character"),
            std::string::npos);
  EXPECT_NE(error_of("name = \"\xc3\x28\"\n").find("not valid UTF-8"), std::string::npos);
  EXPECT_NE(error_of("", {deep.substr(1) + "=1"}).find("a dotted key of more than 32 parts"),
            std::string::npos);
  // What the guard lets through: strings and comments in UTF-8, floats, 32 levels.
  EXPECT_EQ(error_of("name = \"séance ✓\" # déjà\n[cloth]\nhumidity = 0.5\n"), "");
  EXPECT_NE(error_of("[foo]\n").find("bad.toml:1: foo: unknown table"), std::string::npos);
  // toml++ 3.3 is undefined on U+00A1-U+0499 and U+FB66-U+FEFE where it reads
  // ahead: in a basic string they are passed escaped (the same value), in a
  // literal string refused.
  EXPECT_EQ(parse_scene("description = \"\xc3\xa9\xd0\x96\xef\xbb\x9f\" # \xc3\xa9\n", "u.toml")
                .description,
            "\xc3\xa9\xd0\x96\xef\xbb\x9f");
  EXPECT_NE(error_of("description = '\xc3\xa9'\n").find("U+00E9 in a literal string"),
            std::string::npos);
  EXPECT_NE(error_of("name = 0b1'\xef\xbb\x9f\n").find("bad.toml:1"), std::string::npos);
}

TEST(SceneLoader, ResolvedTomlEscapesControlCharacters) {
  const Params p = parse_scene("description = \"a\\u0001b\\u007f\\n\\\"q\\\"\"\n", "c.toml");
  EXPECT_EQ(p.description, std::string("a\x01"
                                       "b\x7f\n\"q\""));
  EXPECT_EQ(parse_scene(to_toml(p), "resolved.toml").description, p.description);
}

// integrator.tier sets the integrator's keys; a key given after it (in the
// scene, or a later --set) overrides it; a type named without a step gets
// its kind's step, not the small one of the tier before.
TEST(SceneLoader, TiersAndAnIntegratorsOwnStep) {
  const double large = 1.0 / 240;
  Params p = parse_scene("", "s.toml");
  EXPECT_EQ(p.integrator.tier, IntegratorTier::Accurate);
  EXPECT_EQ(p.integrator.type, Params{}.integrator.type);
  EXPECT_EQ(p.integrator.dt, Params{}.integrator.dt);
  p = parse_scene("", "s.toml", {"integrator.tier=\"live\""});
  EXPECT_EQ(p.integrator.type, IntegratorType::Xpbd);
  EXPECT_EQ(p.integrator.dt, large);
  // The live tier's default count, as xpbd_substeps gives it.
  EXPECT_EQ(p.integrator.substeps, 0);
  p = parse_scene("[integrator]\ntype = \"xpbd\"\n", "s.toml");
  EXPECT_EQ(p.integrator.dt, large);
  p = parse_scene("[integrator]\ntype = \"xpbd\"\ndt = 0.01\n", "s.toml");
  EXPECT_EQ(p.integrator.dt, 0.01);
  p = parse_scene("", "s.toml", {"integrator.type=\"implicit-euler\""});
  EXPECT_EQ(p.integrator.dt, large);
  // The command line is one source: a step set anywhere in it stands.
  p = parse_scene("", "s.toml", {"integrator.dt=1e-3", "integrator.type=\"implicit-euler\""});
  EXPECT_EQ(p.integrator.dt, 1e-3);
  // The same kind keeps the scene's step.
  p = parse_scene("[integrator]\ndt = 2e-5\n", "s.toml", {"integrator.type=\"explicit-euler\""});
  EXPECT_EQ(p.integrator.dt, 2e-5);
  // A later tier wins over the scene's integrator; a later key over the tier.
  p = parse_scene("[integrator]\ntype = \"implicit-euler\"\n", "s.toml",
                  {"integrator.tier=\"live\"", "integrator.substeps=7"});
  EXPECT_EQ(p.integrator.type, IntegratorType::Xpbd);
  EXPECT_EQ(p.integrator.substeps, 7);
  p = parse_scene("[integrator]\ntier = \"live\"\ntype = \"symplectic-euler\"\n", "s.toml");
  EXPECT_EQ(p.integrator.tier, IntegratorTier::Live);
  EXPECT_EQ(p.integrator.type, IntegratorType::SymplecticEuler);
  EXPECT_EQ(p.integrator.dt, Params{}.integrator.dt);
  // A scene that names no integrator runs with the tier it is loaded with.
  p = parse_scene("", "s.toml", {}, IntegratorTier::Live);
  EXPECT_EQ(p.integrator.type, IntegratorType::Xpbd);
  p = parse_scene("[integrator]\ntype = \"implicit-euler\"\n", "s.toml", {}, IntegratorTier::Live);
  EXPECT_EQ(p.integrator.type, IntegratorType::ImplicitEuler);
  // The resolved scene reads back as it was.
  const Params live = parse_scene("", "s.toml", {"integrator.tier=\"live\""});
  const Params back = parse_scene(to_toml(live), "s.toml");
  EXPECT_EQ(back.integrator.tier, IntegratorTier::Live);
  EXPECT_EQ(back.integrator.type, IntegratorType::Xpbd);
  EXPECT_EQ(back.integrator.dt, large);
  EXPECT_THROW(parse_scene("", "s.toml", {"integrator.tier=\"fast\""}), SceneError);
}
