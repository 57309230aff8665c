// The measurement behind the mesh obstacles' choice of library
// (docs/performance.md, "Mesh obstacles"): a CGAL AABB tree (exact closest
// point) against an OpenVDB level set (a signed distance sampled on a grid),
// on a sphere of about 10 000 triangles and the 51 x 51 particles of a cloth
// draped over it. Not part of the build (OpenVDB is not one of wetcloth's
// dependencies); build and run it with
//
//   apt-get install libcgal-dev libopenvdb-dev
//   g++ -O2 -march=native -std=c++20 bench/mesh_query_compare.cpp -o /tmp/mesh_query_compare \
//       -lopenvdb -ltbb && /tmp/mesh_query_compare
//
// It prints, for each method, the time per particle query (distance and
// normal) and the error of the distance against the mesh's exact distance
// (CGAL's, taken as the reference), near the surface (|d| < 2 mm) and
// farther (2 mm to 5 cm).
#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Simple_cartesian.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/Interpolation.h>
#include <openvdb/tools/MeshToVolume.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <vector>

using K = CGAL::Simple_cartesian<double>;
using Tri = K::Triangle_3;
using Primitive = CGAL::AABB_triangle_primitive<K, std::vector<Tri>::const_iterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<K, Primitive>>;

struct V3 {
  double x, y, z;
};

