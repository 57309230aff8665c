// Animation caches (src/io/caches.cpp): each read back by the rules of its format
// and compared with the simulation's own positions and fields at each frame;
// and metrics.csv's rows (src/io/output.cpp).
#include <gtest/gtest.h>
#include <zlib.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

#include "common.hpp"
#include "wetcloth/caches.hpp"
#include "wetcloth/output.hpp"

namespace wetcloth {
namespace {

namespace fs = std::filesystem;

using test::numbers;
using test::slurp;

// A damp cloth dropped on the table, 9 x 9, with frames at 0, 0.05, ... 0.2 s.
struct CachedRun {
  fs::path dir;
  std::vector<CacheFrame> frames;  // the simulation's own, z up
  std::vector<std::array<int, 3>> triangles;
};

CachedRun run_with_caches(const std::string& name, UpAxis up) {
  CachedRun r;
  r.dir = fs::temp_directory_path() / ("wetcloth_caches_" + name);
  fs::remove_all(r.dir);
  fs::create_directories(r.dir);
  Simulation sim(load_scene("drop-table", {"cloth.resolution=[9,9]", "cloth.center=[0,0,0.01]"}));
  r.triangles = sim.model().triangles;
  CacheWriter caches(r.dir, sim, parse_export_formats("usd,pc2,vtk"), up, 20);
  for (int f = 0; f <= 4; ++f) {
    EXPECT_TRUE(sim.advance_to(0.05 * f));
    caches.add_frame(sim);
    r.frames.push_back(cache_frame(sim, UpAxis::Z));
  }
  caches.finish();
  return r;
}

TEST(Caches, ExportListIsParsedAndAnUnknownFormatNamed) {
  const ExportFormats f = parse_export_formats("vtk, usd");
  EXPECT_TRUE(f.usd && f.vtk && !f.pc2);
  EXPECT_FALSE(parse_export_formats("").any());
  try {
    parse_export_formats("usd,abc");
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("'abc'"), std::string::npos);
  }
  try {
    load_scene("drop-table", {"run.export=usd,alembic"});
    FAIL();
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("run.export"), std::string::npos) << e.what();
  }
}

// The humidity field per vertex: cloth_fields.pc2 (ω, contact, deficit) a
// frame, and USD's primvars:humidity an array a frame.
TEST(Caches, Pc2SideFileAndUsdHoldEachVertexsHumidity) {
  const fs::path dir = fs::temp_directory_path() / "wetcloth_caches_humidity";
  fs::remove_all(dir);
  fs::create_directories(dir);
  Params p = load_scene("drop-table", {"cloth.resolution=[9,9]", "cloth.center=[0,0,0.01]"});
  p.wet["spot"] = {{0.25, 0.25}, 0.05, 1.0};
  Simulation sim(p);
  std::vector<CacheFrame> frames;
  {
    CacheWriter caches(dir, sim, parse_export_formats("usd,pc2"), UpAxis::Z, 20);
    for (int f = 0; f <= 2; ++f) {
      EXPECT_TRUE(sim.advance_to(0.05 * f));
      caches.add_frame(sim);
      frames.push_back(cache_frame(sim, UpAxis::Z));
    }
    caches.finish();
  }
  const std::string data = slurp(dir / "cloth_fields.pc2");
  ASSERT_EQ(data.size(), 32u + 3u * 81u * 12u);
  EXPECT_EQ(std::string(data.c_str()), "POINTCACHE2");
  bool varies = false;
  for (int f = 0; f < 3; ++f)
    for (int i = 0; i < 81; ++i) {
      float v[3];
      std::memcpy(v, data.data() + 32 + (f * 81 + i) * 12, 12);
      EXPECT_EQ(v[0], frames[f].humidity[i]);
      EXPECT_EQ(v[1], frames[f].contact[i]);
      EXPECT_EQ(v[2], static_cast<float>(p.air.p_atm - frames[f].pressure[i]));
      varies = varies || v[0] != frames[f].humidity[0];
    }
  EXPECT_TRUE(varies);
  EXPECT_EQ(frames[2].humidity[0], static_cast<float>(sim.state().humidity[0]));
  const std::string usd = slurp(dir / "cloth.usda");
  EXPECT_NE(usd.find("float[] primvars:humidity ("), std::string::npos);
  EXPECT_NE(usd.find("float[] primvars:humidity.timeSamples"), std::string::npos);
  fs::remove_all(dir);
}

