#include "draw.hpp"

#include <epoxy/gl.h>

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <map>
#include <mutex>
#include <numbers>
#include <stdexcept>
#include <string>

#include "wetcloth/output.hpp"

namespace wetcloth::viewer {

namespace {

constexpr float kDeg = std::numbers::pi_v<float> / 180;

// Unit vector from azimuth and elevation, degrees.
Vec3f direction(float azimuth_deg, float elevation_deg) {
  const float a = azimuth_deg * kDeg, e = elevation_deg * kDeg;
  return Vec3f(std::cos(e) * std::cos(a), std::cos(e) * std::sin(a), std::sin(e));
}

Mat4f look_at(const Vec3f& eye, const Vec3f& target, const Vec3f& up) {
  const Vec3f f = (target - eye).normalized();
  const Vec3f s = f.cross(up).normalized();
  const Vec3f u = s.cross(f);
  Mat4f m;
  m << s.x(), s.y(), s.z(), -s.dot(eye),   //
      u.x(), u.y(), u.z(), -u.dot(eye),    //
      -f.x(), -f.y(), -f.z(), f.dot(eye),  //
      0, 0, 0, 1;
  return m;
}

Mat4f perspective(float fovy, float aspect, float near, float far) {
  const float f = 1.0f / std::tan(fovy / 2);
  Mat4f m = Mat4f::Zero();
  m(0, 0) = f / aspect;
  m(1, 1) = f;
  m(2, 2) = (far + near) / (near - far);
  m(2, 3) = 2 * far * near / (near - far);
  m(3, 2) = -1;
  return m;
}

Mat4f ortho(float half, float near, float far) {
  Mat4f m = Mat4f::Identity();
  m(0, 0) = m(1, 1) = 1 / half;
  m(2, 2) = -2 / (far - near);
  m(2, 3) = -(far + near) / (far - near);
  return m;
}

Mat4f translate_scale(const Vec3f& t, const Vec3f& s) {
  Mat4f m = Mat4f::Identity();
  m.diagonal().head<3>() = s;
  m.block<3, 1>(0, 3) = t;
  return m;
}

// --- shaders -------------------------------------------------------------------

// The sky, shared by the background and the ground's fog (sRGB, neutral grey so
// that the blue cloth stands out).
const char* kSky = R"(
vec3 sky(vec3 d) {
  vec3 horizon = vec3(0.52, 0.53, 0.55), zenith = vec3(0.24, 0.25, 0.28), below = vec3(0.33, 0.33, 0.34);
  return d.z > 0.0 ? mix(horizon, zenith, sqrt(clamp(d.z, 0.0, 1.0)))
                   : mix(horizon, below, clamp(-d.z * 4.0, 0.0, 1.0));
}
)";

const char* kSkyVert = R"(#version 330 core
out vec2 v_ndc;
void main() {  // one triangle covering the screen, no vertex buffer, on the far plane
  vec2 p = vec2((gl_VertexID << 1) & 2, gl_VertexID & 2) * 2.0 - 1.0;
  v_ndc = p;
  gl_Position = vec4(p, 1.0, 1.0);
}
)";

const char* kSkyFrag = R"(
in vec2 v_ndc;
uniform mat4 u_inv_view_proj;
out vec4 frag;
void main() {
  vec4 a = u_inv_view_proj * vec4(v_ndc, -1.0, 1.0), b = u_inv_view_proj * vec4(v_ndc, 1.0, 1.0);
  frag = vec4(sky(normalize(b.xyz / b.w - a.xyz / a.w)), 1.0);
}
)";

const char* kLitVert = R"(#version 330 core
layout(location = 0) in vec3 a_pos;
layout(location = 1) in vec3 a_normal;
layout(location = 2) in vec3 a_color;
layout(location = 3) in float a_gloss;
uniform mat4 u_model;  // unit sphere or unit quad to world; identity for the cloth
uniform mat4 u_view_proj;
out vec3 v_pos;
out vec3 v_normal;
out vec3 v_color;
out float v_gloss;
void main() {
  vec4 p = u_model * vec4(a_pos, 1.0);
  v_pos = p.xyz;
  v_normal = mat3(u_model) * a_normal;
  v_color = a_color;
  v_gloss = a_gloss;
  gl_Position = u_view_proj * p;
}
)";

// One source, specialised by MATERIAL (0 plain, 1 fabric, 2 ground) and SHADOWS:
// a software rasteriser runs both sides of every branch, so variants are compiled
// instead of branching on uniforms.
const char* kLitFrag = R"(
in vec3 v_pos;
in vec3 v_normal;
in vec3 v_color;
in float v_gloss;
uniform vec3 u_eye;
uniform vec3 u_light;  // unit vector towards the light
out vec4 frag;

#if SHADOWS
uniform mat4 u_light_view_proj;
uniform sampler2DShadow u_shadow_map;
uniform float u_softness;       // shadow blur radius, shadow-map uv units
uniform float u_normal_offset;  // m
uniform float u_depth_bias;     // shadow-map depth units
uniform float u_slope_bias;     // blur radius in depth units: a tilted receiver's depth spread
const vec2 kDisk[12] = vec2[](
  vec2(-0.326, -0.406), vec2(-0.840, -0.074), vec2(-0.696, 0.457), vec2(-0.203, 0.621),
  vec2(0.962, -0.195), vec2(0.473, -0.480), vec2(0.519, 0.767), vec2(0.185, -0.893),
  vec2(0.507, 0.064), vec2(0.896, 0.412), vec2(-0.322, -0.933), vec2(-0.792, -0.598));

// Share of the key light that reaches p: percentage-closer filtering over a disk,
// each tap itself bilinear, for soft edges. Outside the map: lit.
float lit_fraction(vec3 p, vec3 n_towards_light) {
  vec4 l = u_light_view_proj * vec4(p + n_towards_light * u_normal_offset, 1.0);
  vec3 c = l.xyz / l.w * 0.5 + 0.5;
  // Over the blur disk a receiver tilted by theta from the light spans r tan(theta)
  // in depth: without that much bias it would shadow itself in stripes.
  float cos_t = clamp(dot(n_towards_light, u_light), 0.2, 1.0);
  float bias = u_depth_bias + u_slope_bias * sqrt(1.0 - cos_t * cos_t) / cos_t;
  float s = 0.0;
  for (int i = 0; i < 12; ++i)
    s += texture(u_shadow_map, vec3(c.xy + kDisk[i] * u_softness, c.z - bias));
  bool inside = all(greaterThanEqual(c, vec3(0.0))) && all(lessThanEqual(c, vec3(1.0)));
  return inside ? s / 12.0 : 1.0;
}
#endif

