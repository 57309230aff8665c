// State is the whole state of a run: a copy taken at t and restored into a
// fresh Simulation of the same scene continues with the same bits, on every
// integrator and with every wet effect the scenes switch on.
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>

#include "common.hpp"
#include "wetcloth/checkpoint.hpp"

namespace wetcloth {
namespace {

struct Case {
  const char* scene;
  std::vector<std::string> sets;
  double t_copy, t_end;
};

void PrintTo(const Case& c, std::ostream* o) {
  *o << c.scene;
  for (const auto& s : c.sets) *o << " " << s;
}

bool same_bits(const Vec3Array& a, const Vec3Array& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i)
    for (int q = 0; q < 3; ++q) {
      const double x = a[i][q], y = b[i][q];
      if (std::memcmp(&x, &y, sizeof x) != 0) return false;
    }
  return true;
}

class Restore : public ::testing::TestWithParam<Case> {};

TEST_P(Restore, ContinuesWithTheSameBits) {
  const Case& c = GetParam();
  std::vector<std::string> sets = c.sets;
  sets.insert(sets.begin(), "cloth.resolution=[15,15]");
  const Params p = load_scene(c.scene, sets);
  Simulation first(p);
  ASSERT_TRUE(first.advance_to(c.t_copy)) << first.blow_up_reason();
  const State copy = first.state();
  ASSERT_TRUE(first.advance_to(c.t_end)) << first.blow_up_reason();

  Simulation second(p);
  second.advance_to(0.25 * c.t_copy);  // a different history, overwritten
  second.restore(copy);
  ASSERT_TRUE(second.advance_to(c.t_end)) << second.blow_up_reason();
  EXPECT_EQ(second.state().steps, first.state().steps);
  EXPECT_TRUE(same_bits(second.state().x, first.state().x));
  EXPECT_TRUE(same_bits(second.state().v, first.state().v));
  EXPECT_EQ(second.state().inner_pressure, first.state().inner_pressure);
  EXPECT_EQ(second.metrics().handle_force_n, first.metrics().handle_force_n);
}

const std::string kImplicit = "integrator.type=\"implicit-euler\"";
const std::string kXpbd = "integrator.type=\"xpbd\"";
const std::string kLarge = "integrator.dt=0.004166666666666667";

INSTANTIATE_TEST_SUITE_P(Scenes, Restore,
                         ::testing::Values(Case{"pull-straight", {}, 0.1, 0.2},  // exchange air
                                           Case{"drape-ball", {}, 0.2, 0.3},     // vented air, ball
                                           Case{"pull-oblique", {}, 0.1, 0.2},   // a move handle
                                           Case{"hang",
                                                {"self_collision.enabled=true"},
                                                0.2,
                                                0.3},  // pins, self-collision
                                           Case{"pull-straight", {kImplicit, kLarge}, 0.1, 0.2},
                                           Case{"drape-ball", {kImplicit, kLarge}, 0.2, 0.3},
                                           Case{"pull-straight", {kXpbd, kLarge}, 0.1, 0.2},
                                           Case{"drape-ball", {kXpbd, kLarge}, 0.2, 0.3}));

TEST(Restore, RefusesAStateOfAnotherGrid) {
  Simulation small(test::bare(3)), large(test::bare(4));
  EXPECT_THROW(large.restore(small.state()), std::invalid_argument);
}

// The same through a checkpoint file: the scene and the state come back, and
// the run continues with the same bits. A damaged file, another format's, or
// not a checkpoint at all, is bad input that names the file.
TEST(Checkpoint, ResumesFromAFileWithTheSameBits) {
  namespace fs = std::filesystem;
  const fs::path file = fs::temp_directory_path() / "wetcloth_test_checkpoint.state";
  const Params p = load_scene("drape-ball", {"cloth.resolution=[15,15]"});
  Simulation first(p);
  ASSERT_TRUE(first.advance_to(0.2));
  save_checkpoint(file, first.model().params, first.state());
  ASSERT_TRUE(first.advance_to(0.3));

  const Checkpoint c = load_checkpoint(file);
  EXPECT_EQ(to_toml(c.params), to_toml(p));
  Simulation second(c.params);
  second.restore(c.state);
  ASSERT_TRUE(second.advance_to(0.3));
  EXPECT_TRUE(same_bits(second.state().x, first.state().x));
  EXPECT_TRUE(same_bits(second.state().v, first.state().v));

  std::string bytes;
  {
    std::ifstream in(file, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), {});
  }
  const auto expect_refused = [&](std::string damaged, const std::string& why) {
    std::ofstream(file, std::ios::binary | std::ios::trunc) << damaged;
    try {
      load_checkpoint(file);
      ADD_FAILURE() << "accepted: " << why;
    } catch (const SceneError& e) {
      EXPECT_NE(std::string(e.what()).find(file.string()), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(why), std::string::npos) << e.what();
    }
  };
  std::string flipped = bytes;
  flipped[bytes.size() / 2] ^= 1;
  expect_refused(flipped, "checksum");
  std::string version = bytes;
  version[16] = 9;
  expect_refused(version, "format 9");
  expect_refused("[cloth]\nhumidity = 0.5\n", "not a wetcloth checkpoint");
  expect_refused(bytes.substr(0, 40), "checksum");
  fs::remove(file);
}

// A program's own record (`wetcloth run`'s: where its outputs stood) comes
// back as it was written, and is covered by the checksum.
TEST(Checkpoint, KeepsTheRunsRecord) {
  namespace fs = std::filesystem;
  const fs::path file = fs::temp_directory_path() / "wetcloth_test_checkpoint_record.state";
  const Params p = load_scene("hang", {"cloth.resolution=[5,5]"});
  Simulation sim(p);
  ASSERT_TRUE(sim.advance_to(0.01));
  const std::string record = "{\"next_frame\": 3}";
  save_checkpoint(file, p, sim.state(), record);
  EXPECT_FALSE(fs::exists(file.string() + ".tmp"));
  EXPECT_EQ(load_checkpoint(file).run, record);
  save_checkpoint(file, p, sim.state());
  EXPECT_EQ(load_checkpoint(file).run, "");
  fs::remove(file);
}

// A scene's meshes are found where the scene was: a checkpoint of a mesh
// cloth (a built-in scene's, built into the program) builds its model again.
TEST(Checkpoint, KeepsWhereTheScenesMeshesAre) {
  namespace fs = std::filesystem;
  const fs::path file = fs::temp_directory_path() / "wetcloth_test_checkpoint_mesh.state";
  const Params p = load_scene("drape-disc");
  ASSERT_EQ(p.scene_dir, "builtin:");
  Simulation sim(p);
  ASSERT_TRUE(sim.advance_to(0.01));
  save_checkpoint(file, p, sim.state());
  const Checkpoint c = load_checkpoint(file);
  EXPECT_EQ(c.params.scene_dir, p.scene_dir);
  Simulation again(c.params);
  again.restore(c.state);
  ASSERT_TRUE(again.advance_to(0.02));
  ASSERT_TRUE(sim.advance_to(0.02));
  EXPECT_TRUE(same_bits(again.state().x, sim.state().x));
  fs::remove(file);
}

}  // namespace
}  // namespace wetcloth
