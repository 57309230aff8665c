// Moving obstacles in the outputs (src/io/output.cpp, caches.cpp, study/run.cpp):
// a run's per-frame obstacle OBJs, the obstacles' own point caches, USD's
// time-sampled transforms and VTK's obstacle frames, each read back and
// compared with where the motions have the obstacles at that frame's time;
// a still scene writes none of them.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

#include "common.hpp"
#include "wetcloth/caches.hpp"
#include "wetcloth/output.hpp"
#include "wetcloth/output_folder.hpp"
#include "wetcloth/run.hpp"

namespace wetcloth {
namespace {

namespace fs = std::filesystem;
using test::TempDir;

using test::numbers;
using test::slurp;

// A cloth dropped on the table, 9 x 9, beside a ball that rolls along x (it
// turns about y) and a plate that slides and turns; frames at 0, 0.05, ... 0.2 s.
Params moving_scene(const TempDir& dir, UpAxis up) {
  dir.write("meshes/plate.obj",
            "v -0.1 -0.1 0\nv 0.1 -0.1 0\nv 0.1 0.1 0\nv -0.1 0.1 0\nf 1 2 3\nf 1 3 4\n");
  Params p = load_scene("drop-table",
                        {"cloth.resolution=[9,9]", "cloth.center=[0,0,0.01]", "run.duration=0.2",
                         "run.fps=20", "run.meshes=true", "run.export=\"usd,pc2,vtk\"",
                         "ball.enabled=true", "ball.center=[0.5,0,0.1]", "ball.radius=0.05"});
  p.run.up = up;
  p.ball.motion.keys = {{0, {0, 0, 0}, {0, 0, 0}}, {0.2, {0.1, 0, 0}, {0, 114.59, 0}}};
  p.scene_dir = dir.path.string();
  ObstacleParams o;
  o.mesh = "meshes/plate.obj";
  o.thickness = 0.002;
  o.translate = {0, 0.5, 0.2};
  o.pivot = {0, 0, 0};
  o.motion.interpolation = Interpolation::Smooth;
  o.motion.keys = {{0, {0, 0, 0}, {0, 0, 0}}, {0.2, {0.05, 0.02, 0.03}, {10, 20, 30}}};
  p.obstacles["plate"] = o;
  return p;
}

// Where the motions have each obstacle's points at time t, z up.
std::vector<std::vector<Vec3>> posed(const Params& p, double t) {
  const std::vector<NamedMesh> meshes = obstacle_meshes(p);
  const std::vector<RigidPose> poses = obstacle_poses(p, t);
  std::vector<std::vector<Vec3>> out;
  for (std::size_t k = 0; k < meshes.size(); ++k) {
    out.emplace_back();
    for (const Vec3& x : meshes[k].points) out.back().push_back(poses[k].to_world(x));
  }
  return out;
}

// The frame's time an obstacle OBJ states in its first line.
double stated_time(const std::string& obj) {
  const auto at = obj.find("at t = ");
  return at == std::string::npos ? -1 : std::stod(obj.substr(at + 7));
}

}  // namespace

// frames/obstacles_NNNNN.obj: every obstacle, in obstacles.obj's order, where
// it is at that frame's time; the same vertices and faces every frame.
TEST(MovingOutputs, ObstacleObjFramesFollowTheMotion) {
  TempDir dir("moving_outputs_obj");
  const Params p = moving_scene(dir, UpAxis::Z);
  const fs::path out = dir.path / "run";
  ASSERT_EQ(run_scene(p, out).code, 0);
  const std::vector<NamedMesh> meshes = obstacle_meshes(p);
  ASSERT_EQ(meshes.size(), 3u);  // table, ball, plate
  for (int f = 0; f <= 4; ++f) {
    char name[64];
    std::snprintf(name, sizeof name, "frames/obstacles_%05d.obj", f);
    const std::string obj = slurp(out / name);
    ASSERT_FALSE(obj.empty()) << name;
    const double t = stated_time(obj);
    EXPECT_NEAR(t, 0.05 * f, p.integrator.dt) << name;
    const auto want = posed(p, t);
    std::istringstream in(obj);
    std::size_t k = 0, i = 0, faces = 0;
    for (std::string line; std::getline(in, line);) {
      if (line.rfind("o ", 0) == 0) {
        ASSERT_LT(k, meshes.size());
        EXPECT_EQ(line.substr(2), meshes[k].name);
        i = 0, ++k;
      } else if (line.rfind("v ", 0) == 0) {
        const auto v = numbers(line);
        ASSERT_EQ(v.size(), 3u);
        ASSERT_LT(i, want[k - 1].size());
        // Printed to 6 digits.
        EXPECT_LT((Vec3(v[0], v[1], v[2]) - want[k - 1][i++]).norm(), 1e-5) << name << ": " << line;
      } else if (line.rfind("f ", 0) == 0) {
        ++faces;
      }
    }
    EXPECT_EQ(k, 3u);
    EXPECT_EQ(faces,
              meshes[0].triangles.size() + meshes[1].triangles.size() + meshes[2].triangles.size());
  }
  // obstacles.obj is the first frame's.
  EXPECT_EQ(slurp(out / "obstacles.obj"), slurp(out / "frames/obstacles_00000.obj"));
  // The manifest lists every file the run wrote, the obstacles' too.
  const std::string manifest = slurp(out / kManifest);
  for (const char* file :
       {"frames/obstacles_00004.obj", "obstacle_ball.pc2", "obstacle_ball_rest.obj",
        "obstacle_plate.pc2", "obstacles.pvd", "vtk/obstacles_00004.vtp",
        ".cloth.usda.samples/xform_ball", ".cloth.usda.samples/xform_plate"}) {
    EXPECT_NE(manifest.find(std::string(file) + "\n"), std::string::npos) << file;
    // (USD's samples go once cloth.usda is whole.)
    if (file[0] != '.') {
      EXPECT_TRUE(fs::exists(out / file)) << file;
    }
  }
  EXPECT_EQ(manifest.find("obstacle_table"), std::string::npos);  // the table stands still
}

// obstacle_NAME.pc2 over obstacle_NAME_rest.obj: a moving obstacle's points
// a frame, as floats, y up as the run asks.
TEST(MovingOutputs, ObstaclePointCachesHoldEachFramesPose) {
  TempDir dir("moving_outputs_pc2");
  const Params p = moving_scene(dir, UpAxis::Y);
  const fs::path out = dir.path / "run";
  ASSERT_EQ(run_scene(p, out).code, 0);
  const std::vector<NamedMesh> meshes = obstacle_meshes(p);
  for (const auto& [k, name] : {std::pair{1, "ball"}, {2, "plate"}}) {
    const std::string data = slurp(out / ("obstacle_" + std::string(name) + ".pc2"));
    ASSERT_GE(data.size(), 32u);
    EXPECT_EQ(std::string(data.c_str()), "POINTCACHE2");
    std::int32_t points, samples;
    std::memcpy(&points, data.data() + 16, 4);
    std::memcpy(&samples, data.data() + 28, 4);
    const auto n = static_cast<int>(meshes[k].points.size());
    ASSERT_EQ(points, n);
    ASSERT_EQ(samples, 5);
    ASSERT_EQ(data.size(), 32u + 5u * 12u * static_cast<std::size_t>(n));
    // The rest OBJ: one object, its vertices and faces in the cache's order.
    const std::string rest = slurp(out / ("obstacle_" + std::string(name) + "_rest.obj"));
    int vertices = 0;
    std::istringstream lines(rest);
    for (std::string line; std::getline(lines, line);) vertices += line.rfind("v ", 0) == 0;
    EXPECT_EQ(vertices, n) << name;
    for (int f = 0; f <= 4; ++f) {
      const double t =
          stated_time(slurp(out / ("frames/obstacles_0000" + std::to_string(f) + ".obj")));
      const auto want = posed(p, t)[k];
      for (int i = 0; i < n; ++i) {
        float x[3];
        std::memcpy(x, data.data() + 32 + (static_cast<std::size_t>(f) * n + i) * 12, 12);
        const Vec3 up = to_up(want[i], UpAxis::Y);
        for (int q = 0; q < 3; ++q) ASSERT_EQ(x[q], static_cast<float>(up[q])) << name << " " << f;
      }
    }
  }
}

// USD: a moving obstacle's Mesh keeps its points and gains a time-sampled
// xformOp:transform, one sample a frame, that carries them where the motion
// has them (row vectors times the matrix); a still one has none.
TEST(MovingOutputs, UsdMovesObstaclesByTimeSampledTransforms) {
  for (const UpAxis up : {UpAxis::Z, UpAxis::Y}) {
    TempDir dir("moving_outputs_usd");
    const Params p = moving_scene(dir, up);
    const fs::path out = dir.path / "run";
    ASSERT_EQ(run_scene(p, out).code, 0);
    const std::string usd = slurp(out / "cloth.usda");
    int depth = 0;
    for (char c : usd) {
      depth += c == '{' || c == '[' || c == '(';
      depth -= c == '}' || c == ']' || c == ')';
      ASSERT_GE(depth, 0);
    }
    EXPECT_EQ(depth, 0);
    const auto prim = [&](const std::string& name) {
      const auto at = usd.find("def Mesh \"" + name + "\"");
      EXPECT_NE(at, std::string::npos) << name;
      return usd.substr(at, usd.find("\n    }\n", at) - at);
    };
    EXPECT_EQ(prim("table").find("xformOp"), std::string::npos);
    const std::vector<NamedMesh> meshes = obstacle_meshes(p);
    for (const auto& [k, name] : {std::pair{1, "ball"}, {2, "plate"}}) {
      const std::string text = prim(name);
      EXPECT_NE(text.find("uniform token[] xformOpOrder = [\"xformOp:transform\"]"),
                std::string::npos);
      const auto pa = text.find("point3f[] points = [");
      const auto rest = numbers(text.substr(pa + 20, text.find(']', pa + 20) - pa - 20));
      ASSERT_EQ(rest.size(), 3 * meshes[k].points.size());
      const auto xa = text.find("matrix4d xformOp:transform.timeSamples = {");
      ASSERT_NE(xa, std::string::npos) << name;
      std::istringstream block(text.substr(xa, text.find("        }\n", xa) - xa));
      std::string line;
      std::getline(block, line);
      for (int f = 0; f <= 4; ++f) {
        ASSERT_TRUE(std::getline(block, line));
        const auto v = numbers(line);
        ASSERT_EQ(v.size(), 17u) << line;
        EXPECT_EQ(v[0], f);  // the frame's number, as the cloth's samples
        Eigen::Matrix4d M;
        for (int r = 0; r < 4; ++r)
          for (int c = 0; c < 4; ++c) M(r, c) = v[1 + 4 * r + c];
        const double t =
            stated_time(slurp(out / ("frames/obstacles_0000" + std::to_string(f) + ".obj")));
        const auto want = posed(p, t)[k];
        for (std::size_t i = 0; i < want.size(); i += 7) {
          const Eigen::RowVector4d x(rest[3 * i], rest[3 * i + 1], rest[3 * i + 2], 1);
          const Eigen::RowVector4d y = x * M;
          EXPECT_LT((y.head<3>().transpose() - to_up(want[i], up)).norm(), 1e-6)
              << name << " frame " << f;
        }
      }
      EXPECT_FALSE(std::getline(block, line));
    }
  }
}

// VTK: vtk/obstacles_NNNNN.vtp a frame, in obstacles.pvd with the cloth's times.
TEST(MovingOutputs, VtkWritesTheObstaclesAFrame) {
  TempDir dir("moving_outputs_vtk");
  const Params p = moving_scene(dir, UpAxis::Z);
  const fs::path out = dir.path / "run";
  ASSERT_EQ(run_scene(p, out).code, 0);
  const std::string pvd = slurp(out / "obstacles.pvd"), cloth = slurp(out / "cloth.pvd");
  std::size_t points = 0;
  for (const NamedMesh& m : obstacle_meshes(p)) points += m.points.size();
  for (int f = 0; f <= 4; ++f) {
    char name[64];
    std::snprintf(name, sizeof name, "vtk/obstacles_%05d.vtp", f);
    EXPECT_NE(pvd.find(std::string("file=\"") + name + "\""), std::string::npos) << name;
    EXPECT_NE(slurp(out / name).find("NumberOfPoints=\"" + std::to_string(points) + "\""),
              std::string::npos);
  }
  // The same times as the cloth's frames.
  EXPECT_EQ(numbers(pvd), numbers(cloth));
}

// A scene whose obstacles stand still writes no obstacle frames, and its
// obstacles.obj says no time.
TEST(MovingOutputs, StillObstaclesWriteNoFrames) {
  TempDir dir("moving_outputs_still");
  Params p = moving_scene(dir, UpAxis::Z);
  p.ball.motion = Motion{};
  p.obstacles["plate"].motion = Motion{};
  EXPECT_FALSE(obstacles_move(p));
  EXPECT_TRUE(moving_obstacle_files(p).empty());
  const fs::path out = dir.path / "run";
  ASSERT_EQ(run_scene(p, out).code, 0);
  for (const char* file : {"frames/obstacles_00000.obj", "obstacles.pvd", "obstacle_ball.pc2",
                           "vtk/obstacles_00000.vtp"})
    EXPECT_FALSE(fs::exists(out / file)) << file;
  const std::string obj = slurp(out / "obstacles.obj");
  EXPECT_EQ(obj.rfind("# wetcloth obstacles, z up, metres\n", 0), 0u);
  EXPECT_EQ(slurp(out / "cloth.usda").find("xformOp"), std::string::npos);
}

}  // namespace wetcloth

