// Fabric presets (material.preset, src/model/presets.cpp): what a preset sets,
// what overrides it, a name that is no preset, and every preset on every
// built-in grid scene.
#include <gtest/gtest.h>

#include "wetcloth/scene.hpp"
#include "wetcloth/simulation.hpp"

using namespace wetcloth;

namespace {

double value_of(const Params& p, const std::string& key) {
  for (const ParamDef& d : param_defs())
    if (d.key == key) return std::get<double>(d.get(p, ""));
  ADD_FAILURE() << "no key " << key;
  return 0;
}

std::string error_of(const std::string& text, const std::vector<std::string>& sets = {}) {
  try {
    parse_scene(text, "bad.toml", sets);
  } catch (const SceneError& e) {
    return e.what();
  }
  return "";
}

const FabricPreset& preset(const std::string& name) {
  const FabricPreset* f = find_preset(name);
  if (!f) throw std::runtime_error("no preset " + name);
  return *f;
}

}  // namespace

TEST(Presets, SetTheirValuesEachWithASource) {
  ASSERT_GE(fabric_presets().size(), 6u);
  for (const FabricPreset& f : fabric_presets()) {
    const Params p = parse_scene("[material]\npreset = \"" + f.name + "\"\n", "s.toml");
    EXPECT_EQ(p.material.preset, f.name);
    // Every preset sets the same keys (apply_preset's "" restores them).
    ASSERT_EQ(f.values.size(), fabric_presets().front().values.size()) << f.name;
    for (const PresetValue& v : f.values) {
      EXPECT_EQ(value_of(p, v.key), v.value) << f.name << " " << v.key;
      EXPECT_FALSE(v.source.empty()) << f.name << " " << v.key;
    }
    // Within what the simulator runs with its default step (docs/model.md).
    EXPECT_LE(p.material.stretch_stiffness, 2000) << f.name;
    EXPECT_DOUBLE_EQ(p.air.k_delta, 0.9 * p.air.d_delta) << f.name;
  }
  // KES B in gf·cm²/cm: 1 gf·cm²/cm = 9.80665e-5 N·m.
  const Params denim = parse_scene("material.preset = \"denim\"\n", "s.toml");
  EXPECT_DOUBLE_EQ(denim.material.bending_rigidity, 9.80665e-5);
  EXPECT_DOUBLE_EQ(denim.cloth.areal_density, 0.40);
  // The paper's polyester is the reference of the membrane's stiffnesses.
  const Params polyester = parse_scene("material.preset = \"polyester\"\n", "s.toml");
  EXPECT_DOUBLE_EQ(polyester.material.stretch_stiffness, Params{}.material.stretch_stiffness);
  EXPECT_DOUBLE_EQ(polyester.material.shear_stiffness, Params{}.material.shear_stiffness);
}

// A key the scene gives overrides the preset's, before or after it in the
// file and in any table.
TEST(Presets, ASceneKeyOverridesThePresetInAnyOrder) {
  const Params p = parse_scene(
      "[cloth]\nareal_density = 0.2\n[material]\nbending_rigidity = 1e-5\npreset = \"denim\"\n"
      "shear_stiffness = 7.0\n[friction]\nmu = 0.9\n",
      "s.toml");
  EXPECT_EQ(p.cloth.areal_density, 0.2);
  EXPECT_EQ(p.material.bending_rigidity, 1e-5);
  EXPECT_EQ(p.material.shear_stiffness, 7.0);
  EXPECT_EQ(p.friction.mu, 0.9);
  EXPECT_EQ(p.material.stretch_stiffness,
            preset_value(preset("denim"), "material.stretch_stiffness"));
  EXPECT_EQ(p.air.d_delta, preset_value(preset("denim"), "air.d_delta"));
}

