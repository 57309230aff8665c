// The simulation (include/wetcloth/simulation.hpp, src/simulation.cpp): the
// state's arrays, the step's threads, and a step that allocates nothing.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <new>
#include <string>
#include <vector>

#include "common.hpp"
#include "wetcloth/simulation.hpp"

using namespace wetcloth;

// Allocations counted while g_count_allocations is set (Step.AllocatesNothingOnceWarm):
// the test binary's operator new counts, then allocates with malloc; its
// operator delete frees with free, replaced alongside (AddressSanitizer
// reports a malloc'd block freed by its own operator delete as a mismatch).
std::atomic<bool> g_count_allocations{false};
std::atomic<long> g_allocations{0};
void* operator new(std::size_t size) {
  if (g_count_allocations) ++g_allocations;
  if (void* p = std::malloc(size ? size : 1)) return p;
  throw std::bad_alloc();
}
// The other forms, as libstdc++'s own go through operator new (std::stable_sort's
// buffer is nothrow): under ASan they would be its allocator's, freed by ours.
void* operator new(std::size_t size, const std::nothrow_t&) noexcept {
  if (g_count_allocations) ++g_allocations;
  return std::malloc(size ? size : 1);
}
void* operator new[](std::size_t size) { return operator new(size); }
void* operator new[](std::size_t size, const std::nothrow_t& t) noexcept {
  return operator new(size, t);
}
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"  // GCC cannot see the pair is ours
#endif
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { std::free(p); }
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic pop
#endif

namespace {

const char* kImplicit = "integrator.type=implicit-euler";
const char* kLargeStep = "integrator.dt=0.004166666666666667";  // 1/240 s

}  // namespace

// The state's arrays hold x, y, z columns; a[i] is a view that reads and
// writes particle i's three components in them.
TEST(Vec3Array, ViewsReadAndWriteTheColumns) {
  Vec3Array a{Vec3(1, 2, 3), Vec3(4, 5, 6)};
  ASSERT_EQ(a.size(), 2u);
  EXPECT_EQ(a.column(0)[1], 4.0);
  EXPECT_EQ(a.column(2)[0], 3.0);
  a[1] += Vec3(1, 1, 1);
  a[0].z() = 9;
  EXPECT_EQ(a.column(1)[1], 6.0);
  EXPECT_EQ(a.column(2)[0], 9.0);
  Vec3 sum = Vec3::Zero();
  for (const Vec3& v : a) sum += v;
  EXPECT_EQ(sum, Vec3(6, 8, 16));
  for (auto&& v : a) v *= 2;
  EXPECT_EQ(Vec3(a[1]), Vec3(10, 12, 14));
  Vec3Array b = a;
  EXPECT_TRUE(b == a);
  b[0].x() = 0;
  EXPECT_FALSE(b == a);
  EXPECT_EQ(Vec3(Vec3Array(std::vector<Vec3>{Vec3(1, 0, 0)})[0]), Vec3(1, 0, 0));
  b.assign(3, Vec3(7, 8, 9));
  ASSERT_EQ(b.size(), 3u);
  EXPECT_EQ(b.column(1)[2], 8.0);
  EXPECT_EQ(Vec3(b[2]), Vec3(7, 8, 9));
}

// Nothing is allocated per step: the scratch arrays of the Workspace grow to
// what the scene needs during the first steps, then are reused. Symplectic
// Euler on two threads with self-collision on, then implicit Euler (whose
// self-collision candidates grow for 0.2 s, as the pull lifts the cloth).
TEST(Step, AllocatesNothingOnceWarm) {
  const auto allocations = [](std::vector<std::string> sets, int warm, int counted) {
    sets.push_back("self_collision.enabled=true");
    Simulation sim(load_scene("pull-straight", sets));
    for (int k = 0; k < warm; ++k) sim.step();
    g_allocations = 0;
    g_count_allocations = true;
    for (int k = 0; k < counted; ++k) sim.step();
    g_count_allocations = false;
    EXPECT_TRUE(sim.blow_up_reason().empty()) << sim.blow_up_reason();
    return g_allocations.load();
  };
  EXPECT_EQ(allocations({"integrator.threads=2"}, 300, 300), 0);
  EXPECT_EQ(allocations({kImplicit, kLargeStep}, 60, 30), 0);
}

// Every force is gathered per particle and every sum is taken in a fixed
// order, so the thread count never changes a bit. At the paper's 51 x 51: a
// smaller grid runs on one thread whatever it asks for.
TEST(Threads, TwoThreadsGiveTheSameBitsAsOne) {
  for (const bool implicit : {false, true}) {
    const char* integrator = implicit ? kImplicit : "integrator.type=symplectic-euler";
    const char* dt = implicit ? kLargeStep : "integrator.dt=5e-5";
    std::vector<Simulation> sims;
    for (const char* threads : {"integrator.threads=1", "integrator.threads=2"})
      sims.emplace_back(
          load_scene("pull-straight", {integrator, dt, threads, "cloth.humidity=0.5"}));
    ASSERT_EQ(sims[1].model().threads, 2);
    const double t = 0.02;
    for (auto& sim : sims) ASSERT_TRUE(sim.advance_to(t));
    for (int i = 0; i < sims[0].model().n; ++i) {
      ASSERT_EQ(sims[0].state().x[i], sims[1].state().x[i]) << integrator << " particle " << i;
      ASSERT_EQ(sims[0].state().v[i], sims[1].state().v[i]) << integrator << " particle " << i;
    }
  }
}

// integrator.threads = 0 switches between one thread and two as it times
// them; the result is the one thread's, bit for bit.
TEST(Threads, ChosenAsItRunsGivesTheSameBitsAsOne) {
  Simulation one(load_scene("pull-straight", {"integrator.threads=1"}));
  Simulation chosen(load_scene("pull-straight", {"integrator.threads=0"}));
  if (chosen.stats().most_threads < 2) GTEST_SKIP() << "one core: nothing to choose";
  ASSERT_TRUE(chosen.stats().threads_chosen);
  const double t = 0.3;  // about a second of wall time: trials every 0.25 s
  ASSERT_TRUE(one.advance_to(t));
  ASSERT_TRUE(chosen.advance_to(t));
  EXPECT_GT(chosen.stats().steps_on_one, 0);
  EXPECT_GT(chosen.stats().steps_on_most, 0);
  for (int i = 0; i < one.model().n; ++i) {
    ASSERT_EQ(one.state().x[i], chosen.state().x[i]) << "particle " << i;
    ASSERT_EQ(one.state().v[i], chosen.state().v[i]) << "particle " << i;
  }
}
