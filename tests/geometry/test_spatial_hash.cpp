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
  Workspace w;
  detail::build_hash(x, 2 * r, w);
  auto skip = [](int i, int j) { return (i + j) % 11 == 0; };
  std::set<std::pair<int, int>> found, expected;
  detail::for_each_close_pair(x, r, w, skip, [&](int i, int j, const Vec3&, double) {
    EXPECT_TRUE(found.emplace(i, j).second) << "pair found twice";
  });
  for (int i = 0; i < 3000; ++i)
    for (int j = i + 1; j < 3000; ++j)
      if (!skip(i, j) && (x[i] - x[j]).norm() < r) expected.emplace(i, j);
  EXPECT_GT(expected.size(), 100u);
  EXPECT_EQ(found, expected);
}
