// `wetcloth view`: a window on a live simulation (GLFW, OpenGL 3.3 core), a Dear
// ImGui panel to change the scene as it runs, and the mouse to pull on the cloth.
#include <epoxy/gl.h>
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <imgui.h>
#include <imgui_impl_glfw.h>
#include <imgui_impl_opengl3.h>

#include <algorithm>
#include <cfloat>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <deque>
#include <memory>
#include <numbers>

#include "common/scene_options.hpp"
#include "draw.hpp"
#include "integrator_step.hpp"
#include "programs.hpp"
#include "wetcloth/checkpoint.hpp"
#include "wetcloth/scene.hpp"
#include "wetcloth/simulation.hpp"

namespace wetcloth::viewer {

namespace fs = std::filesystem;

namespace {

std::string glfw_error_text;
void on_glfw_error(int, const char* text) { glfw_error_text = text; }

// The last samples of one metric, for a scrolling plot.
struct History {
  static constexpr std::size_t kSamples = 600;
  std::deque<float> time, value;
  void add(double t, double v) {
    time.push_back(static_cast<float>(t));
    value.push_back(static_cast<float>(v));
    if (value.size() > kSamples) time.pop_front(), value.pop_front();
  }
  void clear() { time.clear(), value.clear(); }
  float span() const { return time.empty() ? 0.0f : time.back() - time.front(); }
};

// A file name in the current folder that does not exist yet: PREFIX-NNN[SUFFIX].
fs::path unused_name(const std::string& prefix, const std::string& suffix) {
  for (int i = 0;; ++i) {
    char n[16];
    std::snprintf(n, sizeof n, "-%03d", i);
    fs::path p = prefix + n + suffix;
    if (!fs::exists(p)) return p;
  }
}

// Ray against triangle (Moller-Trumbore); the distance along the ray, or -1.
float hit_triangle(const Vec3f& o, const Vec3f& d, const Vec3f& a, const Vec3f& b, const Vec3f& c) {
  const Vec3f e1 = b - a, e2 = c - a, p = d.cross(e2);
  const float det = e1.dot(p);
  if (std::abs(det) < 1e-12f) return -1;
  const Vec3f s = o - a;
  const float u = s.dot(p) / det;
  if (u < 0 || u > 1) return -1;
  const Vec3f q = s.cross(e1);
  const float v = d.dot(q) / det;
  if (v < 0 || u + v > 1) return -1;
  return e2.dot(q) / det;
}

class Viewer {
 public:
  explicit Viewer(const ViewOptions& o) : opts_(o), params_(o.params), color_(o.color) {
    for (const auto& s : builtin_scenes()) scenes_.push_back({s.name, s.name});
    scene_index_ = -1;
    for (std::size_t i = 0; i < scenes_.size(); ++i)
      if (scenes_[i].second == o.scene) scene_index_ = static_cast<int>(i);
    if (scene_index_ < 0) {  // a scene file: keep it pickable
      scenes_.insert(scenes_.begin(), {params_.name + " (file)", ""});
      scene_index_ = 0;
    }
  }

  ~Viewer() {
    if (imgui_) {
      ImGui_ImplOpenGL3_Shutdown();
      ImGui_ImplGlfw_Shutdown();
      ImGui::DestroyContext();
    }
    target_.reset();  // GL objects go while the context lives
    renderer_.reset();
    if (window_) glfwDestroyWindow(window_);
    glfwTerminate();
  }

