// Reading the OBJ meshes a scene names (src/geometry/mesh_io.cpp).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "geometry/mesh_io.hpp"
#include "wetcloth/scene.hpp"

namespace wetcloth {
namespace {

const char* kQuad =
    "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
    "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
    "f 1/1 2/2 3/3 4/4\n";

TEST(MeshIo, AQuadIsTwoTrianglesWithItsDiagonalsAndUVs) {
  const TriangleMesh m = read_obj(kQuad, "quad.obj");
  ASSERT_EQ(m.position.size(), 4u);
  ASSERT_EQ(m.triangles.size(), 2u);
  EXPECT_EQ(m.triangles[0], (std::array<int, 3>{0, 1, 2}));
  EXPECT_EQ(m.triangles[1], (std::array<int, 3>{0, 2, 3}));
  ASSERT_EQ(m.quads.size(), 1u);
  ASSERT_EQ(m.uv.size(), 4u);
  EXPECT_EQ(m.uv[2], (std::array<double, 2>{1, 1}));
  EXPECT_EQ(m.corner_uv[1][2], (std::array<double, 2>{0, 1}));
}

TEST(MeshIo, CoordinatesKeepDoublePrecision) {
  const TriangleMesh m = read_obj("v 0.1234567890123 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "t.obj");
  EXPECT_EQ(m.position[0][0], 0.1234567890123);
  EXPECT_TRUE(m.uv.empty());
}

void expect_refused(const std::string& text, const std::string& what) {
  try {
    read_obj(text, "bad.obj");
    ADD_FAILURE() << "accepted: " << text;
  } catch (const SceneError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("bad.obj"), std::string::npos) << msg;
    EXPECT_NE(msg.find(what), std::string::npos) << msg;
  }
}

TEST(MeshIo, BadMeshesAreRefusedNamingTheFileAndTheFault) {
  expect_refused("hello world\n", "no faces");
  expect_refused("v 0 0 0\nv 1 0 0\nv 0 1 0\n", "no faces");
  expect_refused("v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n", "area is zero");
  expect_refused("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 2\n", "repeats a vertex");
  expect_refused("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n", "not in the file");
  // Three faces on the edge 1-2.
  expect_refused("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\nf 1 2 3\nf 2 1 4\nf 1 2 5\n",
                 "not a manifold mesh");
  expect_refused("v 0 0 1e999\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "not a finite number");
  // Numbers read whole (tinyobjloader read `1,5` as 1, `1.5` as 1, 4294967297 as 1), by line.
  expect_refused("v 1,5 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "bad.obj:1: `1,5` is not a number");
  expect_refused("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1.5 2 3\n", "bad.obj:4: `1.5` is not a face corner");
  expect_refused("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 4294967297 2 3\n",
                 "bad.obj:4: `4294967297` is not a face corner");
  expect_refused("v 0 0 0\nvt 0 x\nv 1 0 0\nv 0 1 0\nf 1 3 4\n", "bad.obj:2: `x` is not a number");
}

TEST(MeshIo, EveryFaceCornerFormIsRead) {
  const TriangleMesh m = read_obj(
      "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nv 2 0 0\nvt 0 0\nvt 1 0\nvt 0 1\nvn 0 0 1\n"
      "f 1/1/1 2/2/1 3/3/1\nf 2//1 4//1 3//1\nf 2/1 5/2 4/3\n",
      "forms.obj");
  EXPECT_EQ(m.triangles.size(), 3u);
}

TEST(MeshIo, AScenesPathsStayInItsFolder) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / "wetcloth_mesh_io_test";
  fs::remove_all(dir);
  fs::create_directories(dir / "meshes");
  std::ofstream(dir / "meshes" / "quad.obj") << kQuad;
  Params p;
  p.scene_dir = dir.string();
  EXPECT_EQ(load_scene_mesh(p, "cloth.mesh", "meshes/quad.obj").triangles.size(), 2u);
  EXPECT_EQ(load_scene_mesh(p, "cloth.mesh", "meshes/../meshes/quad.obj").triangles.size(), 2u);
  for (const std::string bad : {"../x.obj", "/etc/passwd", "meshes/../../x.obj", ""})
    EXPECT_THROW(resolve_scene_path(p, "cloth.mesh", bad), SceneError) << bad;
  // A symbolic link out of the folder leaves it too.
  fs::create_directory_symlink(fs::temp_directory_path(), dir / "out");
  EXPECT_THROW(resolve_scene_path(p, "cloth.mesh", "out/x.obj"), SceneError);
  try {
    load_scene_mesh(p, "obstacle.bowl.mesh", "meshes/none.obj");
    ADD_FAILURE();
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("obstacle.bowl.mesh"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("no such file"), std::string::npos);
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace wetcloth
