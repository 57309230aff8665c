// Contact surfaces and obstacles (docs/model.md section 3): the table plane, the
// ball and the mesh obstacles (mesh_obstacle.cpp).
#include "detail.hpp"

namespace wetcloth::detail {

namespace {

// The table alone, as the general loop below treats it (n = z: x.z -= d, an
// inward v.z becomes v.z - v.z = 0), in scalars without branches: in contact
// the adhesion pulls particles in every step, and a branch per particle was
// mispredicted (BM_collide shows it).
template <bool record>
void collide_with_table(const Model& m, State& s, std::uint8_t* touched, int first, int end) {
  const double height = m.params.table.height;
  const auto table = static_cast<std::uint8_t>(SurfaceKind::Table);
  double* Z = s.x.column(2) + first;
  double* VZ = s.v.column(2) + first;
  const std::uint8_t* driven = m.driven.data() + first;
  std::uint8_t* hit = record ? touched + first : nullptr;
  const int count = end - first;
#pragma omp simd
  for (int i = 0; i < count; ++i) {
    const double z = Z[i], d = z - height, vz = VZ[i];
    const bool in = (d < 0) & (driven[i] == 0);  // &, not &&: no branch
    Z[i] = in ? z - d : z;
    VZ[i] = in & (vz < 0) ? vz - vz : vz;
    if constexpr (record) hit[i] = in ? table : 0;
  }
}

// Each particle that `particles(one)` names, out of every obstacle.
template <class Particles>
void collide_particles(const Model& m, State& s, std::vector<std::uint8_t>* touched, Workspace* w,
                       Particles&& particles) {
  const Params& p = m.params;
  const SurfaceKind kinds[] = {SurfaceKind::Table, SurfaceKind::Ball};
  const bool enabled[] = {p.table.enabled, p.ball.enabled};
  const int meshes = static_cast<int>(m.obstacles.size());
  // Where the surfaces are now (a workspace placed them); none moves without one.
  static const SurfacePoses still;
  const SurfacePoses& poses = w ? w->surfaces : still;
  auto push_out = [&](int i, double distance, const Vec3& normal, int code) {
    sub(s.x[i], distance * normal);
    // The inward velocity relative to the surface is removed: a moving
    // surface carries the particle along its normal (docs/model.md section 3).
    if (pose_of(poses, code)) {
      const double vn = (s.v[i] - surface_velocity(poses, code, s.x[i])).dot(normal);
      if (vn < 0) sub(s.v[i], vn * normal);
    } else {
      const double vn = s.v[i].dot(normal);
      if (vn < 0) sub(s.v[i], vn * normal);
    }
    if (touched) (*touched)[i] = static_cast<std::uint8_t>(code);
  };
  auto one = [&](int i) {
    if (touched) (*touched)[i] = 0;
    if (m.driven[i]) return;
    for (int o = 0; o < 2; ++o) {
      if (!enabled[o]) continue;
      const SurfaceHit h = query_surface(p, poses, kinds[o], s.x[i]);
      if (h.distance >= 0) continue;
      push_out(i, h.distance, h.normal, static_cast<int>(kinds[o]));
    }
    for (int k = 0; k < meshes; ++k) {
      const MeshObstacle::Hit h = query_mesh(mesh_of(m, poses, k), pose_of(poses, kMeshCode + k),
                                             s.x[i], 0.0, w ? &w->mesh_cache[k] : nullptr, i);
      if (h.distance >= 0) continue;
      push_out(i, h.distance, h.normal, kMeshCode + k);
    }
  };
  particles(one);
}

}  // namespace

void place_surfaces(const Model& m, Workspace& w, double t) {
  SurfacePoses& poses = w.surfaces;
  poses.time = t;
  poses.ball = m.params.ball.enabled ? ball_pose(m.params, t) : RigidPose{};
  poses.any = poses.ball.moving;
  poses.obstacles.resize(m.obstacles.size());
  poses.shapes.resize(m.obstacles.size());
  for (std::size_t k = 0; k < m.obstacles.size(); ++k) {
    poses.obstacles[k] = obstacle_pose(m.params, m.obstacles[k]->name, t);
    std::shared_ptr<MeshObstacle>& shape = poses.shapes[k];
    if (!m.obstacles[k]->cache) {
      shape.reset();
    } else {  // a deforming obstacle: its shape at t
      // Made again for a model built anew (Simulation::set), and for a
      // workspace copied from another (the two would share it).
      if (shape && shape->cache != m.obstacles[k]->cache) shape.reset();
      if (!shape || shape.use_count() > 1)
        shape = deformable_copy(shape ? *shape : *m.obstacles[k]);
      reshape(*shape, t);
      poses.obstacles[k].moving = true;  // (the identity pose, without a motion)
    }
    poses.any = poses.any || poses.obstacles[k].moving;
  }
}

void collide(const Model& m, State& s, std::vector<std::uint8_t>* touched, Workspace* w, int first,
             int end) {
  const Params& p = m.params;
  if (p.table.enabled && !p.ball.enabled && m.obstacles.empty())
    return touched ? collide_with_table<true>(m, s, touched->data(), first, end)
                   : collide_with_table<false>(m, s, nullptr, first, end);
  collide_particles(m, s, touched, w, [&](auto& one) {
    for (int i = first; i < end; ++i) one(i);
  });
}

void collide(const Model& m, State& s, std::vector<std::uint8_t>* touched,
             const std::vector<int>* only, Workspace* w) {
  if (w) prepare_contact(m, *w);
  if (only)
    return collide_particles(m, s, touched, w, [&](auto& one) {
      for (const int i : *only) one(i);
    });
  for_each_particle_block(m, [&](int first, int end) { collide(m, s, touched, w, first, end); });
}

void collide_with_meshes(const Model& m, State& s, Workspace& w) {
  w.mesh_cache.resize(m.obstacles.size());
  for (MeshQueryCache& c : w.mesh_cache) c.prepare(m.n);
  for_each_particle(m, [&](int i) {
    if (m.driven[i]) return;
    for (std::size_t k = 0; k < m.obstacles.size(); ++k) {
      const RigidPose* pose = pose_of(w.surfaces, kMeshCode + static_cast<int>(k));
      const MeshObstacle::Hit h = query_mesh(mesh_of(m, w.surfaces, static_cast<int>(k)), pose,
                                             s.x[i], 0.0, &w.mesh_cache[k], i);
      if (h.distance >= 0) continue;
      sub(s.x[i], h.distance * h.normal);
      const Vec3 v =
          pose
              ? Vec3(s.v[i] - surface_velocity(w.surfaces, kMeshCode + static_cast<int>(k), s.x[i]))
              : Vec3(s.v[i]);
      const double vn = v.dot(h.normal);
      if (vn < 0) sub(s.v[i], vn * h.normal);
    }
  });
}

void prepare_contact(const Model& m, Workspace& w) {
  w.mesh_cache.resize(m.obstacles.size());
  for (MeshQueryCache& c : w.mesh_cache) c.prepare(m.n);
}

void update_contact(const Model& m, State& s, Workspace& w, int begin, int end) {
  const Params& p = m.params;
  const double h_th = p.contact.bridge_height;
  // Locals: a byte store may alias anything, so the loop would otherwise
  // reload after each one every pointer and bound it reads through a
  // reference.
  const SurfaceKind kind = m.contact_surface;
  double* __restrict const distance = w.distance.data();
  std::uint8_t* __restrict const contact = s.contact.data();
  double* __restrict const nx = w.surface_normal.column(0);
  double* __restrict const ny = w.surface_normal.column(1);
  double* __restrict const nz = w.surface_normal.column(2);
  if (kind == SurfaceKind::Table) {  // query_surface's table, in a loop that vectorises
    const double* __restrict const z = s.x.column(2);
    const double height = p.table.height;
#pragma omp simd
    for (int i = begin; i < end; ++i) {
      distance[i] = z[i] - height;
      nx[i] = ny[i] = 0.0;
      nz[i] = 1.0;
      contact[i] = distance[i] < h_th;
    }
    return;
  }
  if (kind == SurfaceKind::None) {  // query_surface's answer, in a loop that vectorises
#pragma omp simd
    for (int i = begin; i < end; ++i) {
      distance[i] = kInf;
      nx[i] = ny[i] = 0.0;
      nz[i] = 1.0;
      contact[i] = 0;
    }
    return;
  }
  if (kind == SurfaceKind::Mesh) {  // within the air's band: beyond it nothing needs more
    const MeshObstacle& o = mesh_of(m, w.surfaces, m.contact_obstacle);
    MeshQueryCache* cache = &w.mesh_cache[m.contact_obstacle];
    const RigidPose* pose = pose_of(w.surfaces, m.contact_code());
    const double reach = std::max(p.air.band, h_th);
    for (int i = begin; i < end; ++i) {
      const MeshObstacle::Hit h = query_mesh(o, pose, s.x[i], reach, cache, i);
      distance[i] = h.distance;
      nx[i] = h.normal.x();
      ny[i] = h.normal.y();
      nz[i] = h.normal.z();
      contact[i] = h.distance < h_th;
    }
    return;
  }
  for (int i = begin; i < end; ++i) {  // the ball, where it is now
    const SurfaceHit h = query_surface(p, w.surfaces, kind, s.x[i]);
    distance[i] = h.distance;
    nx[i] = h.normal.x();
    ny[i] = h.normal.y();
    nz[i] = h.normal.z();
    contact[i] = h.distance < h_th;
  }
}

// The border of the contact region: contact particles on the cloth's border or
// next to a lifted particle. They carry eq. 13's edge term. Inside the
// cloth's border, c & ~(left & right & up & down) over a row of 0/1 bytes:
// a loop that vectorises, where a branch per particle did not (locals, as
// above).
void mark_contact_border(const Model& m, const State& s, Workspace& w, int j0, int j1) {
  const int nu = m.nu;
  const std::uint8_t* const c = s.contact.data();
  std::uint8_t* const b = w.border.data();
  for (int j = j0; j < j1; ++j) {
    const int row = j * nu, end = row + nu;
    if (j == 0 || j == m.nv - 1 || nu < 3) {
      for (int k = row; k < end; ++k) b[k] = c[k];  // on the cloth's border
      continue;
    }
    b[row] = c[row];
    b[end - 1] = c[end - 1];
#pragma GCC ivdep
    for (int k = row + 1; k < end - 1; ++k)
      b[k] = c[k] & ((c[k - 1] & c[k + 1] & c[k - nu] & c[k + nu]) ^ 1);
  }
}

void update_contact(const Model& m, State& s, Workspace& w) {
  prepare_contact(m, w);
  for_each_particle_block(m, [&](int first, int end) { update_contact(m, s, w, first, end); });
  if (!m.grid) {
    contact_border_mesh(m, s, w);
    return;
  }
  parallel_for(m, m.nv, [&](int j) { mark_contact_border(m, s, w, j, j + 1); });
}

}  // namespace wetcloth::detail