#if MATERIAL == 2
uniform vec4 u_table;  // table centre xy, half-width, 1 if there is a table
uniform vec2 u_fog;    // fog start and end distance, m
// Anti-aliased grid lines every `cell` metres, faded where they get denser than pixels.
float grid(vec2 p, float cell) {
  vec2 q = p / cell, w = fwidth(q);
  vec2 d = abs(fract(q - 0.5) - 0.5) / max(w, vec2(1e-6));
  return (1.0 - min(min(d.x, d.y), 1.0)) * clamp(1.5 - 4.0 * max(w.x, w.y), 0.0, 1.0);
}
#endif

void main() {
  vec3 n = normalize(v_normal);
  bool back = !gl_FrontFacing;
  if (back) n = -n;  // two-sided lighting: light the side we see
  vec3 v = normalize(u_eye - v_pos);
  vec3 albedo = v_color * v_color;  // sRGB to linear, gamma 2: cheap on a software rasteriser
  float ks = 0.04, shininess = 24.0;
#if MATERIAL == 1
  if (back) albedo *= 0.72;                 // the underside, a shade darker
  // Water darkens fabric (each vertex's colour: fabric_look) and glosses it
  ks = mix(0.03, 0.20, v_gloss);
  shininess = mix(10.0, 60.0, v_gloss);
#elif MATERIAL == 2
  bool on_table = u_table.w > 0.5 && all(lessThan(abs(v_pos.xy - u_table.xy), vec2(u_table.z)));
  vec3 base = on_table ? vec3(0.66, 0.61, 0.54) : vec3(0.42, 0.42, 0.43);
  base *= 1.0 - max(0.22 * grid(v_pos.xy, 0.05), 0.45 * grid(v_pos.xy, 0.5));
  albedo = base * base;
  ks = 0.02;
#endif
  float ndl = max(dot(n, u_light), 0.0);
#if SHADOWS
  float sh = lit_fraction(v_pos, dot(n, u_light) >= 0.0 ? n : -n);
#else
  float sh = 1.0;
#endif
  // Hemisphere ambient: cool sky above, warm bounce from the table below.
  vec3 ambient = mix(vec3(0.20, 0.19, 0.17), vec3(0.40, 0.42, 0.46), 0.5 + 0.5 * n.z);
  vec3 h = normalize(u_light + v);
  float spec = ks * pow(max(dot(n, h), 0.0), shininess) * (shininess + 8.0) / 8.0;
  vec3 c = albedo * (ambient + 1.1 * ndl * sh * vec3(1.0, 0.97, 0.92)) + vec3(spec * ndl * sh);
  c = c / (1.0 + 0.25 * c);  // gentle tone mapping: highlights roll off instead of clipping
  c = sqrt(c * 1.25);
#if MATERIAL == 2  // the ground fades into the sky with distance
  c = mix(c, sky(-v), smoothstep(u_fog.x, u_fog.y, length(v_pos - u_eye)));
#endif
  frag = vec4(c, 1.0);
}
)";

const char* kDepthVert = R"(#version 330 core
layout(location = 0) in vec3 a_pos;
uniform mat4 u_model;
uniform mat4 u_view_proj;
void main() { gl_Position = u_view_proj * u_model * vec4(a_pos, 1.0); }
)";

const char* kDepthFrag = R"(#version 330 core
void main() {}
)";

const char* kFlatFrag = R"(#version 330 core
uniform vec4 u_color;
out vec4 frag;
void main() { frag = u_color; }
)";

GLuint compile(GLenum type, const std::string& src) {
  const GLuint s = glCreateShader(type);
  const char* p = src.c_str();
  glShaderSource(s, 1, &p, nullptr);
  glCompileShader(s);
  GLint ok = 0;
  glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    char log[4096];
    glGetShaderInfoLog(s, sizeof log, nullptr, log);
    glDeleteShader(s);
    throw std::runtime_error(std::string("shader does not compile: ") + log);
  }
  return s;
}

GLuint program(const std::string& vert, const std::string& frag) {
  const GLuint v = compile(GL_VERTEX_SHADER, vert), f = compile(GL_FRAGMENT_SHADER, frag);
  const GLuint p = glCreateProgram();
  glAttachShader(p, v);
  glAttachShader(p, f);
  glLinkProgram(p);
  glDeleteShader(v);
  glDeleteShader(f);
  GLint ok = 0;
  glGetProgramiv(p, GL_LINK_STATUS, &ok);
  if (!ok) {
    char log[4096];
    glGetProgramInfoLog(p, sizeof log, nullptr, log);
    glDeleteProgram(p);
    throw std::runtime_error(std::string("shaders do not link: ") + log);
  }
  return p;
}

GLint loc(GLuint prog, const char* name) { return glGetUniformLocation(prog, name); }
void set(GLuint prog, const char* name, const Mat4f& m) {
  glUniformMatrix4fv(loc(prog, name), 1, GL_FALSE, m.data());
}
void set(GLuint prog, const char* name, const Vec3f& v) {
  glUniform3fv(loc(prog, name), 1, v.data());
}
void set(GLuint prog, const char* name, float x) { glUniform1f(loc(prog, name), x); }
void set(GLuint prog, const char* name, int x) { glUniform1i(loc(prog, name), x); }

// A mesh with interleaved position, normal, colour and gloss (10 floats per vertex).
struct Mesh {
  GLuint vao = 0, vbo = 0, ebo = 0;
  GLsizei count = 0;  // indices

  void create() {
    glGenVertexArrays(1, &vao);
    glGenBuffers(1, &vbo);
    glGenBuffers(1, &ebo);
    glBindVertexArray(vao);
    glBindBuffer(GL_ARRAY_BUFFER, vbo);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, ebo);
    for (GLuint a = 0; a < 4; ++a) {
      glEnableVertexAttribArray(a);
      glVertexAttribPointer(
          a, a < 3 ? 3 : 1, GL_FLOAT, GL_FALSE, 10 * sizeof(float),
          reinterpret_cast<void*>(static_cast<std::uintptr_t>(a * 3 * sizeof(float))));
    }
    glBindVertexArray(0);
  }
  void destroy() {
    glDeleteVertexArrays(1, &vao);
    glDeleteBuffers(1, &vbo);
    glDeleteBuffers(1, &ebo);
  }
  void upload(const std::vector<float>& vertices, const std::vector<unsigned>& indices,
              GLenum usage) {
    glBindVertexArray(vao);
    glBindBuffer(GL_ARRAY_BUFFER, vbo);
    glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(vertices.size() * sizeof(float)),
                 vertices.data(), usage);
    if (!indices.empty()) {
      glBufferData(GL_ELEMENT_ARRAY_BUFFER,
                   static_cast<GLsizeiptr>(indices.size() * sizeof(unsigned)), indices.data(),
                   usage);
      count = static_cast<GLsizei>(indices.size());
    }
    glBindVertexArray(0);
  }
  // Indices [first, first + n) only.
  void draw_range(int first, int n) const {
    glBindVertexArray(vao);
    glDrawElements(GL_TRIANGLES, n, GL_UNSIGNED_INT,
                   reinterpret_cast<void*>(static_cast<std::uintptr_t>(first) * sizeof(unsigned)));
    glBindVertexArray(0);
  }
  void draw() const {
    glBindVertexArray(vao);
    glDrawElements(GL_TRIANGLES, count, GL_UNSIGNED_INT, nullptr);
  }
};

