// Micro-benchmarks of the step and of each of its stages (src/detail.hpp) on the
// pull-straight cloth at 51 x 51 and 201 x 201. `make bench` runs them; items
// per second are particles per second.
#include <benchmark/benchmark.h>

#include <map>
#include <string>
#include <tuple>
#include <utility>

#include "detail.hpp"
#include "forces/spring_edges.hpp"
#include "geometry/spatial_hash.hpp"
#include "wetcloth/scene.hpp"

using namespace wetcloth;
using namespace wetcloth::detail;

namespace {

// Before anything is timed the scene runs until part of the cloth is lifted
// (the rest still held by adhesion and air), as in a real pull, or for at most
// 300 steps.
constexpr int kMaxWarmSteps = 300;
constexpr double kLiftedShare = 0.03;

// pull-straight at G x G (the same cloth: wetcloth::at_resolution) on one
// thread; `plain` leaves a plain cloth: no adhesion, no trapped air, no
// self-collision, no handle (no override removes a handle, so Params does);
// `implicit` takes implicit Euler at 1/240 s.
Params scene(long long grid, bool plain, bool implicit = false) {
  std::vector<std::string> sets{"integrator.threads=1"};
  if (plain)
    sets.insert(sets.end(),
                {"adhesion.enabled=false", "air.model=\"off\"", "self_collision.enabled=false"});
  if (implicit)
    sets.insert(sets.end(),
                {"integrator.type=\"implicit-euler\"", "integrator.dt=0.004166666666666667"});
  Params p = at_resolution(load_scene("pull-straight", sets), grid);
  if (plain) p.handles.clear();
  return p;
}

double lifted_share(const Simulation& sim) {
  const Metrics m = sim.metrics();
  return m.lifted_area_m2 / (m.lifted_area_m2 + m.contact_area_m2);
}

void grids(benchmark::internal::Benchmark* b) {
  b->Arg(51)->Arg(201)->Unit(benchmark::kMicrosecond);
}

// Warmed-up simulations, built once per process and copied by each benchmark:
// at 201 the warm-up costs more than most benchmarks.
const Simulation& warmed(long long grid, bool plain, bool implicit = false) {
  static std::map<std::tuple<long long, bool, bool>, Simulation> cache;
  auto it = cache.find({grid, plain, implicit});
  if (it == cache.end()) {
    it = cache.emplace(std::tuple{grid, plain, implicit}, Simulation(scene(grid, plain, implicit)))
             .first;
    Simulation& sim = it->second;
    for (int k = 0; k < kMaxWarmSteps && lifted_share(sim) < kLiftedShare; ++k) sim.step();
  }
  return it->second;
}

// limit_strain's input as the step hands it over (after integration, collision
// and friction): the warm state one step on, taken with strain limiting off.
const Simulation& before_strain_limit(long long grid) {
  static std::map<long long, Simulation> cache;
  auto it = cache.find(grid);
  if (it == cache.end()) {
    Simulation sim = warmed(grid, false);
    Params p = sim.model().params;
    p.strain_limit.enabled = false;
    sim.set_params(p);  // same grid: the state is kept
    sim.step();
    it = cache.emplace(grid, std::move(sim)).first;
  }
  return it->second;
}

// Particles per second, and the state that was timed (share of the cloth
// lifted, largest structural strain, a label if it blew up), so that a report
// shows what it measured.
void report(benchmark::State& st, const Simulation& sim) {
  st.SetItemsProcessed(st.iterations() * sim.model().n);
  st.counters["lifted"] = lifted_share(sim);
  st.counters["max_strain"] = sim.metrics().max_strain;
  if (!sim.blow_up_reason().empty()) st.SetLabel("blown up");
}

// One whole step, always from the warm state (restored untimed): stepping on
// would time a different state every iteration.
void BM_step(benchmark::State& st, bool plain, bool implicit) {
  const Simulation& warm = warmed(st.range(0), plain, implicit);
  Simulation sim = warm;
  for (auto _ : st) {
    st.PauseTiming();
    sim = warm;
    st.ResumeTiming();
    sim.step();
    benchmark::DoNotOptimize(sim.state().x.column(0));
    benchmark::ClobberMemory();
  }
  report(st, warm);
}
BENCHMARK_CAPTURE(BM_step, full, false, false)->Apply(grids);
BENCHMARK_CAPTURE(BM_step, plain, true, false)->Apply(grids);
// The implicit step is mostly its conjugate-gradient solve.
BENCHMARK_CAPTURE(BM_step, implicit_full, false, true)->Apply(grids);

// One stage, fn(model, state, workspace), on copies of `from`'s state and
// workspace, with the full scene's model (`from` may have a stage turned off). Forces pile up in
// w.force over the iterations; nothing reads them. With `restore`, positions and velocities go back
// to `from`'s (untimed) before each call: stages that move particles would otherwise act on their
// own output.
template <class Fn>
void stage(benchmark::State& st, const Simulation& from, bool restore, Fn fn) {
  const Model& m = warmed(st.range(0), false).model();
  State s = from.state();
  Workspace w = detail::workspace(from);
  benchmark::DoNotOptimize(&s);
  benchmark::DoNotOptimize(&w);
  for (auto _ : st) {
    if (restore) {
      st.PauseTiming();
      s.x = from.state().x;
      s.v = from.state().v;
      st.ResumeTiming();
    }
    fn(m, s, w);
    benchmark::ClobberMemory();
  }
  report(st, from);
}

const Simulation& warm(const benchmark::State& st) { return warmed(st.range(0), false); }

void BM_springs(benchmark::State& st) {
  stage(st, warm(st), false, [](const Model& m, State& s, Workspace& w) {
    // As the symplectic step does: the elastic force; the damping is its own solve.
    set_spring_forces(m, s, w, false);
  });
}
// The symplectic step's damping solve (additive operator splitting over the
// stencil's offsets), on the positions the warm step's set_spring_forces left
// in columns.
void BM_spring_damping(benchmark::State& st) {
  stage(st, warm(st), false, [](const Model& m, State& s, Workspace& w) {
    apply_spring_damping(m, s, w, m.params.integrator.dt);
  });
}
// The same on two threads (the structural offsets on one, the shear's on the
// other): its time against BM_spring_damping's is what two threads save of
// the solve. At 51 x 51, nothing (docs/performance.md, twentieth stop).
void BM_spring_damping_two_threads(benchmark::State& st) {
  Model m = warmed(st.range(0), false).model();
  m.threads = 2;
  const Simulation& from = warm(st);
  State s = from.state();
  Workspace w = detail::workspace(from);
  for (auto _ : st) {
    apply_spring_damping(m, s, w, m.params.integrator.dt);
    benchmark::ClobberMemory();
  }
  report(st, from);
}
// The springs' kernel alone (forces/spring_edges.hpp): every forward edge of
// the warm cloth, damped, in float or double, positions and velocities by
// component. It is what float would speed up most; the step stays in double
// (docs/architecture.md, "Precision").
template <class Real>
void BM_spring_edges(benchmark::State& st) {
  const Simulation& sim = warm(st);
  const Model& m = sim.model();
  const int n = m.n;
  std::vector<Real> cols(6 * std::size_t(n));
  for (int a = 0; a < n; ++a)
    for (int k = 0; k < 3; ++k) {
      cols[k * n + a] = Real(sim.state().x[a][k]);
      cols[(3 + k) * n + a] = Real(sim.state().v[a][k]);
    }
  const SpringColumns<Real> c{&cols[0],     &cols[n],     &cols[2 * n],
                              &cols[3 * n], &cols[4 * n], &cols[5 * n]};
  std::vector<Real> rows(std::size_t(8) * kSpringFields * m.nu);  // one row of each offset's edges
  Real* out[8][kSpringFields];
  for (int e = 0; e < 8; ++e)
    for (int k = 0; k < kSpringFields; ++k)
      out[e][k] = &rows[(e * kSpringFields + k) * std::size_t(m.nu)];
  for (auto _ : st) {
    for (int j = 0; j < m.nv; ++j)
      for (int e = 0; e < 8; ++e)
        if (j + m.topology->stencil[e].dj < m.nv)
          spring_edge_row<Real, true>(m, c, m.topology->stencil[e], j, out[e]);
    benchmark::ClobberMemory();
  }
  report(st, sim);
}
void BM_gravity(benchmark::State& st) {
  stage(st, warm(st), false,
        [](const Model& m, State&, Workspace& w) { add_gravity(m, w.force, 0, m.n); });
}
void BM_viscous_damping(benchmark::State& st) {
  stage(st, warm(st), false,
        [](const Model& m, State& s, Workspace& w) { add_viscous_damping(m, s, w.force, 0, m.n); });
}
// The cloth's drag against the air (wind.k; pull-straight has no wind
// velocity, which costs the same).
void BM_wind(benchmark::State& st) {
  stage(st, warm(st), false,
        [](const Model& m, State& s, Workspace& w) { add_wind(m, s, w, w.force, 0, m.n); });
}
// The pulling hand: its force on the patch, then its constraints after the
// update (a handle that has stopped holds its particles).
void BM_handles(benchmark::State& st) {
  stage(st, warm(st), true, [](const Model& m, State& s, Workspace& w) {
    add_handle_forces(m, s, w);
    apply_handle_constraints(m, s, w);
  });
}
void BM_air(benchmark::State& st) {
  stage(st, warm(st), false, [](const Model& m, State& s, Workspace& w) {
    add_air_pressure(m, s, w);
    update_air(m, s, w, m.params.integrator.dt);
  });
}
void BM_adhesion(benchmark::State& st) {
  stage(st, warm(st), false, [](const Model& m, State& s, Workspace& w) { add_adhesion(m, s, w); });
}
void BM_self_collision(benchmark::State& st) {
  stage(st, warm(st), false,
        [](const Model& m, State& s, Workspace& w) { add_self_collision(m, s, w, true); });
}
void BM_build_hash(benchmark::State& st) {
  const Vec3Array anchor = warm(st).state().x;  // where add_self_collision searches from
  stage(st, warm(st), false, [&anchor](const Model& m, State&, Workspace& w) {
    // The cell add_self_collision uses.
    build_hash(anchor, m.params.self_collision.distance, w);
  });
}
void BM_limit_strain(benchmark::State& st) {
  stage(st, before_strain_limit(st.range(0)), true, [](const Model& m, State& s, Workspace& w) {
    limit_strain(m, s, w, m.params.integrator.dt);
  });
}
// Nothing is inside the table in the warm state: this times the queries; the
// projection, a few flops for a particle that is inside, is rarely taken.
void BM_collide(benchmark::State& st) {
  stage(st, warm(st), false, [](const Model& m, State& s, Workspace&) { collide(m, s, nullptr); });
}
void BM_friction(benchmark::State& st) {
  // Particles on the contact surface take their load from adhesion and forces;
  // `touched` (pushed out of another obstacle) does not arise in this scene.
  std::vector<std::uint8_t> touched(warm(st).model().n, 0);
  stage(st, warm(st), true, [&touched](const Model& m, State& s, Workspace& w) {
    apply_friction(m, s, w, touched, m.params.integrator.dt);
  });
}
// The implicit step's linear solve (block assembly, then conjugate gradients)
// over a whole 1/240 s step from the warm implicit state: the velocities go back
// before each call, else each solve would start from the last one's answer.
void BM_implicit_solve(benchmark::State& st) {
  const Simulation& from = warmed(st.range(0), false, true);
  int iterations = 0;
  stage(st, from, true, [&](const Model&, State& s, Workspace& w) {
    const Model& m = from.model();
    implicit_euler_velocities(m, s, w, m.params.integrator.dt);
    iterations = w.cg_iterations;
  });
  st.counters["cg_iterations"] = iterations;
}
void BM_normals(benchmark::State& st) {
  stage(st, warm(st), false, [](const Model& m, State& s, Workspace& w) {
    detail::compute_normals(m, s.x.column(0), w.normal, w.normals_scratch);
  });
}

BENCHMARK(BM_springs)->Apply(grids);
BENCHMARK(BM_spring_damping)->Apply(grids);
BENCHMARK(BM_spring_damping_two_threads)->Apply(grids);
BENCHMARK(BM_spring_edges<double>)->Apply(grids);
BENCHMARK(BM_spring_edges<float>)->Apply(grids);
BENCHMARK(BM_gravity)->Apply(grids);
BENCHMARK(BM_viscous_damping)->Apply(grids);
BENCHMARK(BM_wind)->Apply(grids);
BENCHMARK(BM_handles)->Apply(grids);
BENCHMARK(BM_air)->Apply(grids);
BENCHMARK(BM_adhesion)->Apply(grids);
BENCHMARK(BM_self_collision)->Apply(grids);
BENCHMARK(BM_build_hash)->Apply(grids);
BENCHMARK(BM_limit_strain)->Apply(grids);
BENCHMARK(BM_collide)->Apply(grids);
BENCHMARK(BM_friction)->Apply(grids);
BENCHMARK(BM_implicit_solve)->Apply(grids);
BENCHMARK(BM_normals)->Apply(grids);

}  // namespace

BENCHMARK_MAIN();
