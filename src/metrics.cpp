// The measurements of docs/model.md section 10: one row of metrics.csv.
#include <algorithm>
#include <cmath>
#include <numbers>

#include "detail.hpp"

namespace wetcloth {

using namespace detail;

namespace {

// Largest extent over 8 directions in the table plane: the diagonal of a square
// footprint, the diameter of a round one.
double footprint_diameter(const Model& m, const State& s) {
  double best = 0;
  for (int d = 0; d < 8; ++d) {
    const double a = d * std::numbers::pi / 8;
    const double cx = std::cos(a), cy = std::sin(a);
    double lo = kInf, hi = -kInf;
    for (int i = 0; i < m.n; ++i) {
      if (!s.contact[i]) continue;
      const double t = s.x[i].x() * cx + s.x[i].y() * cy;
      lo = std::min(lo, t);
      hi = std::max(hi, t);
    }
    if (hi > lo) best = std::max(best, hi - lo);
  }
  return best;
}

// Wrinkles: mean |dihedral angle| over edges between two lifted triangles.
// Each pair's normals computed where used, not stored: a frame's metrics
// would otherwise hold 48 bytes a particle, at 401 x 401 a run's peak.
double wrinkle_angle(const Model& m, const State& s) {
  auto normal = [&](int t) {
    const auto& tr = m.triangles[t];
    return Vec3((s.x[tr[1]] - s.x[tr[0]]).cross(s.x[tr[2]] - s.x[tr[0]]).normalized());
  };
  auto lifted = [&](int t) {
    const auto& tr = m.triangles[t];
    return !s.contact[tr[0]] && !s.contact[tr[1]] && !s.contact[tr[2]];
  };
  double sum = 0;
  long count = 0;
  for (const auto& [a, b] : m.topology->triangle_pairs) {
    if (!lifted(a) || !lifted(b)) continue;
    sum += std::acos(std::clamp(normal(a).dot(normal(b)), -1.0, 1.0));
    ++count;
  }
  return count ? sum / count : 0.0;
}

// The pull across the contact region's edge: the springs (and the bending)
// from lifted particles to particles in contact, their elastic force on the latter along
// the surface normal (the springs between two contact particles cancel). A
// peel rig's force is the lifted part's weight and suction plus this.
double front_pull(const Model& m, const State& s, const Vec3Array& surface_normal) {
  double pull = 0;
  if (m.contact_surface != SurfaceKind::None && !m.grid) {
    for (const SpringSet* set : {&m.structural, &m.shear, &m.bending})
      for (std::size_t e = 0; e < set->size(); ++e)
        for (const auto& [k, o] :
             {std::pair{set->a[e], set->b[e]}, std::pair{set->b[e], set->a[e]}}) {
          if (!s.contact[k] || s.contact[o]) continue;
          const Vec3 d = s.x[o] - s.x[k];
          const double len = d.norm();
          if (len > 0) pull += set->k[e] * (len - set->rest[e]) / len * d.dot(surface_normal[k]);
        }
  } else if (m.contact_surface != SurfaceKind::None)
    for (int k = 0; k < m.n; ++k) {
      if (!s.contact[k]) continue;
      const int i = k % m.nu, j = k / m.nu;
      for (const StencilEdge& e : m.topology->stencil)
        for (const int sign : {1, -1}) {
          const int o = grid_neighbour(m, i, j, sign * e.di, sign * e.dj);
          if (o < 0 || s.contact[o]) continue;
          const Vec3 d = s.x[o] - s.x[k];
          const double len = d.norm();
          if (len > 0) pull += e.k * (len - e.rest) / len * d.dot(surface_normal[k]);
        }
    }
  // The quadratic bending: -Q_kj (x_j - x_k) on contact particle k from each lifted j.
  const BendingMatrix& b = m.topology->bending;
  if (m.contact_surface != SurfaceKind::None && !b.start.empty())
    for (int k = 0; k < m.n; ++k) {
      if (!s.contact[k]) continue;
      b.for_each_in_row(k, [&](int o, double q) {
        if (!s.contact[o]) pull -= q * (s.x[o] - s.x[k]).dot(surface_normal[k]);
      });
    }
  return pull;
}

}  // namespace

Metrics Simulation::metrics() const {
  const Model& m = model_;
  const State& s = state_;
  const Params& p = m.params;
  Metrics r;
  r.time_s = s.time;
  const double base = p.table.enabled ? p.table.height : 0.0;
  if (m.measured_handle >= 0) {
    const Handle& h = m.handles[m.measured_handle];
    double z = 0;
    for (int k : h.particles) z += s.x[k].z();
    r.handle_height_m = z / h.particles.size() - base;
    const Vec3 dir = h.type == HandleType::Move  ? h.velocity
                     : h.type == HandleType::Pin ? Vec3::UnitZ()
                                                 : h.force;
    r.handle_force_n = dir.norm() > 0 ? ws_->handle_force.dot(dir.normalized()) : 0.0;
  }
  double zmax = -kInf, cx = 0, cy = 0, mass = 0;
  for (int i = 0; i < m.n; ++i) {
    zmax = std::max(zmax, s.x[i].z());
    (s.contact[i] ? r.contact_area_m2 : r.lifted_area_m2) += m.area[i];
    r.kinetic_energy_j += 0.5 * m.mass[i] * s.v[i].squaredNorm();
    cx += m.mass[i] * s.x[i].x();
    cy += m.mass[i] * s.x[i].y();
    mass += m.mass[i];
  }
  r.max_height_m = zmax - base;
  r.centroid_x_m = cx / mass;
  r.centroid_y_m = cy / mass;
  if (m.contact_surface == SurfaceKind::None) {
    r.contact_area_m2 = 0;
    r.lifted_area_m2 = 0;
  } else {
    // The tent's base as the paper treats the contact region (eq. 11): a square,
    // here of the lifted area, whose diagonal is √(2 A).
    r.base_diagonal_m = std::sqrt(2 * r.lifted_area_m2);
    r.outer_diagonal_m = footprint_diameter(m, s);
  }
  r.inner_pressure_pa = s.inner_pressure;
  r.trapped_air_m3 = s.air_atm_volume;
  r.air_volume_m3 = s.air_volume;
  for_each_spring(m, SpringKind::Structural, [&](int a, int b, double rest, double, double) {
    const double len = (s.x[b] - s.x[a]).norm();
    r.max_strain = std::max(r.max_strain, len / rest - 1.0);
  });
  r.wrinkle_rad = m.contact_surface == SurfaceKind::None ? 0.0 : wrinkle_angle(m, s);
  r.front_pull_n = front_pull(m, s, ws_->surface_normal);
  // The humidity field (docs/model.md "Humidity field").
  const double capacity = p.cloth.areal_density * p.cloth.water_ratio;  // kg/m² at ω = 1
  double weighted = 0, area = 0;
  r.humidity_min = kInf;
  r.humidity_max = -kInf;
  for (int i = 0; i < m.n; ++i) {
    const double w = s.humidity.empty() ? p.cloth.humidity : s.humidity[i];
    weighted += w * m.area[i];
    area += m.area[i];
    r.humidity_min = std::min(r.humidity_min, w);
    r.humidity_max = std::max(r.humidity_max, w);
  }
  // A uniform field's mean is its ω (the weighted sum would round it).
  r.humidity_mean = r.humidity_min == r.humidity_max ? r.humidity_min
                    : area > 0                       ? weighted / area
                                                     : 0.0;
  r.water_kg = capacity * weighted;
  for (const double f : s.film) r.film_water_kg += f;
  r.evaporated_kg = s.water_evaporated;
  return r;
}

std::vector<std::string> metrics_columns() {
  return {"time_s",          "handle_height_m",  "handle_force_n",
          "max_height_m",    "contact_area_m2",  "lifted_area_m2",
          "base_diagonal_m", "outer_diagonal_m", "inner_pressure_pa",
          "trapped_air_m3",  "air_volume_m3",    "kinetic_energy_j",
          "max_strain",      "wrinkle_rad",      "centroid_x_m",
          "centroid_y_m",    "front_pull_n",     "humidity_mean",
          "humidity_min",    "humidity_max",     "water_kg",
          "film_water_kg",   "evaporated_kg"};
}

std::vector<double> metrics_values(const Metrics& r) {
  return {r.time_s,          r.handle_height_m,  r.handle_force_n,
          r.max_height_m,    r.contact_area_m2,  r.lifted_area_m2,
          r.base_diagonal_m, r.outer_diagonal_m, r.inner_pressure_pa,
          r.trapped_air_m3,  r.air_volume_m3,    r.kinetic_energy_j,
          r.max_strain,      r.wrinkle_rad,      r.centroid_x_m,
          r.centroid_y_m,    r.front_pull_n,     r.humidity_mean,
          r.humidity_min,    r.humidity_max,     r.water_kg,
          r.film_water_kg,   r.evaporated_kg};
}

}  // namespace wetcloth
