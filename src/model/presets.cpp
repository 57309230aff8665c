// Fabric presets (material.preset): real fabrics' values for the keys the
// model has, each with its source. docs/model.md "Fabric presets" derives them.
#include <cstdio>
#include <sstream>

#include "wetcloth/scene.hpp"

namespace wetcloth {

namespace {

// KES units to SI. B: 1 gf·cm²/cm = 9.80665e-3 N × 1e-2 m = 9.80665e-5 N·m.
constexpr double kGfCm2PerCm = 9.80665e-5;
// Air permeability: 1 l/m²/s at 100 Pa = 1e-3 m/s / 100 Pa.
constexpr double kLitrePer100Pa = 1e-5;

// The membrane's stiffnesses follow the model's defaults (200 N/m stretch,
// 20 N/m shear), which stand for the paper's polyester, scaled by the
// fabric's KES tensile stiffness (500 gf/cm over EMT) and shear rigidity G
// relative to that polyester's: EMT 4.0 %, G 0.8 gf/(cm·°).
constexpr double kRefEmt = 4.0, kRefG = 0.8;

struct Kes {
  double emt;  // extensibility at 500 gf/cm, %
  double g;    // shear rigidity, gf/(cm·°)
  double b;    // bending rigidity, gf·cm²/cm
};

std::string kes_text(const char* what, double v, const char* unit) {
  char buf[96];
  std::snprintf(buf, sizeof buf, "KES %s %g %s", what, v, unit);
  return buf;
}

// A fabric as measured or chosen, each value with its source.
struct Fabric {
  std::string name, description;
  double density;  // kg/m²
  std::string density_source;
  Kes kes;
  std::string kes_source;  // EMT and G
  std::string b_source;
  double mu;
  std::string mu_source;
  double permeability;  // l/m²/s at 100 Pa
  std::string permeability_source;
  double water_ratio;
  std::string water_source;
};

// The preset's keys in SI, from the fabric's values.
FabricPreset make(const Fabric& f) {
  const std::string kes = " (" + f.kes_source + ")";
  const std::string b = " (" + f.b_source + ")";
  const double d = f.permeability * kLitrePer100Pa;
  char perm[64];
  std::snprintf(perm, sizeof perm, "%g l/m²/s at 100 Pa (", f.permeability);
  return {
      f.name,
      f.description,
      {{"cloth.areal_density", f.density, f.density_source},
       {"cloth.water_ratio", f.water_ratio, f.water_source},
       {"material.stretch_stiffness", 200 * kRefEmt / f.kes.emt,
        kes_text("EMT", f.kes.emt, "%") + kes +
            "; 200 N/m × EMT 4.0 % (the paper's polyester) / EMT"},
       {"material.shear_stiffness", 20 * f.kes.g / kRefG,
        kes_text("G", f.kes.g, "gf/(cm·°)") + kes + "; 20 N/m × G / 0.8 (the paper's polyester)"},
       {"material.bending_rigidity", f.kes.b * kGfCm2PerCm,
        kes_text("B", f.kes.b, "gf·cm²/cm") + b},
       {"friction.mu", f.mu, f.mu_source},
       {"air.d_delta", d, perm + f.permeability_source + ")"},
       {"air.k_delta", 0.9 * d, "0.9 D_δ, as the model's default (no source per fabric)"}}};
}

// Not one measured fabric's values: chosen where KES-FB measurements of such
// fabrics lie (docs/model.md says so for each).
const std::string kTypical = "estimate within the usual KES-FB range of ";

// Cotton and flax: poplin, linen, denim, terry towel.
std::vector<Fabric> cellulose_fabrics() {
  return {
      {.name = "cotton-poplin",
       .description = "cotton poplin, a shirting (plain weave, about 120 g/m²)",
       .density = 0.12,
       .density_source = "poplin shirting: 100–130 g/m²",
       .kes = {4.0, 1.2, 0.10},
       .kes_source = kTypical + "cotton shirtings",
       .b_source = kTypical + "cotton shirtings; Peirce's bending length 2.0 cm",
       .mu = 0.35,
       .mu_source = "estimate: cotton on a smooth surface, KES MIU a little above polyester's",
       .permeability = 40,
       .permeability_source = "estimate: tight shirtings, 20–60 (ISO 9237)",
       .water_ratio = 1.0,
       .water_source = "estimate: a cotton woven holds about its own weight of water, drained"},
      {.name = "linen",
       .description = "linen, a dress or shirt weight (plain weave, about 180 g/m²)",
       .density = 0.18,
       .density_source = "dress and shirt linens: 150–200 g/m²",
       .kes = {3.0, 1.6, 0.30},
       .kes_source = kTypical + "linens: low extensibility",
       .b_source = kTypical + "linens, crisp; Peirce's bending length 2.6 cm",
       .mu = 0.35,
       .mu_source = "estimate: as cotton (both cellulose, KES MIU alike)",
       .permeability = 250,
       .permeability_source = "estimate: open linen weaves, 150–400 (ISO 9237)",
       .water_ratio = 1.2,
       .water_source = "estimate: flax takes up a little more water than cotton"},
      {.name = "denim",
       .description = "denim, 12 oz (3/1 cotton twill, about 400 g/m²)",
       .density = 0.40,
       .density_source = "12 oz/yd² = 407 g/m², a mid-weight denim",
       .kes = {5.2, 2.0, 1.0},
       .kes_source = "KES table of six denims, J. Textiles 2016, 4614168 (regenerated-cellulose "
                     "denim for tropical regions): EMT 4.7–5.7 %, G 1.5–3.4",
       .b_source = "estimate, from a 12 oz denim's Peirce bending length of about 2.9 cm (the "
                   "regenerated-cellulose denims of that table are softer, B 0.14–0.23)",
       .mu = 0.4,
       .mu_source = "estimate: a rough twill, KES MIU above the smooth fabrics'",
       .permeability = 20,
       .permeability_source = "estimate: dense twills, 10–40 (ISO 9237)",
       .water_ratio = 1.0,
       .water_source = "estimate: as cotton wovens"},
      {.name = "terry-towel",
       .description = "cotton terry towel (about 450 g/m²)",
       .density = 0.45,
       .density_source = "bath towels: 400–600 g/m²",
       .kes = {10.0, 1.5, 0.5},
       .kes_source = "estimates: the loose ground weave under the pile stretches more than a "
                     "plain weave",
       .b_source = "estimate, from a towel's Peirce bending length of about 2.2 cm",
       .mu = 0.5,
       .mu_source = "estimate: the pile's loops grip, KES MIU highest of these",
       .permeability = 400,
       .permeability_source = "estimate: pile fabrics are open, 300–600 (ISO 9237)",
       .water_ratio = 3.0,
       .water_source = "estimate: terry towels absorb several times their weight (Singh & "
                       "Behera 2014 review their absorbency)"},
  };
}

// Filaments: silk and the paper's polyester.
std::vector<Fabric> filament_fabrics() {
  return {
      {.name = "silk",
       .description = "silk crepe de chine, 14 momme (about 60 g/m²)",
       .density = 0.061,
       .density_source = "14 momme × 4.34 g/m² per momme",
       .kes = {8.0, 0.4, 0.03},
       .kes_source = kTypical +
                     "women's thin dress silks; Matsudaira: silk weaves are stretchy, and very "
                     "soft in shear at small strain",
       .b_source = kTypical + "women's thin dress silks; Peirce's bending length 1.7 cm",
       .mu = 0.25,
       .mu_source = "estimate: a smooth filament fabric, KES MIU low",
       .permeability = 150,
       .permeability_source = "estimate: light filament wovens, 100–300 (ISO 9237)",
       .water_ratio = 0.8,
       .water_source = "estimate: silk takes up less water than cotton (regain 11 %)"},
      {.name = "polyester",
       .description = "plain-woven polyester like the paper's (about 120 g/m²)",
       .density = 0.12,
       .density_source = "polyester wovens: 110–130 g/m² (the model's default)",
       .kes = {kRefEmt, kRefG, 0.12},
       .kes_source = kTypical + "polyester filament plain weaves",
       .b_source = kTypical + "polyester filament plain weaves; Peirce's bending length 2.1 cm",
       .mu = 0.3,
       .mu_source = "the model's default (an assumption: docs/model.md section 5)",
       .permeability = 100,
       .permeability_source = "the model's default: a typical woven",
       .water_ratio = 0.5,
       .water_source = "estimate: polyester fibres take up almost no water; the weave holds it"},
  };
}

std::vector<FabricPreset> make_presets() {
  std::vector<FabricPreset> presets;
  for (const auto& group : {cellulose_fabrics(), filament_fabrics()})
    for (const Fabric& f : group) presets.push_back(make(f));
  return presets;
}

std::string format_number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4g", v);
  return buf;
}

// Padded to a width in characters, not bytes: units hold ², ·, δ.
std::string pad(const std::string& text, std::size_t width) {
  std::size_t chars = 0;
  for (const unsigned char c : text) chars += (c & 0xC0) != 0x80;
  return text + std::string(width > chars ? width - chars : 1, ' ');
}

}  // namespace

