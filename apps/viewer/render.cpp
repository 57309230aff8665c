// `wetcloth render` and the sweep's contact sheet: offscreen (EGL), through the
// same Renderer as the window viewer.
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <deque>
#include <fstream>
#include <sstream>

#include "commands.hpp"
#include "draw.hpp"
#include "egl_context.hpp"
#include "programs.hpp"
#include "wetcloth/output.hpp"
#include "wetcloth/scene.hpp"
#include "wetcloth/simulation.hpp"

extern char** environ;

namespace wetcloth::viewer {

namespace fs = std::filesystem;

namespace {

// Runs a program (no shell: arguments are passed as they are); its exit status, or
// -1 if it could not be started.
int spawn_and_wait(const std::vector<std::string>& args) {
  std::vector<char*> argv;
  for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  pid_t pid = 0;
  if (posix_spawnp(&pid, argv[0], nullptr, nullptr, argv.data(), environ) != 0) return -1;
  int status = 0;
  while (waitpid(pid, &status, 0) < 0)
    if (errno != EINTR) return -1;
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128;
}

// A frame of `wetcloth run` (frames/frame_NNNNN.obj): v, vt, vn, f a/a/a b/b/b c/c/c,
// written z up, or y up (run.up) as its first line says: read back z up.
bool read_cloth_obj(const fs::path& path, ClothMesh& mesh) {
  std::ifstream in(path);
  if (!in) return false;
  mesh = ClothMesh{};
  std::string line;
  bool y_up = false;
  while (std::getline(in, line)) {
    std::istringstream s(line);
    std::string tag;
    s >> tag;
    if (tag == "#" && line.find(", y up") != std::string::npos) y_up = true;
    if (tag == "v" || tag == "vn") {
      Vec3f p;
      s >> p.x() >> p.y() >> p.z();
      if (y_up) p = Vec3f(p.x(), -p.z(), p.y());
      (tag == "v" ? mesh.position : mesh.normal).push_back(p);
    } else if (tag == "f") {
      std::array<int, 3> t{};
      std::string tok;
      for (int k = 0; k < 3 && s >> tok; ++k) t[k] = std::atoi(tok.c_str()) - 1;  // "a/a/a": a
      mesh.triangles.push_back(t);
    }
  }
  const int n = static_cast<int>(mesh.position.size());
  for (const auto& t : mesh.triangles)
    for (int i : t)
      if (i < 0 || i >= n) return false;
  if (mesh.normal.size() != mesh.position.size()) {  // no normals in the file: make them
    mesh.normal.assign(n, Vec3f::Zero());
    for (const auto& t : mesh.triangles) {
      const Vec3f c = (mesh.position[t[1]] - mesh.position[t[0]])
                          .cross(mesh.position[t[2]] - mesh.position[t[0]]);
      for (int i : t) mesh.normal[i] += c;
    }
    for (auto& v : mesh.normal) v = v.norm() > 0 ? Vec3f(v.normalized()) : Vec3f::UnitZ();
  }
  mesh.color.assign(n, kClothColor);
  return n > 0;
}

// The last frames/frame_NNNNN.obj of a run folder; empty if there is none.
fs::path last_frame(const fs::path& dir) {
  fs::path best;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir / "frames", ec)) {
    const std::string name = e.path().filename().string();
    if (name.starts_with("frame_") && e.path().extension() == ".obj" &&
        (best.empty() || name > best.filename().string()))
      best = e.path();
  }
  return best;
}

// The render's camera follows the cloth. Each frame frames a box holding what
// it shows (content_box), widened towards where that was in the second before
// and will be in the second after by a margin that grows with the time between
// (half the scene's size per second): the camera moves ahead of the cloth, at a bounded
// speed, and never cuts it off. A short running mean smooths the turns. The
// frames' boxes alone decide it, so the same scene gives the same pictures.
class FollowCamera {
 public:
  static constexpr double kWindow = 1.0, kBlur = 0.25;  // s of simulated time

  FollowCamera(float aspect, const Camera& view) : aspect_(aspect), view_(view) {}