TEST(Caches, Pc2HoldsEveryFrameAsFloats) {
  const CachedRun r = run_with_caches("pc2", UpAxis::Z);
  const std::string data = slurp(r.dir / "cloth.pc2");
  ASSERT_GE(data.size(), 32u);
  EXPECT_EQ(std::string(data.c_str()), "POINTCACHE2");
  std::int32_t version, points, samples;
  float start, rate;
  std::memcpy(&version, data.data() + 12, 4);
  std::memcpy(&points, data.data() + 16, 4);
  std::memcpy(&start, data.data() + 20, 4);
  std::memcpy(&rate, data.data() + 24, 4);
  std::memcpy(&samples, data.data() + 28, 4);
  EXPECT_EQ(version, 1);
  EXPECT_EQ(points, 81);
  EXPECT_EQ(samples, 5);
  EXPECT_EQ(start, 0.0f);
  EXPECT_EQ(rate, 1.0f);
  ASSERT_EQ(data.size(), 32u + 5u * 81u * 12u);
  for (int f = 0; f < 5; ++f)
    for (int i = 0; i < 81; ++i)
      for (int q = 0; q < 3; ++q) {
        float v;
        std::memcpy(&v, data.data() + 32 + (f * 81 + i) * 12 + 4 * q, 4);
        EXPECT_EQ(v, static_cast<float>(r.frames[f].points[i][q]));
      }
  // The rest mesh: the first frame's points, a UV each, the same triangles.
  const std::string rest = slurp(r.dir / "cloth_rest.obj");
  int v = 0, vt = 0, faces = 0;
  std::istringstream in(rest);
  for (std::string line; std::getline(in, line);) {
    v += line.rfind("v ", 0) == 0;
    vt += line.rfind("vt ", 0) == 0;
    faces += line.rfind("f ", 0) == 0;
  }
  EXPECT_EQ(v, 81);
  EXPECT_EQ(vt, 81);
  EXPECT_EQ(faces, static_cast<int>(r.triangles.size()));
}

TEST(Caches, UsdHasOneTimeSampleAFrameWithTheRunsValues) {
  const CachedRun r = run_with_caches("usd", UpAxis::Z);
  const std::string usd = slurp(r.dir / "cloth.usda");
  ASSERT_EQ(usd.rfind("#usda 1.0\n", 0), 0u);
  EXPECT_NE(usd.find("upAxis = \"Z\""), std::string::npos);
  EXPECT_NE(usd.find("metersPerUnit = 1"), std::string::npos);
  EXPECT_NE(usd.find("timeCodesPerSecond = 20"), std::string::npos);
  EXPECT_NE(usd.find("endTimeCode = 4"), std::string::npos);
  // Braces and brackets balance: the file parses as one tree.
  int depth = 0;
  for (char c : usd) {
    depth += c == '{' || c == '[' || c == '(';
    depth -= c == '}' || c == ']' || c == ')';
    ASSERT_GE(depth, 0);
  }
  EXPECT_EQ(depth, 0);
  // The topology: a count and three indices a triangle.
  const auto counts_at = usd.find("int[] faceVertexCounts = [");
  ASSERT_NE(counts_at, std::string::npos);
  const auto counts =
      numbers(usd.substr(counts_at + 26, usd.find(']', counts_at + 26) - counts_at - 26));
  EXPECT_EQ(counts.size(), r.triangles.size());
  // points: 5 samples at codes 0..4, each 81 points equal to the run's frame.
  const auto at = usd.find("point3f[] points.timeSamples = {");
  ASSERT_NE(at, std::string::npos);
  std::istringstream block(usd.substr(at, usd.find("        }\n", at) - at));
  std::string line;
  std::getline(block, line);
  for (int f = 0; f < 5; ++f) {
    ASSERT_TRUE(std::getline(block, line));
    const auto v = numbers(line);
    ASSERT_EQ(v.size(), 1u + 3u * 81u) << line.substr(0, 80);
    EXPECT_EQ(v[0], f);
    for (int i = 0; i < 81; ++i)
      for (int q = 0; q < 3; ++q)
        EXPECT_EQ(static_cast<float>(v[1 + 3 * i + q]),
                  static_cast<float>(r.frames[f].points[i][q]));
  }
  // Contact, per vertex: the last frame lies on the table.
  const auto c = usd.find("float[] primvars:contact.timeSamples = {");
  ASSERT_NE(c, std::string::npos);
  std::istringstream cb(usd.substr(c, usd.find("        }\n", c) - c));
  std::vector<std::string> rows;
  for (std::string l; std::getline(cb, l);) rows.push_back(l);
  ASSERT_EQ(rows.size(), 6u);
  const auto last = numbers(rows.back());
  ASSERT_EQ(last.size(), 82u);
  for (int i = 0; i < 81; ++i) EXPECT_EQ(last[1 + i], r.frames[4].contact[i]);
  EXPECT_GT(std::count(r.frames[4].contact.begin(), r.frames[4].contact.end(), 1.0f), 40);
  // The table as a static mesh.
  EXPECT_NE(usd.find("def Mesh \"table\""), std::string::npos);
}

