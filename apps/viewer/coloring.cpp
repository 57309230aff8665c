#include "coloring.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace wetcloth::viewer {

Vec3f colormap(float t, bool diverging) {
  t = std::clamp(std::isfinite(t) ? t : 0.5f, 0.0f, 1.0f);
  if (diverging) {  // blue, white at 0.5, red
    const Vec3f lo{0.23f, 0.30f, 0.75f}, mid{0.87f, 0.87f, 0.87f}, hi{0.71f, 0.02f, 0.15f};
    return t < 0.5f ? lo + (mid - lo) * (2 * t) : mid + (hi - mid) * (2 * t - 1);
  }
  // Viridis, polynomial fit (Matt Zucker's, CC0).
  const Vec3f c0{0.2777273f, 0.0054073f, 0.3340998f}, c1{0.1050930f, 1.4046135f, 1.3845902f},
      c2{-0.3308618f, 0.2148476f, 0.0950952f}, c3{-4.6342305f, -5.7991010f, -19.3324410f},
      c4{6.2282699f, 14.1799334f, 56.6905526f}, c5{4.7763850f, -13.7451454f, -65.3530326f},
      c6{-5.4354559f, 4.6458526f, 26.3124352f};
  const Vec3f c = c0 + t * (c1 + t * (c2 + t * (c3 + t * (c4 + t * (c5 + t * c6)))));
  return c.cwiseMax(0.0f).cwiseMin(1.0f);
}

namespace {

// Automatic range: follows a new maximum at once, forgets an old one slowly.
float follow(float scale, float current_max, float floor) {
  return std::max({current_max, scale * 0.97f, floor});
}

}  // namespace

Legend cloth_mesh(const Simulation& sim, ColorBy mode, float& scale, ClothMesh& mesh, float range) {
  const Model& m = sim.model();
  const State& s = sim.state();
  const std::vector<double>& adhesion = sim.adhesion();
  const int n = m.n;

  Vec3Array normal(n);
  compute_normals(m, s.x, normal);
  mesh.position.resize(n);
  mesh.normal.resize(n);
  mesh.color.assign(n, kClothColor);
  mesh.gloss.assign(n, 0.0f);
  for (int i = 0; i < n; ++i) {
    mesh.position[i] = s.x[i].cast<float>();
    mesh.normal[i] = normal[i].cast<float>();
  }
  mesh.triangles = m.triangles;

  Legend legend;
  const bool field = s.humidity.size() == static_cast<std::size_t>(n);
  const auto omega = [&](int i) {
    return static_cast<float>(field ? s.humidity[i] : m.params.cloth.humidity);
  };
  switch (mode) {
    case ColorBy::Fabric: {
      // Contact is a yes or no per particle: averaged over each particle's
      // triangles, so that the look fades over a cell at the contact line
      // instead of following the grid's staircase.
      std::vector<float> touch(n, 0.0f), count(n, 0.0f);
      if (s.contact.size() == static_cast<std::size_t>(n))
        for (const auto& t : m.triangles) {
          const float c =
              static_cast<float>(s.contact[t[0]] + s.contact[t[1]] + s.contact[t[2]]) / 3;
          for (const int v : t) touch[v] += c, count[v] += 1;
        }
      for (int i = 0; i < n; ++i) {
        const FabricLook look = fabric_look(omega(i), count[i] > 0 ? touch[i] / count[i] : 0.0f);
        mesh.color[i] = look.color;
        mesh.gloss[i] = look.gloss;
      }
      break;
    }
    case ColorBy::Humidity: {
      const float top = range > 0 ? range : 1.0f;
      legend = {"humidity ω", 0, top, false, false};
      for (int i = 0; i < n; ++i) mesh.color[i] = colormap(omega(i) / top, false);
      break;
    }
    case ColorBy::Contact: {
      legend = {"contact with the surface", 0, 1, false, true};
      for (int i = 0; i < n; ++i)
        mesh.color[i] =
            i < static_cast<int>(s.contact.size()) && s.contact[i] ? kContactColor : kFreeColor;
      break;
    }
    case ColorBy::Pressure: {
      // Gauge pressure of the air pocket under each particle: below zero holds the cloth down.
      std::vector<float> g(n, 0.0f);
      const double p_atm = m.params.air.p_atm;
      for (int i = 0; i < n && i < static_cast<int>(s.pocket_pressure.size()); ++i)
        g[i] = static_cast<float>(s.pocket_pressure[i] - p_atm);
      const float pb = static_cast<float>(m.params.air.breakthrough_pressure);
      const float top = range > 0 ? range : pb > 0 ? pb : 1000.0f;
      legend = {"air pressure - P_atm, Pa", -top, top, true, false};
      for (int i = 0; i < n; ++i) mesh.color[i] = colormap(0.5f + 0.5f * g[i] / top, true);
      break;
    }
    case ColorBy::Strain: {
      // Stretch of the structural springs; the scale ends at the strain limit.
      std::vector<float> strain(n, 0.0f);
      for_each_spring(m, SpringKind::Structural, [&](int a, int b, double rest, double, double) {
        const float e = static_cast<float>((s.x[a] - s.x[b]).norm() / rest - 1.0);
        strain[a] = std::max(strain[a], e);
        strain[b] = std::max(strain[b], e);
      });
      const float hi = range > 0 ? range
                       : m.params.strain_limit.tau > 0
                           ? static_cast<float>(m.params.strain_limit.tau)
                           : 0.1f;
      legend = {"stretch of structural springs", 0, hi, false, false};
      for (int i = 0; i < n; ++i) mesh.color[i] = colormap(strain[i] / hi, false);
      break;
    }
    case ColorBy::Adhesion: {
      const int na = std::min(n, static_cast<int>(adhesion.size()));
      // An inner particle in contact holds adhesion_pressure * its area; the
      // border's share of the edge term comes on top, so the scale goes to twice that.
      // (An inner particle's area: the grid's cell, a mesh's largest.)
      const double cell = m.grid ? m.params.cloth.size[0] / std::max(1, m.nu - 1) *
                                       m.params.cloth.size[1] / std::max(1, m.nv - 1)
                                 : *std::max_element(m.area.begin(), m.area.end());
      float top = range > 0 ? range : static_cast<float>(2 * adhesion_pressure(m.params) * cell);
      if (!(top > 0)) {
        float peak = 0;
        for (int i = 0; i < na; ++i)
          if (std::isfinite(adhesion[i])) peak = std::max(peak, static_cast<float>(adhesion[i]));
        top = scale = follow(scale, peak, 1e-9f);
      }
      legend = {"adhesion force per particle, N", 0, top, false, false};
      for (int i = 0; i < n; ++i)
        mesh.color[i] = colormap(i < na ? static_cast<float>(adhesion[i]) / top : 0.0f, false);
      break;
    }
  }
  return legend;
}

