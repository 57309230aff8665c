// Measures the offscreen drawing speed: ms per frame at a size, with and without
// multisampling and shadows. Not a test; run it by hand:
//   build/tests/viewer/wetcloth_viewer_bench [WIDTH HEIGHT FRAMES]
#include <epoxy/gl.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <ctime>

#include "viewer/coloring.hpp"
#include "viewer/draw.hpp"
#include "viewer/egl_context.hpp"
#include "wetcloth/scene.hpp"

using namespace wetcloth;
using namespace wetcloth::viewer;

int main(int argc, char** argv) {
  const int w = argc > 2 ? std::atoi(argv[1]) : 1280, h = argc > 2 ? std::atoi(argv[2]) : 720;
  const int frames = argc > 3 ? std::atoi(argv[3]) : 10;
  Params p = load_scene("pull-straight", {"run.duration=0.2"});
  Simulation sim(p);
  sim.advance_to(0.2);
  OffscreenContext ctx;
  Renderer r;
  ClothMesh mesh;
  float scale = 0;
  cloth_mesh(sim, ColorBy::Fabric, scale, mesh);
  const Camera cam = frame_scene(p, static_cast<float>(w) / h);
  const Stage stage = stage_from(p);
  for (int samples : {4, 0})
    for (bool shadows : {true, false}) {
      Framebuffer fb(w, h, samples);
      DrawOptions opt;
      opt.shadows = shadows;
      fb.bind();
      r.draw(mesh, stage, cam, w, h, opt);  // warm-up: shader compilation
      fb.read();
      double draw_ms = 0, read_ms = 0;
      const std::clock_t c0 = std::clock();
      for (int i = 0; i < frames; ++i) {
        auto t0 = std::chrono::steady_clock::now();
        fb.bind();
        r.draw(mesh, stage, cam, w, h, opt);
        glFinish();
        auto t1 = std::chrono::steady_clock::now();
        fb.read();
        auto t2 = std::chrono::steady_clock::now();
        draw_ms += std::chrono::duration<double, std::milli>(t1 - t0).count();
        read_ms += std::chrono::duration<double, std::milli>(t2 - t1).count();
      }
      const double cpu_ms = 1000.0 * static_cast<double>(std::clock() - c0) / CLOCKS_PER_SEC;
      std::printf(
          "%dx%d  msaa %d  shadows %-3s  %.1f ms per frame: %.1f draw, %.1f read back (CPU %.1f "
          "ms)\n",
          w, h, samples, shadows ? "on" : "off", (draw_ms + read_ms) / frames, draw_ms / frames,
          read_ms / frames, cpu_ms / frames);
    }
}