TEST(Caches, VtkHasAPolyDataAFrameAndACollection) {
  const CachedRun r = run_with_caches("vtk", UpAxis::Z);
  const std::string pvd = slurp(r.dir / "cloth.pvd");
  for (int f = 0; f < 5; ++f) {
    char name[64];
    std::snprintf(name, sizeof name, "file=\"vtk/cloth_%05d.vtp\"", f);
    EXPECT_NE(pvd.find(name), std::string::npos) << name;
  }
  EXPECT_NE(pvd.find("timestep=\"0.2\""), std::string::npos);
  const std::string vtp = slurp(r.dir / "vtk" / "cloth_00002.vtp");
  EXPECT_NE(vtp.find("NumberOfPoints=\"81\""), std::string::npos);
  EXPECT_NE(vtp.find("NumberOfPolys=\"" + std::to_string(r.triangles.size()) + "\""),
            std::string::npos);
  for (const char* field :
       {"\"contact\"", "\"pressure_pa\"", "\"adhesion_n\"", "\"humidity\"", "\"uv\""})
    EXPECT_NE(vtp.find(field), std::string::npos) << field;
  // Binary, zlib-compressed and appended: the points' tag gives their offset
  // past the '_', where VTK's header (one block: 1, its size twice, its
  // compressed size) and the compressed doubles follow.
  EXPECT_NE(vtp.find("compressor=\"vtkZLibDataCompressor\""), std::string::npos);
  const auto p = vtp.find("<Points>");
  const auto tag = vtp.substr(p, vtp.find("/>", p) - p);
  ASSERT_NE(tag.find("format=\"appended\""), std::string::npos) << tag;
  const auto offset = std::stoull(tag.substr(tag.find("offset=\"") + 8));
  const std::string lead = "<AppendedData encoding=\"raw\">\n_";
  const auto at = vtp.find(lead) + lead.size() + offset;
  std::uint64_t header[4];
  std::memcpy(header, vtp.data() + at, sizeof header);
  ASSERT_EQ(header[0], 1u);
  ASSERT_EQ(header[1], 3u * 81u * sizeof(double));
  std::vector<double> x(3 * 81);
  uLongf size = header[1];
  ASSERT_EQ(uncompress(reinterpret_cast<Bytef*>(x.data()), &size,
                       reinterpret_cast<const Bytef*>(vtp.data() + at + sizeof header), header[3]),
            Z_OK);
  for (int i = 0; i < 81; ++i)
    for (int q = 0; q < 3; ++q) EXPECT_EQ(x[3 * i + q], r.frames[2].points[i][q]);
  // A frame at 9 x 9 is a few kB (the ASCII's was 7.6).
  EXPECT_LT(vtp.size(), 6000u);
  EXPECT_TRUE(fs::exists(r.dir / "vtk" / "obstacles.vtp"));
}

TEST(Caches, YUpTurnsEveryPointAboutX) {
  const CachedRun r = run_with_caches("yup", UpAxis::Y);
  const std::string usd = slurp(r.dir / "cloth.usda");
  EXPECT_NE(usd.find("upAxis = \"Y\""), std::string::npos);
  const std::string data = slurp(r.dir / "cloth.pc2");
  ASSERT_EQ(data.size(), 32u + 5u * 81u * 12u);
  for (int i = 0; i < 81; ++i) {
    float y, z;
    std::memcpy(&y, data.data() + 32 + (4 * 81 + i) * 12 + 4, 4);
    std::memcpy(&z, data.data() + 32 + (4 * 81 + i) * 12 + 8, 4);
    EXPECT_EQ(y, static_cast<float>(r.frames[4].points[i].z()));   // height is y
    EXPECT_EQ(z, static_cast<float>(-r.frames[4].points[i].y()));  // right-handed
  }
}

// metrics.csv: a frame's time as the step's time, 667 x 5e-5 = 0.03335 (in
// binary 0.033350000000000005), and every value in its shortest exact form.
TEST(MetricsCsv, TimesAsTheyAreAndValuesExactly) {
  Metrics m;
  m.time_s = 667 * 5e-5;
  ASSERT_NE(m.time_s, 0.03335);  // the binary product is not the decimal
  m.handle_height_m = 0.1 + 0.2;
  const std::string row = metrics_csv_row(m);
  EXPECT_EQ(row.substr(0, row.find(',')), "0.03335");
  m.time_s = 1800 * 5e-5;
  EXPECT_EQ(metrics_csv_row(m).substr(0, 5), "0.09,");
  const std::vector<std::string> cols = metrics_columns();
  std::vector<double> back;
  std::stringstream in(row);
  for (std::string cell; std::getline(in, cell, ',');) back.push_back(std::stod(cell));
  ASSERT_EQ(back.size(), cols.size());
  EXPECT_EQ(back[1], 0.1 + 0.2);  // 0.30000000000000004, all its digits
}

}  // namespace
}  // namespace wetcloth
