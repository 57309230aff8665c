// Bullet's btSoftBody on a scene's cloth, for `wetcloth bench --peer bullet`
// (bullet_peer.hpp says what it is made of and what it leaves out).
//
// The Bullet set-up (the world and its solvers, the ground box, CreatePatch,
// the collision margin, bending constraints, one stepSimulation per step)
// follows the team's peer sketch peers/bullet-cloth/bullet_cloth.cpp, "a
// starting point for `wetcloth bench --peer bullet`". Changed from it: the
// cloth is the scene's (its grid, corners, table, ball and handles, not a
// fixed 0.3 m patch pulled up at its midpoint), its mass is the dry mass
// (the sketch gave 0.09 × 0.15 kg, 1.35e-2, where 0.12 kg/m² × 0.09 m² is
// 1.08e-2), and Bullet's solver settings stay at its defaults (the sketch
// set piterations 4, kDF 0.5, kDP 0.005 and stiffness 0.9).
#include "bullet_peer.hpp"

#include <BulletSoftBody/btDefaultSoftBodySolver.h>
#include <BulletSoftBody/btSoftBodyHelpers.h>
#include <BulletSoftBody/btSoftBodyRigidBodyCollisionConfiguration.h>
#include <BulletSoftBody/btSoftRigidDynamicsWorld.h>
#include <btBulletDynamicsCommon.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <vector>

#include "wetcloth/scene.hpp"

namespace wetcloth::cli {

namespace {

btVector3 bt(const Vec3& v) {
  return {static_cast<btScalar>(v.x()), static_cast<btScalar>(v.y()), static_cast<btScalar>(v.z())};
}
btVector3 bt(const Vec3d& v) {
  return {static_cast<btScalar>(v[0]), static_cast<btScalar>(v[1]), static_cast<btScalar>(v[2])};
}

// The collision margin of the cloth: Bullet's default, 0.25 m, would hold a
// 0.3 m cloth a quarter of a metre off the table.
constexpr btScalar kMargin = 0.001f;

// The links of Bullet's generateBendingConstraints(2): every pair of nodes
// two links apart and no closer, in the order Bullet appends them, flagged as
// bending links. Bullet finds them in an n × n distance matrix, 6.5 GB and
// minutes at 201 × 201; here from each node's neighbours.
void add_bending_links(btSoftBody& cloth) {
  const int n = cloth.m_nodes.size();
  std::vector<std::vector<int>> near(n);
  const auto index = [&](const btSoftBody::Node* node) { return int(node - &cloth.m_nodes[0]); };
  for (int l = 0; l < cloth.m_links.size(); ++l) {
    const int a = index(cloth.m_links[l].m_n[0]), b = index(cloth.m_links[l].m_n[1]);
    near[a].push_back(b);
    near[b].push_back(a);
  }
  for (auto& list : near) {
    std::sort(list.begin(), list.end());
    list.erase(std::unique(list.begin(), list.end()), list.end());
  }
  // Bullet: for each j, each i > j at distance 2: appendLink(i, j).
  std::vector<int> second;
  for (int j = 0; j < n; ++j) {
    second.clear();
    for (int k : near[j])
      for (int i : near[k])
        if (i > j && !std::binary_search(near[j].begin(), near[j].end(), i)) second.push_back(i);
    std::sort(second.begin(), second.end());
    second.erase(std::unique(second.begin(), second.end()), second.end());
    for (int i : second) {
      cloth.appendLink(i, j, cloth.m_materials[0]);
      cloth.m_links[cloth.m_links.size() - 1].m_bbending = 1;
    }
  }
}

}  // namespace

struct BulletCloth::World {
  // Members are destroyed in reverse: the world before what it was built on.
  btSoftBodyRigidBodyCollisionConfiguration config;
  btCollisionDispatcher dispatcher{&config};
  btDbvtBroadphase broadphase;
  btSequentialImpulseConstraintSolver solver;
  btDefaultSoftBodySolver soft_solver;
  btSoftRigidDynamicsWorld world{&dispatcher, &broadphase, &solver, &config, &soft_solver};
  std::optional<btBoxShape> table_shape;
  std::optional<btSphereShape> ball_shape;
  std::vector<std::unique_ptr<btRigidBody>> obstacles;
  btSoftBody* cloth = nullptr;  // the world's while it is in it

