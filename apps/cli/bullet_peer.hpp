// `wetcloth bench --peer bullet`: Bullet's btSoftBody on a scene's cloth, made
// plain, so that bench can time it beside ours. Compiled only where Bullet
// (Debian's libbullet-dev) was found when the build was configured
// (WETCLOTH_BULLET); this header needs no Bullet header.
#pragma once

#include <memory>
#include <string>

#include "wetcloth/simulation.hpp"

namespace wetcloth::cli {

// The cloth of a Model in Bullet: the same grid of nodes at the same places
// (btSoftBodyHelpers::CreatePatch on the model's four corners: node k is our
// particle k), each node's dry mass (cloth.areal_density times its area, as
// ours has at humidity 0), gravity, the table (a static box whose top is the
// plane) and the ball (a static sphere), and the handles: a pin holds its
// nodes (mass 0), a move handle drives them at its velocity, a force handle
// pulls them with its force, shared by area, until its height cap or travel
// stops it, and then holds them, as ours does. Left out, as Bullet has no
// such thing or leaves it off by default: trapped air, adhesion,
// self-collision, wind, damping, strain limiting. Every setting of Bullet's
// is its default but the collision margin (1 mm, not 0.25 m) and the bending
// links a cloth needs: those of generateBendingConstraints(2), every node tied
// to those two links away (made without its n × n matrix: bullet_peer.cpp).
class BulletCloth {
 public:
  BulletCloth(const Model& m, double dt);
  ~BulletCloth();
  BulletCloth(const BulletCloth&) = delete;
  BulletCloth& operator=(const BulletCloth&) = delete;

  void step();  // one step of dt
  double time() const;
  int nodes() const;
  int links() const;  // every link: the grid's, one diagonal a quad, the bending links
  int faces() const;
  double mass() const;  // kg, the nodes that move
  // Of the nodes: the mean height and the highest, m (z, as ours).
  double mean_z() const;
  double max_z() const;
  bool finite() const;  // no NaN or infinity in the positions

 private:
  struct World;
  std::unique_ptr<World> w_;
};

// Bullet's version, e.g. "3.24".
std::string bullet_version();

}  // namespace wetcloth::cli