  void add(double t, const Vec3f& lo, const Vec3f& hi) {
    if (time_.empty()) rate_ = std::max(0.05f, 0.5f * (hi - lo).norm());  // m per s
    time_.push_back(t), lo_.push_back(lo), hi_.push_back(hi);
  }
  double time(std::size_t f) const { return time_[f]; }
  // How far past a frame's time frames must have been added before at() for it.
  static constexpr double reach() { return kWindow + kBlur; }

  Camera at(std::size_t f) const {
    Vec3f lo = Vec3f::Zero(), hi = Vec3f::Zero();
    int count = 0;
    for (std::size_t s : near(f, kBlur)) {
      Vec3f a = lo_[s], b = hi_[s];
      for (std::size_t j : near(s, kWindow)) {
        const float m = rate_ * static_cast<float>(std::abs(time_[j] - time_[s]));
        a = a.cwiseMin(lo_[j] + Vec3f::Constant(m));
        b = b.cwiseMax(hi_[j] - Vec3f::Constant(m));
      }
      lo += a, hi += b, ++count;
    }
    // The mean may stray inside the frame's own box (by rate * kBlur / 2 at most):
    // that box is always kept whole.
    lo = (lo / count).cwiseMin(lo_[f]);
    hi = (hi / count).cwiseMax(hi_[f]);
    const Vec3f pad = Vec3f::Constant(rate_ * 0.1f);  // a little floor around the cloth
    return frame_box(lo - pad, hi + pad, aspect_, view_);
  }

 private:
  // The frames within dt of frame f's time (the times are in order).
  std::vector<std::size_t> near(std::size_t f, double dt) const {
    const auto first = std::lower_bound(time_.begin(), time_.end(), time_[f] - dt - 1e-9);
    const auto end = std::upper_bound(time_.begin(), time_.end(), time_[f] + dt + 1e-9);
    std::vector<std::size_t> v;
    for (auto it = first; it != end; ++it)
      v.push_back(static_cast<std::size_t>(it - time_.begin()));
    return v;
  }

  float aspect_, rate_ = 1;
  Camera view_;  // its direction
  std::vector<double> time_;
  std::vector<Vec3f> lo_, hi_;
};

// A folder never mixes two renders: the frames and video of an earlier one go.
void clear_render_folder(const fs::path& out) {
  fs::create_directories(out);
  for (const auto& e : fs::directory_iterator(out)) {
    const std::string name = e.path().filename().string();
    if ((name.starts_with("frame_") && e.path().extension() == ".png") || name == "video.mp4")
      fs::remove(e.path());
  }
}

// A frame simulated, waiting until the camera has seen far enough ahead.
struct Pending {
  long long frame;
  double time;  // s: where the moving obstacles are drawn
  ClothMesh mesh;
  Legend legend;  // its own: the adhesion scale may follow the frames
};

// What a render did: its frames, and the time drawing and writing them took.
struct RenderStats {
  long long frames = 0;  // the last frame's index
  long long written = 0;
  double draw_ms = 0, png_ms = 0;
  Legend legend;  // the last frame's, for the summary
};

// The offscreen target and what is drawn into it the same for every frame.
struct FrameDrawer {
  const RenderOptions& o;
  Renderer& renderer;
  Framebuffer& target;
  const Stage stage;
  DrawOptions opt;

  // Draws frame f with its colour key and writes it as OUT/frame_NNNNN.png;
  // false (said on stderr) where it cannot be written. `timed`: its drawing
  // counts in the stats.
  bool write(const Pending& f, const Camera& cam, bool timed, RenderStats& stats) {
    auto t0 = Clock::now();
    target.bind();
    Stage posed = stage;
    pose_stage(posed, o.params, f.time);
    renderer.draw(f.mesh, posed, cam, o.width, o.height, opt);
    Image img = target.read();
    if (o.color != ColorBy::Fabric) draw_key(img, f.legend);
    if (timed) stats.draw_ms += ms_since(t0);
    t0 = Clock::now();
    char name[32];
    std::snprintf(name, sizeof name, "frame_%05lld.png", f.frame);
    if (!write_png(o.out / name, img)) {
      std::fprintf(stderr, "wetcloth: error: cannot write %s\n", (o.out / name).c_str());
      return false;
    }
    stats.png_ms += ms_since(t0);
    ++stats.written;
    return true;
  }
};