  int run() {
    glfwSetErrorCallback(on_glfw_error);
    if (!glfwInit())
      return fail("cannot open a window (no display? try xvfb-run): " + glfw_error_text);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
    glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
    glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
    glfwWindowHint(GLFW_SAMPLES, 0);  // we anti-alias in our own framebuffer, switchable
    const std::string title = "wetcloth - " + params_.name;
    window_ = glfwCreateWindow(opts_.width, opts_.height, title.c_str(), nullptr, nullptr);
    if (!window_) return fail("cannot open an OpenGL 3.3 window: " + glfw_error_text);
    glfwMakeContextCurrent(window_);
    glfwSwapInterval(opts_.screenshot_after ? 0 : 1);

    // Our callbacks first: ImGui's backend chains to them.
    glfwSetWindowUserPointer(window_, this);
    glfwSetMouseButtonCallback(window_,
                               [](GLFWwindow* w, int b, int a, int) { self(w)->on_button(b, a); });
    glfwSetCursorPosCallback(window_,
                             [](GLFWwindow* w, double x, double y) { self(w)->on_cursor(x, y); });
    glfwSetScrollCallback(window_,
                          [](GLFWwindow* w, double, double dy) { self(w)->on_scroll(dy); });
    glfwSetKeyCallback(window_,
                       [](GLFWwindow* w, int k, int, int a, int) { self(w)->on_key(k, a); });

    IMGUI_CHECKVERSION();
    ImGui::CreateContext();
    ImGui::GetIO().IniFilename = nullptr;  // leave no imgui.ini behind
    ImGui::StyleColorsDark();
    ImGui_ImplGlfw_InitForOpenGL(window_, true);
    ImGui_ImplOpenGL3_Init("#version 330 core");
    imgui_ = true;

    // A software rasteriser shades every sample: no anti-aliasing by default there,
    // except for a screenshot, where time does not matter.
    const auto* name = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
    const std::string gl_renderer = name ? name : "";
    software_ = gl_renderer.find("llvmpipe") != std::string::npos ||
                gl_renderer.find("softpipe") != std::string::npos;
    antialias_ = !software_ || opts_.screenshot_after;
    try {
      renderer_ = std::make_unique<Renderer>();
    } catch (const std::exception& e) {
      return fail(e.what());
    }
    start_scene();
    return loop();
  }

 private:
  static Viewer* self(GLFWwindow* w) { return static_cast<Viewer*>(glfwGetWindowUserPointer(w)); }
  int fail(const std::string& why) {
    std::fprintf(stderr, "wetcloth: error: %s\n", why.c_str());
    return 1;
  }

  // --- the simulation ---------------------------------------------------------------

  void start_scene() {
    sim_ = std::make_unique<Simulation>(params_);
    scene_integrator_ = params_.integrator.type;  // what the panel's integrator choice starts from
    scene_dt_ = params_.integrator.dt;
    frame_camera();
    stage_ = stage_from(params_);
    glfwSetWindowTitle(window_, ("wetcloth - " + params_.name).c_str());
    after_reset();
  }

  // The scene framed in the part of the window right of the panel.
  void frame_camera() {
    int w = 0, h = 0;
    glfwGetWindowSize(window_, &w, &h);
    const float free_w = std::max(w - kPanelWidth - 20.0f, w * 0.4f);
    camera_ = frame_scene(params_, h > 0 ? free_w / h : 16.0f / 9);
    camera_.shift_x = w > 0 ? (w - free_w) / w : 0;
  }

  void after_reset() {
    release_grab();
    if (!blow_up_.empty()) paused_ = false;  // it was the blow-up that paused
    blow_up_.clear();
    color_scale_ = 0;
    for (History* h : {&pressure_, &contact_, &height_}) h->clear();
    next_sample_ = 0;
    sample_metrics();
  }

  void pick_scene(int index) {
    const std::string& name = scenes_[index].second;
    if (name.empty()) {  // the file given on the command line
      params_ = opts_.params;
    } else {
      try {
        params_ = load_on_grid(name, opts_.overrides, opts_.grid, "--grid", opts_.tier);
      } catch (const SceneError& e) {  // the command line's --set may not fit this scene
        params_ = load_scene(name, {}, opts_.tier);
        status_ = "--set not applied to " + name + ": " + e.what();
      }
    }
    scene_index_ = index;
    start_scene();
  }

  void apply_params() {
    try {
      sim_->set_params(params_);
    } catch (const SceneError& e) {  // a value typed past a slider's range
      status_ = e.what();
      params_ = sim_->model().params;
    }
    stage_ = stage_from(params_);
  }

  // As many steps as fit in the physics budget, aiming for real time.
  void advance(double wall_dt) {
    const auto t0 = Clock::now();
    const double dt = params_.integrator.dt;
    const long long steps = sim_->state().steps;
    if (blow_up_.empty()) {
      if (step_once_) {
        sim_->step();
        sample_metrics();
      } else if (!paused_) {
        // Screenshot mode: as fast as possible to the requested time, not in real time.
        const double until = opts_.screenshot_after ? *opts_.screenshot_after
                                                    : sim_->state().time + std::min(wall_dt, 0.1);
        const double budget = opts_.screenshot_after ? 250.0 : budget_ms_;
        while (sim_->state().time < until - 0.5 * dt && ms_since(t0) < budget) {
          sim_->step();
          sample_metrics();
        }
      }
      blow_up_ = sim_->blow_up_reason();
      if (!blow_up_.empty()) paused_ = true;
    }
    step_once_ = false;
    // Frames that step nothing (paused, or the screenshot's last few) keep the last
    // figure: the panel would read 0 ms.
    if (sim_->state().steps != steps) physics_ms_ = ms_since(t0);
  }