void push(std::vector<float>& v, const Vec3f& p, const Vec3f& n, const Vec3f& c, float gloss = 0) {
  v.insert(v.end(), {p.x(), p.y(), p.z(), n.x(), n.y(), n.z(), c.x(), c.y(), c.z(), gloss});
}

constexpr int kShadowSize = 1024;

}  // namespace

// --- camera ------------------------------------------------------------------------

Vec3f Camera::eye() const {
  const float y = yaw_deg * kDeg, p = pitch_deg * kDeg;
  return target +
         distance * Vec3f(std::cos(p) * std::cos(y), std::cos(p) * std::sin(y), std::sin(p));
}

Mat4f Camera::view() const { return look_at(eye(), target, Vec3f::UnitZ()); }

Mat4f Camera::projection(float aspect) const {
  Mat4f m = perspective(fov_deg * kDeg, aspect, distance * 0.02f, distance * 20 + 20);
  m(0, 2) = -shift_x;  // x_ndc += shift_x
  return m;
}

void Camera::ray(double px, double py, int w, int h, Vec3f& origin, Vec3f& dir) const {
  const Mat4f inv = (projection(static_cast<float>(w) / h) * view()).inverse();
  const float x = static_cast<float>(2 * px / w - 1), y = static_cast<float>(1 - 2 * py / h);
  const Eigen::Vector4f a = inv * Eigen::Vector4f(x, y, -1, 1),
                        b = inv * Eigen::Vector4f(x, y, 1, 1);
  origin = a.head<3>() / a.w();
  dir = (b.head<3>() / b.w() - origin).normalized();
}

void Camera::move(float forward, float right) {
  const float y = yaw_deg * kDeg;
  const Vec3f f(-std::cos(y), -std::sin(y), 0);  // horizontal, towards the target
  target += forward * f + right * f.cross(Vec3f::UnitZ());
}

Camera frame_box(const Vec3f& lo, const Vec3f& hi, float aspect, const Camera& view) {
  Camera c;
  c.yaw_deg = view.yaw_deg;
  c.pitch_deg = view.pitch_deg;
  c.target = (lo + hi) / 2;
  // The nearest distance from which every corner of the box is in the picture,
  // with a small border.
  const float ty = 0.92f * std::tan(c.fov_deg * kDeg / 2), tx = ty * aspect;
  c.distance = 1;
  const Mat4f v = c.view();
  const Vec3f right = v.block<1, 3>(0, 0).transpose(), up = v.block<1, 3>(1, 0).transpose(),
              back = v.block<1, 3>(2, 0).transpose();
  float d = 0.05f;
  for (int k = 0; k < 8; ++k) {
    const Vec3f q(k & 1 ? hi.x() : lo.x(), k & 2 ? hi.y() : lo.y(), k & 4 ? hi.z() : lo.z());
    const Vec3f r = q - c.target;
    d = std::max(
        {d, r.dot(back) + std::abs(r.dot(right)) / tx, r.dot(back) + std::abs(r.dot(up)) / ty});
  }
  c.distance = d;
  return c;
}

Camera scene_view(const Params& p) {
  Camera c;
  if (p.cloth.orientation == Orientation::Vertical) {
    c.yaw_deg = -75;  // the cloth spans x and z: nearly face on, a little from the side
    c.pitch_deg = 12;
    return c;
  }
  for (const auto& [name, h] : p.handles) {  // the first pulling handle, by name
    if (h.type != HandleType::Force) continue;
    const float du = static_cast<float>((h.at[0] - 0.5) * p.cloth.size[0]),
                dv = static_cast<float>((h.at[1] - 0.5) * p.cloth.size[1]);
    if (std::hypot(du, dv) >
        0.25f * static_cast<float>(std::max(p.cloth.size[0], p.cloth.size[1]))) {
      // From the far side, turned 30 degrees: the flap a corner or edge lifts
      // faces the camera; from the default side it was a thin sliver.
      c.yaw_deg = std::atan2(-dv, -du) / kDeg - 30;
      c.pitch_deg = 28;
    }
    break;
  }
  return c;
}

