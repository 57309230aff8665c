// Animation caches that studio tools read (`run.export`): USD, a PC2 point
// cache with its rest OBJ, VTK PolyData. Each carries the cloth's points and
// normals per output frame and the wet model's fields per vertex: contact (1
// within h_th of the contact surface), pressure (the trapped air's P_in under
// the vertex, Pa; p_atm where none is trapped; in USD also as
// primvars:pressure_deficit, p_atm - P_in, Pa), adhesion (|F_adh|, N) and
// humidity (each vertex's ω); USD has the velocities too (m/s).
//
//   cloth.usda                one Mesh, time-sampled points, normals, velocities, extent and
//                             primvars, UVs (primvars:st), the obstacles as static
//                             meshes; up axis, metres and frames per second in the
//                             stage's metadata. Written when the run ends (the
//                             time samples are spooled, a file an attribute, in
//                             .cloth.usda.samples/, kept until the run is whole
//                             so that a resumed run writes them all).
//   cloth.pc2, cloth_rest.obj Blender's Mesh Cache modifier, Houdini; one sample a
//                             frame. The header's count follows every frame, so
//                             a run cut short leaves a readable cache.
//   cloth_fields.pc2          its side file, the same layout: each point's
//                             (humidity ω, contact 0 or 1, pressure deficit Pa)
//                             in place of (x, y, z).
//   vtk/cloth_NNNNN.vtp       a PolyData a frame (ParaView), its arrays binary,
//                             zlib-compressed and appended; vtk/obstacles.vtp;
//                             cloth.pvd the collection with each frame's time,
//                             rewritten as frames come.
//
// Moving obstacles (docs/guide.md, "Moving obstacles in the outputs"): in USD
// each moving obstacle's Mesh has a time-sampled xformOp:transform, a sample
// a frame (a deforming one's, time-sampled points); PC2 gives each its own obstacle_NAME.pc2 over
// obstacle_NAME_rest.obj; VTK writes vtk/obstacles_NNNNN.vtp a frame and obstacles.pvd. NAME: the
// obstacle's USD prim name (moving_obstacle_files).
#pragma once

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "wetcloth/output.hpp"
#include "wetcloth/simulation.hpp"

namespace wetcloth {

struct ExportFormats {
  bool usd = false, pc2 = false, vtk = false;
  bool any() const { return usd || pc2 || vtk; }
};
// "usd,pc2,vtk", any of them in any order, or "" for none; std::invalid_argument
// naming the word it does not know.
ExportFormats parse_export_formats(const std::string& list);

// The fields of one frame, in the file's up axis.
struct CacheFrame {
  double time = 0;
  std::vector<Vec3> points, normals, velocities;
  std::vector<float> contact, pressure, adhesion;
  std::vector<float> humidity;  // ω per vertex (the humidity field)
};
CacheFrame cache_frame(const Simulation& sim, UpAxis up);

// The NAMEs of the moving obstacles' caches (obstacle_NAME.pc2, and in USD
// the prim /wetcloth/NAME): the obstacle's name made a USD name, unique.
std::vector<std::string> moving_obstacle_files(const Params& p);
// The USD sample files of the moving obstacles, in .cloth.usda.samples/:
// xform_NAME for one that moves by a motion, points_NAME for one that
// deforms by a cache (both for a cache moved by a motion).
std::vector<std::string> obstacle_usd_samples(const Params& p);

// Where the caches stand after some frames: what a checkpoint keeps so that a
// resumed run continues them (CacheWriter::resume).
struct CachePosition {
  long long frames = 0;
  double last_code = 0;                  // USD time code of the last frame
  std::vector<long long> samples_bytes;  // each USD attribute's spooled samples
};

class CacheWriter {
 public:
  // Opens the caches of `formats` in `dir` for the simulation's cloth (at its
  // rest state: cloth_rest.obj is written from it).
  CacheWriter(const std::filesystem::path& dir, const Simulation& sim, ExportFormats formats,
              UpAxis up, double fps);
  // Continues the caches a run left in `dir` at `at` (a checkpoint's): the PC2
  // cut back to its frames, the USD samples to theirs, cloth.pvd rewritten
  // with `frame_times` (one a frame kept). OutputError where a cache is
  // missing or shorter than `at`.
  CacheWriter(const std::filesystem::path& dir, const Simulation& sim, ExportFormats formats,
              UpAxis up, double fps, const CachePosition& at,
              const std::vector<double>& frame_times);
  ~CacheWriter();
  CacheWriter(const CacheWriter&) = delete;
  CacheWriter& operator=(const CacheWriter&) = delete;

  // The simulation's state as the next frame; `code`, its USD time code: the
  // frame's number for a frame on the frame rate (a state's time, a whole
  // number of steps, is a little off f / fps), else (< 0) time × fps.
  void add_frame(const Simulation& sim, double code = -1);
  // The frames so far, flushed (and with `durable`, on the disk).
  CachePosition position(bool durable);
  // Writes what is written at the end (cloth.usda); further frames are refused.
  // The USD samples stay (a run may still resume from them) until remove_samples.
  void finish();
  void remove_samples();

 private:
  struct Spool;  // a time-sampled USD attribute's samples, in a file of their own
  void open_usd_samples(const CachePosition* at);
  void write_pvd();
  void find_moving_obstacles();
  void write_vtk_obstacles(const std::filesystem::path& path, const std::vector<RigidPose>& poses,
                           double t);
  std::filesystem::path dir_;
  ExportFormats formats_;
  UpAxis up_;
  double fps_;
  const Model& model_;
  long long frames_ = 0;
  double last_code_ = 0;  // USD time code of the last frame
  bool finished_ = false;
  std::fstream pc2_, pc2_fields_;
  std::vector<double> vtk_times_;
  std::vector<std::unique_ptr<Spool>> spools_;  // the cloth's, then moving_'s transforms
  std::vector<NamedMesh> meshes_;               // the obstacles (obstacle_meshes)
  std::vector<std::string> prims_;              // their USD names
  std::vector<std::size_t> moving_;             // which of them move (or deform)
  // Per moving_ obstacle, its USD spools (index into spools_, -1: none): the
  // transform of its motion, the points of its cache.
  std::vector<int> xform_spool_, points_spool_;
  std::vector<std::unique_ptr<std::fstream>> obstacle_pc2_;  // one a moving obstacle
};

}  // namespace wetcloth
