#include "coloring.hpp"

#include <algorithm>
#include <cmath>

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

Legend cloth_mesh(const Simulation& sim, ColorBy mode, float& scale, ClothMesh& mesh) {
  const Model& m = sim.model();
  const State& s = sim.state();
  const Workspace& w = sim.workspace();
  const int n = m.n;

  Vec3Array normal(n);
  compute_normals(m, s.x, normal);
  mesh.position.resize(n);
  mesh.normal.resize(n);
  mesh.color.assign(n, kClothColor);
  for (int i = 0; i < n; ++i) {
    mesh.position[i] = s.x[i].cast<float>();
    mesh.normal[i] = normal[i].cast<float>();
  }
  mesh.triangles = m.triangles;

  Legend legend;
  switch (mode) {
    case ColorBy::Fabric:
      break;
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
      float peak = 0;
      const double p_atm = m.params.air.p_atm;
      for (int i = 0; i < n && i < static_cast<int>(s.pocket_pressure.size()); ++i) {
        g[i] = static_cast<float>(s.pocket_pressure[i] - p_atm);
        if (std::isfinite(g[i])) peak = std::max(peak, std::abs(g[i]));
      }
      scale = follow(scale, peak, 1.0f);
      legend = {"air pressure - P_atm, Pa", -scale, scale, true, false};
      for (int i = 0; i < n; ++i) mesh.color[i] = colormap(0.5f + 0.5f * g[i] / scale, true);
      break;
    }
    case ColorBy::Strain: {
      // Stretch of the structural springs; the scale ends at the strain limit.
      std::vector<float> strain(n, 0.0f);
      const SpringSet& sp = m.structural;
      for (std::size_t k = 0; k < sp.size(); ++k) {
        const float e = static_cast<float>((s.x[sp.a[k]] - s.x[sp.b[k]]).norm() / sp.rest[k] - 1.0);
        strain[sp.a[k]] = std::max(strain[sp.a[k]], e);
        strain[sp.b[k]] = std::max(strain[sp.b[k]], e);
      }
      const float hi =
          m.params.strain_limit.tau > 0 ? static_cast<float>(m.params.strain_limit.tau) : 0.1f;
      legend = {"stretch of structural springs", 0, hi, false, false};
      for (int i = 0; i < n; ++i) mesh.color[i] = colormap(strain[i] / hi, false);
      break;
    }
    case ColorBy::Adhesion: {
      float peak = 0;
      const int na = std::min(n, static_cast<int>(w.adhesion.size()));
      for (int i = 0; i < na; ++i)
        if (std::isfinite(w.adhesion[i])) peak = std::max(peak, static_cast<float>(w.adhesion[i]));
      scale = follow(scale, peak, 1e-9f);
      legend = {"adhesion force per particle, N", 0, scale, false, false};
      for (int i = 0; i < n; ++i)
        mesh.color[i] = colormap(i < na ? static_cast<float>(w.adhesion[i]) / scale : 0.0f, false);
      break;
    }
  }
  return legend;
}

}  // namespace wetcloth::viewer
