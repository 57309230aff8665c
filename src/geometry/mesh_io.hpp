// Triangle meshes a scene names (a cloth, an obstacle): read from OBJ files
// with tinyobjloader, checked, and found relative to the scene file.
#pragma once

#include <array>
#include <filesystem>
#include <string>
#include <vector>

#include "wetcloth/params.hpp"

namespace wetcloth {

struct TriangleMesh {
  std::string source;                           // the file, for messages
  std::vector<std::array<double, 3>> position;  // per vertex, in the file's units and axes
  // Per vertex (empty: the file has no texture coordinates). Where faces give
  // one vertex different coordinates (a seam), the first face's are kept and
  // corner_uv has every face's.
  std::vector<std::array<double, 2>> uv;
  std::vector<std::array<int, 3>> triangles;                    // counter-clockwise as in the file
  std::vector<std::array<std::array<double, 2>, 3>> corner_uv;  // per triangle corner (or empty)
  // The file's quadrilaterals (split into two triangles each, along a-c):
  // shear springs tie both diagonals.
  std::vector<std::array<int, 4>> quads;
};

// What a mesh must be to be used.
struct MeshRules {
  bool manifold = true;  // no edge shared by more than two triangles
};

// Reads an OBJ file's faces (polygons are split into a fan of triangles).
// Throws SceneError naming the file and what is wrong: not OBJ, no faces, an
// index out of range, a degenerate triangle (repeated vertex or zero area), a
// non-manifold edge (when the rules ask), a coordinate that is not finite.
TriangleMesh read_obj(const std::string& text, const std::string& source,
                      const MeshRules& rules = {});

// The mesh a scene names with `key` (e.g. cloth.mesh): `path` is relative to
// the scene file's folder (Params::scene_dir) and may not leave it; a built-in
// scene's meshes are built into the program (scenes/meshes/). Throws
// SceneError naming the scene's key and the path.
TriangleMesh load_scene_mesh(const Params& p, const std::string& key, const std::string& path,
                             const MeshRules& rules = {});

// Where load_scene_mesh looks for `path`, after the same checks (for a
// built-in scene: "builtin:" and the path).
std::filesystem::path resolve_scene_path(const Params& p, const std::string& key,
                                         const std::string& path);

}  // namespace wetcloth
