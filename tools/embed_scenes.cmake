# Writes OUT: the scenes/*.toml files as string literals, so that built-in
# scenes are found by name wherever the program runs.
file(GLOB scenes "${SCENES_DIR}/*.toml")
list(SORT scenes)
set(body "// Generated from scenes/*.toml by tools/embed_scenes.cmake. Do not edit.\n#include \"wetcloth/scene.hpp\"\nnamespace wetcloth {\nconst std::vector<BuiltinScene>& builtin_scene_texts() {\n  static const std::vector<BuiltinScene> v = {\n")
foreach(f ${scenes})
  get_filename_component(name "${f}" NAME_WE)
  file(READ "${f}" text)
  string(APPEND body "    {\"${name}\", \"\", R\"wetcloth_scene(${text})wetcloth_scene\"},\n")
endforeach()
string(APPEND body "  };\n  return v;\n}\n}  // namespace wetcloth\n")
file(WRITE "${OUT}.tmp" "${body}")
file(COPY_FILE "${OUT}.tmp" "${OUT}" ONLY_IF_DIFFERENT)