namespace {
// Area-weighted vertex normals of the obstacles' triangles, and their box.
void smooth_normals_and_box(Stage::Obstacles& o) {
  o.normal.assign(o.position.size(), Vec3f::Zero());
  for (const auto& t : o.triangles) {
    const Vec3f n =
        (o.position[t[1]] - o.position[t[0]]).cross(o.position[t[2]] - o.position[t[0]]);
    for (int k : t) o.normal[k] += n;
  }
  for (auto& n : o.normal) n.normalize();
  if (!o.position.empty()) {
    o.lo = o.hi = o.position[0];
    for (const auto& x : o.position) o.lo = o.lo.cwiseMin(x), o.hi = o.hi.cwiseMax(x);
  }
}

// The scene's mesh obstacles for drawing, read once per scene (a stage is
// made again for every tile of a comparison): none when it has none, or
// when they do not load (load_scene has said why already).
std::shared_ptr<const Stage::Obstacles> scene_obstacles(const Params& p) {
  if (p.obstacles.empty()) return nullptr;
  std::string key = p.scene_dir;
  for (const auto& [name, o] : p.obstacles) {
    char t[256];
    std::snprintf(t, sizeof t, "|%s %.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g",
                  name.c_str(), o.translate[0], o.translate[1], o.translate[2], o.rotate[0],
                  o.rotate[1], o.rotate[2], o.scale[0], o.scale[1], o.scale[2]);
    key += t + o.mesh;
    std::snprintf(t, sizeof t, "|%.17g %.17g ", o.cache_fps, o.cache_start);
    key += t + o.cache;
  }
  static std::mutex mutex;
  static std::map<std::string, std::shared_ptr<const Stage::Obstacles>> cache;
  const std::lock_guard<std::mutex> lock(mutex);
  if (const auto it = cache.find(key); it != cache.end()) return it->second;
  auto out = std::make_shared<Stage::Obstacles>();
  try {
    Params only = p;
    only.table.enabled = only.ball.enabled = false;
    for (const NamedMesh& mesh : obstacle_meshes(only)) {
      const int base = static_cast<int>(out->position.size());
      out->parts.push_back({mesh.name, static_cast<int>(3 * out->triangles.size()),
                            static_cast<int>(3 * mesh.triangles.size()), base});
      for (const Vec3& x : mesh.points) out->position.push_back(x.cast<float>());
      for (const auto& t : mesh.triangles)
        out->triangles.push_back({base + t[0], base + t[1], base + t[2]});
      out->shape.emplace_back();
      if (mesh.deforming) {
        out->shape.back() = [mesh](double t) { return mesh.points_at(t); };
        out->deforms = true;
      }
    }
  } catch (const std::exception&) {
    out->position.clear(), out->triangles.clear(), out->parts.clear(), out->shape.clear();
  }
  smooth_normals_and_box(*out);
  return cache[key] = out->position.empty() ? nullptr : out;
}

// A deforming stage's obstacles at time t: a copy with each deforming part's
// points then, its normals and box made again.
std::shared_ptr<const Stage::Obstacles> shaped_obstacles(const Stage::Obstacles& o, double t) {
  static std::atomic<std::uint64_t> serial{0};
  auto out = std::make_shared<Stage::Obstacles>(o);
  out->serial = ++serial;
  for (std::size_t k = 0; k < o.parts.size(); ++k) {
    if (!o.shape[k]) continue;
    const std::vector<Vec3> points = o.shape[k](t);
    for (std::size_t i = 0; i < points.size(); ++i)
      out->position[static_cast<std::size_t>(o.parts[k].vertex0) + i] = points[i].cast<float>();
  }
  smooth_normals_and_box(*out);
  return out;
}

// The box of the corners of [lo, hi] moved by `model`.
void moved_box(const Mat4f& model, Vec3f& lo, Vec3f& hi) {
  Vec3f a = Vec3f::Constant(1e30f), b = Vec3f::Constant(-1e30f);
  for (int c = 0; c < 8; ++c) {
    const Vec3f x((c & 1) ? hi.x() : lo.x(), (c & 2) ? hi.y() : lo.y(), (c & 4) ? hi.z() : lo.z());
    const Vec3f y = model.topLeftCorner<3, 3>() * x + model.block<3, 1>(0, 3);
    a = a.cwiseMin(y), b = b.cwiseMax(y);
  }
  lo = a, hi = b;
}

// Each part's placement at time t, and the box of the parts so placed.
void pose_obstacles(const Params& p, double t, const Stage::Obstacles& o,
                    std::vector<Mat4f>& models, Vec3f& lo, Vec3f& hi) {
  models.clear();
  lo = o.lo, hi = o.hi;
  bool any = false;
  for (const auto& part : o.parts) {
    const auto it = p.obstacles.find(part.name);
    const RigidPose pose = it == p.obstacles.end() ? RigidPose{} : obstacle_pose(p, part.name, t);
    Mat4f m = Mat4f::Identity();
    m.topLeftCorner<3, 3>() = pose.rotation.cast<float>();
    m.block<3, 1>(0, 3) = pose.to_world(Vec3::Zero()).cast<float>();
    models.push_back(m);
    any = any || pose.moving;
  }
  if (!any) {
    models.clear();
    return;
  }
  // Loose but safe: the whole set's box moved by each part's placement.
  Vec3f a = Vec3f::Constant(1e30f), b = Vec3f::Constant(-1e30f);
  for (const Mat4f& m : models) {
    Vec3f l = o.lo, h = o.hi;
    moved_box(m, l, h);
    a = a.cwiseMin(l), b = b.cwiseMax(h);
  }
  lo = a, hi = b;
}

// Widens a box round the cloth to the obstacles in view at time t: the table
// when the cloth is within half its size of it (not under a hanging flag),
// the ball, the mesh obstacles.
void add_obstacles(const Params& p, Vec3f& lo, Vec3f& hi, double t = 0) {
  auto meshes = scene_obstacles(p);
  if (meshes && meshes->deforms) meshes = shaped_obstacles(*meshes, t);
  if (meshes) {
    std::vector<Mat4f> models;
    Vec3f a, b;
    pose_obstacles(p, t, *meshes, models, a, b);
    lo = lo.cwiseMin(a);
    hi = hi.cwiseMax(b);
  }
  const float size = static_cast<float>(std::max(p.cloth.size[0], p.cloth.size[1]));
  const float table = static_cast<float>(p.table.height);
  if (p.table.enabled && lo.z() - table < size * 0.5f) lo.z() = std::min(lo.z(), table);
  if (p.ball.enabled) {
    const Vec3f b = ball_pose(p, t).to_world(to_vec(p.ball.center)).cast<float>();
    const float r = static_cast<float>(p.ball.radius);
    lo = lo.cwiseMin(b - Vec3f::Constant(r));
    hi = hi.cwiseMax(b + Vec3f::Constant(r));
  }
}
}  // namespace

Camera frame_scene(const Params& p, float aspect) {
  const Vec3f center =
      Eigen::Vector3d(p.cloth.center[0], p.cloth.center[1], p.cloth.center[2]).cast<float>();
  const float su = static_cast<float>(p.cloth.size[0]), sv = static_cast<float>(p.cloth.size[1]);
  // The cloth's box: v along y (horizontal) or z (vertical), turned by the tilt.
  const float t = static_cast<float>(p.cloth.tilt * std::numbers::pi / 180);
  const float along = sv / 2 * std::abs(std::cos(t)), across = sv / 2 * std::abs(std::sin(t));
  Vec3f half = p.cloth.orientation == Orientation::Vertical
                   ? Vec3f(su / 2, std::max(0.02f, across), along)
                   : Vec3f(su / 2, along, across);
  Vec3f lo = center - half, hi = center + half;
  // Room above a flat cloth for the tent a pulling handle raises.
  const float lift = std::max(su, sv) * 0.4f;
  if (p.cloth.orientation != Orientation::Vertical) hi.z() += lift;
  add_obstacles(p, lo, hi);
  return frame_box(lo, hi, aspect, scene_view(p));
}

