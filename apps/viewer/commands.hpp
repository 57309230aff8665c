// The graphical commands of the wetcloth program: `view` (a window, live
// simulation) and `render` (offscreen PNG frames, optional MP4), and the
// sweep's contact sheet. All of it draws through draw.hpp.
#pragma once

#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace CLI {
class App;
}

namespace wetcloth::viewer {

// Registers `view` and `render` on app. After parsing, the returned callable runs
// whichever of them was chosen and returns its exit code; std::nullopt if neither.
std::function<std::optional<int>()> add_commands(CLI::App& app);

// Renders the last frame of each case side by side in one PNG, with its label on
// the tile, all tiles from the same camera (a 3/4 view from above). A case is
// (label, folder written by `wetcloth run`: scene.toml, frames/frame_NNNNN.obj).
// Offscreen (EGL); returns false with *error set on failure.
bool render_contact_sheet(const std::vector<std::pair<std::string, std::filesystem::path>>& cases,
                          const std::filesystem::path& png, int tile_w, int tile_h,
                          std::string* error);

}  // namespace wetcloth::viewer
