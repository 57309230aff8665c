// The spatial hash (src/geometry/spatial_hash.hpp) that self-collision searches
// with: the pairs it finds are exactly those an all-pairs search finds. (Its
// suite is still SelfCollision: test names stay as CI and the docs know them.)
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <set>
#include <utility>
#include <vector>

#include "detail.hpp"  // the Workspace the hash fills
#include "geometry/spatial_hash.hpp"

using namespace wetcloth;

TEST(SelfCollision, HashFindsExactlyTheAllPairsPairs) {
  std::vector<Vec3> x;
  std::uint64_t seed = 12345;
  auto rnd = [&] {
    seed = seed * 6364136223846793005ULL + 1442695040888963407ULL;
    return double(seed >> 11) / double(1ULL << 53);
  };
  for (int i = 0; i < 3000; ++i) x.emplace_back(0.1 * rnd() - 0.05, 0.1 * rnd(), 0.03 * rnd());
  const double r = 0.005;
  auto skip = [](int i, int j) { return (i + j) % 11 == 0; };
  std::set<std::pair<int, int>> expected;
  for (int i = 0; i < 3000; ++i)
    for (int j = i + 1; j < 3000; ++j)
      if (!skip(i, j) && (x[i] - x[j]).norm() < r) expected.emplace(i, j);
  EXPECT_GT(expected.size(), 100u);
  // Cells of the radius (self-collision's), between it and twice it, of
  // twice it; a hash of 3000 particles in 8192 buckets, some shared.
  for (const double cell : {r, 1.3 * r, 2 * r}) {
    Workspace w;
    detail::build_hash(x, cell, w);
    std::set<std::pair<int, int>> found;
    NearScratch scratch;
    detail::for_each_close_pair(x, r, w, scratch, {}, [&](int i, int j, double) {
      if (!skip(i, j)) EXPECT_TRUE(found.emplace(i, j).second) << "pair found twice, cell " << cell;
    });
    EXPECT_EQ(found, expected) << "cell " << cell;
  }
}

// Few particles, few buckets: the 27 cells a search visits share buckets
// (12 particles hash into 32), and particles of cells it does not visit sit
// in them. Each pair within the radius is still found, once.
TEST(SelfCollision, HashWithSharedBucketsFindsEachPairOnce) {
  std::uint64_t seed = 777;
  auto rnd = [&] {
    seed = seed * 6364136223846793005ULL + 1442695040888963407ULL;
    return double(seed >> 11) / double(1ULL << 53);
  };
  const double r = 0.01;
  std::vector<Vec3> x;
  for (int i = 0; i < 12; ++i) x.emplace_back(0.03 * rnd(), 0.02 * rnd(), 0.02 * rnd());
  Workspace w;
  detail::build_hash(x, r, w);
  ASSERT_EQ(w.cell_start.size(), 33u);
  std::set<std::pair<int, int>> found, expected;
  NearScratch scratch;
  detail::for_each_close_pair(x, r, w, scratch, {}, [&](int i, int j, double) {
    EXPECT_TRUE(found.emplace(i, j).second) << "pair found twice";
  });
  for (int i = 0; i < 12; ++i)
    for (int j = i + 1; j < 12; ++j)
      if ((x[i] - x[j]).norm() < r) expected.emplace(i, j);
  EXPECT_GE(expected.size(), 3u);
  EXPECT_EQ(found, expected);
}

// On a lattice whose points sit on the cells' faces (x / cell a whole
// number), (x ± r) / cell rounds across a face: a search visits 4 cells a
// side, 64 in all (a fixed list of 27 had overrun).
TEST(SelfCollision, HashOnCellFacesFindsEachPairOnce) {
  const double r = 0.01;
  std::vector<Vec3> x;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j)
      for (int k = 0; k < 4; ++k)
        x.emplace_back(-0.15 + 0.005 * i, -0.15 + 0.005 * j, 0.6 + 0.005 * k);
  Workspace w;
  detail::build_hash(x, r, w);
  std::set<std::pair<int, int>> found, expected;
  NearScratch scratch;
  detail::for_each_close_pair(x, r, w, scratch, {}, [&](int i, int j, double) {
    EXPECT_TRUE(found.emplace(i, j).second) << "pair found twice";
  });
  for (int i = 0; i < int(x.size()); ++i)
    for (int j = i + 1; j < int(x.size()); ++j)
      if ((x[i] - x[j]).norm() < r) expected.emplace(i, j);
  EXPECT_GT(expected.size(), 100u);
  EXPECT_EQ(found, expected);
}

// A blown-up cloth (stopped only after its step) at 1e14 m: there a double
// holds whole numbers of cells only 2 or 4 apart, and a search's last cell
// could land 4 past its first. It visits at most 4 a side (the sanitizer
// build checks the list it keeps of them).
TEST(SelfCollision, HashOfABlownUpClothStaysInItsCells) {
  std::vector<Vec3> x;
  for (int i = 0; i < 40; ++i)
    x.emplace_back(-8.56803e13 * (1 + 1e-3 * i), -9.2669e13 * (1 - 1e-3 * i), 2.37738e13);
  x.emplace_back(x[0]);
  const double r = 0.01;
  Workspace w;
  detail::build_hash(x, r, w);
  int pairs = 0;
  NearScratch scratch;
  detail::for_each_close_pair(x, r, w, scratch, {}, [&](int, int, double) { ++pairs; });
  EXPECT_EQ(pairs, 0);  // the only two that coincide are not a pair (len2 == 0)
}

// Searches around some of the particles, every other particle a partner (not
// only later ones), grid neighbours left out by the search itself: exactly
// the pairs an all-pairs search finds, each once, with its squared distance.
// The points are a crumpled grid of 30 x 20, so that far grid neighbours meet.
TEST(SelfCollision, HashSearchesAroundSomeParticlesLeaveOutGridNeighbours) {
  const int nu = 30, nv = 20, reach = 2;
  const double r = 0.012;
  std::vector<Vec3> x;
  for (int j = 0; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      const double u = 0.004 * i, v = 0.004 * j;
      x.emplace_back(0.02 * std::sin(40 * u), v,
                     0.02 * std::cos(40 * u) + 0.002 * std::sin(50 * v));
    }
  std::vector<int> queries;
  for (int i = 0; i < nu * nv; i += 7) queries.push_back(i);
  const detail::GridNear near(nu, reach);
  std::set<std::pair<int, int>> expected;
  for (const int i : queries)
    for (int j = 0; j < nu * nv; ++j) {
      const bool grid = std::abs(i % nu - j % nu) <= reach && std::abs(i / nu - j / nu) <= reach;
      EXPECT_EQ(near(i, j), grid) << i << " " << j;
      const double len2 = (x[i] - x[j]).squaredNorm();
      if (!grid && len2 < r * r && len2 > 0) expected.emplace(i, j);
    }
  EXPECT_GT(expected.size(), 50u);
  Workspace w;
  detail::build_hash(x, r, w, 1, 64);  // fewer buckets than cells: shared ones
  std::vector<NearSearch> plan;
  detail::plan_searches(x, queries, r, w, plan);
  NearScratch scratch;
  std::set<std::pair<int, int>> found;
  detail::for_each_near(x, r, w, scratch, plan, 0, plan.size(), false, near,
                        [&](int i, int j, double len2) {
                          EXPECT_DOUBLE_EQ(len2, (x[i] - x[j]).squaredNorm());
                          EXPECT_TRUE(found.emplace(i, j).second) << "pair found twice";
                        });
  EXPECT_EQ(found, expected);
}