  // --- mouse and keys ---------------------------------------------------------------

  // The particle under the cursor: nearest corner of the nearest triangle hit.
  int pick(double x, double y) const {
    int w = 0, h = 0;
    glfwGetWindowSize(window_, &w, &h);
    Vec3f o, d;
    camera_.ray(x, y, w, h, o, d);
    float best = 1e30f;
    int particle = -1;
    const auto& p = mesh_.position;
    for (const auto& t : mesh_.triangles) {
      const float s = hit_triangle(o, d, p[t[0]], p[t[1]], p[t[2]]);
      if (s > 0 && s < best) {
        best = s;
        const Vec3f at = o + s * d;
        particle = *std::min_element(t.begin(), t.end(), [&](int a, int b) {
          return (p[a] - at).squaredNorm() < (p[b] - at).squaredNorm();
        });
      }
    }
    return particle;
  }

  // Pulls the grabbed particle towards the cursor's point on the plane through the
  // grabbed point facing the camera.
  void update_grab() {
    if (grab_ < 0) return;
    double x = 0, y = 0;
    int w = 0, h = 0;
    glfwGetCursorPos(window_, &x, &y);
    glfwGetWindowSize(window_, &w, &h);
    Vec3f o, d;
    camera_.ray(x, y, w, h, o, d);
    const float denom = d.dot(grab_normal_);
    if (std::abs(denom) < 1e-6f) return;
    grab_target_ = o + d * ((grab_point_ - o).dot(grab_normal_) / denom);
    // Critically damped spring; capped so that explicit steps stay stable (omega dt <= 0.5).
    const double m = sim_->model().mass[grab_], dt = params_.integrator.dt;
    const double k = std::min<double>(grab_k_, 0.25 * m / (dt * dt));
    sim_->grab(grab_, grab_target_.cast<double>(), k);
  }

  void release_grab() {
    if (grab_ >= 0 && sim_) sim_->release();
    grab_ = -1;
  }

  void on_button(int button, int action) {
    if (action == GLFW_RELEASE) {
      release_grab();
      drag_ = Drag::None;
      return;
    }
    if (ImGui::GetIO().WantCaptureMouse) return;
    glfwGetCursorPos(window_, &last_x_, &last_y_);
    drag_ = button == GLFW_MOUSE_BUTTON_MIDDLE ? Drag::Pan : Drag::Orbit;
    const bool shift = glfwGetKey(window_, GLFW_KEY_LEFT_SHIFT) == GLFW_PRESS ||
                       glfwGetKey(window_, GLFW_KEY_RIGHT_SHIFT) == GLFW_PRESS;
    if (button == GLFW_MOUSE_BUTTON_LEFT && shift) {  // the brush: wets where it is dragged
      drag_ = Drag::Brush;
      brush(last_x_, last_y_);
      return;
    }
    if (button == GLFW_MOUSE_BUTTON_LEFT) {
      const int p = pick(last_x_, last_y_);
      if (p >= 0) {
        drag_ = Drag::Grab;
        grab_ = p;
        grab_point_ = mesh_.position[p];
        grab_normal_ = (camera_.target - camera_.eye()).normalized();
        update_grab();
      }
    }
  }

  // Shift + left button: the particles within the brush's radius of the one
  // under the cursor get its ω (wetter only; ω 0 dries them).
  void brush(double x, double y) {
    const int p = pick(x, y);
    if (p >= 0) sim_->wet_near(sim_->state().x[p], brush_radius_cm_ / 100.0, brush_omega_);
  }

  void on_cursor(double x, double y) {
    const double dx = x - last_x_, dy = y - last_y_;
    last_x_ = x, last_y_ = y;
    if (drag_ == Drag::Brush) {
      brush(x, y);
    } else if (drag_ == Drag::Orbit) {
      camera_.yaw_deg -= static_cast<float>(dx) * 0.3f;
      camera_.pitch_deg =
          std::clamp(camera_.pitch_deg + static_cast<float>(dy) * 0.3f, -89.0f, 89.0f);
    } else if (drag_ == Drag::Pan) {
      int w = 0, h = 0;
      glfwGetWindowSize(window_, &w, &h);
      const float per_pixel = 2 * camera_.distance *
                              std::tan(camera_.fov_deg * std::numbers::pi_v<float> / 360) /
                              std::max(h, 1);
      const Mat4f v = camera_.view();
      const Vec3f right = v.block<1, 3>(0, 0).transpose(), up = v.block<1, 3>(1, 0).transpose();
      camera_.target += per_pixel * (-static_cast<float>(dx) * right + static_cast<float>(dy) * up);
    }
  }

