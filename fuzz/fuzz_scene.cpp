// Fuzzing the scene loader: a scene file from bytes (load_scene's parse_scene)
// and the --set parser. The first byte chooses: even, the rest is a scene
// file; odd, each line of the rest is one --set on the built-in scene
// pull-straight. Bad input must end in SceneError, nothing else; a scene that
// loads must read back from its resolved TOML (what `run` writes and reads).
// Built as a libFuzzer target (make fuzz) and as the corpus replay test.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "wetcloth/scene.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const std::string text(reinterpret_cast<const char*>(data) + 1, size - 1);
  wetcloth::Params p;
  try {
    if (data[0] % 2 == 0) {
      p = wetcloth::parse_scene(text, "fuzz.toml");
    } else {
      std::vector<std::string> sets;
      for (std::size_t at = 0; at <= text.size();) {
        std::size_t end = text.find('\n', at);
        if (end == std::string::npos) end = text.size();
        sets.push_back(text.substr(at, end - at));
        at = end + 1;
      }
      p = wetcloth::load_scene("pull-straight", sets);
    }
  } catch (const wetcloth::SceneError&) {
    return 0;  // bad input, said so
  }
  try {
    wetcloth::parse_scene(wetcloth::to_toml(p), "resolved.toml");
  } catch (const wetcloth::SceneError& e) {
    std::fprintf(stderr, "a scene that loads does not read back from its resolved TOML: %s\n",
                 e.what());
    std::abort();
  }
  return 0;
}
