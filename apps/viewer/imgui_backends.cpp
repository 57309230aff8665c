// Dear ImGui's GLFW and OpenGL 3 backends (Debian ships them as sources), built
// against epoxy, our GL loader, instead of the backend's own: one loader for all
// GL calls, whether the context comes from GLFW or EGL.
#include <epoxy/gl.h>
#define GLFW_INCLUDE_NONE
#define IMGUI_IMPL_OPENGL_LOADER_CUSTOM
#include "imgui_impl_glfw.cpp"
#include "imgui_impl_opengl3.cpp"