// --set overrides the preset and the scene's keys; a --set preset is the
// preset, under the scene's own keys.
TEST(Presets, SetOverridesThePresetAndTheScene) {
  const std::string scene = "[material]\npreset = \"denim\"\nshear_stiffness = 7.0\n";
  const Params p = parse_scene(scene, "s.toml", {"material.shear_stiffness=9", "friction.mu=0.8"});
  EXPECT_EQ(p.material.shear_stiffness, 9);
  EXPECT_EQ(p.friction.mu, 0.8);
  const Params q = parse_scene(scene, "s.toml", {"material.preset=silk"});
  EXPECT_EQ(q.material.preset, "silk");
  EXPECT_EQ(q.material.shear_stiffness, 7.0);  // the scene's
  EXPECT_EQ(q.cloth.areal_density, preset_value(preset("silk"), "cloth.areal_density"));
  EXPECT_EQ(load_scene("drop-table", {"material.preset=linen"}).cloth.areal_density,
            preset_value(preset("linen"), "cloth.areal_density"));
}

TEST(Presets, AnUnknownNameFailsNamingTheKeyAndThePresets) {
  const std::string e = error_of("name = \"x\"\n\n[material]\npreset = \"dennim\"\n");
  EXPECT_NE(e.find("bad.toml:4: material.preset: 'dennim' is not one of"), std::string::npos) << e;
  EXPECT_NE(e.find("(did you mean denim?)"), std::string::npos) << e;
  for (const FabricPreset& f : fabric_presets()) EXPECT_NE(e.find(f.name), std::string::npos) << e;
  const std::string set = error_of("", {"material.preset=wool"});
  EXPECT_NE(set.find("--set 'material.preset=wool': material.preset: 'wool' is not one of"),
            std::string::npos)
      << set;
  EXPECT_NE(error_of("[material]\npreset = 3\n")
                .find("bad.toml:2: material.preset: expected a "
                      "string"),
            std::string::npos);
  Params in_code;
  in_code.material.preset = "wool";
  EXPECT_THROW(validate(in_code), SceneError);
  EXPECT_THROW(apply_preset(in_code, "wool"), SceneError);
}

// The resolved scene (scene.toml, a checkpoint's) reads back to the same
// Params; a preset given over a resolved scene (Python's Scene and set) sets
// its values, and the other overrides still win.
TEST(Presets, ResolvedSceneReadsBackAndTakesANewPreset) {
  const Params p = parse_scene("[material]\npreset = \"denim\"\n[friction]\nmu = 0.9\n", "s.toml");
  const Params q = parse_scene(to_toml(p), "resolved.toml");
  EXPECT_EQ(to_toml(q), to_toml(p));
  EXPECT_EQ(q.friction.mu, 0.9);
  const Params silk = reparse_scene(p, {"material.preset=silk", "air.d_delta=0.002"});
  EXPECT_EQ(silk.material.preset, "silk");
  EXPECT_EQ(silk.cloth.areal_density, preset_value(preset("silk"), "cloth.areal_density"));
  EXPECT_EQ(silk.friction.mu, preset_value(preset("silk"), "friction.mu"));
  EXPECT_EQ(silk.air.d_delta, 0.002);
  // "": the defaults again.
  const Params none = reparse_scene(p, {"material.preset=\"\""});
  EXPECT_EQ(to_toml(none), to_toml(parse_scene("", "s.toml")));
}

// Every preset on every built-in grid scene, at a small grid, for 0.02 s.
TEST(Presets, EveryPresetRunsEveryBuiltInGridScene) {
  for (const FabricPreset& f : fabric_presets())
    for (const BuiltinScene& s : builtin_scenes()) {
      Params p = load_scene(s.name, {"material.preset=" + f.name});
      if (!p.cloth.mesh.empty()) continue;  // a mesh cloth has its file's particles
      p = at_resolution(p, 21);
      p.integrator.threads = 1;
      Simulation sim(p);
      EXPECT_TRUE(sim.advance_to(0.02))
          << f.name << " on " << s.name << ": " << sim.blow_up_reason();
    }
}
