// The cloth grid of docs/model.md section 1: particles, areas, masses, springs.
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <unordered_map>

#include "detail.hpp"
#include "geometry/mesh_io.hpp"

namespace wetcloth {

namespace {
double deg(double d) { return d * std::numbers::pi / 180.0; }
}  // namespace

double particle_areal_mass(const Params& p) {
  return p.cloth.areal_density * (1.0 + p.cloth.water_ratio * p.cloth.humidity);
}

// eq. 5: permeability falls linearly with humidity, never below zero.
double permeability(const Params& p, double omega) {
  return std::max(0.0, p.air.d_delta - p.air.k_delta * omega);
}
double permeability(const Params& p) { return permeability(p, p.cloth.humidity); }

AdhesionConstants adhesion_constants(const Params& p) {
  const auto& a = p.adhesion;
  AdhesionConstants c;
  c.enabled = a.enabled;
  c.gamma = a.surface_tension;
  c.cos_sum = std::cos(deg(a.theta_a_deg)) + std::cos(deg(a.theta_b_deg));
  c.sin_a = std::sin(deg(a.theta_a_deg));
  c.h = a.film_height;
  return c;
}

// eq. 13, the part proportional to the contact area: ω γ (cos θa + cos θb) / h.
double adhesion_pressure(const Params& p) {
  return adhesion_constants(p).pressure_per_omega(p.cloth.humidity);
}

// eq. 13, the border part per unit of 2√S_now: ω γ sin θa.
double adhesion_edge_tension(const Params& p) {
  return adhesion_constants(p).tension_per_omega(p.cloth.humidity);
}

double adhesion_total(const Params& p, double s_now) {
  return adhesion_pressure(p) * s_now + 2.0 * std::sqrt(s_now) * adhesion_edge_tension(p);
}

ResolvedSprings resolve_springs(const Params& p) {
  ResolvedSprings r;
  const auto [nu, nv] = p.cloth.resolution;
  r.du = p.cloth.size[0] / static_cast<double>(nu - 1);
  r.dv = p.cloth.size[1] / static_cast<double>(nv - 1);
  const double du = r.du, dv = r.dv;
  // Each ratio is exactly 1 on a square grid, so that a 0.3 m cloth of 51 x 51
  // gets exactly 200/20/20 N/m.
  const double shear_ratio = 2 * du * dv / (du * du + dv * dv);
  const auto& m = p.material;
  const auto& s = p.springs;
  const auto spring = [](const std::optional<double>& k, const std::optional<double>& d,
                         double k_material, double d_material) {
    return SpringConstants{k.value_or(k_material), d.value_or(d_material)};
  };
  r.structural_u = spring(s.structural_k, s.structural_damping, m.stretch_stiffness * (dv / du),
                          m.stretch_damping * (dv / du));
  r.structural_v = spring(s.structural_k, s.structural_damping, m.stretch_stiffness * (du / dv),
                          m.stretch_damping * (du / dv));
  r.shear = spring(s.shear_k, s.shear_damping, m.shear_stiffness * shear_ratio,
                   m.shear_damping * shear_ratio);
  r.bending_u = spring(s.bending_k, s.bending_damping, m.bending_rigidity / (du * du) * (dv / du),
                       m.bending_damping / (du * du) * (dv / du));
  r.bending_v = spring(s.bending_k, s.bending_damping, m.bending_rigidity / (dv * dv) * (du / dv),
                       m.bending_damping / (dv * dv) * (du / dv));
  r.bending_diagonal = spring(s.bending_k, s.bending_damping,
                              m.bending_rigidity / (du * dv) * (shear_ratio * shear_ratio),
                              m.bending_damping / (du * dv) * (shear_ratio * shear_ratio));
  // The quadratic bending is no spring (forces/bending.cpp).
  if (m.bending == BendingModel::Quadratic) r.bending_u = r.bending_v = r.bending_diagonal = {};
  return r;
}

std::string detail::step_limit_springs_text(const Params& p) {
  const ResolvedSprings r = resolve_springs(p);
  char b[200];
  if (p.material.bending == BendingModel::Quadratic)
    std::snprintf(b, sizeof b, "structural %g N/m, shear %g N/m, bending B %g N·m",
                  std::max(r.structural_u.k, r.structural_v.k), r.shear.k,
                  p.material.bending_rigidity);
  else
    std::snprintf(b, sizeof b, "structural %g N/m, shear %g N/m, bending %g N/m",
                  std::max(r.structural_u.k, r.structural_v.k), r.shear.k,
                  std::max({r.bending_u.k, r.bending_v.k, r.bending_diagonal.k}));
  return b;
}

namespace {

// The stiffness of the explicit limit's chain of springs, N/m.
double chain_stiffness(const Params& p) {
  const ResolvedSprings r = resolve_springs(p);
  const double ks = std::max(r.structural_u.k, r.structural_v.k);
  const double kb = std::max({r.bending_u.k, r.bending_v.k, r.bending_diagonal.k});
  // A chain's highest mode: 4 k_s / m at wave number π while k_s >= 4 k_b;
  // beyond, where the bending springs' pair of steps rings (cos θ = -k_s / 4 k_b).
  return ks >= 4 * kb ? ks : (2 * ks + 4 * kb + ks * ks / (4 * kb)) / 4;
}

// The springs' highest frequency squared, 8 k / m, for the lightest particle
// (a corner's) and the stiffest chain (chain_stiffness). The shear springs add
// to the stiffest mode as the structural ones do (a particle's four diagonal
// neighbours pull along its motion with k_shear / 2 each): without them a
// stiff shear spring blew up "within the limit".
double spring_omega2(const Params& p) {
  const ResolvedSprings r = resolve_springs(p);
  const double k = chain_stiffness(p) + r.shear.k;
  const double m_min = particle_areal_mass(p) * r.du * r.dv / 4;  // a corner's
  return 8.0 * k / m_min;
}

double step_limit(double omega2) { return omega2 > 0 ? 2.0 / std::sqrt(omega2) : 1.0; }

}  // namespace

// The small steps' 1e-4 s is the default fabric's at 51 x 51 (the accurate
// tier, measured: docs/performance.md, twelfth stop). Every other grid cloth
// gets the same fraction of its own explicit limit, taken dry (the lightest
// the cloth gets): a finer grid or a lighter fabric a shorter step. The
// limit's formula is conservative (the dry drape at 51 x 51 runs to 1.4e-4 s
// and blows up at 1.5e-4 s, 2.9 times it), and the ratio keeps that margin.
double default_step(const Params& p) {
  if (takes_large_steps(p.integrator.type)) return 1.0 / 240;
  const double step = Params::Integrator{}.dt;
  if (!p.cloth.mesh.empty()) return step;
  Params dry = p;
  dry.cloth.humidity = 0;
  return step * std::min(1.0, explicit_step_limit(dry) / explicit_step_limit(Params{}));
}

// The tiers' settings, chosen by measurement (docs/performance.md, "Work
// against precision", tools/work_precision.py): accurate, symplectic Euler at
// 1e-4 s on the default cloth (default_step; median error 0.7 %, worst 3.0 %,
// a rig read by its mean force); live, xpbd at 1/240 s in its default
// substeps (about 4 times cheaper, median 26 %).
void apply_tier(Params& p, IntegratorTier tier) {
  Params::Integrator& i = p.integrator;
  const Params::Integrator accurate;
  i.tier = tier;
  i.type = accurate.type;
  i.dt = accurate.dt;
  i.substeps = accurate.substeps;
  i.max_step_strain = accurate.max_step_strain;
  if (tier == IntegratorTier::Live) {
    i.type = IntegratorType::Xpbd;
    i.dt = default_step(p);
  }
}

double explicit_step_limit(const Params& p) {
  double omega2 = spring_omega2(p);
  if (p.material.bending == BendingModel::Quadratic) {
    // The quadratic bending's highest mode: B (4/du² + 4/dv²)² / ρ inside the
    // cloth (the 13-point biharmonic's Gershgorin bound, 64 B / l⁴ρ on a square
    // grid), twice that for the rows next to the border, which carry its area.
    const ResolvedSprings r = resolve_springs(p);
    const double lap = 4 / (r.du * r.du) + 4 / (r.dv * r.dv);
    omega2 += 2 * p.material.bending_rigidity * lap * lap / particle_areal_mass(p);
  }
  return step_limit(omega2);
}

double explicit_step_limit(const Model& m) {
  double omega2 = 0;
  if (m.grid) {
    omega2 = spring_omega2(m.params);
  } else {  // the grid's rule, with the mesh's stiffest springs and lightest particle
    const auto stiffest = [](const SpringSet& s) {
      return s.k.empty() ? 0.0 : *std::max_element(s.k.begin(), s.k.end());
    };
    const double ks = stiffest(m.structural), kb = stiffest(m.bending);
    const double chain = ks >= 4 * kb ? ks : (2 * ks + 4 * kb + ks * ks / (4 * kb)) / 4;
    const double k = chain + stiffest(m.shear);
    const double m_min = m.mass.empty() ? 0.0 : *std::min_element(m.mass.begin(), m.mass.end());
    if (m_min > 0) omega2 = 8.0 * k / m_min;
  }
  // The quadratic bending: Gershgorin's bound on each row of M⁻¹ Q.
  const BendingMatrix& b = m.topology->bending;
  double bending = 0;
  for (std::size_t i = 0; i < b.bound.size(); ++i)
    if (m.mass[i] > 0) bending = std::max(bending, b.bound[i] / m.mass[i]);
  return step_limit(omega2 + bending);
}

namespace {

// The grid's spring of stencil offset st from (i0, j0), if both ends are on
// the grid and it has a constant: f(a, b, rest, k, damping).
template <class F>
void grid_spring(const Model& m, const StencilEdge& st, int i0, int j0, F&& f) {
  const int i1 = i0 + st.di, j1 = j0 + st.dj;
  auto inside = [&](int i, int j) { return i >= 0 && j >= 0 && i < m.nu && j < m.nv; };
  if (!inside(i0, j0) || !inside(i1, j1) || (st.k == 0 && st.damping == 0)) return;
  const int a = m.index(i0, j0), b = m.index(i1, j1);
  f(a, b, (m.rest_position[b] - m.rest_position[a]).norm(), st.k, st.damping);
}

// The grid: particles, areas, the springs' stencil offsets, triangles.
void build_grid(Model& m, Topology& t, const Params& p);

int nearest(double t, int n) {
  return std::clamp(static_cast<int>(std::lround(t * (n - 1))), 0, n - 1);
}

}  // namespace

Vec3 cloth_start_position(const Params& p, int i, int j) {
  const auto [nu, nv] = p.cloth.resolution;
  const double u = i * (p.cloth.size[0] / (nu - 1)) - 0.5 * p.cloth.size[0];
  const double v = j * (p.cloth.size[1] / (nv - 1)) - 0.5 * p.cloth.size[1];
  // Vertical cloths hang with v = 0 at the top.
  const Vec3 flat = p.cloth.orientation == Orientation::Vertical ? Vec3(u, 0, -v) : Vec3(u, v, 0);
  const Eigen::AngleAxisd tilt(p.cloth.tilt * std::numbers::pi / 180, Vec3::UnitX());
  return to_vec(p.cloth.center) + (p.cloth.tilt != 0 ? Vec3(tilt * flat) : flat);
}

Model build_model(const Params& p) {
  Model m;
  m.params = p;
  const auto topology = std::make_shared<Topology>();
  m.topology = topology;
  if (p.cloth.mesh.empty())
    build_grid(m, *topology, p);
  else
    build_mesh_cloth(m, *topology, p);
  if (p.material.bending == BendingModel::Quadratic)
    topology->bending = detail::build_bending_matrix(m, p.material.bending_rigidity);
  // Triangles sharing an edge (for the wrinkle measure).
  std::unordered_map<long long, int> first;
  for (int t = 0; t < static_cast<int>(m.triangles.size()); ++t)
    for (int e = 0; e < 3; ++e) {
      const int u = m.triangles[t][e], v = m.triangles[t][(e + 1) % 3];
      const long long key = static_cast<long long>(std::min(u, v)) * m.n + std::max(u, v);
      const auto [it, fresh] = first.emplace(key, t);
      if (!fresh) topology->triangle_pairs.push_back({it->second, t});
    }

  if (p.contact.surface == SurfaceChoice::Table && p.table.enabled)
    m.contact_surface = SurfaceKind::Table;
  if (p.contact.surface == SurfaceChoice::Ball && p.ball.enabled)
    m.contact_surface = SurfaceKind::Ball;
  for (const auto& [name, o] : p.obstacles) {  // [obstacle.NAME], in name order
    if (o.contact && p.contact.surface == SurfaceChoice::Obstacle) {
      m.contact_surface = SurfaceKind::Mesh;
      m.contact_obstacle = static_cast<int>(m.obstacles.size());
    }
    m.obstacles.push_back(build_mesh_obstacle(p, name));
  }

  for (const auto& [name, hp] : p.handles) {
    Handle h;
    h.name = name;
    h.type = hp.type;
    if (!hp.vertices.empty()) {
      h.particles = handle_vertex_indices(p, name, m.n);  // painted: by index
    } else if (m.grid) {
      // The grid rectangle from `at` to `at + span`, widened by the patch.
      const int r = static_cast<int>(hp.patch);
      // (std::minmax of two temporaries would return dangling references; of a
      // list it returns values)
      const auto [i0, i1] =
          std::minmax({nearest(hp.at[0], m.nu), nearest(hp.at[0] + hp.span[0], m.nu)});
      const auto [j0, j1] =
          std::minmax({nearest(hp.at[1], m.nv), nearest(hp.at[1] + hp.span[1], m.nv)});
      for (int j = std::max(0, j0 - r); j <= std::min(m.nv - 1, j1 + r); ++j)
        for (int i = std::max(0, i0 - r); i <= std::min(m.nu - 1, i1 + r); ++i)
          h.particles.push_back(m.index(i, j));
    } else {
      h.particles = mesh_handle_particles(m, hp);
    }
    h.force = to_vec(hp.force);
    double area = 0;
    for (int k : h.particles) area += m.area[k];
    for (int k : h.particles) h.share.push_back(m.area[k] / area);
    h.velocity = to_vec(hp.velocity);
    h.max_height = hp.max_height;
    h.max_travel = hp.max_travel;
    h.start = hp.start;
    for (int k : h.particles) {
      h.anchor.push_back(m.rest_position[k]);
      // A pin or move handle that starts late leaves its particles free until
      // then (apply_handle_constraints then takes them where they are).
      if (h.type != HandleType::Force && h.start == 0) m.driven[k] = 1;
    }
    if (m.measured_handle < 0 && h.type != HandleType::Pin)
      m.measured_handle = static_cast<int>(m.handles.size());
    m.handles.push_back(std::move(h));
  }
  // With pins alone the metrics follow the first: the force it holds the cloth up with.
  if (m.measured_handle < 0 && !m.handles.empty()) m.measured_handle = 0;
  detail::build_wicking(m, *topology);
  m.initial_humidity = detail::initial_humidity(m, p);
  set_masses(m, m.initial_humidity);
  return m;
}

namespace {

void build_grid(Model& m, Topology& t, const Params& p) {
  m.nu = static_cast<int>(p.cloth.resolution[0]);
  m.nv = static_cast<int>(p.cloth.resolution[1]);
  m.n = m.nu * m.nv;
  const double du = p.cloth.size[0] / (m.nu - 1), dv = p.cloth.size[1] / (m.nv - 1);

  m.spacing = std::min(du, dv);
  m.uv.resize(m.n);
  m.rest_position.resize(m.n);
  m.area.resize(m.n);
  m.on_border.assign(m.n, 0);
  m.in_wind.assign(m.n, 0);
  m.driven.assign(m.n, 0);
  for (int j = 0; j < m.nv; ++j) {
    for (int i = 0; i < m.nu; ++i) {
      const int k = m.index(i, j);
      m.rest_position[k] = cloth_start_position(p, i, j);
      const bool edge_u = i == 0 || i == m.nu - 1, edge_v = j == 0 || j == m.nv - 1;
      // Voronoi area: l² inside, half on an edge, a quarter at a corner.
      m.area[k] = du * dv * (edge_u ? 0.5 : 1.0) * (edge_v ? 0.5 : 1.0);
      m.on_border[k] = edge_u || edge_v;
      const double uu = m.nu > 1 ? double(i) / (m.nu - 1) : 0,
                   vv = m.nv > 1 ? double(j) / (m.nv - 1) : 0;
      m.uv[k] = {uu, vv};
      m.in_wind[k] = uu >= p.wind.region_min[0] && uu <= p.wind.region_max[0] &&
                     vv >= p.wind.region_min[1] && vv <= p.wind.region_max[1];
    }
  }

  // The grid's eight spring offsets and their constants (resolve_springs).
  const ResolvedSprings sp = resolve_springs(p);
  const double diag = std::hypot(du, dv);
  const auto edge = [](int di, int dj, const SpringConstants& c, double rest) {
    return StencilEdge{di, dj, c.k, c.damping, rest};
  };
  t.stencil = {{edge(1, 0, sp.structural_u, du), edge(0, 1, sp.structural_v, dv),
                edge(1, 1, sp.shear, diag), edge(-1, 1, sp.shear, diag),
                edge(2, 0, sp.bending_u, 2 * du), edge(0, 2, sp.bending_v, 2 * dv),
                edge(2, 2, sp.bending_diagonal, 2 * diag),
                edge(-2, 2, sp.bending_diagonal, 2 * diag)}};
  // At least kParticlesPerThread particles a thread: on a smaller grid a
  // thread's share costs less than the barriers that end each stage, and when
  // processes share the cores (parallel tests, sweeps) a barrier waits for a
  // descheduled thread. The thread count never changes the result.
  constexpr int kParticlesPerThread = 1024;
  const int wanted = p.integrator.threads > 0 ? static_cast<int>(p.integrator.threads)
                                              : std::max(1, omp_get_num_procs());
  m.threads = std::clamp(m.n / kParticlesPerThread, 1, wanted);
  for (int j = 0; j < m.nv; ++j) {
    for (int i = 0; i < m.nu; ++i) {
      if (i + 1 < m.nu && j + 1 < m.nv) {
        const int a = m.index(i, j), b = m.index(i + 1, j), cc = m.index(i + 1, j + 1),
                  d = m.index(i, j + 1);
        // Diagonals alternate like a chequerboard, so that on an odd grid the
        // mesh (and the normals) keep the cloth's mirror symmetries.
        // compute_normals (forces/normals.cpp) follows this pattern quad by quad.
        if ((i + j) % 2 == 0) {
          m.triangles.push_back({a, b, cc});
          m.triangles.push_back({a, cc, d});
        } else {
          m.triangles.push_back({a, b, d});
          m.triangles.push_back({b, cc, d});
        }
      }
    }
  }
}

}  // namespace

void for_each_spring(const Model& m, SpringKind kind,
                     const std::function<void(int, int, double, double, double)>& f) {
  if (!m.grid) {
    const SpringSet& set = kind == SpringKind::Structural ? m.structural
                           : kind == SpringKind::Shear    ? m.shear
                                                          : m.bending;
    for (std::size_t e = 0; e < set.size(); ++e)
      f(set.a[e], set.b[e], set.rest[e], set.k[e], set.damping[e]);
    return;
  }
  // Stencil offsets 0-7 (build_grid), each from (i0, j0) to (i0 + di, j0 + dj).
  const auto& st = m.topology->stencil;
  for (int j = 0; j < m.nv; ++j)
    for (int i = 0; i < m.nu; ++i) switch (kind) {
        case SpringKind::Structural:
          grid_spring(m, st[0], i, j, f);
          grid_spring(m, st[1], i, j, f);
          break;
        case SpringKind::Shear:
          grid_spring(m, st[2], i, j, f);
          grid_spring(m, st[3], i + 1, j, f);
          break;
        case SpringKind::Bending:
          grid_spring(m, st[4], i, j, f);
          grid_spring(m, st[5], i, j, f);
          grid_spring(m, st[6], i, j, f);
          grid_spring(m, st[7], i + 2, j, f);
          break;
      }
}

std::size_t spring_count(const Model& m, SpringKind kind) {
  std::size_t count = 0;
  for_each_spring(m, kind, [&](int, int, double, double, double) { ++count; });
  return count;
}

SpringSet spring_set(const Model& m, SpringKind kind) {
  SpringSet set;
  for_each_spring(m, kind, [&](int a, int b, double rest, double k, double damping) {
    set.a.push_back(a);
    set.b.push_back(b);
    set.rest.push_back(rest);
    set.k.push_back(k);
    set.damping.push_back(damping);
  });
  return set;
}

void set_humidity(Model& m, double omega) {
  m.params.cloth.humidity = omega;
  m.initial_humidity.assign(m.n, omega);
  set_masses(m, m.initial_humidity);
}

// m_i = ρ_A (1 + r_w ω_i) A_i: with a uniform ω the same bits as
// particle_areal_mass(p) A_i.
void set_masses(Model& m, const std::vector<double>& omega) {
  const double rho_a = m.params.cloth.areal_density, r_w = m.params.cloth.water_ratio;
  m.mass.resize(m.n);
  m.inv_mass.resize(m.n);
  for (int k = 0; k < m.n; ++k) {
    m.mass[k] = rho_a * (1.0 + r_w * omega[k]) * m.area[k];
    m.inv_mass[k] = m.driven[k] ? 0.0 : 1.0 / m.mass[k];
  }
}

}  // namespace wetcloth
