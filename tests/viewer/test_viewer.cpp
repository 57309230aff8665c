// The viewer and the offscreen renderer, end to end: `wetcloth render` writes
// pictures of the cloth that are lit and that change with the physics, `wetcloth
// view` opens a window under Xvfb and saves a screenshot with its panel, and the
// sweep's contact sheet puts labelled tiles side by side.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "viewer/coloring.hpp"
#include "viewer/commands.hpp"
#include "viewer/draw.hpp"
#include "viewer/integrator_step.hpp"
#include "wetcloth/motion.hpp"
#include "wetcloth/scene.hpp"
#include "wetcloth/simulation.hpp"

#define STB_IMAGE_STATIC
#define STB_IMAGE_IMPLEMENTATION
#include <stb/stb_image.h>

namespace fs = std::filesystem;

namespace {

const fs::path kCli = WETCLOTH_CLI;
const fs::path kOut = VIEWER_TEST_OUT;

// A fresh folder for one test's outputs.
fs::path fresh(const std::string& name) {
  const fs::path d = kOut / name;
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

// Runs the wetcloth program with these arguments (shell syntax); its exit code.
int run_cli(const std::string& args) {
  const std::string cmd = "'" + kCli.string() + "' " + args;
  const int status = std::system(cmd.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

struct Picture {
  int width = 0, height = 0;
  std::vector<unsigned char> rgb;
  const unsigned char* at(int x, int y) const {
    return &rgb[(static_cast<std::size_t>(y) * width + x) * 3];
  }
  double luma(int x, int y) const {
    const auto* p = at(x, y);
    return 0.299 * p[0] + 0.587 * p[1] + 0.114 * p[2];
  }
};

Picture load(const fs::path& png) {
  Picture p;
  int channels = 0;
  unsigned char* data = stbi_load(png.c_str(), &p.width, &p.height, &channels, 3);
  if (data) {
    p.rgb.assign(data, data + static_cast<std::size_t>(p.width) * p.height * 3);
    stbi_image_free(data);
  }
  return p;
}

// The cloth's own colour is the only blue thing in a picture (sky, ground and
// table are neutral or warm).
bool cloth_blue(const unsigned char* p) { return p[2] > p[0] + 40 && p[2] > p[1] + 10; }
// The contact colouring's orange (kContactColor).
bool contact_orange(const unsigned char* p) { return p[0] > p[2] + 80 && p[0] > 150; }

template <class Pred>
std::vector<double> luma_where(const Picture& pic, Pred pred) {
  std::vector<double> v;
  for (int y = 0; y < pic.height; ++y)
    for (int x = 0; x < pic.width; ++x)
      if (pred(pic.at(x, y))) v.push_back(pic.luma(x, y));
  return v;
}

double stddev(const std::vector<double>& v) {
  if (v.size() < 2) return 0;
  double mean = 0, sq = 0;
  for (double x : v) mean += x;
  mean /= v.size();
  for (double x : v) sq += (x - mean) * (x - mean);
  return std::sqrt(sq / (v.size() - 1));
}

// A short pull on a coarse cloth: fast, and the tent has started to rise.
const std::string kPull =
    "pull-straight --duration 0.5 --fps 10 --set 'cloth.resolution=[25,25]' --quiet";

}  // namespace

TEST(Render, ClothCoversAPlausibleShareAndIsLit) {
  const fs::path out = fresh("lit");
  ASSERT_EQ(run_cli("render " + kPull + " --size 480x270 --out '" + out.string() + "'"), 0);
  for (int f = 0; f <= 5; ++f) {  // 0.5 s at 10 fps: frames 0 to 5
    char name[32];
    std::snprintf(name, sizeof name, "frame_%05d.png", f);
    EXPECT_TRUE(fs::exists(out / name)) << name;
  }
  EXPECT_FALSE(fs::exists(out / "frame_00006.png"));

  const Picture pic = load(out / "frame_00005.png");
  ASSERT_EQ(pic.width, 480);
  ASSERT_EQ(pic.height, 270);
  const auto cloth = luma_where(pic, cloth_blue);
  const double share = static_cast<double>(cloth.size()) / (pic.width * pic.height);
  EXPECT_GT(share, 0.05) << "the cloth should fill a fair part of the frame";
  EXPECT_LT(share, 0.70) << "the table and the sky should show around the cloth";
  // Lit, not flat: the tent's flanks and the folds differ in brightness.
  auto sorted = cloth;
  std::sort(sorted.begin(), sorted.end());
  const double spread = sorted[sorted.size() * 95 / 100] - sorted[sorted.size() * 5 / 100];
  std::printf("cloth share %.3f, brightness stddev %.1f, 5-95%% spread %.1f\n", share,
              stddev(cloth), spread);
  EXPECT_GT(stddev(cloth), 3.0);
  EXPECT_GT(spread, 10.0) << "5th to 95th percentile of brightness over the cloth";
}

TEST(Render, HumidityChangesThePicture) {
  // Coloured by contact: the wetter cloth clings to more of the table (eq. 13),
  // and the colours show it without the fabric's wet tint getting in the way.
  std::vector<Picture> pics;
  for (const char* w : {"0.3", "1.0"}) {
    const fs::path out = fresh(std::string("humidity-") + w);
    ASSERT_EQ(run_cli("render " + kPull + " --humidity " + w +
                      " --color contact --size 480x270 --out '" + out.string() + "'"),
              0);
    pics.push_back(load(out / "frame_00005.png"));
    ASSERT_EQ(pics.back().width, 480);
  }
  const auto dry = luma_where(pics[0], contact_orange), wet = luma_where(pics[1], contact_orange);
  std::printf("pixels in contact: %zu at humidity 0.3, %zu at 1.0\n", dry.size(), wet.size());
  EXPECT_GT(dry.size(), 500u);
  EXPECT_GT(wet.size(), dry.size() * 1.1) << "more of the wet cloth in contact";

  double diff = 0;
  for (std::size_t i = 0; i < pics[0].rgb.size(); ++i)
    diff += std::abs(pics[0].rgb[i] - pics[1].rgb[i]);
  diff /= pics[0].rgb.size();
  std::printf("mean absolute difference %.2f\n", diff);
  EXPECT_GT(diff, 0.5) << "mean absolute difference per channel";
}

TEST(Render, DefaultPictureShowsWhereTheClothTouches) {
  // The same run drawn twice: coloured by contact, which says where the cloth
  // touches, and in the default fabric look, where those parts must show
  // darker (a wet patch's look), though they lie flat in the light. Before the
  // look followed contact they were 2.5 % darker than the rest of the cloth.
  const fs::path look = fresh("touch-look"), contact = fresh("touch-contact");
  const std::string args = "render " + kPull + " --humidity 0.7 --size 480x270 --out ";
  ASSERT_EQ(run_cli(args + "'" + look.string() + "'"), 0);
  ASSERT_EQ(run_cli(args + "'" + contact.string() + "' --color contact"), 0);
  const Picture a = load(look / "frame_00005.png"), c = load(contact / "frame_00005.png");
  ASSERT_EQ(a.width, c.width);
  double on = 0, off = 0;
  std::size_t n_on = 0, n_off = 0;
  for (int y = 0; y < a.height; ++y)
    for (int x = 0; x < a.width; ++x) {
      if (!cloth_blue(a.at(x, y))) continue;
      if (contact_orange(c.at(x, y)))
        on += a.luma(x, y), ++n_on;
      else
        off += a.luma(x, y), ++n_off;
    }
  ASSERT_GT(n_on, 1000u);
  ASSERT_GT(n_off, 1000u);
  std::printf("cloth brightness: %.1f touching (%zu px), %.1f free (%zu px)\n", on / n_on, n_on,
              off / n_off, n_off);
  EXPECT_LT(on / n_on, 0.9 * off / n_off);
}

TEST(FabricLook, WaterDarkensAndGlossesMoreWhereTheClothTouches) {
  using wetcloth::viewer::fabric_look;
  const auto luma = [](const wetcloth::viewer::Vec3f& c) { return c.squaredNorm(); };
  EXPECT_EQ(fabric_look(0, 0).gloss, 0.0f);  // dry cloth is matt, touching or not
  EXPECT_EQ(fabric_look(0, 1).gloss, 0.0f);
  for (float w : {0.0f, 0.3f, 0.7f, 1.0f}) {
    EXPECT_LT(luma(fabric_look(w, 1).color), luma(fabric_look(w, 0).color)) << w;
    EXPECT_GE(fabric_look(w, 1).gloss, fabric_look(w, 0).gloss) << w;
  }
  EXPECT_LT(luma(fabric_look(1, 0).color), luma(fabric_look(0.3f, 0).color));
  EXPECT_GT(fabric_look(0.5f, 1).gloss, fabric_look(0.5f, 0).gloss);
}

TEST(Render, VideoThroughFfmpeg) {
  const fs::path out = fresh("video");
  ASSERT_EQ(run_cli("render pull-straight --duration 0.1 --fps 20 --set 'cloth.resolution=[11,11]' "
                    "--size 161x91 "
                    "--video --quiet --out '" +
                    out.string() + "'"),
            0);
  EXPECT_TRUE(fs::exists(out / "frame_00002.png"));
  ASSERT_TRUE(fs::exists(out / "video.mp4"));
  EXPECT_GT(fs::file_size(out / "video.mp4"), 1000u);
}

TEST(Render, BadInputExitsWithTwoAndWritesNothing) {
  const fs::path out = kOut / "bad";
  fs::remove_all(out);
  EXPECT_EQ(run_cli("render no-such-scene --out '" + out.string() + "' 2>/dev/null"), 2);
  EXPECT_EQ(
      run_cli("render pull-straight --set no.such.key=1 --out '" + out.string() + "' 2>/dev/null"),
      2);
  EXPECT_EQ(run_cli("render pull-straight --humidity 7 --out '" + out.string() + "' 2>/dev/null"),
            2);
  EXPECT_EQ(run_cli("render pull-straight --fps 0 --out '" + out.string() + "' 2>/dev/null"), 2);
  EXPECT_FALSE(fs::exists(out));
}

TEST(Render, OutputsAreCheckedBeforeTheSimulation) {
  // A folder that cannot be made, a screenshot into one, and --video without
  // ffmpeg: bad input (2), found before simulating, nothing left behind.
  EXPECT_EQ(run_cli("render hang --duration 0.05 --out /proc/nope 2>/dev/null"), 2);
  EXPECT_EQ(run_cli("view hang --screenshot-after 0.05 /proc/nope/x.png 2>/dev/null"), 2);
  const fs::path out = kOut / "no-ffmpeg";
  fs::remove_all(out);
  const std::string cmd = "PATH=/nonexistent '" + kCli.string() +
                          "' render hang --duration 0.05 --video --out '" + out.string() +
                          "' 2>/dev/null";
  const int status = std::system(cmd.c_str());
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 2);
  EXPECT_FALSE(fs::exists(out));
}

TEST(View, ScreenshotUnderXvfbShowsTheSceneAndThePanel) {
  const fs::path out = fresh("view");
  const fs::path shot = out / "viewer.png";
  const std::string cmd = "xvfb-run -a -s '-screen 0 1280x800x24' '" + kCli.string() +
                          "' view --screenshot-after 0.05 '" + shot.string() + "' > '" +
                          (out / "stdout.txt").string() + "' 2> '" + (out / "stderr.txt").string() +
                          "'";
  const int status = std::system(cmd.c_str());
  ASSERT_TRUE(WIFEXITED(status));
  ASSERT_EQ(WEXITSTATUS(status), 0) << "xvfb-run or the viewer failed";
  ASSERT_TRUE(fs::exists(shot));

  const Picture pic = load(shot);
  ASSERT_EQ(pic.width, 1280);
  ASSERT_EQ(pic.height, 720);
  std::vector<double> all;
  for (int y = 0; y < pic.height; y += 4)
    for (int x = 0; x < pic.width; x += 4) all.push_back(pic.luma(x, y));
  EXPECT_GT(stddev(all), 10.0) << "not blank";
  EXPECT_GT(luma_where(pic, cloth_blue).size(), 20000u) << "the cloth is in the picture";

  // The panel: ImGui's near-black window at the top left (the scene is never that dark).
  int dark = 0, total = 0;
  for (int y = 40; y < 400; y += 2)
    for (int x = 20; x < 390; x += 2, ++total) {
      const auto* p = pic.at(x, y);
      dark += p[0] < 40 && p[1] < 40 && p[2] < 40;
    }
  EXPECT_GT(dark, total / 2) << "the panel is visible";

  // The whole run's real-time factor, the one the panel shows: not the 0 of
  // the last frames, which step nothing.
  std::ifstream err(out / "stderr.txt");
  std::string line, last;
  while (std::getline(err, line))
    if (line.rfind("wetcloth view: t = ", 0) == 0) last = line;
  ASSERT_NE(last.find("s simulated in"), std::string::npos) << last;
  const double factor = std::stod(last.substr(last.rfind(", ") + 2));
  EXPECT_GT(factor, 0.0) << last;
}

// An integrator picked in the panel gets a step of its kind: the large-step
// ones 1/240 s from a small-step scene (at 5e-5 s xpbd would take ten
// substeps where one is too many), the small-step ones 5e-5 s from a
// large-step scene; a step of the scene's own kind stays. The step picked
// runs: xpbd takes the straight pull 0.05 s in 12 steps.
// The stage follows the moving obstacles: the ball and each mesh part are
// drawn where their motions have them at the cloth's time (the viewer and
// the render pose it each frame); a still scene keeps its stage as it was.
TEST(Stage, MovingObstaclesArePosedAtTheClothsTime) {
  using namespace wetcloth;
  using viewer::pose_stage;
  const Params roll = load_scene("ball-roll");
  viewer::Stage s = viewer::stage_from(roll);
  EXPECT_LT((s.ball_center - Eigen::Vector3f(0, 0, 0.1f)).norm(), 1e-6f);
  pose_stage(s, roll, 1.6);
  EXPECT_TRUE(s.ball_moves);
  EXPECT_LT((s.ball_center - Eigen::Vector3f(0.12f, 0, 0.1f)).norm(), 1e-6f);
  EXPECT_LT((s.ball_rotation - ball_pose(roll, 1.6).rotation.cast<float>()).norm(), 1e-6f);
  EXPECT_NEAR(std::acos(s.ball_rotation(0, 0)), 1.2, 1e-5);  // 0.12 m / 0.1 m rolled

  const Params swing = load_scene("arm-swing");
  viewer::Stage arm = viewer::stage_from(swing);
  ASSERT_TRUE(arm.obstacles);
  ASSERT_EQ(arm.obstacles->parts.size(), 1u);
  EXPECT_EQ(arm.obstacles->parts[0].name, "arm");
  for (const double t : {0.5, 1.2}) {
    pose_stage(arm, swing, t);
    ASSERT_EQ(arm.obstacle_models.size(), 1u);
    const RigidPose pose = obstacle_pose(swing, "arm", t);
    for (std::size_t k = 0; k < arm.obstacles->position.size(); k += 97) {
      const Eigen::Vector3f x = arm.obstacles->position[k];
      const Eigen::Vector3f drawn = (arm.obstacle_models[0] * x.homogeneous()).head<3>();
      EXPECT_LT((drawn - pose.to_world(x.cast<double>()).cast<float>()).norm(), 1e-5f) << t;
      EXPECT_TRUE(((drawn.array() >= arm.obstacles_lo.array() - 1e-5f) &&
                   (drawn.array() <= arm.obstacles_hi.array() + 1e-5f))
                      .all());
    }
  }
  const Params still = load_scene("drape-ball");
  viewer::Stage d = viewer::stage_from(still);
  pose_stage(d, still, 1.0);
  EXPECT_FALSE(d.ball_moves);
  EXPECT_EQ(d.ball_rotation, Eigen::Matrix3f::Identity());
}

// A deforming obstacle (obstacle.NAME.cache) is drawn in its shape at the
// cloth's time: pose_stage gives the stage a new shape (a new serial, so the
// renderer uploads it again), its box grown with it.
TEST(Stage, DeformingObstaclesAreDrawnInTheirShapeAtTheClothsTime) {
  using namespace wetcloth;
  namespace fs = std::filesystem;
  const fs::path dir =
      fs::temp_directory_path() / ("wetcloth_stage_deform_" + std::to_string(::getpid()));
  fs::create_directories(dir / "meshes");
  const auto plate = [](double z) {
    return "v -0.5 -0.5 0\nv 0.5 -0.5 0\nv 0.5 0.5 " + std::to_string(z) +
           "\nv -0.5 0.5 0\nf 1 2 3\nf 1 3 4\n";
  };
  std::ofstream(dir / "meshes/plate.obj") << plate(0);
  std::ofstream(dir / "meshes/plate_1.obj") << plate(0);
  std::ofstream(dir / "meshes/plate_2.obj") << plate(0.1);
  std::ofstream(dir / "s.toml")
      << "[cloth]\ncenter = [0, 0, 0.3]\n[table]\nenabled = false\n[contact]\nsurface = "
         "\"none\"\n[obstacle.plate]\nmesh = \"meshes/plate.obj\"\nthickness = 0.002\n"
         "cache = \"meshes/plate_#.obj\"\ncache_fps = 24\n";
  const Params p = load_scene((dir / "s.toml").string());
  viewer::Stage s = viewer::stage_from(p);
  ASSERT_TRUE(s.obstacles);
  EXPECT_TRUE(s.obstacles->deforms);
  EXPECT_NEAR(s.obstacles->position[2].z(), 0.0f, 1e-7f);
  const auto before = s.obstacles->serial;
  viewer::pose_stage(s, p, 1.0 / 48);  // half way: 5 cm up
  EXPECT_NE(s.obstacles->serial, before);
  EXPECT_NEAR(s.obstacles->position[2].z(), 0.05f, 1e-6f);
  EXPECT_NEAR(s.obstacles_hi.z(), 0.05f, 1e-6f);
  viewer::pose_stage(s, p, 5.0);  // held at the last frame
  EXPECT_NEAR(s.obstacles->position[2].z(), 0.1f, 1e-6f);
  EXPECT_NEAR(s.obstacles->position[0].z(), 0.0f, 1e-7f);
  fs::remove_all(dir);
}

TEST(Panel, AnIntegratorPickedGetsAStepOfItsKind) {
  using wetcloth::IntegratorType;
  using wetcloth::viewer::step_for_integrator;
  const wetcloth::Params pull = wetcloth::load_scene("pull-straight");
  const wetcloth::Params sleeve = wetcloth::load_scene("sleeve-pull");
  ASSERT_EQ(pull.integrator.type, IntegratorType::SymplecticEuler);
  ASSERT_EQ(sleeve.integrator.type, IntegratorType::Xpbd);
  const auto from = [](const wetcloth::Params& p, IntegratorType picked) {
    wetcloth::Params q = p;
    q.integrator.type = picked;
    return step_for_integrator(q, p.integrator.type, p.integrator.dt);
  };
  EXPECT_EQ(from(pull, IntegratorType::Xpbd), 1.0 / 240);
  EXPECT_EQ(from(pull, IntegratorType::ImplicitEuler), 1.0 / 240);
  EXPECT_EQ(from(pull, IntegratorType::ExplicitEuler), pull.integrator.dt);
  EXPECT_EQ(from(sleeve, IntegratorType::SymplecticEuler), 1e-4);  // a mesh cloth
  EXPECT_EQ(from(sleeve, IntegratorType::ImplicitEuler), sleeve.integrator.dt);

  wetcloth::Params p = pull;
  p.integrator.type = IntegratorType::Xpbd;
  p.integrator.dt = from(pull, p.integrator.type);
  wetcloth::Simulation sim(p);
  ASSERT_TRUE(sim.advance_to(0.05)) << sim.blow_up_reason();
  EXPECT_EQ(sim.state().steps, 12);
}

TEST(ContactSheet, LabelledTilesSideBySide) {
  const fs::path out = fresh("sheet");
  std::vector<std::pair<std::string, fs::path>> cases;
  for (const char* w : {"0.2", "1.0"}) {
    const fs::path dir = out / (std::string("w") + w);
    ASSERT_EQ(
        run_cli(
            "run pull-straight --duration 0.1 --set 'cloth.resolution=[15,15]' --set run.fps=20 "
            "--humidity " +
            std::string(w) + " --quiet --out '" + dir.string() + "'"),
        0);
    cases.push_back({std::string("\xCF\x89 = ") + w, dir});  // ω
  }
  std::string error;
  const fs::path png = out / "sheet.png";
  ASSERT_TRUE(wetcloth::viewer::render_contact_sheet(cases, png, 320, 200, &error)) << error;
  const Picture pic = load(png);
  ASSERT_EQ(pic.width, 640);
  ASSERT_EQ(pic.height, 200);
  for (int tile = 0; tile < 2; ++tile) {
    int cloth = 0, white = 0;
    for (int y = 0; y < 200; ++y)
      for (int x = tile * 320; x < (tile + 1) * 320; ++x) {
        const auto* p = pic.at(x, y);
        cloth += cloth_blue(p);
        white += y < 40 && x < tile * 320 + 160 && p[0] == 255 && p[1] == 255 && p[2] == 255;
      }
    EXPECT_GT(cloth, 2000) << "tile " << tile;
    EXPECT_GT(white, 30) << "tile " << tile << " has its label";
  }

  EXPECT_FALSE(wetcloth::viewer::render_contact_sheet({{"missing", out / "nothing-here"}},
                                                      out / "x.png", 320, 200, &error));
  EXPECT_NE(error.find("missing"), std::string::npos) << error;
  EXPECT_FALSE(fs::exists(out / "x.png"));
}