const std::vector<FabricPreset>& fabric_presets() {
  static const std::vector<FabricPreset> presets = make_presets();
  return presets;
}

const FabricPreset* find_preset(const std::string& name) {
  for (const FabricPreset& f : fabric_presets())
    if (f.name == name) return &f;
  return nullptr;
}

void apply_preset(Params& p, const std::string& name) {
  const FabricPreset* preset = find_preset(name);
  if (!preset && !name.empty())
    throw SceneError("material.preset: '" + name + "' is not a preset (" + preset_names() + ")");
  // "": the defaults of every key a preset sets.
  const Params defaults;
  for (const PresetValue& v : fabric_presets().front().values) {
    const ParamDef* d = nullptr;
    for (const ParamDef& def : param_defs())
      if (def.key == v.key) d = &def;
    d->set(p, "", preset ? ParamValue(preset_value(*preset, v.key)) : d->get(defaults, ""));
  }
  p.material.preset = name;
}

double preset_value(const FabricPreset& preset, const std::string& key) {
  for (const PresetValue& v : preset.values)
    if (v.key == key) return v.value;
  throw SceneError("material.preset: '" + preset.name + "' sets no " + key);
}

std::string preset_names() {
  std::string names;
  for (const FabricPreset& f : fabric_presets()) names += (names.empty() ? "" : ", ") + f.name;
  return names;
}

std::string presets_text() {
  std::ostringstream o;
  for (const FabricPreset& f : fabric_presets()) o << pad(f.name, 15) << f.description << "\n";
  return o.str();
}

std::string preset_text(const FabricPreset& preset) {
  std::ostringstream o;
  o << "# material.preset = \"" << preset.name << "\": " << preset.description << "\n";
  for (const PresetValue& v : preset.values) {
    std::string unit;
    for (const ParamDef& d : param_defs())
      if (d.key == v.key) unit = d.unit;
    // A ratio's unit, "1", would read as a second number.
    const std::string value = format_number(v.value) + (unit == "1" ? "" : " " + unit);
    o << pad(v.key, 28) << pad(value, 18) << v.source << "\n";
  }
  return o.str();
}

}  // namespace wetcloth