void content_box(const Params& p, const std::vector<Vec3f>& cloth, Vec3f& lo, Vec3f& hi, double t) {
  lo = Vec3f::Constant(1e30f), hi = Vec3f::Constant(-1e30f);
  for (const auto& x : cloth) lo = lo.cwiseMin(x), hi = hi.cwiseMax(x);
  if (lo.x() > hi.x())
    lo = hi =
        Eigen::Vector3d(p.cloth.center[0], p.cloth.center[1], p.cloth.center[2]).cast<float>();
  add_obstacles(p, lo, hi, t);
}

void pose_stage(Stage& s, const Params& p, double t) {
  if (s.ball) {
    const RigidPose pose = ball_pose(p, t);
    s.ball_center = pose.to_world(to_vec(p.ball.center)).cast<float>();
    s.ball_rotation = pose.rotation.cast<float>();
    s.ball_moves = pose.moving;
  }
  if (s.obstacles && s.obstacles->deforms) s.obstacles = shaped_obstacles(*s.obstacles, t);
  if (s.obstacles)
    pose_obstacles(p, t, *s.obstacles, s.obstacle_models, s.obstacles_lo, s.obstacles_hi);
}

Stage stage_from(const Params& p) {
  Stage s;
  // The key light from the camera's left, set with the view so that it stays put
  // as one orbits. Over a flat cloth: high and well to the side, so the tent's two
  // flanks get different light and its shadow falls beside it. A hanging cloth
  // faces the camera: the light comes from nearer the camera and lower, or the
  // side we see would be the dark one.
  const Camera view = scene_view(p);
  s.light = p.cloth.orientation == Orientation::Vertical ? direction(view.yaw_deg - 45, 35)
                                                         : direction(view.yaw_deg - 95, 53);
  s.table = p.table.enabled;
  s.table_center = {static_cast<float>(p.cloth.center[0]), static_cast<float>(p.cloth.center[1])};
  s.table_half = static_cast<float>(std::max(p.cloth.size[0], p.cloth.size[1]) * 2);
  s.ball = p.ball.enabled;
  s.ball_center =
      Eigen::Vector3d(p.ball.center[0], p.ball.center[1], p.ball.center[2]).cast<float>();
  s.ball_radius = static_cast<float>(p.ball.radius);
  s.obstacles = scene_obstacles(p);
  pose_stage(s, p, 0);
  if (s.table) {
    s.ground_z = static_cast<float>(p.table.height);
  } else {  // no table: the grid a little below the lowest thing in the scene
    // (a hanging cloth's lower edge is half its height below its centre; a little
    // more below it, as much as it stretches and swings, or a big empty floor shows).
    float low = static_cast<float>(p.cloth.center[2]);
    if (p.cloth.orientation == Orientation::Vertical)
      low -= static_cast<float>(p.cloth.size[1]) * 0.75f;
    if (s.ball) low = std::min(low, s.ball_center.z() - s.ball_radius);
    if (s.obstacles) low = std::min(low, s.obstacles_lo.z());
    s.ground_z = low - (p.cloth.orientation == Orientation::Vertical ? 0.0f : 0.1f);
  }
  return s;
}

// --- renderer -----------------------------------------------------------------------

enum Material { kPlain = 0, kFabric = 1, kGround = 2 };

// What every pass of one draw shares: its inputs, the two cameras (the eye's
// and the light's), and the box of what casts shadows.
struct DrawFrame {
  const ClothMesh& cloth;
  const Stage& stage;
  const Camera& cam;
  const DrawOptions& opt;
  Mat4f view_proj = Mat4f::Identity(), light_view_proj = Mat4f::Identity(),
        ball_model = Mat4f::Identity();
  Vec3f lo = Vec3f::Zero(), hi = Vec3f::Zero();  // the shadow casters' box (cloth, ball, obstacles)
  float radius = 0;                              // of the light's frustum around that box
};

// Receivers this far below the casters still get their shadow.
constexpr float kShadowReach = 20;

DrawFrame draw_frame(const ClothMesh& cloth, const Stage& stage, const Camera& cam, int width,
                     int height, const DrawOptions& opt) {
  DrawFrame f{cloth, stage, cam, opt};
  f.view_proj = cam.projection(static_cast<float>(width) / std::max(height, 1)) * cam.view();
  // The ball drawn a hair smaller than it is: the cloth resting on it may sink into it
  // by a fraction of a millimetre, which would show as specks of ball through the cloth.
  const float ball_r = std::max(stage.ball_radius - 0.0015f, stage.ball_radius * 0.98f);
  f.ball_model = translate_scale(stage.ball_center, Vec3f::Constant(ball_r));
  f.ball_model.topLeftCorner<3, 3>() = stage.ball_rotation * ball_r;

  // Light frustum: an orthographic box around what casts shadows (cloth, ball).
  Vec3f lo = Vec3f::Constant(1e30f), hi = Vec3f::Constant(-1e30f);
  for (const auto& p : cloth.position) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  if (stage.ball) {
    lo = lo.cwiseMin(stage.ball_center - Vec3f::Constant(stage.ball_radius));
    hi = hi.cwiseMax(stage.ball_center + Vec3f::Constant(stage.ball_radius));
  }
  if (stage.obstacles) lo = lo.cwiseMin(stage.obstacles_lo), hi = hi.cwiseMax(stage.obstacles_hi);
  if (lo.x() > hi.x()) lo = hi = Vec3f::Zero();
  const Vec3f center = (lo + hi) / 2;
  f.lo = lo, f.hi = hi;
  f.radius = (hi - lo).norm() / 2 + 0.02f;
  f.light_view_proj = ortho(f.radius, 0.0f, 2 * f.radius + kShadowReach) *
                      look_at(center + stage.light * (f.radius + 0.01f), center, Vec3f::UnitZ());
  return f;
}

struct Renderer::Impl {
  GLuint sky = 0, depth = 0, flat = 0;
  GLuint lit[3][2] = {};  // [material][shadows], compiled when first used
  GLuint empty_vao = 0;
  Mesh cloth, sphere, quad;
  Mesh banded;     // the unit sphere in eight coloured gores: a moving ball, its turning seen
  Mesh obstacles;  // the stage's mesh obstacles, as last uploaded
  const Stage::Obstacles* uploaded = nullptr;
  std::uint64_t uploaded_serial = 0;
  GLuint line_vao = 0, line_vbo = 0;
  GLuint shadow_tex = 0, shadow_fbo = 0;
  std::vector<float> vertices;
  std::vector<std::array<int, 3>> triangles;  // the cloth's, as last uploaded

