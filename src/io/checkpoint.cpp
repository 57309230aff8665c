// Layout: "WETCLOTH-STATE\0\0", the format version (u32), the scene as TOML
// (u64 length, bytes), then the State's fields in declaration order (arrays
// as a u64 count and their elements; Vec3Arrays x, y, z columns; format 4
// adds the humidity field, its film and the water evaporated, format 5 the
// end of a landing's substeps), then
// (format 2) the run's own record (u64 length, bytes), then the FNV-1a 64
// hash of everything before it. Little-endian, as the machines we
// run on.
#include "wetcloth/checkpoint.hpp"

#include <cstdint>
#include <cstring>
#include <fstream>
#include <sstream>
#include <type_traits>

#include "wetcloth/output.hpp"
#include "wetcloth/scene.hpp"

namespace wetcloth {

namespace {

constexpr char kMagic[16] = "WETCLOTH-STATE";
// 1 had no run record, 2 no scene folder, 3 no humidity field: still read
constexpr std::uint32_t kVersion = 5;

std::uint64_t fnv1a(const std::string& bytes) {
  std::uint64_t h = 1469598103934665603ULL;
  for (unsigned char c : bytes) h = (h ^ c) * 1099511628211ULL;
  return h;
}

struct Writer {
  std::string out;
  template <class T>
  void pod(const T& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    out.append(reinterpret_cast<const char*>(&v), sizeof v);
  }
  template <class T>
  void vec(const std::vector<T>& v) {
    pod(static_cast<std::uint64_t>(v.size()));
    for (const T& e : v) pod(e);
  }
  void vec(const std::vector<Vec3>& v) {
    pod(static_cast<std::uint64_t>(v.size()));
    for (const Vec3& e : v)
      for (int q = 0; q < 3; ++q) pod(e[q]);
  }
  void vec3(const Vec3Array& a) {
    pod(static_cast<std::uint64_t>(a.size()));
    for (int q = 0; q < 3; ++q)
      for (std::size_t i = 0; i < a.size(); ++i) pod(a[i][q]);
  }
};

struct Reader {
  const std::string& in;
  std::size_t at = 0;
  std::string file;
  [[noreturn]] void bad(const std::string& what) const { throw SceneError(file + ": " + what); }
  template <class T>
  T pod() {
    T v;
    if (in.size() - at < sizeof v) bad("the checkpoint is cut short");
    std::memcpy(&v, in.data() + at, sizeof v);
    at += sizeof v;
    return v;
  }
  std::size_t count(std::size_t element) {
    const auto n = pod<std::uint64_t>();
    if (element != 0 && n > (in.size() - at) / element) bad("the checkpoint is cut short");
    return static_cast<std::size_t>(n);
  }
  template <class T>
  void vec(std::vector<T>& v) {
    v.resize(count(sizeof(T)));
    for (T& e : v) e = pod<T>();
  }
  void vec(std::vector<Vec3>& v) {
    v.resize(count(3 * sizeof(double)));
    for (Vec3& e : v)
      for (int q = 0; q < 3; ++q) e[q] = pod<double>();
  }
  void vec3(Vec3Array& a) {
    a.assign(count(3 * sizeof(double)), Vec3::Zero());
    for (int q = 0; q < 3; ++q)
      for (std::size_t i = 0; i < a.size(); ++i) a[i][q] = pod<double>();
  }
};

// Every field of State, in one place for both directions.
template <class IO>
void fields(IO& io, State& s, std::uint32_t version) {
  const auto scalar = [&](auto& v) {
    if constexpr (std::is_same_v<IO, Writer>)
      io.pod(v);
    else
      v = io.template pod<std::remove_reference_t<decltype(v)>>();
  };
  scalar(s.time);
  scalar(s.steps);
  io.vec3(s.x);
  io.vec3(s.v);
  io.vec(s.contact);
  io.vec(s.held);
  io.vec(s.held_at);
  scalar(s.air_atm_volume);
  scalar(s.air_volume);
  scalar(s.inner_pressure);
  scalar(s.peak_deficit);
  io.vec(s.air_share);
  io.vec(s.air_gap);
  io.vec(s.pocket_pressure);
  io.vec(s.source_distance);
  scalar(s.sources_found);
  io.vec(s.pocket);
  io.vec(s.pocket_air);
  scalar(s.halvings);
  io.vec3(s.acceleration);
  if (version < 4) return;  // no field: restore starts the scene's
  io.vec(s.humidity);
  io.vec(s.film);
  scalar(s.water_evaporated);
  if (version < 5) return;  // no landing under way
  scalar(s.landing_until);
}

}  // namespace

void save_checkpoint(const std::filesystem::path& path, const Params& params, const State& state,
                     const std::string& run) {
  Writer w;
  w.out.append(kMagic, sizeof kMagic);
  w.pod(kVersion);
  const std::string toml = to_toml(params);
  w.pod(static_cast<std::uint64_t>(toml.size()));
  w.out += toml;
  // Where the scene's meshes are found (Params::scene_dir): not a key.
  w.pod(static_cast<std::uint64_t>(params.scene_dir.size()));
  w.out += params.scene_dir;
  fields(w, const_cast<State&>(state), kVersion);  // the writer only reads
  w.pod(static_cast<std::uint64_t>(run.size()));
  w.out += run;
  w.pod(fnv1a(w.out));
  write_file_atomic(path, w.out, Durability::kSynced);
}

Checkpoint load_checkpoint(const std::filesystem::path& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw SceneError(path.string() + ": cannot read");
  std::ostringstream buf;
  buf << f.rdbuf();
  const std::string bytes = buf.str();
  Reader r{bytes, 0, path.string()};
  if (bytes.size() < sizeof kMagic + 4 + 8 || std::memcmp(bytes.data(), kMagic, sizeof kMagic) != 0)
    r.bad("not a wetcloth checkpoint");
  r.at = sizeof kMagic;
  const auto version = r.pod<std::uint32_t>();
  if (version < 1 || version > kVersion)
    r.bad("a checkpoint of format " + std::to_string(version) +
          "; this wetcloth reads formats 1 to " + std::to_string(kVersion));
  std::uint64_t stored;
  std::memcpy(&stored, bytes.data() + bytes.size() - 8, 8);
  if (fnv1a(bytes.substr(0, bytes.size() - 8)) != stored)
    r.bad("the checksum does not match: the file is damaged");
  Checkpoint c;
  const std::size_t length = r.count(1);
  const std::string toml(bytes, r.at, length);
  r.at += length;
  c.params = parse_scene(toml, path.string() + " (its scene)");
  if (version >= 3) {
    const std::size_t dir = r.count(1);
    if (dir > bytes.size() - 8 - r.at) r.bad("the checkpoint is cut short");
    c.params.scene_dir.assign(bytes, r.at, dir);
    r.at += dir;
  }
  fields(r, c.state, version);
  if (version >= 2) {
    const std::size_t run = r.count(1);
    if (run > bytes.size() - 8 - r.at) r.bad("the checkpoint is cut short");
    c.run.assign(bytes, r.at, run);
    r.at += run;
  }
  if (r.at != bytes.size() - 8) r.bad("unexpected bytes after the state");
  return c;
}

}  // namespace wetcloth