FabricLook fabric_look(float omega, float touching) {
  const float w = std::clamp(omega, 0.0f, 1.0f), t = std::clamp(touching, 0.0f, 1.0f);
  // The albedo (the colour squared: the shader's linear light).
  const float albedo = (1.0f - 0.45f * w) * (1.0f - t * (0.1f + 0.3f * w));
  return {kClothColor * std::sqrt(albedo), std::min(1.0f, (1.0f + 0.6f * t) * w)};
}

bool touches_stage(const Stage& stage, const Vec3f& p, float h) {
  if (stage.table && p.z() - stage.ground_z < h &&
      ((p.head<2>() - stage.table_center).cwiseAbs().array() <= stage.table_half).all())
    return true;
  return stage.ball && (p - stage.ball_center).norm() - stage.ball_radius < h;
}

std::string key_number(float v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.4g", v);
  return text;
}

void draw_key(Image& img, const Legend& legend) {
  const int s = std::max(1, img.height / 400);  // font pixels per unit
  const int margin = 8 * s, bar_w = std::min(180 * s, img.width / 3), bar_h = 10 * s;
  auto rgb = [](const Vec3f& c, std::uint8_t out[3]) {
    for (int k = 0; k < 3; ++k)
      out[k] = static_cast<std::uint8_t>(std::clamp(c[k], 0.0f, 1.0f) * 255 + 0.5f);
  };
  int tw = 0, th = 0;
  label_size(legend.title, s, tw, th);
  std::uint8_t c[3];
  if (legend.binary) {  // title, then a swatch and a word for each colour
    const int y = img.height - margin - th;
    int x = margin;
    const std::array<std::pair<Vec3f, const char*>, 2> swatches{
        {{kContactColor, "in contact"}, {kFreeColor, "free"}}};
    for (const auto& [color, word] : swatches) {
      rgb(color, c);
      fill_rect(img, x, y + (th - bar_h) / 2, x + bar_h, y + (th + bar_h) / 2, c, 1.0f);
      int ww = 0, wh = 0;
      label_size(word, s, ww, wh);
      draw_label(img, x + bar_h + 2 * s, y, word, s);
      x += bar_h + 2 * s + ww + 6 * s;
    }
    draw_label(img, margin, y - th - 2 * s, legend.title, s);
    return;
  }
  // Title, the bar, its numbers under it: the ends, and 0 in the middle of a diverging one.
  const int numbers_y = img.height - margin - th, bar_y = numbers_y - bar_h - s;
  const std::uint8_t dark[3] = {0, 0, 0};
  fill_rect(img, margin - s, bar_y - s, margin + bar_w + s, bar_y + bar_h + s, dark, 0.55f);
  for (int x = 0; x < bar_w; ++x) {
    rgb(colormap((x + 0.5f) / bar_w, legend.diverging), c);
    fill_rect(img, margin + x, bar_y, margin + x + 1, bar_y + bar_h, c, 1.0f);
  }
  const std::string lo = key_number(legend.lo), hi = key_number(legend.hi);
  int w = 0, h = 0;
  draw_label(img, margin, numbers_y, lo, s);
  label_size(hi, s, w, h);
  draw_label(img, margin + bar_w - w, numbers_y, hi, s);
  if (legend.diverging) {
    label_size("0", s, w, h);
    draw_label(img, margin + (bar_w - w) / 2, numbers_y, "0", s);
  }
  draw_label(img, margin, bar_y - s - th, legend.title, s);
}

}  // namespace wetcloth::viewer