  Impl() {
    const std::string header = "#version 330 core\n";
    sky = program(kSkyVert, header + kSky + kSkyFrag);
    depth = program(kDepthVert, kDepthFrag);
    flat = program(kDepthVert, kFlatFrag);
    glGenVertexArrays(1, &empty_vao);
    cloth.create();
    sphere.create();
    quad.create();
    obstacles.create();
    banded.create();

    // Unit sphere (ball, grab marker).
    std::vector<float> v;
    std::vector<unsigned> idx;
    const int rings = 32, segs = 64;
    for (int r = 0; r <= rings; ++r)
      for (int s = 0; s <= segs; ++s) {
        const float th = std::numbers::pi_v<float> * r / rings,
                    ph = 2 * std::numbers::pi_v<float> * s / segs;
        const Vec3f p(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th));
        push(v, p, p, Vec3f(0.85f, 0.52f, 0.30f));
      }
    for (int r = 0; r < rings; ++r)
      for (int s = 0; s < segs; ++s) {
        const unsigned a = r * (segs + 1) + s, b = a + 1, c = a + segs + 1, d = c + 1;
        idx.insert(idx.end(), {a, c, d, a, d, b});  // counter-clockwise seen from outside
      }
    sphere.upload(v, idx, GL_STATIC_DRAW);
    for (int r = 0; r <= rings; ++r)  // the same, every other gore a paler shade
      for (int s = 0; s <= segs; ++s)
        if ((s * 8 / segs) % 2 == 1 && s % (segs / 8) != 0)
          for (int q = 0; q < 3; ++q)
            v[9 * (r * (segs + 1) + s) + 6 + q] = Vec3f(0.96f, 0.86f, 0.70f)[q];
    banded.upload(v, idx, GL_STATIC_DRAW);

    // Unit ground quad in z = 0, facing up.
    v.clear();
    for (auto [x, y] : {std::pair{-1, -1}, {1, -1}, {1, 1}, {-1, 1}})
      push(v, Vec3f(x, y, 0), Vec3f::UnitZ(), Vec3f::Ones());
    quad.upload(v, {0, 1, 2, 0, 2, 3}, GL_STATIC_DRAW);

    glGenVertexArrays(1, &line_vao);
    glGenBuffers(1, &line_vbo);
    glBindVertexArray(line_vao);
    glBindBuffer(GL_ARRAY_BUFFER, line_vbo);
    glBufferData(GL_ARRAY_BUFFER, 6 * sizeof(float), nullptr, GL_STREAM_DRAW);
    glEnableVertexAttribArray(0);
    glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 3 * sizeof(float), nullptr);
    glBindVertexArray(0);

    // Shadow map: depth texture compared in hardware (sampler2DShadow), linear
    // filtering so that each tap is already a 2x2 percentage-closer filter.
    glGenTextures(1, &shadow_tex);
    glBindTexture(GL_TEXTURE_2D, shadow_tex);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_DEPTH_COMPONENT24, kShadowSize, kShadowSize, 0,
                 GL_DEPTH_COMPONENT, GL_UNSIGNED_INT, nullptr);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_COMPARE_MODE, GL_COMPARE_REF_TO_TEXTURE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_COMPARE_FUNC, GL_LEQUAL);
    glGenFramebuffers(1, &shadow_fbo);
    glBindFramebuffer(GL_FRAMEBUFFER, shadow_fbo);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_TEXTURE_2D, shadow_tex, 0);
    glDrawBuffer(GL_NONE);
    glReadBuffer(GL_NONE);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
  }

  ~Impl() {
    for (GLuint p : {sky, depth, flat}) glDeleteProgram(p);
    for (auto& m : lit)
      for (GLuint p : m)
        if (p) glDeleteProgram(p);
    glDeleteVertexArrays(1, &empty_vao);
    cloth.destroy();
    sphere.destroy();
    obstacles.destroy();
    banded.destroy();
    quad.destroy();
    glDeleteVertexArrays(1, &line_vao);
    glDeleteBuffers(1, &line_vbo);
    glDeleteTextures(1, &shadow_tex);
    glDeleteFramebuffers(1, &shadow_fbo);
  }

  GLuint lit_program(Material m, bool shadows) {
    GLuint& p = lit[m][shadows];
    if (!p)
      p = program(kLitVert, "#version 330 core\n#define MATERIAL " + std::to_string(m) +
                                "\n#define SHADOWS " + std::to_string(shadows ? 1 : 0) + "\n" +
                                kSky + kLitFrag);
    return p;
  }

  void upload_cloth(const ClothMesh& m) {
    vertices.clear();
    vertices.reserve(m.position.size() * 10);
    for (std::size_t i = 0; i < m.position.size(); ++i)
      push(vertices, m.position[i], i < m.normal.size() ? m.normal[i] : Vec3f::UnitZ(),
           i < m.color.size() ? m.color[i] : kClothColor, i < m.gloss.size() ? m.gloss[i] : 0);
    std::vector<unsigned> idx;
    if (m.triangles != triangles) {  // the grid changed (or first frame)
      triangles = m.triangles;
      for (const auto& t : triangles)
        idx.insert(idx.end(), {unsigned(t[0]), unsigned(t[1]), unsigned(t[2])});
      if (idx.empty()) cloth.count = 0;
    }
    cloth.upload(vertices, idx, GL_STREAM_DRAW);
  }

  void upload_obstacles(const Stage& stage) {
    if (!stage.obstacles ||
        (stage.obstacles.get() == uploaded && stage.obstacles->serial == uploaded_serial))
      return;
    std::vector<float> v;
    std::vector<unsigned> idx;
    const Stage::Obstacles& o = *stage.obstacles;
    for (std::size_t k = 0; k < o.position.size(); ++k)
      push(v, o.position[k], o.normal[k], Vec3f(0.80f, 0.78f, 0.74f));  // a pale stone
    for (const auto& t : o.triangles) idx.insert(idx.end(), t.begin(), t.end());
    obstacles.upload(v, idx, GL_STATIC_DRAW);
    uploaded = stage.obstacles.get();
    uploaded_serial = stage.obstacles->serial;
  }

  // The mesh obstacles, each part where the stage has it (u_model of `program`).
  void draw_obstacles(GLuint program, const Stage& stage) {
    if (stage.obstacle_models.empty()) {
      set(program, "u_model", Mat4f(Mat4f::Identity()));
      obstacles.draw();
      return;
    }
    for (std::size_t k = 0; k < stage.obstacles->parts.size(); ++k) {
      set(program, "u_model", stage.obstacle_models[k]);
      obstacles.draw_range(stage.obstacles->parts[k].first, stage.obstacles->parts[k].count);
    }
  }

  // The passes of a draw, in order.
  void shadow_pass(const DrawFrame& f);
  GLuint use_lit(const DrawFrame& f, Material m, bool shadows);
  void opaque_pass(const DrawFrame& f);
  void ground_pass(const DrawFrame& f);
  void sky_pass(const DrawFrame& f);
  void overlay_pass(const DrawFrame& f);
};

