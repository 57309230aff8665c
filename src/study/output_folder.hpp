// A run's output folder: what a run may write there and remove (docs/guide.md,
// Outputs); the checks before a run are wetcloth/run.hpp's. A run lists the files it writes in
// DIR/.wetcloth.manifest before it writes them; the next run into DIR removes those and nothing
// else, so a user's own file in DIR (or in DIR/frames) stays. No symbolic link is followed when
// writing or clearing.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "wetcloth/run.hpp"

namespace wetcloth {

inline constexpr const char* kManifest = ".wetcloth.manifest";

// Throws SceneError naming the first of `files` (paths relative to OUT), or a
// folder on the way to one, that is a symbolic link: a run writes through none.
void refuse_links(const std::filesystem::path& out, const std::vector<std::string>& files);

// The files the earlier run in OUT wrote: its manifest's, or where OUT holds
// a run of a wetcloth that wrote none, the names such a run writes. Entries
// that would leave OUT are dropped.
std::vector<std::string> earlier_outputs(const std::filesystem::path& out);

// Removes each of `files` (relative to OUT) that is a regular file reached
// without a symbolic link, its `.tmp` beside it, and then the folders among
// them (a trailing '/') that are left empty. OutputError where one cannot be.
void remove_outputs(const std::filesystem::path& out, const std::vector<std::string>& files);

// Writes OUT/.wetcloth.manifest listing `files`.
void write_manifest(const std::filesystem::path& out, const std::vector<std::string>& files);

}  // namespace wetcloth
