// A run's output folder (docs/guide.md, Outputs): the checks before a run
// writes into it, and what a run may write there and remove. A run lists the
// files it writes in DIR/.wetcloth.manifest before it writes them; the next
// run into DIR removes those and nothing else, so a user's own file in DIR (or
// in DIR/frames) stays. No symbolic link is followed when writing or clearing.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace wetcloth {

// `option` names the folder in an error: "--out" on the command line, "out"
// in Python.

// A scene's name as one folder under out/ (the default output folder): a name
// is a label, not a path, so '/', '\\' and control characters become '_', and
// a leading '.' too (no "..", no hidden folder); an empty name is "scene".
std::string folder_name(const std::string& name);
// Throws SceneError (bad input) when `out`, or the nearest part of it that
// exists, is not a folder: checked before anything runs or is written.
void check_output_folder(const std::filesystem::path& out, const std::string& option = "--out");
// Throws SceneError (bad input) where OUT is the filesystem's root or a
// system folder (/etc, /proc, /usr, ...), however it is spelt (`..`, a link):
// no command writes there, force or not.
void refuse_system_folder(const std::filesystem::path& out, const std::string& option = "--out");
// check_output_folder, then makes the folder: one that cannot be made (no
// permission, a read-only place) is bad input too, as is a system folder. (An
// existing folder that cannot be written into fails as the first file does:
// exit 4, an output that cannot be written.)
void make_output_folder(const std::filesystem::path& out, const std::string& option = "--out");
// Throws SceneError where OUT exists, holds something, and holds no earlier
// wetcloth output (no manifest, no scene.toml a run wrote, nothing named as
// one of `marks`, or one of them and a suffix after a '.'): the command,
// `what` ("run", "sweep", ...), would mix its files with someone else's.
// `force` writes into it all the same.
void refuse_foreign_folder(const std::filesystem::path& out, const std::string& option = "--out",
                           const std::string& what = "run",
                           const std::vector<std::string>& marks = {});

// --- what a run writes and removes (study/run.cpp) ---

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
