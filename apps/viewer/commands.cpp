// `wetcloth view` and `wetcloth render`: options, scene loading, exit codes.
#include "commands.hpp"

#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <memory>
#include <string_view>

#include "common/scene_options.hpp"
#include "programs.hpp"
#include "wetcloth/output_folder.hpp"

namespace wetcloth::viewer {

namespace {

// "1280x720" -> width, height; false if it is not that.
bool parse_size(const std::string& s, int& w, int& h) {
  char x = 0, extra = 0;
  return std::sscanf(s.c_str(), "%d%c%d%c", &w, &x, &h, &extra) == 3 && (x == 'x' || x == 'X') &&
         w >= 16 && h >= 16 && w <= 8192 && h <= 8192;
}

const CLI::Validator kSize(
    [](std::string& s) {
      int w = 0, h = 0;
      return parse_size(s, w, h) ? std::string() : "expected WxH, e.g. 1280x720 (16 to 8192 each)";
    },
    "WxH");

namespace fs = std::filesystem;

// Makes the folder an output goes into and writes a file of ours there: a place
// that cannot be written (no permission, /proc, read-only) is bad input, found
// before anything is simulated. True if the folder was made here.
bool check_writable_folder(const fs::path& dir, const std::string& option) {
  std::error_code ec;
  const bool existed = fs::exists(dir, ec);
  make_output_folder(dir, option);
  const fs::path probe = dir / (".wetcloth-probe-" + std::to_string(getpid()));
  const bool ok = static_cast<bool>(std::ofstream(probe));
  const int err = errno;
  fs::remove(probe, ec);
  if (!ok) {
    if (!existed) fs::remove(dir, ec);
    throw SceneError(option + " " + dir.string() + ": cannot write into it (" + std::strerror(err) +
                     ")");
  }
  return !existed;
}

// Whether a program of this name is on PATH, as posix_spawnp would find it.
bool on_path(const std::string& program) {
  const char* path = std::getenv("PATH");
  std::string_view rest = path ? path : "/usr/bin:/bin";
  while (true) {
    const auto colon = rest.find(':');
    const std::string dir(rest.substr(0, colon));
    if (access(((dir.empty() ? "." : dir) + "/" + program).c_str(), X_OK) == 0) return true;
    if (colon == std::string_view::npos) return false;
    rest.remove_prefix(colon + 1);
  }
}

// CLI::PositiveNumber names its range in 300 digits (0 to DBL_MAX).
const CLI::Validator kPositive(
    [](std::string& s) {
      double v = 0;
      if (!CLI::detail::lexical_cast(s, v)) return "not a number: " + s;
      return std::isfinite(v) && v > 0 ? std::string() : std::string("must be a positive number");
    },
    "> 0");

ColorBy color_by(const std::string& name) {
  for (std::size_t i = 0; i < kColorByNames.size(); ++i)
    if (name == kColorByNames[i]) return static_cast<ColorBy>(i);
  return ColorBy::Fabric;
}

struct Commands {
  CLI::App *view = nullptr, *render = nullptr;
  cli::SceneOptions view_scene, render_scene;
  std::string view_size = "1280x720", render_size = "1280x720";
  std::string view_color = "none", render_color = "none";
  std::pair<double, std::string> shot;
  std::string out;
  double fps = 0, color_range = 0;
  bool video = false, quiet = false, force = false;

  int run_view() {
    ViewOptions o;
    if (view_scene.scene.empty()) view_scene.scene = "pull-straight";
    o.scene = view_scene.scene;
    o.params = view_scene.load();
    o.overrides = view_scene.overrides();
    o.grid = view_scene.grid;
    o.tier = view_scene.tier;
    parse_size(view_size, o.width, o.height);
    o.color = color_by(view_color);
    if (view->count("--screenshot-after")) {
      if (!(shot.first >= 0) || shot.second.empty())
        throw SceneError("--screenshot-after: expected SECONDS >= 0 and a FILE name");
      o.screenshot_after = shot.first;
      o.screenshot_file = shot.second;
      // Its folder is made and tried now, not after the simulation has run.
      std::error_code ec;
      if (fs::is_directory(o.screenshot_file, ec))
        throw SceneError("--screenshot-after: " + shot.second + " is a folder, not a PNG file");
      const fs::path dir =
          o.screenshot_file.has_parent_path() ? o.screenshot_file.parent_path() : fs::path(".");
      const bool made = check_writable_folder(dir, "--screenshot-after");
      const int code = run_viewer(o);
      if (made && code != 0) fs::remove(dir, ec);  // only if still empty: nothing left behind
      return code;
    }
    return run_viewer(o);
  }

