// The humidity field (docs/model.md "Humidity field"): ω per particle, its
// start (cloth.humidity, cloth.humidity_map, [wet.NAME]), and once a step the
// water taken up from a wet surface's film, the drying, and the wicking
// (diffusion in the fabric's plane, backward Euler by conjugate gradients).
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <string>

#include "detail.hpp"
#include "geometry/mesh_io.hpp"
#include "wetcloth/scene.hpp"

// A static copy: no clash with the stb symbols libstb.so exports for ImGui.
#define STB_IMAGE_STATIC
#define STB_IMAGE_IMPLEMENTATION
#define STBI_ONLY_PNG
#define STBI_ONLY_JPEG
#define STBI_ONLY_BMP
#define STBI_ONLY_PNM
#define STBI_ONLY_TGA
#define STBI_NO_STDIO
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wunused-function"
#pragma GCC diagnostic ignored "-Wmissing-field-initializers"
#pragma GCC diagnostic ignored "-Wsign-compare"
#include <stb/stb_image.h>
#pragma GCC diagnostic pop

namespace wetcloth::detail {

namespace {

constexpr double kWaterDensity = 1000;  // kg/m³

// A grayscale image, its values in [0, 1], row 0 at the top.
struct GrayImage {
  int width = 0, height = 0;
  std::vector<double> value;
  // Bilinear at texture coordinates (u, v): u along the rows, v up (row 0 is v = 1),
  // as a texture lies on an OBJ's (and Blender's) UV square.
  double at(double u, double v) const {
    const double x = std::clamp(u, 0.0, 1.0) * (width - 1);
    const double y = (1 - std::clamp(v, 0.0, 1.0)) * (height - 1);
    const int x0 = std::min(static_cast<int>(x), std::max(0, width - 2));
    const int y0 = std::min(static_cast<int>(y), std::max(0, height - 2));
    const int x1 = std::min(x0 + 1, width - 1), y1 = std::min(y0 + 1, height - 1);
    const double fx = x - x0, fy = y - y0;
    const auto px = [&](int i, int j) { return value[std::size_t(j) * width + i]; };
    return (1 - fy) * ((1 - fx) * px(x0, y0) + fx * px(x1, y0)) +
           fy * ((1 - fx) * px(x0, y1) + fx * px(x1, y1));
  }
};

// cloth.humidity_map read: throws SceneError ("Params: cloth.humidity_map: ...").
GrayImage load_map(const Params& p) {
  const std::string key = "cloth.humidity_map";
  if (p.scene_dir == "builtin:")
    throw SceneError("Params: " + key + ": \"" + p.cloth.humidity_map +
                     "\": a built-in scene has no image files (place wet regions with [wet.NAME])");
  const std::string bytes = scene_file_text(p, key, p.cloth.humidity_map);
  int w = 0, h = 0, channels = 0;
  stbi_uc* pixels = stbi_load_from_memory(reinterpret_cast<const stbi_uc*>(bytes.data()),
                                          static_cast<int>(bytes.size()), &w, &h, &channels, 1);
  if (!pixels)
    throw SceneError(
        "Params: " + key + ": " + resolve_scene_path(p, key, p.cloth.humidity_map).string() +
        ": not an image stb_image reads (PNG, JPEG, BMP, TGA, PGM): " + stbi_failure_reason());
  GrayImage img;
  img.width = w;
  img.height = h;
  img.value.resize(std::size_t(w) * h);
  for (std::size_t k = 0; k < img.value.size(); ++k) img.value[k] = pixels[k] / 255.0;
  stbi_image_free(pixels);
  return img;
}

// The particle nearest to (u, v), as a handle's `at` picks it.
int nearest_particle(const Model& m, const Vec2d& at) {
  if (m.grid) {
    const auto nearest = [](double t, int n) {
      return std::clamp(static_cast<int>(std::lround(t * (n - 1))), 0, n - 1);
    };
    return m.index(nearest(at[0], m.nu), nearest(at[1], m.nv));
  }
  int best = 0;
  double best_d = kInf;
  for (int k = 0; k < m.n; ++k) {
    const double du = m.uv[k][0] - at[0], dv = m.uv[k][1] - at[1];
    if (const double d = du * du + dv * dv; d < best_d) best_d = d, best = k;
  }
  return best;
}

bool all_equal(const std::vector<double>& w) {
  for (std::size_t k = 1; k < w.size(); ++k)
    if (w[k] != w[0]) return false;
  return true;
}

// Water (kg) particle k holds at ω = 1.
double capacity(const Model& m, int k) {
  return m.params.cloth.areal_density * m.params.cloth.water_ratio * m.area[k];
}

// Moves what rounding left above 1 (or below 0) in a particle to its
// neighbours along the wicking's edges that have room (or water): the cap
// neither makes nor loses water. Exact arithmetic never needs it (backward
// Euler's solution is a weighted mean of the old field, within its bounds).
void settle(const Model& m, std::vector<double>& c) {
  const Topology& t = *m.topology;
  for (int sweep = 0; sweep < 3; ++sweep) {
    bool moved = false;
    for (std::size_t e = 0; e < t.wick_a.size(); ++e) {
      const int ends[2] = {t.wick_a[e], t.wick_b[e]};
      for (int side = 0; side < 2; ++side) {
        const int a = ends[side], b = ends[1 - side];
        if (c[a] > 1 && c[b] < 1) {  // a's excess water into b's room
          const double water = std::min((c[a] - 1) * m.area[a], (1 - c[b]) * m.area[b]);
          c[a] = water == (c[a] - 1) * m.area[a] ? 1.0 : c[a] - water / m.area[a];
          c[b] += water / m.area[b];
          moved = true;
        } else if (c[a] < 0 && c[b] > 0) {  // a's deficit from b's water
          const double water = std::min(-c[a] * m.area[a], c[b] * m.area[b]);
          c[a] = water == -c[a] * m.area[a] ? 0.0 : c[a] + water / m.area[a];
          c[b] -= water / m.area[b];
          moved = true;
        }
      }
    }
    if (!moved) return;
  }
}

}  // namespace

long long wicking_steps(double dt) {
  return std::max(1LL, static_cast<long long>(std::floor(kWickingInterval / dt * (1 + 1e-9))));
}

void check_humidity_map(const Params& p, const std::string& source) {
  if (p.cloth.humidity_map.empty()) return;
  try {
    load_map(p);
  } catch (const SceneError& e) {
    const std::string what = e.what(), lead = "Params: ";
    throw SceneError(what.rfind(lead, 0) == 0 ? source + ": " + what.substr(lead.size()) : what);
  }
}

std::vector<double> initial_humidity(const Model& m, const Params& p) {
  std::vector<double> omega(m.n, p.cloth.humidity);
  if (!p.cloth.humidity_map.empty()) {
    const GrayImage img = load_map(p);
    for (int k = 0; k < m.n; ++k) omega[k] = img.at(m.uv[k][0], m.uv[k][1]);
  }
  for (const auto& [name, region] : p.wet) {  // in name order: a later one over an earlier
    const Vec3 centre = m.rest_position[nearest_particle(m, region.at)];
    const double r2 = region.radius * region.radius;
    for (int k = 0; k < m.n; ++k)
      if ((m.rest_position[k] - centre).squaredNorm() <= r2) omega[k] = region.humidity;
  }
  return omega;
}

void build_wicking(const Model& m, Topology& t) {
  t.wick_a.clear();
  t.wick_b.clear();
  t.wick_w.clear();
  if (m.grid) {
    // The 5-point Laplacian with the Voronoi areas: an edge's weight is its
    // dual edge (the cell face between the two particles) over its length;
    // along the border the cell face is half as long.
    const double du = m.params.cloth.size[0] / (m.nu - 1), dv = m.params.cloth.size[1] / (m.nv - 1);
    for (int j = 0; j < m.nv; ++j)
      for (int i = 0; i < m.nu; ++i) {
        const int k = m.index(i, j);
        if (i + 1 < m.nu) {
          const bool edge = j == 0 || j == m.nv - 1;
          t.wick_a.push_back(k);
          t.wick_b.push_back(m.index(i + 1, j));
          t.wick_w.push_back(dv / du * (edge ? 0.5 : 1.0));
        }
        if (j + 1 < m.nv) {
          const bool edge = i == 0 || i == m.nu - 1;
          t.wick_a.push_back(k);
          t.wick_b.push_back(m.index(i, j + 1));
          t.wick_w.push_back(du / dv * (edge ? 0.5 : 1.0));
        }
      }
    return;
  }
  // A mesh: the cotangent weights, (cot α + cot β) / 2 over the edge's two
  // opposite angles in the rest shape; a negative sum (an obtuse pair) is
  // taken as zero, so that water never flows uphill (the maximum principle).
  std::map<std::pair<int, int>, double> weight;
  for (const auto& tri : m.triangles)
    for (int c = 0; c < 3; ++c) {
      const int o = tri[c], a = tri[(c + 1) % 3], b = tri[(c + 2) % 3];
      const Vec3 ea = m.rest_position[a] - m.rest_position[o],
                 eb = m.rest_position[b] - m.rest_position[o];
      const double cross = ea.cross(eb).norm();
      if (cross <= 0) continue;
      weight[{std::min(a, b), std::max(a, b)}] += 0.5 * ea.dot(eb) / cross;
    }
  for (const auto& [edge, w] : weight) {
    if (!(w > 0)) continue;
    t.wick_a.push_back(edge.first);
    t.wick_b.push_back(edge.second);
    t.wick_w.push_back(w);
  }
}

void wick(const Model& m, std::vector<double>& c, HumidityScratch& h, double tau) {
  const Topology& t = *m.topology;
  const int n = m.n;
  const std::size_t edges = t.wick_a.size();
  if (tau <= 0 || edges == 0) return;
  for (auto* v : {&h.delta, &h.r, &h.z, &h.p, &h.q, &h.diagonal, &h.flux}) v->assign(n, 0.0);
  // (M + τ L) δ = -τ L c, δ = c' - c: M the areas, L c_i = Σ_j w_ij (c_i - c_j).
  for (int k = 0; k < n; ++k) h.diagonal[k] = m.area[k];
  double largest = 0;
  for (std::size_t e = 0; e < edges; ++e) {
    const int a = t.wick_a[e], b = t.wick_b[e];
    const double tw = tau * t.wick_w[e], f = tw * (c[b] - c[a]);
    h.diagonal[a] += tw;
    h.diagonal[b] += tw;
    h.r[a] += f;
    h.r[b] -= f;
  }
  for (int k = 0; k < n; ++k) largest = std::max(largest, std::abs(c[k]));
  // The new field is c' + r / A (below), so the residual is asked to be small
  // against the mass term: each ω within 1e-13 of the largest.
  const double tolerance = 1e-13 * std::max(largest, 1e-300);
  const auto converged = [&] {
    for (int k = 0; k < n; ++k)
      if (std::abs(h.r[k]) > tolerance * m.area[k]) return false;
    return true;
  };
  const auto precondition = [&] {
    double rz = 0;
    for (int k = 0; k < n; ++k) {
      h.z[k] = h.diagonal[k] > 0 ? h.r[k] / h.diagonal[k] : 0.0;
      rz += h.r[k] * h.z[k];
    }
    return rz;
  };
  h.cg_iterations = 0;
  if (!converged()) {
    double rz = precondition();
    h.p = h.z;
    const int most = std::max(100, 4 * (m.grid ? std::max(m.nu, m.nv) : n));
    for (int it = 0; it < most; ++it) {
      ++h.cg_iterations;
      for (int k = 0; k < n; ++k) h.q[k] = m.area[k] * h.p[k];
      for (std::size_t e = 0; e < edges; ++e) {
        const int a = t.wick_a[e], b = t.wick_b[e];
        const double f = tau * t.wick_w[e] * (h.p[a] - h.p[b]);
        h.q[a] += f;
        h.q[b] -= f;
      }
      double pq = 0;
      for (int k = 0; k < n; ++k) pq += h.p[k] * h.q[k];
      if (!(pq > 0)) break;
      const double alpha = rz / pq;
      for (int k = 0; k < n; ++k) {
        h.delta[k] += alpha * h.p[k];
        h.r[k] -= alpha * h.q[k];
      }
      if (converged()) break;
      const double rz_new = precondition();
      const double beta = rz_new / rz;
      rz = rz_new;
      for (int k = 0; k < n; ++k) h.p[k] = h.z[k] + beta * h.p[k];
    }
  }
  // The water moved along each edge, from the solved field: equal and
  // opposite at its two ends, so the total is kept to rounding however
  // closely the solve converged (the field is then c' + r / A).
  for (std::size_t e = 0; e < edges; ++e) {
    const int a = t.wick_a[e], b = t.wick_b[e];
    const double f = tau * t.wick_w[e] * ((c[b] + h.delta[b]) - (c[a] + h.delta[a]));
    h.flux[a] += f;
    h.flux[b] -= f;
  }
  for (int k = 0; k < n; ++k)
    if (m.area[k] > 0) c[k] += h.flux[k] / m.area[k];
  settle(m, c);
}

double film_depth(const Model& m) {
  switch (m.contact_surface) {
    case SurfaceKind::Table:
      return m.params.table.water_film;
    case SurfaceKind::Ball:
      return m.params.ball.water_film;
    case SurfaceKind::Mesh:  // the one obstacle with contact = true
      for (const auto& [name, o] : m.params.obstacles)
        if (o.contact) return o.water_film;
      return 0;
    default:
      return 0;
  }
}

void start_film(const Model& m, State& s) {
  s.film.clear();
  if (const double h = film_depth(m); h > 0) {
    s.film.resize(m.n);
    for (int k = 0; k < m.n; ++k) s.film[k] = kWaterDensity * h * m.area[k];
  }
}

void start_humidity(const Model& m, State& s, Workspace& w) {
  s.humidity = m.initial_humidity;
  s.water_evaporated = 0;
  start_film(m, s);
  w.humidity.uniform = all_equal(s.humidity);
}

void note_humidity_changed(const State& s, Workspace& w) {
  w.humidity.uniform = all_equal(s.humidity);
}

bool update_humidity(Model& m, State& s, Workspace& w, double dt) {
  const Params& p = m.params;
  const Params::Material& mat = p.material;
  std::vector<double>& omega = s.humidity;
  bool changed = false;
  // Uptake from the contact surface's film: dω/dt = k_u (1 - ω) while the
  // film under the particle lasts, solved exactly over the step.
  if (!s.film.empty() && mat.uptake_rate > 0 && p.cloth.water_ratio > 0) {
    const double gain = -std::expm1(-mat.uptake_rate * dt);
    for (int k = 0; k < m.n; ++k) {
      if (!s.contact[k] || s.film[k] <= 0 || omega[k] >= 1) continue;
      const double cap = capacity(m, k);
      if (cap <= 0) continue;
      const double take = std::min((1 - omega[k]) * gain * cap, s.film[k]);
      s.film[k] -= take;
      omega[k] = std::min(1.0, omega[k] + take / cap);
      changed = true;
    }
  }
  // Drying: dω/dt = -k_e (1 - RH) ω, slower by drying_contact_factor where the
  // cloth lies on the contact surface (one face of two open to the air).
  if (mat.drying_rate > 0 && p.air.relative_humidity < 1) {
    const double rate = mat.drying_rate * (1 - p.air.relative_humidity);
    const double lifted = std::exp(-rate * dt);
    const double lying = std::exp(-rate * mat.drying_contact_factor * dt);
    double evaporated = 0;
    for (int k = 0; k < m.n; ++k) {
      if (omega[k] == 0) continue;
      const double after = omega[k] * (s.contact[k] ? lying : lifted);
      evaporated += (omega[k] - after) * capacity(m, k);
      omega[k] = after;
      changed = true;
    }
    s.water_evaporated += evaporated;
  }
  if (changed) w.humidity.uniform = all_equal(omega);
  // Wicking, once the field varies, every wicking_steps(dt) steps over their
  // time together (its own time scale, l²/D, is seconds at a 6 mm spacing).
  const long long every = wicking_steps(dt);
  if (mat.wicking_diffusivity > 0 && !w.humidity.uniform && s.steps % every == 0) {
    wick(m, omega, w.humidity, mat.wicking_diffusivity * dt * static_cast<double>(every));
    w.humidity.uniform = all_equal(omega);
    changed = true;
  }
  if (changed) set_masses(m, omega);
  return changed;
}

}  // namespace wetcloth::detail
