#include "wetcloth/output_folder.hpp"

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <fstream>
#include <iterator>
#include <tuple>

#include "wetcloth/output.hpp"
#include "wetcloth/scene.hpp"

namespace wetcloth {

namespace fs = std::filesystem;

namespace {

// A file a wetcloth run writes, as a relative path that stays in its folder.
bool inside_name(const std::string& name) {
  if (name.empty() || name.front() == '/' || name.size() > 1024) return false;
  for (const char c : name)
    if (static_cast<unsigned char>(c) < 0x20) return false;
  for (const auto& part : fs::path(name))
    if (part == ".." || part == ".") return false;
  const std::string file = name.back() == '/' ? name.substr(0, name.size() - 1) : name;
  return !file.empty() && file != kManifest && file != ".wetcloth.lock";
}

// lstat's kind of PATH: 'f' a regular file, 'd' a folder, 'l' a link, 'o'
// something else, 0 nothing there.
char kind(const fs::path& path) {
  struct stat st {};
  if (::lstat(path.c_str(), &st) != 0) return 0;
  return S_ISREG(st.st_mode) ? 'f' : S_ISDIR(st.st_mode) ? 'd' : S_ISLNK(st.st_mode) ? 'l' : 'o';
}

// The folders between OUT and OUT/REL are folders, not links.
bool reached_without_links(const fs::path& out, const std::string& rel) {
  fs::path at = out;
  const fs::path r(rel);
  for (auto it = r.begin(); it != r.end(); ++it) {
    if (std::next(it) == r.end() || it->empty()) break;
    at /= *it;
    if (kind(at) != 'd') return false;
  }
  return true;
}

// A run of a wetcloth that wrote no manifest: its scene.toml says so.
bool holds_older_run(const fs::path& out) {
  if (kind(out / "scene.toml") != 'f') return false;
  std::ifstream f(out / "scene.toml");
  std::string first;
  std::getline(f, first);
  return first.rfind("# resolved by wetcloth", 0) == 0;
}

// What such a run wrote: its fixed names, and the frames by their pattern.
std::vector<std::string> older_run_outputs(const fs::path& out) {
  std::vector<std::string> files = {"metrics.csv",         "summary.json", "scene.toml",
                                    "obstacles.obj",       "cloth.usda",   "cloth.pc2",
                                    "cloth_rest.obj",      "cloth.pvd",    "checkpoint.state",
                                    "vtk/obstacles.vtp",   "frames/",      "vtk/",
                                    ".cloth.usda.samples/"};
  for (const char* a : {"points", "normals", "extent", "contact", "pressure", "adhesion",
                        "humidity", "velocities", "deficit"})
    files.push_back(std::string(".cloth.usda.samples/") + a);
  for (const auto& [folder, prefix, extension] :
       {std::tuple{"frames", "frame_", ".obj"}, {"vtk", "cloth_", ".vtp"}}) {
    if (kind(out / folder) != 'd') continue;
    std::error_code ec;
    for (fs::directory_iterator it(out / folder, ec), end; !ec && it != end; it.increment(ec)) {
      const std::string name = it->path().filename().string(), p = prefix, e = extension;
      const bool digits = name.size() >= p.size() + 5 + e.size() && name.rfind(p, 0) == 0 &&
                          name.compare(name.size() - e.size(), e.size(), e) == 0 &&
                          std::all_of(name.begin() + static_cast<long>(p.size()),
                                      name.end() - static_cast<long>(e.size()),
                                      [](char c) { return c >= '0' && c <= '9'; });
      if (digits) files.push_back(std::string(folder) + "/" + name);
    }
  }
  return files;
}

}  // namespace

void refuse_foreign_folder(const fs::path& out, const std::string& option, const std::string& what,
                           const std::vector<std::string>& marks) {
  std::error_code ec;
  if (!fs::is_directory(out, ec)) return;  // made new, or refused as a file elsewhere
  // A mark with a suffix: the temporary file of one being written (a sweep's
  // cases.csv.PID.tmp, as another task of its job array starts).
  const auto marked = [&](const std::string& name) {
    for (const std::string& m : marks)
      if (name == m || name.rfind(m + ".", 0) == 0) return true;
    return false;
  };
  std::string first;
  for (fs::directory_iterator it(out, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name == ".wetcloth.lock") continue;  // an older run's, or one under way
    if (name == kManifest || marked(name)) return;
    if (first.empty()) first = name;
  }
  if (first.empty() || holds_older_run(out)) return;
  throw SceneError(option + " " + out.string() + ": holds files no wetcloth " + what + " wrote (" +
                   first + ", ...): a " + what +
                   " would mix its outputs with them; choose a new or empty folder, or give "
                   "--force to write beside them" +
                   (what == "run" ? " (a run removes only what a wetcloth run wrote there)" : ""));
}

void refuse_links(const fs::path& out, const std::vector<std::string>& files) {
  for (const std::string& rel : files) {
    fs::path at = out;
    for (const auto& part : fs::path(rel)) {
      if (part.empty()) continue;
      at /= part;
      const char k = kind(at);
      if (k == 'l')
        throw SceneError(at.string() +
                         ": a symbolic link, where the run writes its outputs: wetcloth writes "
                         "through no link (remove it, or choose another folder)");
      if (k != 'd') break;  // a file, or not there yet: nothing below it to check
    }
  }
}

std::vector<std::string> earlier_outputs(const fs::path& out) {
  std::vector<std::string> files;
  if (kind(out / kManifest) == 'f') {
    std::ifstream f(out / kManifest);
    for (std::string line; std::getline(f, line);)
      if (!line.empty() && line[0] != '#' && inside_name(line)) files.push_back(line);
    return files;
  }
  return holds_older_run(out) ? older_run_outputs(out) : files;
}

void remove_outputs(const fs::path& out, const std::vector<std::string>& files) {
  std::vector<std::string> folders;
  for (const std::string& rel : files) {
    if (!inside_name(rel) || !reached_without_links(out, rel)) continue;
    if (rel.back() == '/') {
      folders.push_back(rel.substr(0, rel.size() - 1));
      continue;
    }
    for (const fs::path& path : {out / rel, fs::path((out / rel).string() + ".tmp")})
      if (kind(path) == 'f' && ::unlink(path.c_str()) != 0 && errno != ENOENT)
        throw_output_error(path, "cannot remove", errno);
  }
  // The deepest first; a folder that holds something else stays.
  std::sort(folders.begin(), folders.end(),
            [](const std::string& a, const std::string& b) { return a.size() > b.size(); });
  for (const std::string& rel : folders)
    if (kind(out / rel) == 'd' && ::rmdir((out / rel).c_str()) != 0 && errno != ENOTEMPTY &&
        errno != EEXIST && errno != ENOENT)
      throw_output_error(out / rel, "cannot remove", errno);
}

std::string folder_name(const std::string& name) {
  std::string f;
  for (const char c : name) {
    const auto u = static_cast<unsigned char>(c);
    f += (c == '/' || c == '\\' || u < 0x20 || u == 0x7F || (f.empty() && c == '.')) ? '_' : c;
  }
  return f.empty() ? "scene" : f;
}

void check_output_folder(const fs::path& out, const std::string& option) {
  for (fs::path at = out; !at.empty() && at != at.parent_path(); at = at.parent_path()) {
    std::error_code ec;
    const auto st = fs::status(at, ec);
    if (!fs::exists(st)) continue;
    if (fs::is_directory(st)) return;
    throw SceneError(option + " " + out.string() + ": " +
                     (at == out ? "exists and is not a folder" : at.string() + " is not a folder"));
  }
}

void refuse_system_folder(const fs::path& out, const std::string& option) {
  std::error_code ec;
  fs::path real = fs::absolute(out, ec);
  if (!ec) {
    const fs::path through_links = fs::weakly_canonical(real, ec);
    real = ec ? real.lexically_normal() : through_links;
  }
  std::string at = real.lexically_normal().generic_string();
  while (at.size() > 1 && at.back() == '/') at.pop_back();
  // Folders of the system and of everyone, whose files are not a run's...
  static const char* const kExactly[] = {"/",    "/home", "/media", "/mnt", "/opt", "/root",
                                         "/run", "/snap", "/srv",   "/tmp", "/var"};
  // ... and those of the system all the way down.
  static const char* const kUnder[] = {"/bin",   "/boot",   "/dev",  "/etc",  "/lib", "/lib32",
                                       "/lib64", "/libx32", "/proc", "/sbin", "/sys", "/usr"};
  bool system = std::find(std::begin(kExactly), std::end(kExactly), at) != std::end(kExactly);
  for (const std::string u : kUnder) system = system || at == u || at.rfind(u + "/", 0) == 0;
  if (system)
    throw SceneError(
        option + " " + out.string() + ": " +
        (at == "/" ? std::string("the filesystem's root") : at + " is a system folder") +
        ": wetcloth writes no outputs there (choose a folder of your own, e.g. out/NAME)");
}

void make_output_folder(const fs::path& out, const std::string& option) {
  check_output_folder(out, option);
  refuse_system_folder(out, option);
  std::error_code ec;
  std::filesystem::create_directories(out, ec);
  if (ec) throw SceneError(option + " " + out.string() + ": cannot make it (" + ec.message() + ")");
}

void write_manifest(const fs::path& out, const std::vector<std::string>& files) {
  std::string text =
      "# wetcloth " WETCLOTH_VERSION
      ": the files a run writes in this folder; the next run into it removes these, and "
      "nothing else\n";
  for (const std::string& f : files) text += f + "\n";
  write_file_atomic(out / kManifest, text);
}

}  // namespace wetcloth