// Simulates the scene frame by frame and draws each frame once the camera
// has seen far enough past it. 0, 1 (a frame could not be written) or 3 (the
// simulation blew up: the frames so far are kept).
int draw_frames(const RenderOptions& o, double fps, FrameDrawer& drawer, RenderStats& stats) {
  const Params& p = o.params;
  Simulation sim(p);
  const long long frames = stats.frames = last_frame_index(p.run.duration, fps);
  const bool progress = !o.quiet && isatty(STDERR_FILENO);
  FollowCamera follow(static_cast<float>(o.width) / o.height, scene_view(p));
  std::deque<Pending> pending;
  float scale = 0;
  Vec3f lo = Vec3f::Zero(), hi = Vec3f::Zero();
  bool ok = true;
  for (long long f = 0; f <= frames && ok; ++f) {
    const double t = frame_time(f, p.run.duration, fps);
    ok = sim.advance_to(t);
    ClothMesh mesh;
    stats.legend = cloth_mesh(sim, o.color, scale, mesh, o.color_range);
    // A frame that blew up keeps the box of the one before: its flung
    // particles would zoom out every frame the camera looks ahead from.
    if (ok || f == 0) content_box(p, mesh.position, lo, hi, sim.state().time);
    follow.add(t, lo, hi);
    pending.push_back({f, sim.state().time, std::move(mesh), stats.legend});
    while (!pending.empty() &&
           (!ok || f == frames || follow.time(pending.front().frame) + follow.reach() <= t)) {
      const long long g = pending.front().frame;
      // Frame 0 also compiles the shaders: its drawing is not counted.
      if (!drawer.write(pending.front(), follow.at(g), g > 0 || frames == 0, stats)) return 1;
      pending.pop_front();
      if (progress) std::fprintf(stderr, "\rframe %lld/%lld", g + 1, frames + 1);
    }
  }
  if (progress) std::fprintf(stderr, "\n");
  if (!ok) {
    std::fprintf(stderr, "wetcloth: %s\nframes so far: %s\n", sim.blow_up_reason().c_str(),
                 o.out.c_str());
    return 3;
  }
  return 0;
}

// OUT/video.mp4 from the frames (ffmpeg); false (said on stderr) where it failed.
bool make_video(const fs::path& out, double fps) {
  // yuv420p (what players expect) needs even sizes: pad by a pixel if odd.
  const int code =
      spawn_and_wait({"ffmpeg", "-y", "-loglevel", "error", "-framerate", format_number(fps), "-i",
                      (out / "frame_%05d.png").string(), "-vf", "pad=ceil(iw/2)*2:ceil(ih/2)*2",
                      "-pix_fmt", "yuv420p", (out / "video.mp4").string()});
  if (code == 0) return true;
  std::fprintf(
      stderr, "wetcloth: error: %s\n",
      code < 0 ? "cannot run ffmpeg (apt-get install ffmpeg)" : "ffmpeg failed to make video.mp4");
  return false;
}

void print_render_summary(const RenderOptions& o, const RenderStats& s) {
  std::printf("%s: %lld frame%s, %dx%d, in %s%s (%.1f ms per frame to draw, %.1f ms to write)\n",
              o.params.name.c_str(), s.written, s.written == 1 ? "" : "s", o.width, o.height,
              o.out.c_str(), o.video ? " + video.mp4" : "", s.draw_ms / std::max(1LL, s.frames),
              s.png_ms / s.written);
  if (o.color != ColorBy::Fabric && !s.legend.binary)
    std::printf("colour: %s, %s to %s\n", s.legend.title.c_str(), key_number(s.legend.lo).c_str(),
                key_number(s.legend.hi).c_str());
}

}  // namespace

int render_frames(const RenderOptions& o) {
  const double fps = o.fps > 0 ? o.fps : o.params.run.fps;
  try {
    // The context first: if there is no GL, nothing is written.
    OffscreenContext context;
    Renderer renderer;
    Framebuffer target(o.width, o.height);
    clear_render_folder(o.out);
    FrameDrawer drawer{o, renderer, target, stage_from(o.params), {}};
    drawer.opt.fabric = o.color == ColorBy::Fabric;
    RenderStats stats;
    if (const int code = draw_frames(o, fps, drawer, stats); code != 0) return code;
    if (o.video && !make_video(o.out, fps)) return 1;
    if (!o.quiet) print_render_summary(o, stats);
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "wetcloth: error: %s\n", e.what());
    return 1;
  }
}

