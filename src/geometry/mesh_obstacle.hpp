// Obstacles made of triangle meshes ([obstacle.NAME], docs/model.md section 3):
// the signed distance, closest point and outward normal of a particle, from a
// CGAL AABB tree (docs/performance.md, "Mesh obstacles", for the choice).
#pragma once

#include <array>
#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "wetcloth/simulation.hpp"

namespace wetcloth {

struct MeshObstacle {
  std::string name;    // NAME of [obstacle.NAME]
  std::string source;  // the file, for messages
  // In the simulation's frame (the scene's transform applied); a closed mesh's
  // triangles are counter-clockwise seen from outside (turned so if the file
  // had them the other way).
  std::vector<Vec3> points;
  std::vector<std::array<int, 3>> triangles;
  // Closed: every edge between two triangles, in opposite directions: the
  // inside is the solid and the distance is signed (angle-weighted
  // pseudo-normals, Bærentzen & Aanæs 2005). Open: a shell of `thickness`
  // about the surface, its distance the unsigned one less half the thickness.
  bool closed = true;
  double half_thickness = 0;
  Vec3 lo = Vec3::Zero(), hi = Vec3::Zero();  // bounding box

  struct Hit {
    double distance = std::numeric_limits<double>::infinity();  // signed, m
    Vec3 normal = Vec3::UnitZ();                                // outward at the closest point
    double unsigned_distance = std::numeric_limits<double>::infinity();  // to the triangles
    int triangle = -1;          // the closest point's triangle (-1: none found)
    Vec3 point = Vec3::Zero();  // the closest point
  };
  // The signed distance and outward normal at x, exactly (a search of the whole tree).
  Hit query(const Vec3& x) const { return query_within(x, kWhole); }
  // The same, searching only the triangles nearer than `bound` (m): beyond it
  // the hit has distance and unsigned distance infinite. The result does not
  // depend on the bound otherwise (but for exact ties between triangles).
  Hit query_within(const Vec3& x, double bound) const;
  static constexpr double kWhole = 1e30;

  struct Geometry;  // the tree, pseudo-normals (mesh_obstacle.cpp)
  std::shared_ptr<const Geometry> geometry;

  // A deforming obstacle's cache (obstacle.NAME.cache): its vertices at
  // each frame, placed as `points` are (its body frame). Null: rigid.
  struct Cache {
    std::string source;  // the file (or the sequence's first file), for messages
    double start = 0;    // s: frame 0's time
    double step = 1;     // s between frames
    std::vector<std::vector<Vec3>> frames;
  };
  std::shared_ptr<const Cache> cache;

  // A shape made by reshape (deformable_copy): each vertex's velocity (m/s,
  // body frame), the time it is the shape of, and `travel`, the sum over
  // its reshapes of the farthest any vertex moved: the distance to the mesh
  // changes by no more, so MeshQueryCache's bounds stay bounds.
  std::vector<Vec3> velocity;
  double time = std::numeric_limits<double>::quiet_NaN();
  double travel = 0;
};

// The cache's vertices at time t: linear between frames (velocity the
// frame-to-frame difference over the step, the next interval's at a frame),
// held at the first before it and at the last after it (velocity zero).
void sample_cache(const MeshObstacle::Cache& c, double t, std::vector<Vec3>& points,
                  std::vector<Vec3>& velocity);
// A copy of a mesh obstacle with a tree of its own, to reshape.
std::shared_ptr<MeshObstacle> deformable_copy(const MeshObstacle& o);
// A deformable copy moved to its cache's shape at time t: points, bounding
// box, pseudo-normals and the tree (rebuilt: CGAL's has no refit, and its
// build is O(T log T), small beside a step's queries of every particle).
void reshape(MeshObstacle& o, double t);
// The velocity of a deforming obstacle's surface (body frame) at a hit's
// closest point: its triangle's vertex velocities, barycentrically.
Vec3 surface_velocity_at(const MeshObstacle& o, const MeshObstacle::Hit& h);

// Builds [obstacle.NAME]'s mesh: read (load_scene_mesh, so relative to the
// scene's folder), transformed, checked (a closed mesh must be consistently
// oriented; an open one needs a thickness). Throws SceneError naming the file
// and the key.
std::shared_ptr<const MeshObstacle> build_mesh_obstacle(const Params& p, const std::string& name);

// Every obstacle's mesh loads and passes the checks above, and the cloth does
// not start inside one (load_scene: wetcloth check, run, view). Throws
// SceneError starting with `source`, the scene file.
// A cache's errors name the key's line too, ":LINE" as `line_of(key)` gives it.
void check_obstacle_meshes(const Params& p, const std::string& source,
                           const std::function<std::string(const std::string&)>& line_of = {});

// A particle's last query of one obstacle, to bound the next: the signed
// distance is 1-Lipschitz, so from x_last it is at least lo - |x - x_last|
// and the nearest triangle no farther than hi + |x - x_last|. Only the search
// is bounded with it, never the answer: the same bits with or without it.
struct MeshQueryCache {
  std::vector<double> x, y, z, lo, hi;  // hi: infinite when not known
  // Sized to n particles, nothing known.
  void prepare(int n) {
    if (static_cast<int>(lo.size()) == n) return;
    const auto k = static_cast<std::size_t>(n);
    x.assign(k, 0), y.assign(k, 0), z.assign(k, 0);
    lo.assign(k, -std::numeric_limits<double>::infinity());
    hi.assign(k, std::numeric_limits<double>::infinity());
  }
};

namespace detail {

// The obstacle's hit at x, with its distance capped at `reach` (m): where the
// particle is `reach` or more outside, {reach, +z} without the normal. The
// cache (sized to the particles on first use; may be null) bounds the search.
MeshObstacle::Hit query_mesh(const MeshObstacle& o, const Vec3& x, double reach,
                             MeshQueryCache* cache, int particle);

}  // namespace detail

}  // namespace wetcloth
