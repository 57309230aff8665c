// The two graphical programs behind `wetcloth view` and `wetcloth render`, with
// their options already parsed and the scene loaded.
#pragma once

#include <chrono>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "coloring.hpp"
#include "wetcloth/params.hpp"

namespace wetcloth::viewer {

using Clock = std::chrono::steady_clock;
inline double ms_since(Clock::time_point t) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t).count();
}

struct RenderOptions {
  Params params;
  std::filesystem::path out;
  int width = 1280, height = 720;
  double fps = 0;  // 0: the scene's run.fps
  bool video = false, quiet = false;
  ColorBy color = ColorBy::Fabric;
  float color_range = 0;  // > 0: the top of the colour scale (cloth_mesh's range)
};
// Exit code: 0 ok, 1 error (no GL, cannot write, ffmpeg failed), 3 the run blew up.
int render_frames(const RenderOptions& o);

struct ViewOptions {
  std::string scene;  // as given: a built-in name or a file
  Params params;
  std::vector<std::string> overrides;  // --set etc., applied again to scenes picked in the panel
  std::optional<long long> grid;       // --grid, likewise
  IntegratorTier tier = IntegratorTier::Live;  // of a scene that names no integrator
  int width = 1280, height = 720;
  ColorBy color = ColorBy::Fabric;
  std::optional<double> screenshot_after;  // simulated seconds
  std::filesystem::path screenshot_file;
};
// Exit code: 0 ok (window closed, or screenshot saved), 1 error.
int run_viewer(const ViewOptions& o);

}  // namespace wetcloth::viewer