bool render_contact_sheet(const std::vector<std::pair<std::string, fs::path>>& cases,
                          const fs::path& png, int tile_w, int tile_h, std::string* error) {
  auto fail = [&](const std::string& why) {
    if (error) *error = why;
    return false;
  };
  if (cases.empty()) return fail("contact sheet: no cases");
  if (tile_w < 16 || tile_h < 16 || tile_w > 8192 || tile_h > 8192)
    return fail("contact sheet: tile size out of range");

  struct Tile {
    std::string label;
    Params params;
    ClothMesh mesh;
  };
  std::vector<Tile> tiles;
  Vec3f lo = Vec3f::Constant(1e30f), hi = Vec3f::Constant(-1e30f);
  for (const auto& [label, dir] : cases) {
    Tile t{label, {}, {}};
    try {
      t.params = load_scene((dir / "scene.toml").string());
    } catch (const std::exception& e) {
      return fail(label + ": " + e.what());
    }
    const fs::path frame = last_frame(dir);
    if (frame.empty()) return fail(label + ": no frames/frame_*.obj in " + dir.string());
    if (!read_cloth_obj(frame, t.mesh)) return fail(label + ": cannot read " + frame.string());
    // The run's last frame holds no field: the fabric wet as the case's
    // humidity, touching where it lies within the bridge height of the stage,
    // its obstacles where they are at the run's duration.
    Stage s = stage_from(t.params);
    pose_stage(s, t.params, t.params.run.duration);
    const float omega = static_cast<float>(t.params.cloth.humidity);
    const float h = static_cast<float>(t.params.contact.bridge_height);
    t.mesh.color.resize(t.mesh.position.size());
    t.mesh.gloss.resize(t.mesh.position.size());
    for (std::size_t i = 0; i < t.mesh.position.size(); ++i) {
      const FabricLook look =
          fabric_look(omega, touches_stage(s, t.mesh.position[i], h) ? 1.0f : 0.0f);
      t.mesh.color[i] = look.color;
      t.mesh.gloss[i] = look.gloss;
    }
    for (const auto& p : t.mesh.position) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
    if (s.table) lo.z() = std::min(lo.z(), s.ground_z);
    if (s.ball) {
      lo = lo.cwiseMin(s.ball_center - Vec3f::Constant(s.ball_radius));
      hi = hi.cwiseMax(s.ball_center + Vec3f::Constant(s.ball_radius));
    }
    tiles.push_back(std::move(t));
  }
  // One camera for every tile, so that the tiles compare.
  const Camera cam =
      frame_box(lo, hi, static_cast<float>(tile_w) / tile_h, scene_view(tiles.front().params));

  // A row for a few cases, a grid for many.
  const int n = static_cast<int>(tiles.size());
  const int cols = n <= 6 ? n : static_cast<int>(std::ceil(std::sqrt(static_cast<double>(n))));
  const int rows = (n + cols - 1) / cols;
  Image sheet(cols * tile_w, rows * tile_h, 40);
  const int text_scale = std::max(1, tile_h / 160);
  try {
    OffscreenContext context;
    Renderer renderer;
    Framebuffer target(tile_w, tile_h);
    for (int i = 0; i < n; ++i) {
      target.bind();
      Stage stage = stage_from(tiles[i].params);
      pose_stage(stage, tiles[i].params, tiles[i].params.run.duration);
      renderer.draw(tiles[i].mesh, stage, cam, tile_w, tile_h, {});
      Image tile = target.read();
      draw_label(tile, 4 * text_scale, 4 * text_scale, tiles[i].label, text_scale);
      blit(sheet, tile, (i % cols) * tile_w, (i / cols) * tile_h);
    }
  } catch (const std::exception& e) {
    return fail(std::string("contact sheet: ") + e.what());
  }
  std::error_code ec;
  if (png.has_parent_path()) fs::create_directories(png.parent_path(), ec);
  if (!write_png(png, sheet)) return fail("cannot write " + png.string());
  return true;
}

}  // namespace wetcloth::viewer
