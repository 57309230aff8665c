// A checkpoint: a run's whole State with the scene it belongs to, in a
// versioned binary file with a checksum, written whole or not at all.
#pragma once

#include <filesystem>
#include <string>

#include "wetcloth/params.hpp"
#include "wetcloth/simulation.hpp"

namespace wetcloth {

struct Checkpoint {
  Params params;  // the resolved scene
  State state;
  std::string run;  // what a program running the scene keeps with it (`wetcloth run`: JSON)
};

// Writes under a temporary name, on the disk (fsync) before the rename, then
// renames. `run` is stored as it is (format 2; format 1 files had none).
void save_checkpoint(const std::filesystem::path& path, const Params& params, const State& state,
                     const std::string& run = {});
// Throws SceneError (bad input) naming the file and what is wrong: not a
// checkpoint, another format version, a checksum that does not match, a
// state that does not fit its scene.
Checkpoint load_checkpoint(const std::filesystem::path& path);

}  // namespace wetcloth