int main() {
  const double R = 0.1;
  const int rings = 70, segs = 72;  // 9 936 triangles
  std::vector<V3> pts;
  std::vector<std::array<int, 3>> tris;
  pts.push_back({0, 0, R});
  for (int r = 1; r < rings; ++r)
    for (int s = 0; s < segs; ++s) {
      const double th = std::numbers::pi * r / rings, ph = 2 * std::numbers::pi * s / segs;
      pts.push_back(
          {R * std::sin(th) * std::cos(ph), R * std::sin(th) * std::sin(ph), R * std::cos(th)});
    }
  pts.push_back({0, 0, -R});
  const int south = static_cast<int>(pts.size()) - 1;
  auto ring = [&](int r, int s) { return 1 + (r - 1) * segs + (s % segs); };
  for (int s = 0; s < segs; ++s) tris.push_back({0, ring(1, s), ring(1, s + 1)});
  for (int r = 1; r < rings - 1; ++r)
    for (int s = 0; s < segs; ++s) {
      tris.push_back({ring(r, s), ring(r + 1, s), ring(r + 1, s + 1)});
      tris.push_back({ring(r, s), ring(r + 1, s + 1), ring(r, s + 1)});
    }
  for (int s = 0; s < segs; ++s)
    tris.push_back({south, ring(rings - 1, s + 1), ring(rings - 1, s)});
  std::printf("sphere: %zu triangles, R = %g m\n", tris.size(), R);

  // The particles: a 51 x 51 cloth of 0.3 m laid over the ball, at heights
  // from 0.5 mm inside to 5 cm off (a drape: most within a few mm).
  std::vector<V3> q;
  for (int j = 0; j < 51; ++j)
    for (int i = 0; i < 51; ++i) {
      const double u = (i / 50.0 - 0.5) * 0.3, v = (j / 50.0 - 0.5) * 0.3;
      const double rho = std::hypot(u, v), ph = std::atan2(v, u);
      const double th = std::min(rho / R, std::numbers::pi / 2);  // arc length -> polar angle
      const double off = -5e-4 + 5.05e-2 * std::pow(((i * 7 + j * 13) % 101) / 100.0, 4);
      const double r = R + off;
      q.push_back(
          {r * std::sin(th) * std::cos(ph), r * std::sin(th) * std::sin(ph), r * std::cos(th)});
    }

  // CGAL: the reference, and its timing.
  std::vector<Tri> triangles;
  for (auto& t : tris)
    triangles.emplace_back(K::Point_3(pts[t[0]].x, pts[t[0]].y, pts[t[0]].z),
                           K::Point_3(pts[t[1]].x, pts[t[1]].y, pts[t[1]].z),
                           K::Point_3(pts[t[2]].x, pts[t[2]].y, pts[t[2]].z));
  auto t0 = std::chrono::steady_clock::now();
  Tree tree(triangles.begin(), triangles.end());
  tree.accelerate_distance_queries();
  const double build_cgal =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::vector<double> exact(q.size());
  double sink = 0;
  const int reps = 20;
  t0 = std::chrono::steady_clock::now();
  for (int rep = 0; rep < reps; ++rep)
    for (std::size_t k = 0; k < q.size(); ++k) {
      const K::Point_3 p(q[k].x, q[k].y, q[k].z);
      const auto [c, id] = tree.closest_point_and_primitive(p);
      const K::Vector_3 n = p - c;
      const double d = std::sqrt(n.squared_length());
      // sign from the face normal (a sphere: exact enough for the reference)
      const K::Vector_3 fn =
          CGAL::cross_product(id->vertex(1) - id->vertex(0), id->vertex(2) - id->vertex(0));
      exact[k] = n * fn < 0 ? -d : d;
      sink += n.x();
    }
  const double per_cgal =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() /
      (reps * q.size());
  std::printf("CGAL AABB tree: build %.1f ms, %.2f us a query (closest point, normal, sign)\n",
              build_cgal * 1e3, per_cgal * 1e6);
  // As wetcloth searches (src/geometry/mesh_obstacle.cpp): bounded by the particle's
  // last answer (here its exact distance plus a step's move of 50 um), the
  // hint a point that far away on no triangle.
  t0 = std::chrono::steady_clock::now();
  for (int rep = 0; rep < reps; ++rep)
    for (std::size_t k = 0; k < q.size(); ++k) {
      const K::Point_3 p(q[k].x, q[k].y, q[k].z);
      const double bound = std::abs(exact[k]) + 5e-5;
      const K::Point_3 hint(q[k].x + bound, q[k].y, q[k].z);
      const auto [c, id] = tree.closest_point_and_primitive(p, {hint, triangles.begin()});
      sink += c.x();
    }
  const double per_bounded =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() /
      (reps * q.size());
  std::printf("CGAL AABB tree, search bounded by the last answer + 50 um: %.2f us a query\n",
              per_bounded * 1e6);
  double chord = 0;
  for (std::size_t k = 0; k < q.size(); ++k) {
    const double analytic = std::sqrt(q[k].x * q[k].x + q[k].y * q[k].y + q[k].z * q[k].z) - R;
    chord = std::max(chord, std::abs(analytic - exact[k]));
  }
  std::printf("  mesh against the analytic sphere: largest difference %.1f um (the chord error)\n",
              chord * 1e6);

  openvdb::initialize();
  std::vector<openvdb::Vec3s> vpts;
  std::vector<openvdb::Vec3I> vtris;
  for (auto& p : pts) vpts.emplace_back(p.x, p.y, p.z);
  for (auto& t : tris) vtris.emplace_back(t[0], t[1], t[2]);
  for (const double voxel : {2e-3, 1e-3, 5e-4}) {
    auto xform = openvdb::math::Transform::createLinearTransform(voxel);
    const float band = static_cast<float>(0.05 / voxel) + 2;  // 5 cm out: the air's band
    t0 = std::chrono::steady_clock::now();
    auto grid = openvdb::tools::meshToSignedDistanceField<openvdb::FloatGrid>(
        *xform, vpts, vtris, std::vector<openvdb::Vec4I>(), band, 3.0f);
    const double build =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    auto acc = grid->getConstAccessor();
    openvdb::tools::GridSampler<openvdb::FloatGrid::ConstAccessor, openvdb::tools::BoxSampler>
        sampler(acc, grid->transform());
    std::vector<double> d(q.size());
    t0 = std::chrono::steady_clock::now();
    for (int rep = 0; rep < reps; ++rep)
      for (std::size_t k = 0; k < q.size(); ++k) {
        const openvdb::Vec3d p(q[k].x, q[k].y, q[k].z);
        d[k] = sampler.wsSample(p);
        // the normal: central differences, six more samples
        const double h = voxel / 2;
        const double gx = sampler.wsSample(p + openvdb::Vec3d(h, 0, 0)) -
                          sampler.wsSample(p - openvdb::Vec3d(h, 0, 0));
        const double gy = sampler.wsSample(p + openvdb::Vec3d(0, h, 0)) -
                          sampler.wsSample(p - openvdb::Vec3d(0, h, 0));
        const double gz = sampler.wsSample(p + openvdb::Vec3d(0, 0, h)) -
                          sampler.wsSample(p - openvdb::Vec3d(0, 0, h));
        sink += gx + gy + gz;
      }
    const double per =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() /
        (reps * q.size());
    double near = 0, far = 0;
    for (std::size_t k = 0; k < q.size(); ++k) {
      const double e = std::abs(d[k] - exact[k]);
      (std::abs(exact[k]) < 2e-3 ? near : far) =
          std::max(std::abs(exact[k]) < 2e-3 ? near : far, e);
    }
    std::printf(
        "OpenVDB level set, voxel %.1f mm (band 5 cm): build %.0f ms, %.0f MB, %.2f us a query "
        "(distance + 6 samples for the normal); largest error %.1f um within 2 mm, %.1f um "
        "beyond\n",
        voxel * 1e3, build * 1e3, grid->memUsage() / 1e6, per * 1e6, near * 1e6, far * 1e6);
  }
  return sink == 12345.678 ? 1 : 0;
}