  void on_scroll(double dy) {
    if (ImGui::GetIO().WantCaptureMouse) return;
    camera_.distance =
        std::clamp(camera_.distance * std::pow(0.88f, static_cast<float>(dy)), 0.02f, 50.0f);
  }

  void on_key(int key, int action) {
    if (action != GLFW_PRESS && !(action == GLFW_REPEAT && key == GLFW_KEY_N)) return;
    if (ImGui::GetIO().WantCaptureKeyboard) return;
    switch (key) {
      case GLFW_KEY_ESCAPE:
        glfwSetWindowShouldClose(window_, GLFW_TRUE);
        break;
      case GLFW_KEY_SPACE:
        paused_ = !paused_;
        break;
      case GLFW_KEY_N:
        paused_ = true, step_once_ = true;
        break;
      case GLFW_KEY_R:
        sim_->reset(), after_reset();
        break;
      case GLFW_KEY_O:
        draw_.wireframe = !draw_.wireframe;
        break;
      case GLFW_KEY_P:
        screenshot_ = true;
        break;
      case GLFW_KEY_F:
        frame_camera();
        break;
      case GLFW_KEY_F5:
        save_state();
        break;
      case GLFW_KEY_F9:
        load_state();
        break;
      default:
        break;
    }
  }

  // W/A/S/D, held: move the camera's target over the ground.
  void move_camera(double wall_dt) {
    if (ImGui::GetIO().WantCaptureKeyboard) return;
    auto down = [&](int k) { return glfwGetKey(window_, k) == GLFW_PRESS ? 1.0f : 0.0f; };
    const float speed = camera_.distance * 0.8f * static_cast<float>(std::min(wall_dt, 0.1));
    camera_.move(speed * (down(GLFW_KEY_W) - down(GLFW_KEY_S)),
                 speed * (down(GLFW_KEY_D) - down(GLFW_KEY_A)));
  }

  // --- pictures -------------------------------------------------------------------------

  // The window's back buffer as drawn so far.
  Image grab_window() {
    int w = 0, h = 0;
    glfwGetFramebufferSize(window_, &w, &h);
    glBindFramebuffer(GL_READ_FRAMEBUFFER, 0);
    glReadBuffer(GL_BACK);
    return read_pixels(w, h);
  }

  void save_screenshot(const fs::path& path) {
    if (write_png(path, grab_window())) {
      std::printf("screenshot: %s\n", path.c_str());
      std::fflush(stdout);
      status_ = "saved " + path.string();
    } else {
      std::fprintf(stderr, "wetcloth: error: cannot write %s\n", path.c_str());
      status_ = "cannot write " + path.string();
    }
  }

  // F5 / F9: the whole state with its scene, into out/viewer/NAME.state and
  // back (wetcloth::save_checkpoint); a loaded run continues as it would have.
  fs::path state_file() const { return fs::path("out") / "viewer" / (params_.name + ".state"); }

  void save_state() {
    const fs::path path = state_file();
    try {
      fs::create_directories(path.parent_path());
      save_checkpoint(path, sim_->model().params, sim_->state());
      status_ = "state saved: " + path.string();
    } catch (const std::exception& e) {
      status_ = std::string("cannot save the state: ") + e.what();
    }
  }

  void load_state() {
    const fs::path path = state_file();
    try {
      Checkpoint c = load_checkpoint(path);
      if (to_toml(c.params) != to_toml(sim_->model().params)) {
        params_ = std::move(c.params);
        start_scene();
      }
      sim_->restore(c.state);
      after_reset();
      status_ = "state loaded: " + path.string();
    } catch (const std::exception& e) {
      status_ = std::string("cannot load the state: ") + e.what();
    }
  }

  void toggle_recording() {
    recording_ = !recording_;
    if (recording_) {
      record_dir_ = unused_name("wetcloth-record-" + params_.name, "");
      std::error_code ec;
      fs::create_directories(record_dir_, ec);
      record_frame_ = 0;
      status_ = "recording into " + record_dir_.string();
    } else {
      status_ =
          "recorded " + std::to_string(record_frame_) + " frames into " + record_dir_.string();
    }
    std::printf("%s\n", status_.c_str());
    std::fflush(stdout);
  }

