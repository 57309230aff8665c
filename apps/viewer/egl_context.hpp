// An OpenGL 3.3 core context with no window, through EGL: works on a server with
// no display and no GPU (Mesa's llvmpipe).
#pragma once

namespace wetcloth::viewer {

class OffscreenContext {
 public:
  // Creates the context and makes it current. Throws std::runtime_error.
  OffscreenContext();
  ~OffscreenContext();
  OffscreenContext(const OffscreenContext&) = delete;
  OffscreenContext& operator=(const OffscreenContext&) = delete;

 private:
  void* display_ = nullptr;
  void* context_ = nullptr;
  void* surface_ = nullptr;  // a 1x1 pbuffer, only where surfaceless contexts are missing
};

}  // namespace wetcloth::viewer
