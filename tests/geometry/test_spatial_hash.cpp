// The spatial hash (src/geometry/spatial_hash.hpp) that self-collision searches
// with: the pairs it finds are exactly those an all-pairs search finds. (Its
// suite is still SelfCollision: test names stay as CI and the docs know them.)
#include <gtest/gtest.h>

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
    detail::for_each_close_pair(x, r, w, skip, [&](int i, int j, const Vec3&, double) {
      EXPECT_TRUE(found.emplace(i, j).second) << "pair found twice, cell " << cell;
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
  detail::for_each_close_pair(
      x, r, w, [](int, int) { return false; },
      [&](int i, int j, const Vec3&, double) {
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
  detail::for_each_close_pair(
      x, r, w, [](int, int) { return false; },
      [&](int i, int j, const Vec3&, double) {
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
  detail::for_each_close_pair(
      x, r, w, [](int, int) { return false; }, [&](int, int, const Vec3&, double) { ++pairs; });
  EXPECT_EQ(pairs, 0);  // the only two that coincide are not a pair (len2 == 0)
}