  // --- the panel ------------------------------------------------------------------------

  // A scrolling plot whose scale spans at least min_span: noise around a steady
  // value stays a flat line instead of being stretched into spikes.
  void plot(const char* label, const History& h, const char* format, float min_span) {
    std::vector<float> v(h.value.begin(), h.value.end());
    char overlay[64] = "";
    if (!v.empty()) std::snprintf(overlay, sizeof overlay, format, v.back());
    float lo = FLT_MAX, hi = -FLT_MAX;
    for (float x : v)
      if (std::isfinite(x)) lo = std::min(lo, x), hi = std::max(hi, x);
    if (lo > hi) lo = hi = 0;
    if (hi - lo < min_span) {
      const float mid = (lo + hi) / 2;
      lo = mid - min_span / 2, hi = mid + min_span / 2;
    }
    ImGui::Text("%s", label);
    ImGui::PlotLines((std::string("##") + label).c_str(), v.data(), static_cast<int>(v.size()), 0,
                     overlay, lo, hi, ImVec2(ImGui::GetContentRegionAvail().x, 45));
  }

  // The plots' samples, on the simulation's clock so that they do not depend on the frame rate.
  void sample_metrics() {
    const State& s = sim_->state();
    if (s.time < next_sample_) return;
    next_sample_ = s.time + kSampleInterval;
    const Metrics m = sim_->metrics();
    pressure_.add(s.time,
                  params_.air.p_atm - m.inner_pressure_pa);  // the deficit, as the sweep plots it
    contact_.add(s.time, m.contact_area_m2 * 1e4);
    height_.add(s.time, m.handle_height_m * 1e2);
  }

  void legend() {
    if (color_ == ColorBy::Fabric) return;
    ImGui::TextDisabled("%s", legend_.title.c_str());
    if (legend_.binary) {
      ImGui::ColorButton("##in", ImVec4(kContactColor.x(), kContactColor.y(), kContactColor.z(), 1),
                         ImGuiColorEditFlags_NoTooltip, ImVec2(14, 14));
      ImGui::SameLine();
      ImGui::Text("in contact");
      ImGui::SameLine();
      ImGui::ColorButton("##free", ImVec4(kFreeColor.x(), kFreeColor.y(), kFreeColor.z(), 1),
                         ImGuiColorEditFlags_NoTooltip, ImVec2(14, 14));
      ImGui::SameLine();
      ImGui::Text("free");
      return;
    }
    // A colour bar, its two ends labelled.
    ImDrawList* dl = ImGui::GetWindowDrawList();
    const ImVec2 p = ImGui::GetCursorScreenPos();
    const float w = ImGui::GetContentRegionAvail().x, h = 14;
    const int steps = 48;
    for (int i = 0; i < steps; ++i) {
      const Vec3f c = colormap((i + 0.5f) / steps, legend_.diverging);
      dl->AddRectFilled(ImVec2(p.x + w * i / steps, p.y),
                        ImVec2(p.x + w * (i + 1) / steps + 1, p.y + h),
                        ImGui::GetColorU32(ImVec4(c.x(), c.y(), c.z(), 1)));
    }
    ImGui::Dummy(ImVec2(w, h));
    ImGui::Text("%s", key_number(legend_.lo).c_str());
    const std::string hi = key_number(legend_.hi);
    ImGui::SameLine(std::max(0.0f, w - ImGui::CalcTextSize(hi.c_str()).x));
    ImGui::Text("%s", hi.c_str());
  }

  // A scene's choice (an enum), offered by its names.
  template <class E>
  bool combo(const char* label, E& value) {
    bool changed = false;
    if (ImGui::BeginCombo(label, to_string(value).c_str())) {
      const auto& names = ChoiceNames<E>::names;
      for (std::size_t k = 0; k < names.size(); ++k) {
        const auto e = static_cast<E>(k);
        if (ImGui::Selectable(names[k], e == value)) changed = e != value, value = e;
      }
      ImGui::EndCombo();
    }
    return changed;
  }