  int run_render() {
    RenderOptions o;
    o.params = render_scene.load();
    o.out = out;
    parse_size(render_size, o.width, o.height);
    o.fps = fps;
    o.video = video;
    o.quiet = quiet;
    o.color = color_by(render_color);
    o.color_range = static_cast<float>(color_range);
    // Everything that would fail after the simulation is checked before it.
    if (video && !on_path("ffmpeg"))
      throw SceneError("--video: ffmpeg is not on PATH (apt-get install ffmpeg)");
    // An earlier render's folder holds its frames or its video.
    if (!force) {
      refuse_system_folder(o.out, "--out");
      refuse_foreign_folder(o.out, "--out", "render", {"frame_00000.png", "video.mp4"});
    }
    const bool made = check_writable_folder(o.out, "--out");
    const int code = render_frames(o);
    std::error_code ec;
    if (made && code != 0) fs::remove(o.out, ec);  // only if still empty: no GL, nothing drawn
    return code;
  }
};

}  // namespace

std::function<std::optional<int>()> add_commands(CLI::App& app) {
  auto c = std::make_shared<Commands>();
  const std::vector<std::string> colors(kColorByNames.begin(), kColorByNames.end());

  c->view = app.add_subcommand("view", "open a window and run a scene live (GLFW, OpenGL 3.3)");
  c->view_scene.tier = IntegratorTier::Live;  // as fast as it can be
  c->view_scene.add_to(c->view, /*scene_required=*/false);
  c->view->add_option("--size", c->view_size, "window size")->check(kSize)->capture_default_str();
  c->view->add_option("--color", c->view_color, "colour the cloth by")
      ->check(CLI::IsMember(colors))
      ->capture_default_str();
  c->view
      ->add_option("--screenshot-after", c->shot,
                   "run to SECONDS of simulated time, save the window (panel included) as the PNG "
                   "FILE and exit")
      ->type_name("SECONDS FILE");
  c->view->footer(
      "SCENE defaults to pull-straight. The simulation runs live, as close to real time as the\n"
      "machine allows (the panel shows the real-time factor); --duration is not a limit here.\n"
      "Mouse: left-drag the cloth to pull it, left- or right-drag elsewhere to orbit, middle-drag\n"
      "to pan, wheel to zoom. Keys: W/A/S/D move, F frame the scene, Space pause, N single\n"
      "step, R reset, O wireframe, P screenshot (PNG in the current folder), Esc quit.");

  c->render = app.add_subcommand("render", "render a scene offscreen to PNG frames (and an MP4)");
  c->render_scene.add_to(c->render);
  c->render->add_option("--out", c->out, "output folder")->required()->check(cli::a_path());
  c->render->add_option("--size", c->render_size, "image size")
      ->check(kSize)
      ->capture_default_str();
  c->render
      ->add_option("--fps", c->fps, "frames per simulated second (default: the scene's run.fps)")
      ->check(kPositive);
  c->render->add_flag("--video", c->video, "also make DIR/video.mp4 with ffmpeg");
  c->render->add_option("--color", c->render_color, "colour the cloth by")
      ->check(CLI::IsMember(colors))
      ->capture_default_str();
  c->render
      ->add_option(
          "--color-range", c->color_range,
          "top of the colour scale: pressure +-MAX Pa (default air.breakthrough_pressure), "
          "strain 0 to MAX (default strain_limit.tau), adhesion 0 to MAX N (default twice "
          "an inner particle's share)")
      ->check(kPositive);
  c->render->add_flag("--quiet", c->quiet, "no progress, no summary");
  c->render->add_flag("--force", c->force,
                      "write into DIR even where it holds files of no wetcloth render");
  c->render->footer(
      "Writes DIR/frame_00000.png ... one per output frame (EGL, no display needed), with a key\n"
      "to the colours when --color is given, and with\n"
      "--video DIR/video.mp4. Exit codes: 0 ok, 1 error (no OpenGL, ffmpeg failed), 2 bad input:\n"
      "options, an --out that cannot be written, --video without ffmpeg (nothing written),\n"
      "3 the simulation blew up (frames so far kept).");

  return [c]() -> std::optional<int> {
    if (!*c->view && !*c->render) return std::nullopt;
    try {
      return *c->view ? c->run_view() : c->run_render();
    } catch (const SceneError& e) {
      std::fprintf(stderr, "wetcloth: error: %s\n", e.what());
      return 2;
    }
  };
}

}  // namespace wetcloth::viewer
