// Scenes: TOML files (or built-in names) turned into Params, with every key
// checked against one table of definitions that also documents them.
#pragma once

#include <functional>
#include <stdexcept>
#include <string>
#include <variant>
#include <vector>

#include "wetcloth/params.hpp"

namespace wetcloth {

// Bad input: the message names the file, line and key.
struct SceneError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// A list of numbers: a motion's keyframes, 7 numbers each (time, translate,
// rotate), or a handle's particle indices (ParamDef::list says which).
using NumberList = std::vector<double>;
using ParamValue =
    std::variant<bool, long long, double, std::string, Vec2i, Vec2d, Vec3d, NumberList>;

// One scene parameter. Keys under a handle read `handle.*.KEY`.
struct ParamDef {
  std::string key;
  std::string unit;
  std::string meaning;
  double min = 0, max = 0;           // range for numbers (inclusive); min > max: none
  std::vector<std::string> choices;  // allowed strings
  ParamValue default_value;          // an optional number unset: NaN
  bool optional = false;             // a number that may be left unset (get gives NaN)
  // What a NumberList holds: keyframes [[t, [x, y, z], [rx, ry, rz]], ...]
  // (flattened, 7 numbers a key), or particle indices [i, ...], which may
  // instead be a string: a file of indices.
  enum class List { None, Keyframes, Indices };
  List list = List::None;
  std::function<ParamValue(const Params&, const std::string& handle)> get;
  std::function<void(Params&, const std::string& handle, const ParamValue&)> set;

  std::string type_name() const;
  std::string range_text() const;
  std::string default_text() const;  // the default as TOML, or "unset"
};

const std::vector<ParamDef>& param_defs();
std::string format_value(const ParamValue& v);
// The value as the scene file writes it: keyframes as nested arrays.
std::string format_value(const ParamDef& d, const ParamValue& v);

struct BuiltinScene {
  std::string name, description, text;
};
const std::vector<BuiltinScene>& builtin_scenes();

// SCENE is a path to a TOML file or a built-in name; overrides are KEY=VALUE
// strings in TOML syntax (`cloth.resolution=[25,25]`). `tier`: the integrator
// settings a scene that names none runs with (the viewer's is live). Throws
// SceneError.
Params load_scene(const std::string& scene, const std::vector<std::string>& overrides = {},
                  IntegratorTier tier = IntegratorTier::Accurate);
Params parse_scene(const std::string& toml_text, const std::string& source_name,
                   const std::vector<std::string>& overrides = {},
                   IntegratorTier tier = IntegratorTier::Accurate);

// The same physical scene on a cloth `grid` particles wide, its height in
// particles scaled alike: handle patches keep their size in metres, and an
// explicit step shrinks as its stability limit does (the same springs on
// particles 1/grid² as heavy: Δt ∝ 1/grid). `--grid` and the benchmarks use
// it; `--set cloth.resolution` alone changes only the grid. Throws SceneError
// when a side would be under 3 or over cloth.resolution's range, and for a
// mesh cloth (cloth.mesh), whose resolution is its file's.
Params at_resolution(Params p, long long grid);

// The text of a file a scene names by `key` (cloth.mesh, obstacle.NAME.mesh):
// from the scene file's folder, or a built-in scene's copy in the program.
// `wetcloth run` copies them beside its scene.toml. Throws SceneError.
std::string scene_file_text(const Params& p, const std::string& key, const std::string& path);

// The files obstacle NAME's cache (obstacle.NAME.cache) reads, as the scene
// names them (relative to its folder), in frame order: a PC2 file, or an OBJ
// sequence's files, the # run the zero-padded frame number, numbered on from
// the lowest found. Throws SceneError (no file, a gap in the sequence).
std::vector<std::string> obstacle_cache_files(const Params& p, const std::string& name);

// A mesh cloth's size (cloth.mesh), for estimates before the model is built:
// its vertices (the particles), triangles and mean edge, m. Throws SceneError.
struct ClothMeshSize {
  long long vertices = 0, triangles = 0;
  double mean_edge = 0;
};
ClothMeshSize cloth_mesh_size(const Params& p);

// Every parameter, resolved, as TOML that load_scene reads back to the same Params
// (an optional key left unset is a comment), with the springs' constants as
// the model resolves them from the material and the spacing (springs_text).
std::string to_toml(const Params& p);

// Comment lines: each kind of spring's stiffness and damping on this grid
// (resolve_springs), and where they come from.
std::string springs_text(const Params& p);

// The checks a scene file gets (ranges, choices, keys that combine), on
// Params made in code; Simulation's constructor and set_params run it. Throws
// SceneError naming the key: "Params: cloth.humidity: value 3.0 is out of range [0, 1]".
void validate(const Params& p);

// Fabric presets (material.preset; docs/model.md "Fabric presets"): each
// sets the same keys, each value with its source.
struct PresetValue {
  std::string key;  // a ParamDef's key: a number
  double value;
  std::string source;
};
struct FabricPreset {
  std::string name, description;
  std::vector<PresetValue> values;
};
const std::vector<FabricPreset>& fabric_presets();
const FabricPreset* find_preset(const std::string& name);  // nullptr: no such preset
double preset_value(const FabricPreset& preset, const std::string& key);
std::string preset_names();  // "cotton-poplin, linen, ..."
// Sets the preset's values and its name ("": the defaults of the keys a
// preset sets). Throws SceneError for an unknown name.
void apply_preset(Params& p, const std::string& name);
// A resolved scene (its to_toml) with overrides, as Python's Scene and
// Simulation.set take them: to_toml writes the preset's values out, so a
// material.preset among the overrides sets its values over them first (as
// apply_preset), then every override applies.
Params reparse_scene(const Params& base, const std::vector<std::string>& overrides);
// `wetcloth params --preset`: the presets, a line each; and what one sets
// (key, value, unit, source).
std::string presets_text();
std::string preset_text(const FabricPreset& preset);

// Markdown table of every parameter (the table in docs/guide.md).
std::string params_markdown();
// `wetcloth params`: a line a parameter, in aligned columns.
std::string params_text();

}  // namespace wetcloth