  // The scene's name and description, where the run stands, and how fast it goes.
  void panel_status() {
    const State& s = sim_->state();
    ImGui::Text("%s", params_.name.c_str());
    ImGui::PushTextWrapPos(0);
    ImGui::TextDisabled("%s", params_.description.c_str());
    ImGui::PopTextWrapPos();
    if (sim_->model().grid)
      ImGui::Text("t = %.3f s   %lld steps   %dx%d particles", s.time, s.steps, sim_->model().nu,
                  sim_->model().nv);
    else
      ImGui::Text("t = %.3f s   %lld steps   %d particles (mesh)", s.time, s.steps,
                  sim_->model().n);
    ImGui::Text("%.3fx real time   %.0f fps", rtf_, ImGui::GetIO().Framerate);
    ImGui::TextDisabled("physics %.0f ms, drawing %.0f ms per frame", physics_ms_, draw_ms_);
    if (!blow_up_.empty()) {
      ImGui::PushTextWrapPos(0);
      ImGui::TextColored(ImVec4(1, 0.35f, 0.3f, 1), "%s (R: reset)", blow_up_.c_str());
      ImGui::PopTextWrapPos();
    }
  }

  // Run, step, reset; record, screenshot; save and load the state.
  void panel_buttons() {
    if (ImGui::Button(paused_ ? "Run" : "Pause")) paused_ = !paused_;
    ImGui::SameLine();
    if (ImGui::Button("Step")) paused_ = true, step_once_ = true;
    ImGui::SameLine();
    if (ImGui::Button("Reset")) sim_->reset(), after_reset();
    ImGui::SameLine();
    const bool was_recording = recording_;  // the button may toggle it
    if (was_recording) ImGui::PushStyleColor(ImGuiCol_Button, ImVec4(0.75f, 0.15f, 0.15f, 1));
    if (ImGui::Button(was_recording ? "Stop recording" : "Record")) toggle_recording();
    if (was_recording) ImGui::PopStyleColor();
    ImGui::SameLine();
    if (ImGui::Button("Screenshot")) screenshot_ = true;
    if (ImGui::Button("Save state")) save_state();
    ImGui::SameLine();
    if (ImGui::Button("Load state")) load_state();
    if (!status_.empty()) {
      ImGui::PushTextWrapPos(0);
      ImGui::TextDisabled("%s", status_.c_str());
      ImGui::PopTextWrapPos();
    }
  }

  // The scene and the parameters that can change as it runs.
  void panel_parameters() {
    if (ImGui::BeginCombo("scene", scenes_[scene_index_].first.c_str())) {
      for (int i = 0; i < static_cast<int>(scenes_.size()); ++i)
        if (ImGui::Selectable(scenes_[i].first.c_str(), i == scene_index_)) pick_scene(i);
      ImGui::EndCombo();
    }
    float humidity = static_cast<float>(params_.cloth.humidity);
    if (ImGui::SliderFloat("humidity", &humidity, 0, 1, "%.2f", ImGuiSliderFlags_AlwaysClamp)) {
      params_.cloth.humidity = humidity;
      sim_->set_humidity(humidity);  // live: mass, permeability, adhesion follow
    }
    if (combo("air model", params_.air.model)) apply_params();

    // The first pulling handle: its force, along its own direction.
    for (auto& [name, hp] : params_.handles) {
      if (hp.type != HandleType::Force) continue;
      Vec3 f = to_vec(hp.force);
      float mag = static_cast<float>(f.norm());
      if (ImGui::SliderFloat(("force '" + name + "', N").c_str(), &mag, 0, 5, "%.2f")) {
        const Vec3 dir = f.norm() > 0 ? Vec3(f.normalized()) : Vec3::UnitZ();
        for (int k = 0; k < 3; ++k) hp.force[k] = dir[k] * mag;
        apply_params();
      }
      break;
    }
    if (combo("integrator", params_.integrator.type)) {
      params_.integrator.dt = step_for_integrator(params_, scene_integrator_, scene_dt_);
      apply_params();
    }
    float dt = static_cast<float>(params_.integrator.dt);
    if (ImGui::SliderFloat("time step, s", &dt, 1e-6f, 1.0f / 60, "%.1e",
                           ImGuiSliderFlags_Logarithmic)) {
      params_.integrator.dt = dt;
      apply_params();
    }
    ImGui::SliderFloat("grab stiffness, N/m", &grab_k_, 1, 2000, "%.0f",
                       ImGuiSliderFlags_Logarithmic);
    ImGui::SliderFloat("brush radius, cm", &brush_radius_cm_, 0.5f, 20, "%.1f");
    ImGui::SliderFloat("brush humidity", &brush_omega_, 0, 1, "%.2f", ImGuiSliderFlags_AlwaysClamp);
    ImGui::TextUnformatted("Shift + drag: the brush wets the cloth (humidity 0: dries it)");
    ImGui::SliderFloat("physics ms/frame", &budget_ms_, 1, 200, "%.0f",
                       ImGuiSliderFlags_Logarithmic);
  }