Renderer::Renderer() : impl_(std::make_unique<Impl>()) {}
Renderer::~Renderer() = default;

// The shadow map: the casters' depth seen from the light.
void Renderer::Impl::shadow_pass(const DrawFrame& f) {
  const Mat4f identity = Mat4f::Identity();
  glBindFramebuffer(GL_FRAMEBUFFER, shadow_fbo);
  glViewport(0, 0, kShadowSize, kShadowSize);
  glClear(GL_DEPTH_BUFFER_BIT);
  glEnable(GL_POLYGON_OFFSET_FILL);
  glPolygonOffset(1.5f, 2.0f);  // slope-scaled bias against shadow acne
  glUseProgram(depth);
  set(depth, "u_view_proj", f.light_view_proj);
  set(depth, "u_model", identity);
  cloth.draw();
  if (f.stage.ball) {
    set(depth, "u_model", f.ball_model);
    sphere.draw();
  }
  if (f.stage.obstacles) draw_obstacles(depth, f.stage);
  glDisable(GL_POLYGON_OFFSET_FILL);
}

// A lit program in use, with the eye and the light set, and the shadow map's
// lookups where asked for and shadows are on.
GLuint Renderer::Impl::use_lit(const DrawFrame& f, Material m, bool shadows) {
  const bool shadowed = shadows && f.opt.shadows;
  const GLuint p = lit_program(m, shadowed);
  glUseProgram(p);
  set(p, "u_view_proj", f.view_proj);
  set(p, "u_eye", f.cam.eye());
  set(p, "u_light", f.stage.light);
  if (shadowed) {
    const float texel = 2 * f.radius / kShadowSize;
    set(p, "u_light_view_proj", f.light_view_proj);
    set(p, "u_shadow_map", 0);
    const float blur = 0.004f, depth_range = 2 * f.radius + kShadowReach;  // ~4 mm penumbra
    set(p, "u_softness", blur / (2 * f.radius));
    set(p, "u_normal_offset", 1.5f * texel);
    set(p, "u_depth_bias", 0.0005f / depth_range);
    set(p, "u_slope_bias", blur / depth_range);
  }
  return p;
}

// Opaque things nearest first, so that the expensive ground and sky are shaded
// only where they show (early depth test): the cloth, the ball, the obstacles.
void Renderer::Impl::opaque_pass(const DrawFrame& f) {
  const Mat4f identity = Mat4f::Identity();
  GLuint p = use_lit(f, f.opt.fabric ? kFabric : kPlain, true);
  set(p, "u_model", identity);
  if (f.opt.wireframe) {  // the lines drawn later must win the depth test
    glEnable(GL_POLYGON_OFFSET_FILL);
    glPolygonOffset(1.0f, 1.0f);
  }
  cloth.draw();
  glDisable(GL_POLYGON_OFFSET_FILL);

  if (f.stage.ball) {
    p = use_lit(f, kPlain, true);
    set(p, "u_model", f.ball_model);
    (f.stage.ball_moves ? banded : sphere).draw();
  }
  if (f.stage.obstacles) {
    // Pushed back a little, as the ball is drawn a hair small: the cloth
    // resting on the mesh would show specks of it through.
    glEnable(GL_POLYGON_OFFSET_FILL);
    glPolygonOffset(2.0f, 8.0f);
    p = use_lit(f, kPlain, true);
    draw_obstacles(p, f.stage);
    glDisable(GL_POLYGON_OFFSET_FILL);
  }
}

// The ground in two pieces: a patch where shadows can fall (the casters' box
// stretched away from the light), then the rest, lost in the fog at its edges,
// without shadow lookups. Both pushed back a little: the cloth lies within a
// millimetre of the table.
void Renderer::Impl::ground_pass(const DrawFrame& f) {
  const Stage& stage = f.stage;
  const Eigen::Vector2f shift =
      -stage.light.head<2>() / stage.light.z() * std::max(0.0f, f.hi.z() - stage.ground_z);
  const Eigen::Vector2f a =
      f.lo.head<2>().cwiseMin(f.lo.head<2>() + shift) - Eigen::Vector2f::Constant(0.02f);
  const Eigen::Vector2f b =
      f.hi.head<2>().cwiseMax(f.hi.head<2>() + shift) + Eigen::Vector2f::Constant(0.02f);
  const float extent = 30;
  glEnable(GL_POLYGON_OFFSET_FILL);
  for (bool patch : {true, false}) {
    if (patch && !f.opt.shadows) continue;
    const GLuint p = use_lit(f, kGround, patch);
    glUniform4f(loc(p, "u_table"), stage.table_center.x(), stage.table_center.y(), stage.table_half,
                stage.table ? 1.0f : 0.0f);
    glUniform2f(loc(p, "u_fog"), f.cam.distance * 2.0f,
                std::min(f.cam.distance * 8.0f, extent * 0.8f));
    const Vec3f mid = patch ? Vec3f((a.x() + b.x()) / 2, (a.y() + b.y()) / 2, stage.ground_z)
                            : Vec3f(stage.table_center.x(), stage.table_center.y(), stage.ground_z);
    const Vec3f half =
        patch ? Vec3f((b.x() - a.x()) / 2, (b.y() - a.y()) / 2, 1) : Vec3f(extent, extent, 1);
    set(p, "u_model", translate_scale(mid, half));
    glPolygonOffset(patch ? 1.0f : 2.0f, patch ? 4.0f : 16.0f);  // the patch wins over the rest
    quad.draw();
  }
  glDisable(GL_POLYGON_OFFSET_FILL);
}

// The sky where nothing else was drawn: on the far plane, no depth written.
void Renderer::Impl::sky_pass(const DrawFrame& f) {
  glDepthFunc(GL_LEQUAL);
  glDepthMask(GL_FALSE);
  glUseProgram(sky);
  set(sky, "u_inv_view_proj", Mat4f(f.view_proj.inverse()));
  glBindVertexArray(empty_vao);
  glDrawArrays(GL_TRIANGLES, 0, 3);
  glDepthMask(GL_TRUE);
  glDepthFunc(GL_LESS);
}