  const Model* model = nullptr;
  btScalar dt = 0;
  double time = 0, dry_mass = 0;
  // Per handle: started (a pin or move handle has taken its nodes), stopped
  // (a capped force handle holds, a move handle has travelled max_travel).
  std::vector<char> started, stopped;

  ~World() {
    if (cloth != nullptr) {
      world.removeSoftBody(cloth);
      delete cloth;
    }
    for (auto& body : obstacles) world.removeRigidBody(body.get());
  }

  void add_static(btCollisionShape& shape, const btVector3& at) {
    btRigidBody::btRigidBodyConstructionInfo info(0, nullptr, &shape);
    btTransform t;
    t.setIdentity();
    t.setOrigin(at);
    info.m_startWorldTransform = t;
    obstacles.push_back(std::make_unique<btRigidBody>(info));
    world.addRigidBody(obstacles.back().get());
  }

  void hold(int node, const btVector3& velocity) {
    cloth->setMass(node, 0);  // Bullet moves a node of mass 0 at its velocity alone
    cloth->m_nodes[node].m_v = velocity;
  }

  double height(int node) const {
    const double z = cloth->m_nodes[node].m_x.z();
    return model->params.table.enabled ? z - model->params.table.height : z;
  }

  // Pins and move handles that have started take their nodes (once).
  void take_nodes() {
    for (std::size_t h = 0; h < model->handles.size(); ++h) {
      const Handle& handle = model->handles[h];
      if (handle.type == HandleType::Force || started[h] || time < handle.start) continue;
      started[h] = 1;
      for (int k : handle.particles)
        hold(k, handle.type == HandleType::Move ? bt(handle.velocity) : btVector3(0, 0, 0));
    }
  }

  // Force handles that have started and not stopped pull, shared by area.
  void pull() {
    for (const Handle& handle : model->handles) {
      const std::size_t h = &handle - model->handles.data();
      if (handle.type != HandleType::Force || stopped[h] || time < handle.start) continue;
      for (std::size_t e = 0; e < handle.particles.size(); ++e)
        cloth->addForce(bt(handle.share[e] * handle.force), handle.particles[e]);
    }
  }