  // What the cloth is coloured by; a new choice finds its scale afresh.
  void colour_by_combo() {
    int c = static_cast<int>(color_);
    if (ImGui::Combo("colour by", &c, kColorByNames.data(),
                     static_cast<int>(kColorByNames.size()))) {
      color_ = static_cast<ColorBy>(c);
      color_scale_ = 0;
    }
  }

  void draw_checkboxes() {
    ImGui::Checkbox("wireframe (O)", &draw_.wireframe);
    ImGui::SameLine();
    ImGui::Checkbox("shadows", &draw_.shadows);
    ImGui::SameLine();
    ImGui::Checkbox("anti-alias", &antialias_);
  }

  // The last seconds of pressure deficit, contact area and handle height.
  void panel_plots() {
    ImGui::TextDisabled("last %.2f s of simulated time", pressure_.span());
    // At least 5 % of the breakthrough deficit: a vented or open cloth's 0 Pa stays flat.
    plot("pressure deficit P_atm - p, Pa", pressure_, "%.1f Pa",
         std::max(10.0f, 0.05f * static_cast<float>(params_.air.breakthrough_pressure)));
    plot("contact area, cm\xC2\xB2", contact_, "%.1f cm\xC2\xB2", 1.0f);
    // A pin (measured when there are only pins) holds one height: nothing to plot.
    if (sim_->model().measures_a_pull()) plot("handle height, cm", height_, "%.2f cm", 1.0f);
  }

  void panel(int window_h) {
    ImGui::SetNextWindowPos(ImVec2(10, 10), ImGuiCond_FirstUseEver);
    ImGui::SetNextWindowSize(ImVec2(kPanelWidth, std::min(window_h - 20.0f, 780.0f)),
                             ImGuiCond_FirstUseEver);
    ImGui::Begin("wetcloth");
    panel_status();
    panel_buttons();
    ImGui::Separator();
    // The sliders and menus take half the panel's width, their labels the other half.
    ImGui::PushItemWidth(ImGui::GetContentRegionAvail().x * 0.5f);
    panel_parameters();
    ImGui::Separator();
    colour_by_combo();
    ImGui::PopItemWidth();
    legend();
    draw_checkboxes();
    ImGui::Separator();
    panel_plots();
    if (ImGui::CollapsingHeader("mouse and keys")) {
      ImGui::TextWrapped(
          "Left-drag the cloth: pull it. Left- or right-drag elsewhere: orbit. Middle-drag: pan. "
          "Wheel: zoom. W/A/S/D: move. F: frame the scene. Space: pause. N: step. R: reset. "
          "O: wireframe. P: screenshot. Esc: quit.");
    }
    ImGui::End();
  }

  // --- the frame loop ---------------------------------------------------------------