// Flat colour over the picture: the wireframe, and the grab's pull.
void Renderer::Impl::overlay_pass(const DrawFrame& f) {
  const Mat4f identity = Mat4f::Identity();
  glUseProgram(flat);
  set(flat, "u_view_proj", f.view_proj);
  if (f.opt.wireframe) {
    set(flat, "u_model", identity);
    glUniform4f(loc(flat, "u_color"), 0.05f, 0.07f, 0.12f, 1.0f);
    glPolygonMode(GL_FRONT_AND_BACK, GL_LINE);
    cloth.draw();
    glPolygonMode(GL_FRONT_AND_BACK, GL_FILL);
  }
  const int grab = f.opt.grab_particle;
  if (grab >= 0 && grab < static_cast<int>(f.cloth.position.size())) {
    const Vec3f pa = f.cloth.position[grab], pb = f.opt.grab_target;
    const float line[6] = {pa.x(), pa.y(), pa.z(), pb.x(), pb.y(), pb.z()};
    glBindBuffer(GL_ARRAY_BUFFER, line_vbo);
    glBufferSubData(GL_ARRAY_BUFFER, 0, sizeof line, line);
    glUniform4f(loc(flat, "u_color"), 1.0f, 0.85f, 0.1f, 1.0f);
    set(flat, "u_model", identity);
    glDisable(GL_DEPTH_TEST);  // the pull stays visible through the cloth
    glBindVertexArray(line_vao);
    glDrawArrays(GL_LINES, 0, 2);
    set(flat, "u_model", translate_scale(pb, Vec3f::Constant(f.cam.distance * 0.006f)));
    sphere.draw();
    glEnable(GL_DEPTH_TEST);
  }
}

void Renderer::draw(const ClothMesh& cloth, const Stage& stage, const Camera& cam, int width,
                    int height, const DrawOptions& opt) {
  Impl& r = *impl_;
  r.upload_cloth(cloth);
  r.upload_obstacles(stage);
  const DrawFrame f = draw_frame(cloth, stage, cam, width, height, opt);

  GLint target_fbo = 0;
  glGetIntegerv(GL_DRAW_FRAMEBUFFER_BINDING, &target_fbo);
  glDisable(GL_BLEND);
  glDisable(GL_SCISSOR_TEST);
  glDisable(GL_CULL_FACE);  // the cloth has two sides; the rest is seen from outside only
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDepthMask(GL_TRUE);
  glPolygonMode(GL_FRONT_AND_BACK, GL_FILL);
  if (opt.shadows) r.shadow_pass(f);

  glBindFramebuffer(GL_FRAMEBUFFER, target_fbo);
  glViewport(0, 0, width, height);
  glClear(GL_DEPTH_BUFFER_BIT);
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_2D, r.shadow_tex);
  r.opaque_pass(f);
  r.ground_pass(f);
  r.sky_pass(f);
  r.overlay_pass(f);
  glBindVertexArray(0);
  glUseProgram(0);
}
// --- offscreen target ----------------------------------------------------------------

Framebuffer::Framebuffer(int width, int height, int samples) : w_(width), h_(height) {
  GLint max_samples = 0;
  glGetIntegerv(GL_MAX_SAMPLES, &max_samples);
  samples_ = samples = std::clamp(samples, 0, static_cast<int>(max_samples));
  glGenFramebuffers(1, &msaa_fbo_);
  glGenRenderbuffers(1, &color_rb_);
  glGenRenderbuffers(1, &depth_rb_);
  glBindRenderbuffer(GL_RENDERBUFFER, color_rb_);
  glRenderbufferStorageMultisample(GL_RENDERBUFFER, samples, GL_RGBA8, w_, h_);
  glBindRenderbuffer(GL_RENDERBUFFER, depth_rb_);
  glRenderbufferStorageMultisample(GL_RENDERBUFFER, samples, GL_DEPTH_COMPONENT24, w_, h_);
  glBindFramebuffer(GL_FRAMEBUFFER, msaa_fbo_);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, color_rb_);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, depth_rb_);
  const bool ok = glCheckFramebufferStatus(GL_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE;

  glGenFramebuffers(1, &resolve_fbo_);
  glGenRenderbuffers(1, &resolve_rb_);
  glBindRenderbuffer(GL_RENDERBUFFER, resolve_rb_);
  glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, w_, h_);
  glBindFramebuffer(GL_FRAMEBUFFER, resolve_fbo_);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, resolve_rb_);
  const bool ok2 = glCheckFramebufferStatus(GL_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE;
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  if (!ok || !ok2)
    throw std::runtime_error("cannot make a " + std::to_string(w_) + "x" + std::to_string(h_) +
                             " offscreen framebuffer");
}

Framebuffer::~Framebuffer() {
  glDeleteFramebuffers(1, &msaa_fbo_);
  glDeleteFramebuffers(1, &resolve_fbo_);
  for (GLuint rb : {color_rb_, depth_rb_, resolve_rb_}) glDeleteRenderbuffers(1, &rb);
}

void Framebuffer::bind() { glBindFramebuffer(GL_FRAMEBUFFER, msaa_fbo_); }

Image Framebuffer::read() {
  glBindFramebuffer(GL_READ_FRAMEBUFFER, msaa_fbo_);
  glBindFramebuffer(GL_DRAW_FRAMEBUFFER, resolve_fbo_);
  glBlitFramebuffer(0, 0, w_, h_, 0, 0, w_, h_, GL_COLOR_BUFFER_BIT, GL_NEAREST);
  glBindFramebuffer(GL_READ_FRAMEBUFFER, resolve_fbo_);
  Image img = read_pixels(w_, h_);
  glBindFramebuffer(GL_FRAMEBUFFER, msaa_fbo_);
  return img;
}

void Framebuffer::blit_to(unsigned fbo) {
  glBindFramebuffer(GL_READ_FRAMEBUFFER, msaa_fbo_);
  glBindFramebuffer(GL_DRAW_FRAMEBUFFER, fbo);
  glBlitFramebuffer(0, 0, w_, h_, 0, 0, w_, h_, GL_COLOR_BUFFER_BIT, GL_NEAREST);
  glBindFramebuffer(GL_FRAMEBUFFER, fbo);
}

Image read_pixels(int width, int height) {
  Image img(width, height);
  std::vector<std::uint8_t> raw(img.rgb.size());
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, width, height, GL_RGB, GL_UNSIGNED_BYTE, raw.data());
  // GL's rows go bottom up; images top down.
  const std::size_t row = static_cast<std::size_t>(width) * 3;
  for (int y = 0; y < height; ++y)
    std::copy_n(&raw[(height - 1 - y) * row], row, &img.rgb[y * row]);
  return img;
}

}  // namespace wetcloth::viewer
