// A checkpoint: a run's whole State with the scene it belongs to, in a
// versioned binary file with a checksum, written whole or not at all.
#pragma once

#include <filesystem>

#include "wetcloth/params.hpp"
#include "wetcloth/simulation.hpp"

namespace wetcloth {

struct Checkpoint {
  Params params;  // the resolved scene
  State state;
};

// Writes under a temporary name, then renames.
void save_checkpoint(const std::filesystem::path& path, const Params& params, const State& state);
// Throws SceneError (bad input) naming the file and what is wrong: not a
// checkpoint, another format version, a checksum that does not match, a
// state that does not fit its scene.
Checkpoint load_checkpoint(const std::filesystem::path& path);

}  // namespace wetcloth
