// Air trapped between cloth and contact surface (docs/model.md section 6, eqs. 2-5).
#include <algorithm>
#include <cmath>

#include "detail.hpp"

namespace wetcloth::detail {

namespace {

// Particles whose gap to the surface holds trapped air: above the table, or
// within the band around the ball or a mesh obstacle (its distance is along
// the normal from its closest point).
bool banded(const Model& m) {
  return m.contact_surface == SurfaceKind::Ball || m.contact_surface == SurfaceKind::Mesh;
}
bool holds_air(const Model& m, double d) {
  if (d <= 0) return false;
  return !banded(m) || d < m.params.air.band;
}

// The gap counted in V_sum: the air film a resting cloth keeps in its weave
// (air.film), plus the height above the surface. Around the ball a particle
// beyond the band counts as a column of the band's height rather than dropping
// out: V_sum stays continuous as particles cross the band (a jump in V_sum is a
// jump in pressure, which kicks the cloth). Without the film a cloth that
// starts flat traps no air at all, and `sealed` holds a full vacuum.
double air_gap(const Model& m, double d) {
  const double above = std::max(d, 0.0);
  return m.params.air.film + (banded(m) ? std::min(above, m.params.air.band) : above);
}

// Advances one pocket's V_atm over dt while V_sum grows linearly from v_old
// to v_sum, exactly: the lag L = V_sum - V_atm obeys dL/dt = r - L/τ (eq. 4,
// r = dV_sum/dt), so L ends at rτ + (L0 - rτ) e^(-dt/τ). (Taking V_sum at its
// new value for the whole step would let a step much longer than τ, the
// implicit one, seep away the whole lag, and with it the suction.) Then lets
// air break through the wet pores when the deficit exceeds P_b.
double exchange(const Params& p, double delta, double v_atm, double v_old, double v_sum,
                double a_sum, double dt, bool breakthrough) {
  if (v_sum <= 0) return 0.0;
  if (delta > 0 && a_sum > 0 && dt > 0) {
    const double tau = v_sum / (p.air.p_atm * delta * a_sum);
    const double r_tau = (v_sum - v_old) / dt * tau, lag = v_old - v_atm;
    v_atm = v_sum - (r_tau + (lag - r_tau) * std::exp(-dt / tau));
  }
  if (breakthrough) {
    const double v_min = v_sum * (p.air.p_atm - p.air.breakthrough_pressure) / p.air.p_atm;
    if (v_atm < v_min) v_atm = v_min;
  }
  return v_atm;
}

double pressure(const Params& p, double v_atm, double v_sum) {
  return v_sum > 0 ? p.air.p_atm * v_atm / v_sum : p.air.p_atm;  // eq. 2
}

// How the deficit at the end of a step answers the change of V_sum over it,
// dΔP/dΔV, for correct_air_implicitly, in parts that do not depend on the
// step (the next step may be a substep of another length). With V_sum growing
// linearly over the step and eq. 4 solved exactly, it is
//   P_atm (V_atm - V_sum) / V_sum² + (P_atm / V_sum) (τ/Δt)(1 - e^(-Δt/τ)):
// a gas spring P_atm V_atm / V_sum² when Δt << τ (a 1 mm film under a
// 0.2 kg/m² cloth rings at kHz), and a damper 1 / (δ A_sum Δt) when Δt >> τ
// (air seeping through as fast as the tent grows), so that large implicit steps
// keep the suction that slows a lifting cloth. Sealed air is a pure gas spring
// (1/τ = 0); at the breakthrough cap the deficit cannot grow.
PocketAir pocket_air(const Params& p, double delta, double v_atm, double v_sum, double a_sum,
                     bool leaks) {
  if (v_sum <= 0) return {};
  if (!leaks || delta <= 0 || a_sum <= 0)
    return {p.air.p_atm * (v_atm - v_sum) / (v_sum * v_sum), p.air.p_atm / v_sum, 0.0};
  if (p.air.p_atm - pressure(p, v_atm, v_sum) >= p.air.breakthrough_pressure * (1 - 1e-12))
    return {};
  return {p.air.p_atm * (v_atm - v_sum) / (v_sum * v_sum), p.air.p_atm / v_sum,
          p.air.p_atm * delta * a_sum / v_sum};
}

double stiffness(const PocketAir& a, double dt) {
  const double x = dt * a.seep_rate;  // Δt/τ
  const double seep = x > 1e-6 ? -std::expm1(-x) / x : 1 - x / 2;
  return a.gas + a.spring * seep;
}

// Eq. 5 with the humidity field: a pocket's air seeps through each of its
// lifted particles at that particle's δ(ω_i), so the pocket's permeability is
// their area-weighted mean, Σ δ(ω_i) A_i / Σ A_i (conductance over area).
// With a uniform field, δ(ω) itself (the same bits as before the field).
struct PocketPermeability {
  const Model& m;
  const State& s;
  bool field;
  double uniform;  // δ where the field is uniform
  PocketPermeability(const Model& model, const State& state, const Workspace& w)
      : m(model),
        s(state),
        field(state.humidity.size() == static_cast<std::size_t>(model.n) && !w.humidity.uniform),
        uniform(
            permeability(model.params, state.humidity.size() == static_cast<std::size_t>(model.n)
                                           ? state.humidity[0]
                                           : model.params.cloth.humidity)) {}
  double conductance(int i) const {  // δ(ω_i) A_i, m³/(s·Pa)
    return field ? permeability(m.params, s.humidity[i]) * m.area[i] : 0.0;
  }
  double of(double conductance_sum, double a_sum) const {
    return field && a_sum > 0 ? conductance_sum / a_sum : uniform;
  }
};

// `vented`: each connected lifted region is its own pocket; one that reaches the
// cloth's border is open to the room. Around the ball a region runs on
// through its particles beyond the band, which hold no air of their own: a
// cloth falling onto the ball is one region, open at its hem, until its
// contact closes a ring (flooding only within the band had sealed the
// falling cloth's middle into a cushion from the first step).
void update_vented(const Model& m, State& s, Workspace& w, double dt) {
  const Params& p = m.params;
  const PocketPermeability perm(m, s, w);
  // Not in a pocket: in contact (or not reached yet), or lifted beyond the band
  // (in a region, but holding no air).
  constexpr int kNone = -1, kBeyondBand = -2;
  std::fill(s.pocket.begin(), s.pocket.end(), kNone);
  s.pocket_air.clear();
  double total_atm = 0, total_sum = 0;
  int pockets = 0;
  const auto mark = [&](int k, int id) {
    s.pocket[k] = holds_air(m, w.distance[k]) ? id : kBeyondBand;
    w.queue.push_back(k);
  };
  for (int seed = 0; seed < m.n; ++seed) {
    if (s.pocket[seed] != kNone || s.contact[seed]) continue;
    // Breadth-first flood over structural neighbours.
    const int id = pockets++;
    w.queue.clear();
    mark(seed, id);
    bool open = false;
    double v_atm = 0, v_old = 0, v_sum = 0, a_sum = 0, conductance = 0;
    for (std::size_t q = 0; q < w.queue.size(); ++q) {
      const int k = w.queue[q];
      open = open || m.on_border[k];
      if (s.pocket[k] == id) {
        v_atm += s.air_share[k];
        v_old += s.air_gap[k];
        v_sum += m.area[k] * air_gap(m, w.distance[k]);
        a_sum += m.area[k];
        conductance += perm.conductance(k);
      }
      if (!m.grid) {  // a mesh cloth: along its edges
        for (int e = m.topology->edge_start[k]; e < m.topology->edge_start[k + 1]; ++e) {
          const int kk = m.topology->edge_neighbour[e];
          if (s.pocket[kk] == kNone && !s.contact[kk]) mark(kk, id);
        }
        continue;
      }
      const int i = k % m.nu, j = k / m.nu;
      const int nb[4][2] = {{i - 1, j}, {i + 1, j}, {i, j - 1}, {i, j + 1}};
      for (const auto& c : nb) {
        if (c[0] < 0 || c[1] < 0 || c[0] >= m.nu || c[1] >= m.nv) continue;
        const int kk = m.index(c[0], c[1]);
        if (s.pocket[kk] == kNone && !s.contact[kk]) mark(kk, id);
      }
    }
    const double delta = perm.of(conductance, a_sum);
    v_atm = open ? v_sum : exchange(p, delta, v_atm, v_old, v_sum, a_sum, dt, true);
    s.pocket_air.push_back(open ? PocketAir{} : pocket_air(p, delta, v_atm, v_sum, a_sum, true));
    // Open: P_atm exactly (P_atm V / V may round an ulp off it).
    const double pin = open ? p.air.p_atm : pressure(p, v_atm, v_sum);
    for (int k : w.queue) {
      if (s.pocket[k] != id) continue;
      s.air_share[k] = v_sum > 0 ? v_atm * m.area[k] * air_gap(m, w.distance[k]) / v_sum : 0;
      s.pocket_pressure[k] = pin;
    }
    total_atm += v_atm;
    total_sum += v_sum;
  }
  for (int k = 0; k < m.n; ++k) {
    if (s.pocket[k] >= 0) continue;
    s.pocket[k] = kNone;
    // Open to the room: its gap's air at P_atm, which it brings to the pocket
    // it joins (one peeling from contact, one entering the band), so V_atm
    // stays continuous. Bringing none, each particle a closed tent peeled
    // was a vacuum of its 1 mm gap: the straight pull's tent sat at the
    // breakthrough cap, 5 times the suction of `exchange`.
    s.air_share[k] = m.area[k] * air_gap(m, w.distance[k]);
    s.pocket_pressure[k] = p.air.p_atm;
  }
  for (int k = 0; k < m.n; ++k) s.air_gap[k] = m.area[k] * air_gap(m, w.distance[k]);
  s.air_atm_volume = total_atm;
  s.air_volume = total_sum;
  s.inner_pressure = pressure(p, total_atm, total_sum);
}

// One pocket under the whole cloth (every model but `vented`): row j's
// particles' pockets (0 where they hold air, -1 where not), and its part of
// the sums: the air's volume, the lifted area, the contact area and the
// lifted particles' conductance.
std::array<double, 4> pocket_row_sums(const Model& m, State& s, const Workspace& w,
                                      const PocketPermeability& perm, int j) {
  // In locals, not the returned array: its stores and reloads, one per add,
  // had made the loop 5 % of the step at 201 x 201.
  double volume = 0, lifted = 0, touching = 0, conducting = 0;
  int* __restrict pocket = s.pocket.data();
  const double* __restrict distance = w.distance.data(), * __restrict area = m.area.data();
  const std::uint8_t* __restrict contact = s.contact.data();
  for (int i = j * m.nu; i < (j + 1) * m.nu; ++i) {
    const bool held = holds_air(m, distance[i]);
    pocket[i] = held ? 0 : -1;
    volume += area[i] * air_gap(m, distance[i]);
    if (held && !contact[i]) {
      lifted += area[i];
      conducting += perm.conductance(i);
    }
    if (contact[i]) touching += area[i];
  }
  return {volume, lifted, touching, conducting};
}

// The one pocket's air after a step of dt, from the cloth's sums and the
// state's air before it (which this does not change).
struct PocketUpdate {
  double atm_volume, volume, inner_pressure;
  PocketAir air;
};
PocketUpdate next_pocket(const Params& p, const State& s, const PocketPermeability& perm,
                         const std::array<double, 4>& sums, double dt) {
  const AirModel model = p.air.model;
  const auto [v_sum, a_sum, s_now, conductance] = sums;
  const double delta = perm.of(conductance, a_sum);
  const double grown = v_sum - s.air_volume;
  double atm = s.air_atm_volume;
  if (model == AirModel::Off || s_now == 0) {
    // Nothing is trapped while no part of the cloth touches the surface: the
    // air under it is open to the room.
    atm = v_sum;
  } else if (model == AirModel::Exchange) {
    const bool update = !p.air.paper_update_rule || grown > p.air.paper_threshold;
    atm = exchange(p, delta, atm, s.air_volume, v_sum, update ? a_sum : 0, dt, true);
  }
  // `sealed` (Yamada et al. 2013): the amount of air never changes.
  // With no lifted cloth over the surface there is no pocket to hold air
  // above the room's pressure: a cloth that lands flat, its last lifted
  // particles reaching h_th in one step, would keep the air of the step
  // before squeezed into the film of its weave (11 atm), with no lifted
  // area left for it to seep through, and blow up the first particle a
  // pull lifts. The excess escapes; a deficit (a flat cloth just starting
  // to peel) stays.
  if (model != AirModel::Off && s_now > 0 && a_sum == 0) atm = std::min(atm, v_sum);
  const bool trapped = model != AirModel::Off && s_now > 0;
  return {
      atm, v_sum, pressure(p, atm, v_sum),
      trapped ? pocket_air(p, delta, atm, v_sum, a_sum, model == AirModel::Exchange) : PocketAir{}};
}

void apply_pocket(const PocketUpdate& u, State& s) {
  s.pocket_air.push_back(u.air);
  s.air_atm_volume = u.atm_volume;
  s.air_volume = u.volume;
  s.inner_pressure = u.inner_pressure;
}

void note_peak_deficit(const Params& p, State& s) {
  const double deficit = p.air.p_atm - s.inner_pressure;
  if (deficit > s.peak_deficit) s.peak_deficit = deficit;
}

}  // namespace

void update_air(const Model& m, State& s, Workspace& w, double dt) {
  const Params& p = m.params;
  s.pocket_air.clear();
  if (m.contact_surface == SurfaceKind::None) {  // no surface, no trapped air
    std::fill(s.pocket.begin(), s.pocket.end(), -1);
    s.air_atm_volume = s.air_volume = 0;
    s.inner_pressure = p.air.p_atm;
    return;
  }
  if (p.air.model == AirModel::Vented) {
    update_vented(m, s, w, dt);
  } else {
    const PocketPermeability perm(m, s, w);
    const auto sums =
        ordered_sums<4>(m, w, [&](int j) { return pocket_row_sums(m, s, w, perm, j); });
    apply_pocket(next_pocket(p, s, perm, sums, dt), s);
    for_each_particle(m, [&](int i) { s.pocket_pressure[i] = s.inner_pressure; });
  }
  note_peak_deficit(p, s);
}

// On a grid with one pocket, in one parallel region: each thread's rows'
// contact, then (after the ordered sums' wait) their border, which reads the
// rows either side, and their pocket pressure. Each thread works the pocket
// out alike; the state takes it after the region. Four regions had cost
// about 5 µs a step at 51 x 51 on two threads (docs/performance.md,
// eighteenth stop).
void update_contact_and_air(const Model& m, State& s, Workspace& w, double dt) {
  if (!m.grid || m.contact_surface == SurfaceKind::None || m.params.air.model == AirModel::Vented) {
    update_contact(m, s, w);
    update_air(m, s, w, dt);
    return;
  }
  prepare_contact(m, w);
  s.pocket_air.clear();
  const PocketPermeability perm(m, s, w);
  w.row_sums.resize(4 * std::size_t(m.nv));
  PocketUpdate next{};
  for_each_row_block(m, [&](int j0, int j1, int thread) {
    update_contact(m, s, w, j0 * m.nu, j1 * m.nu);
    const auto sums = ordered_sums_in_rows<4>(
        m, w, j0, j1, [&](int j) { return pocket_row_sums(m, s, w, perm, j); });
    mark_contact_border(m, s, w, j0, j1);
    const PocketUpdate u = next_pocket(m.params, s, perm, sums, dt);
    std::fill(s.pocket_pressure.begin() + j0 * m.nu, s.pocket_pressure.begin() + j1 * m.nu,
              u.inner_pressure);
    if (thread == 0) next = u;
  });
  apply_pocket(next, s);
  note_peak_deficit(m.params, s);
}

void start_air(const Model& m, State& s, Workspace& w) {
  for (int i = 0; i < m.n; ++i) s.air_share[i] = m.area[i] * air_gap(m, w.distance[i]);
  update_air(m, s, w, 0.0);
  s.air_atm_volume = s.air_volume;
  s.inner_pressure = m.params.air.p_atm;
  std::fill(s.pocket_pressure.begin(), s.pocket_pressure.end(), s.inner_pressure);
  s.peak_deficit = 0;
}

// eq. 3: F_i = -(P_atm - P_in) A_i n_i on lifted particles, so that suction
// pushes the cloth toward the surface. By default n_i is the surface normal n_s:
// then F_i = -ΔP ∂V_sum/∂x_i for V_sum = Σ A_i d_i, and the air does no net work
// around a closed path. With the cloth normal (air.force_direction = "cloth", the
// paper's literal n_i, oriented away from the trapped air) the force is not the
// gradient of the volume that sets the pressure: it pumps energy into lifted
// flaps until a pulled cloth flutters and blows up (docs/model.md).
void add_air_pressure(const Model& m, const State& s, Workspace& w, int first, int end) {
  // No air: air_direction stays zero, as reset left it.
  if (m.params.air.model == AirModel::Off || m.contact_surface == SurfaceKind::None) return;
  const double p_atm = m.params.air.p_atm;
  const bool along_cloth_normal = m.params.air.force_direction == AirForceDirection::Cloth;
  for (int i = first; i < end; ++i) {
    if (s.contact[i] || !holds_air(m, w.distance[i])) {
      put(w.air_direction[i], Vec3::Zero());
      continue;
    }
    Vec3 n = w.surface_normal[i];
    if (along_cloth_normal) {
      n = w.normal[i];
      if (n.dot(w.surface_normal[i]) < 0) n = -n;
    }
    put(w.air_direction[i], m.area[i] * n);
    sub(w.force[i], (p_atm - s.pocket_pressure[i]) * w.air_direction[i]);
  }
}

void add_air_pressure(const Model& m, const State& s, Workspace& w) {
  for_each_particle_block(m, [&](int first, int end) { add_air_pressure(m, s, w, first, end); });
}

// Backward Euler for the air term alone: the force over the step is the one of
// the deficit at its end. Linearised, ΔP_end = ΔP e^(-Δt/τ) + c ΔV_sum with
// ΔV_sum = Δt Σ_j b_j·v_j (b_j = A_j n_s) and c = stiffness(): the deficit the
// step started with seeps away by e^(-Δt/τ) over it, as in exchange(), and the
// growth of V_sum adds to it. The explicit step applied ΔP, so each particle
// gets back Δt M⁻¹ a_i ΔP (1 - e^(-Δt/τ)) (without it the suction was too
// strong by about Δt/τ: 19 % at 5e-5 s on pull-straight, whose tent rose that
// much too slowly), and the growth is a rank-one stiffness per pocket:
// (I + Δt² c M⁻¹ a bᵀ) v = v*, solved exactly by Sherman-Morrison in O(n).
// Without it the air film's kHz ringing and the follower direction of eq. 3
// make explicit steps blow up. With `move`, after the constraints: the
// velocities the strain limiter gave are in Σ b·v, and each free particle
// moves by Δt times its change (docs/model.md section 8).
bool correct_air_implicitly(const Model& m, State& s, Workspace& w, double dt, bool move,
                            const ParticleChunks& after) {
  const std::size_t pockets = s.pocket_air.size();
  // Air open to the room (or `off`) has no stiffness and nothing to seep:
  // every change below would be zero.
  const auto inert = [](const PocketAir& a) {
    return a.gas == 0 && a.spring == 0 && a.seep_rate == 0;
  };
  if (std::all_of(s.pocket_air.begin(), s.pocket_air.end(), inert)) return false;
  const double p_atm = m.params.air.p_atm;
  // Per pocket: Σ b·v (with the seeped deficit given back), Σ b·M⁻¹a, and the
  // share of the deficit that seeps away over the step.
  w.pocket_sums.assign(3 * pockets, 0.0);
  for (std::size_t k = 0; k < pockets; ++k)
    w.pocket_sums[3 * k + 2] = -std::expm1(-dt * s.pocket_air[k].seep_rate);
  // Each particle's terms of its pocket's sums, over [c0, c0 + count) into t0
  // and t1 (zero outside a pocket): Σ b·v with the seeped deficit given back,
  // Δt ΔP (1 - e^(-Δt/τ)) a velocity per unit M⁻¹a, and Σ b·M⁻¹a. Over
  // columns in a loop that vectorises (a branch a particle had been a tenth
  // of the dry pull's step); the columns are locals: read through the
  // closure, they were loaded again every particle.
  const auto terms = [&](int c0, int count, const double* sums, double* t0, double* t1,
                         auto single) {
    const double h = dt, atm = p_atm;
    const double *__restrict area = m.area.data(), *__restrict inv_mass = m.inv_mass.data(),
                             *__restrict p_in = s.pocket_pressure.data();
    const double *__restrict nx = w.surface_normal.column(0),
                             *__restrict ny = w.surface_normal.column(1),
                             *__restrict nz = w.surface_normal.column(2);
    const double *__restrict ax = w.air_direction.column(0),
                             *__restrict ay = w.air_direction.column(1),
                             *__restrict az = w.air_direction.column(2);
    const double* __restrict vx = s.v.column(0), * __restrict vy = s.v.column(1), * __restrict vz = s.v.column(2);
    const int* __restrict pocket = s.pocket.data();
#pragma omp simd
    for (int q = 0; q < count; ++q) {
      const int i = c0 + q, k = pocket[i];
      const double bx = area[i] * nx[i], by = area[i] * ny[i], bz = area[i] * nz[i];
      // Eigen's dot of three: x0 + (x1 + x2) (its unrolled sum splits in halves).
      const double b_a = inv_mass[i] * (bx * ax[i] + (by * ay[i] + bz * az[i]));
      // One pocket: its share a constant, not a gather.
      const double given = h * (atm - p_in[i]) * sums[single ? 2 : 3 * std::max(k, 0) + 2];
      const double b_v = bx * vx[i] + (by * vy[i] + bz * vz[i]);
      t0[q] = k >= 0 ? b_v + given * b_a : 0.0;
      t1[q] = k >= 0 ? b_a : 0.0;
    }
  };
  // Each particle's change over [first, end), from its pocket's sums (3 per
  // pocket: Σ b·v turned into the pocket's ΔP_end term, Σ b·M⁻¹a, the seeped
  // share), applied by a select (a particle outside a pocket, or held, keeps
  // its velocity and place).
  const auto change = [&](int first, int end, const double* sums, auto moving, auto single) {
    const double h = dt, atm = p_atm;
    const double* __restrict inv_mass = m.inv_mass.data(), * __restrict p_in =
                                                               s.pocket_pressure.data();
    const double *__restrict ax = w.air_direction.column(0),
                             *__restrict ay = w.air_direction.column(1),
                             *__restrict az = w.air_direction.column(2);
    double* __restrict vx = s.v.column(0), * __restrict vy = s.v.column(1), * __restrict vz = s.v.column(2);
    double* __restrict xx = s.x.column(0), * __restrict xy = s.x.column(1), * __restrict xz = s.x.column(2);
    const int* __restrict pocket = s.pocket.data();
    const std::uint8_t* __restrict driven = m.driven.data(), * __restrict held = s.held.data();
#pragma omp simd
    for (int i = first; i < end; ++i) {
      // (std::max returned a reference: a gather.) One pocket: its sums constants.
      const int k = single || pocket[i] < 0 ? 0 : pocket[i];
      const double dv = h * (atm - p_in[i]) * sums[3 * k + 2] - sums[3 * k];
      bool act = pocket[i] >= 0 && dv != 0;
      if constexpr (moving) act = act && !driven[i] && !held[i];
      const double f = dv * inv_mass[i];
      const double cx = f * ax[i], cy = f * ay[i], cz = f * az[i];
      vx[i] = act ? vx[i] + cx : vx[i];
      vy[i] = act ? vy[i] + cy : vy[i];
      vz[i] = act ? vz[i] + cz : vz[i];
      if constexpr (moving) {
        xx[i] = act ? xx[i] + h * cx : xx[i];
        xy[i] = act ? xy[i] + h * cy : xy[i];
        xz[i] = act ? xz[i] + h * cz : xz[i];
      }
    }
  };
  const auto change_and_after = [&](int first, int end, const double* sums, auto single) {
    if (move)
      change(first, end, sums, std::true_type{}, single);
    else
      change(first, end, sums, std::false_type{}, single);
    if (after) after(first, end);
  };
  const auto solve = [&](std::size_t k, double* pocket_sums) {
    const double c = dt * dt * stiffness(s.pocket_air[k], dt);
    pocket_sums[3 * k] = c * pocket_sums[3 * k] / (1.0 + c * pocket_sums[3 * k + 1]);
  };
  // The terms a chunk at a time, added in particle order: the bits of a
  // particle loop. A particle outside a pocket adds +0 to a sum that starts
  // at +0, and so is never -0: nothing.
  constexpr int kChunk = 64;
  double t0[kChunk], t1[kChunk];
  // One pocket: by rows on the threads, in one region. Each thread adds up
  // the rows in order (ordered_sums_in_rows) and solves the pocket alike, then
  // changes its own particles and runs `after` on them.
  if (pockets == 1) {
    const int nu = m.nu;
    w.row_sums.resize(2 * std::size_t(m.nv));
    for_each_row_block(m, [&](int j0, int j1, int) {
      const auto row_sums = ordered_sums_in_rows<2>(m, w, j0, j1, [&](int j) {
        std::array<double, 2> row{};
        double r0[kChunk], r1[kChunk];  // this thread's
        for (int c0 = j * nu; c0 < (j + 1) * nu; c0 += kChunk) {
          const int count = std::min(kChunk, (j + 1) * nu - c0);
          terms(c0, count, w.pocket_sums.data(), r0, r1, std::true_type{});
          for (int q = 0; q < count; ++q) {
            row[0] += r0[q];
            row[1] += r1[q];
          }
        }
        return row;
      });
      double sums[3] = {row_sums[0], row_sums[1], w.pocket_sums[2]};
      solve(0, sums);
      change_and_after(j0 * nu, j1 * nu, sums, std::true_type{});
    });
    return true;
  }
  // The pockets of `vented`, in particle order.
  for (int c0 = 0; c0 < m.n; c0 += kChunk) {
    const int count = std::min(kChunk, m.n - c0);
    terms(c0, count, w.pocket_sums.data(), t0, t1, std::false_type{});
    for (int q = 0; q < count; ++q)
      if (const int k = s.pocket[c0 + q]; k >= 0) {
        w.pocket_sums[3 * k] += t0[q];
        w.pocket_sums[3 * k + 1] += t1[q];
      }
  }
  for (std::size_t k = 0; k < pockets; ++k) solve(k, w.pocket_sums.data());
  for_each_particle_block(m, [&](int first, int end) {
    change_and_after(first, end, w.pocket_sums.data(), std::false_type{});
  });
  return true;
}

}  // namespace wetcloth::detail
