// Checkpoint files (src/io/checkpoint.cpp): a run resumed from one continues
// with the same bits; a damaged file is refused, naming it.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include "common.hpp"
#include "wetcloth/checkpoint.hpp"

namespace wetcloth {
namespace {

// A run through a checkpoint file: its scene and its state come back, and it
// continues with the same bits, as a restored State does (test_state.cpp). A
// damaged file, another format's, or not a checkpoint at all, is bad input
// that names the file.
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
  EXPECT_TRUE(test::same_bits(second.state().x, first.state().x));
  EXPECT_TRUE(test::same_bits(second.state().v, first.state().v));

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

// A run saved while a landing's substeps are under way (integrator.landing_dt)
// resumes them: the file keeps when they end.
TEST(Checkpoint, ResumesALandingInItsSubsteps) {
  namespace fs = std::filesystem;
  const fs::path file = fs::temp_directory_path() / "wetcloth_test_checkpoint_landing.state";
  const Params p = load_scene("drop-ball", {"cloth.resolution=[21,21]", "cloth.humidity=1"});
  Simulation first(p);
  ASSERT_TRUE(first.advance_to(0.098));
  ASSERT_GT(first.state().landing_until, first.state().time);  // landed at 0.0963 s
  save_checkpoint(file, first.model().params, first.state());
  ASSERT_TRUE(first.advance_to(0.11));

  const Checkpoint c = load_checkpoint(file);
  fs::remove(file);
  Simulation second(c.params);
  second.restore(c.state);
  ASSERT_TRUE(second.advance_to(0.11));
  EXPECT_TRUE(test::same_bits(second.state().x, first.state().x));
  EXPECT_TRUE(test::same_bits(second.state().v, first.state().v));
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
  EXPECT_TRUE(test::same_bits(again.state().x, sim.state().x));
  fs::remove(file);
}

}  // namespace
}  // namespace wetcloth
