// The scene keys of issue 39's moving obstacles and placed garments
// (src/model/scene.cpp, mesh_cloth.cpp): keyframes read, written and
// refused with the file, line and key; a y-up cloth mesh placed by cloth.up;
// handles by particle index, listed or in a file, holding those particles.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <fstream>

#include "common.hpp"
#include "detail.hpp"

using namespace wetcloth;
namespace fs = std::filesystem;

namespace {

using test::TempDir;

std::string error_of(const std::string& text, const std::vector<std::string>& sets = {}) {
  try {
    parse_scene(text, "s.toml", sets);
  } catch (const SceneError& e) {
    return e.what();
  }
  return "";
}

std::string load_error(const fs::path& scene) {
  try {
    load_scene(scene.string());
  } catch (const SceneError& e) {
    return e.what();
  }
  return "";
}

bool has(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

}  // namespace

TEST(SceneMotion, KeyframesAreReadWrittenAndReadBack) {
  const std::string text =
      "[ball]\nenabled = true\nmotion = [[0, [0, 0, 0], [0, 0, 0]],\n"
      "  [1.5, [0.1, -0.2, 0.3], [0, 90, 720]]]\nmotion_interpolation = \"smooth\"\n";
  const Params p = parse_scene(text, "s.toml");
  ASSERT_EQ(p.ball.motion.keys.size(), 2u);
  EXPECT_EQ(p.ball.motion.keys[1], (Keyframe{1.5, {0.1, -0.2, 0.3}, {0, 90, 720}}));
  EXPECT_EQ(p.ball.motion.interpolation, Interpolation::Smooth);
  const Params back = parse_scene(to_toml(p), "back.toml");
  EXPECT_EQ(back.ball.motion.keys, p.ball.motion.keys);
  EXPECT_EQ(back.ball.motion.interpolation, Interpolation::Smooth);
  // An obstacle's, through --set as Python's Simulation.set gives it.
  const Params arm = load_scene("arm-swing", {"obstacle.arm.motion=[[0, [0, 0, 0.1], [0, 0, 0]]]"});
  ASSERT_EQ(arm.obstacles.at("arm").motion.keys.size(), 1u);
  EXPECT_EQ(arm.obstacles.at("arm").motion.keys[0].translate[2], 0.1);
  EXPECT_EQ(parse_scene(to_toml(arm), "back.toml").obstacles.at("arm").motion.keys,
            arm.obstacles.at("arm").motion.keys);
}

// Bad keyframes name the file, the line of the keyframe at fault and the key.
TEST(SceneMotion, BadKeyframesNameTheLineAndKey) {
  const std::string head = "[ball]\nenabled = true\n";
  const std::string order =
      error_of(head +
               "motion = [[0, [0, 0, 0], [0, 0, 0]],\n  [1, [0, 0, 0], [0, 0, 0]],\n"
               "  [1, [0, 0, 0], [0, 0, 0]]]\n");
  EXPECT_TRUE(has(order,
                  "s.toml:5: ball.motion: keyframe 3's time 1.0 s is not after keyframe "
                  "2's, 1.0 s"))
      << order;
  const std::string shape = error_of(head + "motion = [[0, [0, 0], [0, 0, 0]]]\n");
  EXPECT_TRUE(has(shape, "s.toml:3: ball.motion: keyframe 1: expected [t, [x, y, z]")) << shape;
  const std::string word = error_of(head + "motion = [[0, [0, 0, \"a\"], [0, 0, 0]]]\n");
  EXPECT_TRUE(has(word, "ball.motion: keyframe 1's translation: expected a number")) << word;
  EXPECT_TRUE(has(error_of(head + "motion = [[-1, [0, 0, 0], [0, 0, 0]]]\n"),
                  "keyframe 1's time: value -1.0 is out of range"));
  EXPECT_TRUE(has(error_of("[ball]\nmotion = [[0, [0, 0, 0], [0, 0, 0]]]\n"),
                  "ball.motion: moves a ball that is not there"));
  EXPECT_TRUE(has(error_of(head + "motion_interpolation = \"cubic\"\n"),
                  "'cubic' is not one of linear | smooth"));
  // Params made in code get the same check.
  Params p;
  p.ball.enabled = true;
  p.ball.motion.keys = {{1, {0, 0, 0}, {0, 0, 0}}, {0.5, {0, 0, 0}, {0, 0, 0}}};
  try {
    validate(p);
    ADD_FAILURE() << "keyframes out of order were taken";
  } catch (const SceneError& e) {
    EXPECT_TRUE(has(e.what(), "ball.motion: keyframe 2's time 0.5 s is not after")) << e.what();
  }
}

// A garment made y-up (Blender's OBJ export) stands up with cloth.up = "y",
// from the file's own origin, scaled and moved as obstacles are; and check
// says which axis a file seems to use when it starts inside an obstacle.
TEST(SceneMotion, YUpClothMeshIsPlacedByItsKeys) {
  TempDir dir("scene_motion_up");
  // A 0.2 x 0.1 sheet in the file's xz plane (y-up: the file's "floor"),
  // 0.05 above its origin along the file's y.
  dir.write("meshes/sheet.obj",
            "v 0 0.05 0\nv 0.2 0.05 0\nv 0.2 0.05 -0.1\nv 0 0.05 -0.1\nf 1 2 3 4\n");
  const fs::path scene =
      dir.write("s.toml",
                "[cloth]\nmesh = \"meshes/sheet.obj\"\nup = \"y\"\nscale = [2, 2, 2]\n"
                "translate = [1, 2, 3]\n[table]\nenabled = false\n[contact]\nsurface = \"none\"\n");
  const Params p = load_scene(scene.string());
  const Model m = build_model(p);
  Vec3 lo = m.rest_position[0], hi = lo;
  for (const Vec3& x : m.rest_position) lo = lo.cwiseMin(x), hi = hi.cwiseMax(x);
  // y-up (x, y, z) -> z-up (x, -z, y); times 2; plus [1, 2, 3].
  EXPECT_LT((lo - Vec3(1, 2, 3.1)).norm(), 1e-12) << lo.transpose();
  EXPECT_LT((hi - Vec3(1.4, 2.2, 3.1)).norm(), 1e-12) << hi.transpose();
  // The grid has no file to place; and the mesh is placed one way or the other.
  EXPECT_TRUE(has(error_of("[cloth]\ntranslate = [0, 0, 1]\n"), "place a cloth.mesh"));
  EXPECT_TRUE(has(error_of("[cloth]\nmesh = \"m.obj\"\nup = \"y\"\ncenter = [0, 0, 1]\n"),
                  "cloth.center: places the mesh's bounding box"));
  // Starting inside an obstacle, check names the up axis that would not.
  dir.write("meshes/box.obj",
            "v -1 -1 -1\nv 1 -1 -1\nv 1 1 -1\nv -1 1 -1\nv -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\n"
            "f 1 3 2\nf 1 4 3\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\nf 2 3 7\nf 2 7 6\nf 3 4 8\n"
            "f 3 8 7\nf 4 1 5\nf 4 5 8\n");
  const fs::path inside = dir.write(
      "inside.toml",
      "[cloth]\nmesh = \"meshes/sheet.obj\"\ntranslate = [0, 0, 0.001]\n[table]\nenabled = false\n"
      "[contact]\nsurface = \"none\"\n[obstacle.box]\nmesh = \"meshes/box.obj\"\n");
  const std::string e = load_error(inside);
  EXPECT_TRUE(has(e, "inside obstacle.box")) << e;
  EXPECT_TRUE(has(e, "cloth.up = \"y\"")) << e;
}

// Handles by particle index: a list, or a file of whitespace-separated
// indices; the listed particles of a pin stay where they started; a bad index
// names the file, its line and the key.
TEST(SceneMotion, VertexListHandlesHoldTheirParticles) {
  TempDir dir("scene_motion_vertices");
  dir.write("cuff.txt", "# the top corners\n0 10\n\n  120 # and the last\n");
  const std::string cloth =
      "[cloth]\nresolution = [11, 11]\nsize = [0.1, 0.1]\ncenter = [0, 0, 0.3]\n"
      "[table]\nenabled = false\n[contact]\nsurface = \"none\"\n";
  const fs::path scene =
      dir.write("s.toml", cloth +
                              "[handle.cuff]\ntype = \"pin\"\nvertices = \"cuff.txt\"\n"
                              "[handle.two]\ntype = \"pin\"\nvertices = [60, 5]\n");
  const Params p = load_scene(scene.string());
  Simulation sim(p);
  EXPECT_EQ(sim.model().handles[0].particles, (std::vector<int>{0, 10, 120}));
  EXPECT_EQ(sim.model().handles[1].particles, (std::vector<int>{5, 60}));
  const Vec3Array start = sim.state().x;
  ASSERT_TRUE(sim.advance_to(0.2)) << sim.blow_up_reason();
  for (const int i : {0, 10, 120, 5, 60}) EXPECT_EQ(sim.state().x[i], start[i]) << i;
  EXPECT_LT(sim.state().x[55].z(), start[55].z() - 0.005);  // the rest falls
  // Written out and read back: the file and the list.
  const Params back = parse_scene(to_toml(p), "back.toml");
  EXPECT_EQ(back.handles.at("cuff").vertices.file, "cuff.txt");
  EXPECT_EQ(back.handles.at("two").vertices.indices, (std::vector<long long>{60, 5}));
  // Errors: the file's line, the scene's key, the grid's count.
  dir.write("bad.txt", "0 1\n2 x3\n");
  dir.write("far.txt", "0\n\n121\n");
  const std::string bad = load_error(
      dir.write("b.toml", cloth + "[handle.cuff]\ntype = \"pin\"\nvertices = \"bad.txt\"\n"));
  EXPECT_TRUE(has(bad, "bad.txt:2: handle.cuff.vertices: 'x3' is not a particle index")) << bad;
  const std::string far = load_error(
      dir.write("f.toml", cloth + "[handle.cuff]\ntype = \"pin\"\nvertices = \"far.txt\"\n"));
  EXPECT_TRUE(has(far,
                  "far.txt:3: handle.cuff.vertices: index 121 is out of range: the cloth "
                  "has 121 particles (0 to 120)"))
      << far;
  const std::string listed =
      error_of(cloth + "[handle.cuff]\ntype = \"pin\"\nvertices = [3, 200]\n");
  EXPECT_TRUE(has(listed, "handle.cuff.vertices: index 200 is out of range")) << listed;
  const std::string missing = load_error(
      dir.write("m.toml", cloth + "[handle.cuff]\ntype = \"pin\"\nvertices = \"none.txt\"\n"));
  EXPECT_TRUE(has(missing, "handle.cuff.vertices")) << missing;
  EXPECT_TRUE(has(missing, "no such file")) << missing;
  EXPECT_TRUE(has(error_of(cloth + "[handle.cuff]\ntype = \"pin\"\nvertices = [-1]\n"),
                  "a particle index is an integer from 0"));
  EXPECT_TRUE(has(error_of(cloth + "[handle.cuff]\nvertices = [1]\npatch = 2\n"),
                  "handle.cuff.vertices: names the handle's particles"));
  EXPECT_THROW(at_resolution(p, 21), SceneError);  // indices are not the same particles there
}

namespace {

// A PC2 file of `frames` samples of `points` points, point i of sample k at
// (i, k, 0) / 10.
std::string pc2_bytes(int points, int frames) {
  std::string o("POINTCACHE2\0", 12);
  const auto put = [&](const auto v) { o.append(reinterpret_cast<const char*>(&v), sizeof v); };
  put(std::int32_t{1}), put(points), put(0.0f), put(1.0f), put(frames);
  for (int k = 0; k < frames; ++k)
    for (int i = 0; i < points; ++i) put(i / 10.0f), put(k / 10.0f), put(0.0f);
  return o;
}

}  // namespace

// obstacle.NAME.cache: read with its mesh; a bad one names the scene file,
// the key's line and the key, and what is wrong with the cache's file.
TEST(SceneMotion, BadObstacleCachesNameTheFileLineAndKey) {
  TempDir dir("scene_motion_cache");
  dir.write("meshes/plate.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n");
  dir.write("meshes/plate.pc2", pc2_bytes(4, 3));
  dir.write("meshes/three.pc2", pc2_bytes(3, 3));
  dir.write("meshes/short.pc2", pc2_bytes(4, 3).substr(0, 60));
  for (int k = 0; k < 3; ++k)
    dir.write("meshes/plate_00" + std::to_string(k + 1) + ".obj",
              k == 1 ? "v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3\n"
                     : "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n");
  dir.write("meshes/gap_1.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n");
  dir.write("meshes/gap_3.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n");
  const std::string head =
      "[cloth]\ncenter = [0.5, 0.5, 0.3]\n[table]\nenabled = false\n[contact]\n"
      "surface = \"none\"\n[obstacle.plate]\nmesh = \"meshes/plate.obj\"\nthickness = 0.002\n";
  // Good: a PC2 file at 12 frames a second, from 0.5 s.
  const Params p =
      load_scene(dir.write("good.toml", head + "cache = \"meshes/plate.pc2\"\ncache_fps = 12\n"
                                               "cache_start = 0.5\n")
                     .string());
  EXPECT_EQ(p.obstacles.at("plate").cache, "meshes/plate.pc2");
  EXPECT_EQ(p.obstacles.at("plate").cache_fps, 12);
  const Params back = parse_scene(to_toml(p), "back.toml");
  EXPECT_EQ(back.obstacles.at("plate").cache, "meshes/plate.pc2");
  EXPECT_EQ(back.obstacles.at("plate").cache_start, 0.5);
  const auto error = [&](const std::string& name, const std::string& keys) {
    return load_error(dir.write(name + ".toml", head + keys));
  };
  // Line 10: the cache's key.
  const std::string missing = error("missing", "cache = \"meshes/none.pc2\"\n");
  EXPECT_TRUE(has(missing, "missing.toml:10: obstacle.plate.cache: ")) << missing;
  EXPECT_TRUE(has(missing, "none.pc2: no such file")) << missing;
  const std::string count = error("count", "cache = \"meshes/three.pc2\"\n");
  EXPECT_TRUE(has(count, "count.toml:10: obstacle.plate.cache: ")) << count;
  EXPECT_TRUE(has(count, "three.pc2 has 3 vertices a frame, and obstacle.plate.mesh")) << count;
  EXPECT_TRUE(has(count, "has 4")) << count;
  const std::string cut = error("cut", "cache = \"meshes/short.pc2\"\n");
  EXPECT_TRUE(has(cut, "cut.toml:10: obstacle.plate.cache: ")) << cut;
  EXPECT_TRUE(has(cut, "short.pc2: 60 bytes where its header")) << cut;
  const std::string frame = error("frame", "cache = \"meshes/plate_###.obj\"\n");
  EXPECT_TRUE(has(frame, "frame.toml:10: obstacle.plate.cache: ")) << frame;
  EXPECT_TRUE(has(frame, "plate_002.obj has 3 vertices a frame")) << frame;
  const std::string none = error("none", "cache = \"meshes/arm_##.obj\"\n");
  EXPECT_TRUE(has(none, "none.toml:10: obstacle.plate.cache: ")) << none;
  EXPECT_TRUE(has(none, "arm_##.obj: no such files")) << none;
  const std::string gap = error("gap", "cache = \"meshes/gap_#.obj\"\n");
  EXPECT_TRUE(has(gap, "gap_2.obj: no such file, and the sequence goes on after it")) << gap;
  const std::string fps = error("fps", "cache = \"meshes/plate.pc2\"\ncache_fps = 0\n");
  EXPECT_TRUE(has(fps, "fps.toml:11")) << fps;
  EXPECT_TRUE(has(fps, "obstacle.plate.cache_fps")) << fps;
  EXPECT_TRUE(has(fps, "out of range")) << fps;
  const std::string kind = error("kind", "cache = \"meshes/plate.txt\"\n");
  EXPECT_TRUE(has(kind,
                  "kind.toml:10: obstacle.plate.cache: \"meshes/plate.txt\" is neither a "
                  "PC2 file"))
      << kind;
  const std::string folder = error("folder", "cache = \"m#/plate.obj\"\n");
  EXPECT_TRUE(has(folder, "obstacle.plate.cache: \"m#/plate.obj\": the # of an OBJ sequence"))
      << folder;
}