namespace wetcloth {
namespace {

// A plate whose far corner rises, by a PC2 cache (float32) of 7 frames at
// 24 fps, under a cloth dropped on the table: frames at 24 fps too.
Params deforming_scene(const TempDir& dir) {
  dir.write("meshes/plate.obj",
            "v -0.1 -0.1 0\nv 0.1 -0.1 0\nv 0.1 0.1 0\nv -0.1 0.1 0\nf 1 2 3\nf 1 3 4\n");
  std::string pc2("POINTCACHE2\0", 12);
  const auto put = [&](const auto v) { pc2.append(reinterpret_cast<const char*>(&v), sizeof v); };
  put(std::int32_t{1}), put(std::int32_t{4}), put(0.0f), put(1.0f), put(std::int32_t{7});
  for (int k = 0; k < 7; ++k)
    for (const auto& [x, y] : {std::pair{-0.1f, -0.1f}, {0.1f, -0.1f}, {0.1f, 0.1f}, {-0.1f, 0.1f}})
      put(x), put(y), put(x > 0 && y > 0 ? 0.01f * static_cast<float>(k) : 0.0f);
  dir.write("meshes/plate.pc2", pc2);
  Params p = load_scene("drop-table",
                        {"cloth.resolution=[9,9]", "cloth.center=[0,0,0.01]", "run.duration=0.25",
                         "run.fps=24", "run.meshes=true", "run.export=\"usd,pc2,vtk\""});
  p.scene_dir = dir.path.string();
  ObstacleParams o;
  o.mesh = "meshes/plate.obj";
  o.thickness = 0.002;
  o.translate = {0, 0.5, 0.2};
  o.cache = "meshes/plate.pc2";
  p.obstacles["plate"] = o;
  return p;
}

// The cache's point i at time t (straight between its frames), placed
// (translate), as the outputs have it.
Vec3 cached_point(double t, int i) {
  const float x = i == 1 || i == 2 ? 0.1f : -0.1f, y = i >= 2 ? 0.1f : -0.1f;
  const double s = std::clamp(t * 24, 0.0, 6.0);
  const int k = std::min(static_cast<int>(s), 5);
  const double z0 = 0.01f * static_cast<float>(k), z1 = 0.01f * static_cast<float>(k + 1);
  const double z = i == 2 ? z0 + (s - k) * (z1 - z0) : 0.0;
  return Vec3(x, y, z) + Vec3(0, 0.5, 0.2);
}

}  // namespace

// A deforming obstacle's outputs carry its shape each frame: obstacle_NAME.pc2
// the cache's points (frame k at the cache's frame k: the same fps), the
// frames' OBJs the same, USD time-sampled points and no transform, VTK a
// frame each; scene.toml names the cache copied to OUT/caches/.
TEST(MovingOutputs, DeformingObstacleOutputsCarryTheCachesPoints) {
  TempDir dir("moving_outputs_deform");
  const Params p = deforming_scene(dir);
  EXPECT_TRUE(obstacles_move(p));
  EXPECT_EQ(moving_obstacle_files(p), std::vector<std::string>{"plate"});
  EXPECT_EQ(obstacle_usd_samples(p), std::vector<std::string>{"points_plate"});
  const fs::path out = dir.path / "run";
  ASSERT_EQ(run_scene(p, out).code, 0);
  const std::string data = slurp(out / "obstacle_plate.pc2");
  std::int32_t points, samples;
  ASSERT_GE(data.size(), 32u);
  std::memcpy(&points, data.data() + 16, 4);
  std::memcpy(&samples, data.data() + 28, 4);
  ASSERT_EQ(points, 4);
  ASSERT_EQ(samples, 7);  // 0, 1/24, ... 0.25 s
  for (int f = 0; f < 7; ++f) {
    char name[64];
    std::snprintf(name, sizeof name, "frames/obstacles_%05d.obj", f);
    const std::string obj = slurp(out / name);
    const double t = stated_time(obj);
    EXPECT_NEAR(t, f / 24.0, 1e-4) << name;  // (the step that ends nearest)
    const auto v = numbers(obj.substr(obj.find("o plate")));
    for (int i = 0; i < 4; ++i) {
      float x[3];
      std::memcpy(x, data.data() + 32 + (static_cast<std::size_t>(f) * 4 + i) * 12, 12);
      const Vec3 want = cached_point(t, i);
      for (int q = 0; q < 3; ++q) {
        EXPECT_NEAR(x[q], want[q], 1e-6) << "pc2 frame " << f << " point " << i;
        EXPECT_NEAR(v[3 * i + q], want[q], 1e-5) << name << " point " << i;
      }
    }
  }
  const std::string usd = slurp(out / "cloth.usda");
  const auto at = usd.find("def Mesh \"plate\"");
  ASSERT_NE(at, std::string::npos);
  const std::string prim = usd.substr(at, usd.find("\n    }\n", at) - at);
  EXPECT_EQ(prim.find("xformOp"), std::string::npos);
  const auto samples_at = prim.find("point3f[] points.timeSamples = {");
  ASSERT_NE(samples_at, std::string::npos);
  std::istringstream block(prim.substr(samples_at));
  std::string line;
  std::getline(block, line);
  for (int f = 0; f < 7; ++f) {
    ASSERT_TRUE(std::getline(block, line));
    const auto v = numbers(line);
    ASSERT_EQ(v.size(), 13u) << line;
    EXPECT_EQ(v[0], f);
    char name[64];
    std::snprintf(name, sizeof name, "frames/obstacles_%05d.obj", f);
    const double t = stated_time(slurp(out / name));
    EXPECT_NEAR(v[1 + 3 * 2 + 2], cached_point(t, 2).z(), 1e-6) << line;
  }
  for (int f = 0; f < 7; ++f) {
    char name[64];
    std::snprintf(name, sizeof name, "vtk/obstacles_%05d.vtp", f);
    EXPECT_TRUE(fs::exists(out / name)) << name;
  }
  const std::string manifest = slurp(out / kManifest);
  for (const char* file : {"obstacle_plate.pc2", ".cloth.usda.samples/points_plate",
                           "caches/plate.pc2", "meshes/plate.obj"})
    EXPECT_NE(manifest.find(std::string(file) + "\n"), std::string::npos) << file;
  EXPECT_EQ(slurp(out / "caches/plate.pc2"), slurp(dir.path / "meshes/plate.pc2"));
  EXPECT_NE(slurp(out / "scene.toml").find("cache = \"caches/plate.pc2\""), std::string::npos);
}

}  // namespace wetcloth