  // After a step: a capped force handle that has reached its height or
  // travel holds its nodes there; a move handle stops after max_travel.
  void stop_handles() {
    for (std::size_t h = 0; h < model->handles.size(); ++h) {
      const Handle& handle = model->handles[h];
      if (stopped[h] || time < handle.start || (handle.max_travel <= 0 && handle.max_height <= 0))
        continue;
      const double n = static_cast<double>(handle.particles.size());
      if (handle.type == HandleType::Move) {
        if (handle.velocity.norm() * (time - handle.start) < handle.max_travel) continue;
        for (int k : handle.particles) hold(k, btVector3(0, 0, 0));
        stopped[h] = 1;
      } else if (handle.type == HandleType::Force) {
        double z = 0;
        Vec3 moved = Vec3::Zero();
        for (std::size_t e = 0; e < handle.particles.size(); ++e) {
          const btVector3& x = cloth->m_nodes[handle.particles[e]].m_x;
          z += height(handle.particles[e]);
          moved += Vec3(x.x(), x.y(), x.z()) - handle.anchor[e];
        }
        if ((handle.max_height > 0 && z / n >= handle.max_height) ||
            (handle.max_travel > 0 && moved.norm() / n >= handle.max_travel)) {
          for (int k : handle.particles) hold(k, btVector3(0, 0, 0));
          stopped[h] = 1;
        }
      }
    }
  }
};

BulletCloth::BulletCloth(const Model& m, double dt) : w_(std::make_unique<World>()) {
  World& w = *w_;
  w.model = &m;
  w.dt = static_cast<btScalar>(dt);
  const Params& p = m.params;
  const btVector3 gravity = bt(p.forces.gravity);
  w.world.setGravity(gravity);
  btSoftBodyWorldInfo& info = w.world.getWorldInfo();
  info.m_gravity = gravity;  // the soft bodies' own (Bullet's default is y down)
  info.m_sparsesdf.Initialize();

  // The table: a box, its top the plane, wide enough that no node passes
  // its edge; the ball: a sphere.
  const double reach = std::max(1.0, 4.0 * std::max(p.cloth.size[0], p.cloth.size[1]));
  if (p.table.enabled) {
    const btScalar half = static_cast<btScalar>(reach), thick = 0.5f;
    w.table_shape.emplace(btVector3(half, half, thick));
    const Vec3 centre = to_vec(p.cloth.center);
    w.add_static(*w.table_shape,
                 btVector3(static_cast<btScalar>(centre.x()), static_cast<btScalar>(centre.y()),
                           static_cast<btScalar>(p.table.height) - thick));
  }
  if (p.ball.enabled) {
    w.ball_shape.emplace(static_cast<btScalar>(p.ball.radius));
    w.add_static(*w.ball_shape, bt(p.ball.center));
  }

  // CreatePatch puts node x + nu y at the bilinear blend of the corners, as
  // our grid puts particle (i, j) = j nu + i: the cloth is flat, so the two
  // agree (to float).
  if (!m.grid)
    throw SceneError(
        "bench --peer bullet: the peer builds the grid's cloth; a mesh cloth "
        "(cloth.mesh) has no Bullet counterpart here");
  const auto corner = [&](int i, int j) { return bt(m.rest_position[m.index(i, j)]); };
  w.cloth =
      btSoftBodyHelpers::CreatePatch(info, corner(0, 0), corner(m.nu - 1, 0), corner(0, m.nv - 1),
                                     corner(m.nu - 1, m.nv - 1), m.nu, m.nv, 0, true);
  w.cloth->getCollisionShape()->setMargin(kMargin);
  add_bending_links(*w.cloth);
  for (int k = 0; k < m.n; ++k) {
    const double mass = p.cloth.areal_density * m.area[k];
    w.cloth->setMass(k, static_cast<btScalar>(mass));
    w.dry_mass += mass;
  }
  w.world.addSoftBody(w.cloth);
  w.started.assign(m.handles.size(), 0);
  w.stopped.assign(m.handles.size(), 0);
  w.take_nodes();  // what holds the cloth from t = 0 holds it before the first step
}

BulletCloth::~BulletCloth() = default;

void BulletCloth::step() {
  World& w = *w_;
  w.take_nodes();
  w.pull();
  // maxSubSteps 0: exactly one step of dt, no interpolation.
  w.world.stepSimulation(w.dt, 0);
  w.time += w.dt;
  w.stop_handles();
}

double BulletCloth::time() const { return w_->time; }
int BulletCloth::nodes() const { return w_->cloth->m_nodes.size(); }
int BulletCloth::links() const { return w_->cloth->m_links.size(); }
int BulletCloth::faces() const { return w_->cloth->m_faces.size(); }
double BulletCloth::mass() const { return w_->dry_mass; }

double BulletCloth::mean_z() const {
  double sum = 0;
  const auto& nodes = w_->cloth->m_nodes;
  for (int k = 0; k < nodes.size(); ++k) sum += nodes[k].m_x.z();
  return sum / nodes.size();
}

double BulletCloth::max_z() const {
  double top = -INFINITY;
  const auto& nodes = w_->cloth->m_nodes;
  for (int k = 0; k < nodes.size(); ++k) top = std::max(top, static_cast<double>(nodes[k].m_x.z()));
  return top;
}

bool BulletCloth::finite() const {
  const auto& nodes = w_->cloth->m_nodes;
  for (int k = 0; k < nodes.size(); ++k)
    for (int c = 0; c < 3; ++c)
      if (!std::isfinite(nodes[k].m_x[c])) return false;
  return true;
}

std::string bullet_version() {
  const int v = btGetVersion();
  return std::to_string(v / 100) + "." + std::to_string(v % 100);
}

}  // namespace wetcloth::cli
