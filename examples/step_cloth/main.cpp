// Steps a damp cloth falling onto the table and prints how it settles.
#include <cstdio>
#include <wetcloth/scene.hpp>
#include <wetcloth/simulation.hpp>

int main() {
  wetcloth::Params p = wetcloth::load_scene("drop-table", {"cloth.resolution=[21,21]"});
  p.cloth.humidity = 0.8;  // parameters are plain data: set them in code too
  wetcloth::Simulation sim(p);
  for (int frame = 1; frame <= 10; ++frame) {
    if (!sim.advance_to(frame * 0.1)) {
      std::fprintf(stderr, "%s\n", sim.blow_up_reason().c_str());
      return 3;
    }
    const wetcloth::Metrics m = sim.metrics();
    std::printf("t = %.1f s  height %.4f m  contact area %.4f m²  kinetic energy %.2e J\n",
                m.time_s, m.max_height_m, m.contact_area_m2, m.kinetic_energy_j);
  }
  return 0;
}