  int loop() {
    auto last = Clock::now(), rtf_wall = last, run_start = last;
    double rtf_sim = sim_->state().time;
    const double start_time = rtf_sim;
    double shot_time = start_time, next_progress = 1.0;
    int frames_at_target = 0;
    while (!glfwWindowShouldClose(window_)) {
      glfwPollEvents();
      const double wall_dt = std::chrono::duration<double>(Clock::now() - last).count();
      last = Clock::now();
      move_camera(wall_dt);
      update_grab();
      advance(wall_dt);
      const State& s = sim_->state();
      if (opts_.screenshot_after) {
        // The whole run's real-time factor (the last frames, at the target
        // time, step nothing), and a progress line about every second.
        const double run_wall = std::chrono::duration<double>(Clock::now() - run_start).count();
        if (run_wall > 0 && s.time > shot_time) {
          rtf_ = (s.time - start_time) / run_wall;
          shot_time = s.time;
        }
        if (run_wall >= next_progress) {
          std::fprintf(stderr, "wetcloth view: t = %.3f of %.3f s simulated, %.3fx real time\n",
                       s.time, *opts_.screenshot_after, rtf_);
          next_progress = run_wall + 1.0;
        }
      } else if (const double wall = std::chrono::duration<double>(Clock::now() - rtf_wall).count();
                 wall > 0.5 || s.time < rtf_sim) {  // over about half a second of wall time
        rtf_ = std::max(0.0, s.time - rtf_sim) / wall;
        rtf_sim = s.time;
        rtf_wall = Clock::now();
      }

      int w = 0, h = 0;
      glfwGetFramebufferSize(window_, &w, &h);
      if (w <= 0 || h <= 0) continue;  // minimised
      const auto t0 = Clock::now();
      legend_ = cloth_mesh(*sim_, color_, color_scale_, mesh_);
      draw_.fabric = color_ == ColorBy::Fabric;
      draw_.grab_particle = grab_;
      draw_.grab_target = grab_target_;
      const int samples = antialias_ ? 4 : 0;
      if (!target_ || target_->width() != w || target_->height() != h ||
          (target_->samples() > 0) != antialias_) {
        target_.reset();
        target_ = std::make_unique<Framebuffer>(w, h, samples);
      }
      target_->bind();
      pose_stage(stage_, params_, sim_->state().time);
      renderer_->draw(mesh_, stage_, camera_, w, h, draw_);
      if (recording_) {  // the scene without the panel
        char name[32];
        std::snprintf(name, sizeof name, "frame_%05lld.png", record_frame_++);
        if (!write_png(record_dir_ / name, target_->read())) toggle_recording();
      }
      target_->blit_to(0);

      ImGui_ImplOpenGL3_NewFrame();
      ImGui_ImplGlfw_NewFrame();
      ImGui::NewFrame();
      int win_w = 0, win_h = 0;
      glfwGetWindowSize(window_, &win_w, &win_h);
      panel(win_h);
      ImGui::Render();
      ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());

      if (screenshot_) {
        screenshot_ = false;
        save_screenshot(unused_name("wetcloth-" + params_.name, ".png"));
      }
      // --screenshot-after: a few frames at the target time so the panel has settled.
      if (opts_.screenshot_after &&
          sim_->state().time >= *opts_.screenshot_after - 0.5 * params_.integrator.dt)
        if (++frames_at_target >= 3 || !blow_up_.empty()) {
          if (!blow_up_.empty()) return fail("the simulation blew up: " + blow_up_);
          std::fprintf(stderr, "wetcloth view: t = %.3f s simulated in %.1f s, %.3fx real time\n",
                       sim_->state().time,
                       std::chrono::duration<double>(Clock::now() - run_start).count(), rtf_);
          save_screenshot(opts_.screenshot_file);
          return fs::exists(opts_.screenshot_file) ? 0 : 1;
        }
      glfwSwapBuffers(window_);
      draw_ms_ = 0.8 * draw_ms_ + 0.2 * ms_since(t0);
    }
    return 0;
  }

  enum class Drag { None, Orbit, Pan, Grab, Brush };
  static constexpr float kPanelWidth = 400;
  static constexpr double kSampleInterval = 0.005;  // s of simulated time between plot samples

  ViewOptions opts_;
  Params params_;
  // The integrator and step the scene came with (step_for_integrator).
  IntegratorType scene_integrator_ = IntegratorType::SymplecticEuler;
  double scene_dt_ = 0;
  std::vector<std::pair<std::string, std::string>> scenes_;  // label, built-in name ("": the file)
  int scene_index_ = 0;
  GLFWwindow* window_ = nullptr;
  bool imgui_ = false;
  std::unique_ptr<Renderer> renderer_;
  std::unique_ptr<Framebuffer> target_;  // the scene is drawn here, then copied to the window
  bool software_ = false, antialias_ = true;
  std::unique_ptr<Simulation> sim_;
  Camera camera_;
  Stage stage_;
  ClothMesh mesh_;
  DrawOptions draw_;
  ColorBy color_;
  float color_scale_ = 0;
  Legend legend_;

  bool paused_ = false, step_once_ = false, screenshot_ = false;
  bool recording_ = false;
  fs::path record_dir_;
  long long record_frame_ = 0;
  std::string status_, blow_up_;
  float budget_ms_ = 25;
  double rtf_ = 0, physics_ms_ = 0, draw_ms_ = 0;
  History pressure_, contact_, height_;
  double next_sample_ = 0;

  Drag drag_ = Drag::None;
  double last_x_ = 0, last_y_ = 0;
  int grab_ = -1;
  float grab_k_ = 50;
  float brush_radius_cm_ = 3, brush_omega_ = 1;  // Shift + drag: the wetting brush
  Vec3f grab_point_{0, 0, 0}, grab_normal_{0, 0, 1}, grab_target_{0, 0, 0};
};

}  // namespace

int run_viewer(const ViewOptions& o) {
  Viewer v(o);
  return v.run();
}

}  // namespace wetcloth::viewer
