// The one drawing module: camera, stage (table, ball, ground grid), cloth, shadows.
// The window viewer, the offscreen renderer and the contact sheet all draw through
// Renderer::draw, so every picture of a scene looks the same.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "image.hpp"
#include "wetcloth/params.hpp"

namespace wetcloth::viewer {

using Vec3f = Eigen::Vector3f;
using Mat4f = Eigen::Matrix4f;

// An orbit camera around a target point; z is up.
struct Camera {
  Vec3f target{0, 0, 0};
  float yaw_deg = -60;   // azimuth of the eye around the target, from +x
  float pitch_deg = 30;  // elevation of the eye
  float distance = 0.8f;
  float fov_deg = 35;  // vertical
  float shift_x = 0;   // lens shift, NDC units: centres the view right of a side panel

  Vec3f eye() const;
  Mat4f view() const;
  Mat4f projection(float aspect) const;
  // The ray through pixel (px, py) of a w x h image, py counted from the top.
  void ray(double px, double py, int w, int h, Vec3f& origin, Vec3f& dir) const;
  // Moves the target in the camera's horizontal frame (W/A/S/D).
  void move(float forward, float right);
};

// Frames the box [lo, hi] in an image of this aspect, seen from view's direction
// (its yaw and pitch; by default a 3/4 view from above).
Camera frame_box(const Vec3f& lo, const Vec3f& hi, float aspect, const Camera& view = {});
// The direction a scene is best seen from: a hanging cloth face on, nearly level;
// a cloth pulled by a corner or an edge from across it, so that the lifted part
// shows its face, not its edge; anything else the default 3/4 view.
Camera scene_view(const Params& p);
// Frames the cloth at rest, room left above it for a tent (or a fall), from scene_view.
Camera frame_scene(const Params& p, float aspect);
// The box of what a picture must show: the cloth as it is now, the ball, and the
// table's height when the cloth is near it.
// Moving obstacles where they are at time t (s).
void content_box(const Params& p, const std::vector<Vec3f>& cloth, Vec3f& lo, Vec3f& hi,
                 double t = 0);

// Everything drawn besides the cloth, from the scene's parameters.
struct Stage {
  Vec3f light{0, 0, 1};  // unit vector towards the key light, set from scene_view
  float ground_z = 0;    // the ground grid; the table top when there is a table
  bool table = false;
  Eigen::Vector2f table_center{0, 0};
  float table_half = 0.6f;  // half-width of the table top (as in obstacles.obj)
  bool ball = false;
  Vec3f ball_center{0, 0, 0};  // where it is now (pose_stage)
  float ball_radius = 0;
  bool ball_moves = false;  // then drawn in bands, so that its turning shows
  Eigen::Matrix3f ball_rotation = Eigen::Matrix3f::Identity();
  // The [obstacle.NAME] meshes, triangles in float (shared: a stage made
  // again from the same scene reuses them, and the renderer uploads them once).
  struct Obstacles {
    std::vector<Vec3f> position, normal;  // per vertex, normals smoothed
    std::vector<std::array<int, 3>> triangles;
    Vec3f lo{0, 0, 0}, hi{0, 0, 0};
    struct Part {  // an obstacle's triangles: [first, first + count)
      std::string name;
      int first = 0, count = 0;
      int vertex0 = 0;  // its first vertex
    };
    std::vector<Part> parts;
    // Deforming obstacles (obstacle.NAME.cache): each part's time and its
    // points then (pose_stage reshapes a copy); `serial` tells an upload a
    // new shape from the last, whatever its address.
    std::vector<std::function<std::vector<Eigen::Vector3d>(double)>> shape;  // per part, or null
    bool deforms = false;
    std::uint64_t serial = 0;
  };
  std::shared_ptr<const Obstacles> obstacles;
  // Each part's placement now (moving ones; empty: all where they were
  // read), and the box they fill then.
  std::vector<Mat4f> obstacle_models;
  Vec3f obstacles_lo{0, 0, 0}, obstacles_hi{0, 0, 0};
};
// The stage at time 0.
Stage stage_from(const Params& p);
// Moves the ball and the mesh obstacles to where their motions have them at
// time t (s): the viewer and the render call it as the cloth moves.
void pose_stage(Stage& s, const Params& p, double t);

// The cloth as drawn: float positions, normals, per-vertex sRGB colours and,
// for the fabric look, per-vertex gloss 0..1 (how wet its surface looks).
struct ClothMesh {
  std::vector<Vec3f> position, normal, color;
  std::vector<float> gloss;
  std::vector<std::array<int, 3>> triangles;
};

// The cloth's own colour (a blue fabric), when it is not coloured by a field.
inline const Vec3f kClothColor{0.30f, 0.50f, 0.86f};

struct DrawOptions {
  bool wireframe = false;
  bool shadows = true;
  bool fabric = true;      // material look: underside a shade darker, glossy by ClothMesh::gloss
  int grab_particle = -1;  // >= 0: a line from that particle to grab_target
  Vec3f grab_target{0, 0, 0};
};

// Owns the GL objects. A GL 3.3 core context must be current while it lives.
class Renderer {
 public:
  Renderer();
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  // Draws into the bound draw framebuffer, viewport (0, 0, width, height).
  void draw(const ClothMesh& cloth, const Stage& stage, const Camera& cam, int width, int height,
            const DrawOptions& opt);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// An offscreen render target: multisampled, resolved when read back.
class Framebuffer {
 public:
  Framebuffer(int width, int height, int samples = 4);
  ~Framebuffer();
  Framebuffer(const Framebuffer&) = delete;
  Framebuffer& operator=(const Framebuffer&) = delete;
  void bind();                 // as the draw framebuffer
  Image read();                // resolves and reads back
  void blit_to(unsigned fbo);  // resolves into fbo (0: the window), leaves fbo bound
  int width() const { return w_; }
  int height() const { return h_; }
  int samples() const { return samples_; }

 private:
  int w_, h_, samples_;
  unsigned msaa_fbo_ = 0, color_rb_ = 0, depth_rb_ = 0, resolve_fbo_ = 0, resolve_rb_ = 0;
};

// Reads the bound read framebuffer (e.g. the window's back buffer) into an image.
Image read_pixels(int width, int height);

}  // namespace wetcloth::viewer
