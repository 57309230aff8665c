// The cloth as the viewer shows it: positions, normals and a colour per particle,
// either the fabric's own or a field of the simulation mapped through a colour scale.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "draw.hpp"
#include "wetcloth/simulation.hpp"

namespace wetcloth::viewer {

enum class ColorBy { Fabric, Contact, Pressure, Strain, Adhesion, Humidity };
inline constexpr std::array<const char*, 6> kColorByNames{"none",   "contact",  "pressure",
                                                          "strain", "adhesion", "humidity"};

// The legend of the current colouring.
struct Legend {
  std::string title;       // what is shown, with its unit
  float lo = 0, hi = 1;    // values at the two ends of the scale
  bool diverging = false;  // blue - white - red around zero
  bool binary = false;     // contact: two colours
};

// sRGB colour of t in [0, 1] on the sequential (viridis) or diverging scale.
Vec3f colormap(float t, bool diverging);
// The two colours of the contact colouring.
inline const Vec3f kContactColor{0.95f, 0.55f, 0.15f}, kFreeColor{0.55f, 0.60f, 0.68f};

// Builds the mesh of the simulation's cloth, coloured by mode. The scales are
// fixed by the scene, so that a colour means the same value all along a run:
// pressure +-air.breakthrough_pressure (the deficit at which air breaks
// through), strain 0 to strain_limit.tau, adhesion 0 to twice an inner
// particle's share of eq. 13, humidity 0 to 1 (each particle's ω). range > 0
// sets the top of the scale instead. The fabric's own look (ColorBy::Fabric)
// follows each particle's ω and whether it touches a surface (fabric_look).
// Only without adhesion (a scale of 0) is there an automatic one: scale grows
// at once and shrinks slowly, so that colours do not flicker; keep it between calls.
Legend cloth_mesh(const Simulation& sim, ColorBy mode, float& scale, ClothMesh& mesh,
                  float range = 0);

// The fabric as it looks at humidity ω, lying on a surface or not. Water
// darkens cloth (light goes into the water-filled weave instead of back out)
// and glosses it; where a wet cloth lies on a surface it is pressed flat into
// its film, darker and glossier still, as a wet patch looks, so the default
// picture shows where the cloth clings. touching: 0 (free) to 1 (on a
// surface). The albedo (the colour squared) is (1 - 0.45 ω)(1 - touching
// (0.1 + 0.3 ω)); the gloss (0..1, the shader's specular weight and
// sharpness) is (1 + 0.6 touching) ω, at most 1.
struct FabricLook {
  Vec3f color;
  float gloss;
};
FabricLook fabric_look(float omega, float touching);

// Whether a point of a cloth whose frame holds no contact field touches the
// stage: within h of the table top (and over it) or of the ball (a run's
// last frame, read back for the contact sheet).
bool touches_stage(const Stage& stage, const Vec3f& p, float h);

// Draws the legend as a key into the bottom-left corner of a picture (what the
// viewer's panel shows): a colour bar with its numbers, or the two contact colours.
void draw_key(Image& img, const Legend& legend);

// A legend's number, short: 1000, 0.05, 1.2e-05.
std::string key_number(float v);

}  // namespace wetcloth::viewer
