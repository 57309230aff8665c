// A sweep's plan, its cases run and its folder gathered (include/wetcloth/sweep.hpp).
#include "wetcloth/sweep.hpp"

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <set>
#include <sstream>
#include <variant>

#include "wetcloth/output.hpp"

namespace wetcloth::sweep {

namespace fs = std::filesystem;

namespace {

std::string trim(const std::string& s) {
  const auto a = s.find_first_not_of(" \t"), b = s.find_last_not_of(" \t");
  return a == std::string::npos ? std::string() : s.substr(a, b - a + 1);
}

}  // namespace

// KEY=V1,V2,...: the values split at the commas outside brackets and quotes,
// so that arrays may be varied (cloth.resolution=[25,25],[51,51]).
Varied parse_vary(const std::string& text) {
  const auto eq = text.find('=');
  const std::string key = eq == std::string::npos ? std::string() : trim(text.substr(0, eq));
  if (key.empty())
    throw SceneError("--vary '" + text + "': expected KEY=V1,V2,..., e.g. cloth.humidity=0.3,0.7");
  Varied v{key, {}, "--vary " + key};
  std::string cur;
  int depth = 0;
  char quote = 0;
  const auto push = [&] {
    const std::string value = trim(cur);
    if (value.empty()) throw SceneError("--vary '" + text + "': an empty value");
    v.values.push_back(value);
    cur.clear();
  };
  for (char c : text.substr(eq + 1)) {
    if (quote) {
      if (c == quote) quote = 0;
    } else if (c == '"' || c == '\'') {
      quote = c;
    } else if (c == '[') {
      ++depth;
    } else if (c == ']') {
      --depth;
    } else if (c == ',' && depth == 0) {
      push();
      continue;
    }
    cur += c;
  }
  push();
  return v;
}

// The parameter a key names (handle.NAME.KEY: handle.*.KEY; obstacle.NAME.KEY:
// obstacle.*.KEY), and the NAME.
const ParamDef* def_of(const std::string& key, std::string* name) {
  std::string want = key;
  for (const std::string kind : {"handle.", "obstacle."})
    if (key.rfind(kind, 0) == 0) {
      const auto dot = key.find('.', kind.size());
      if (dot == std::string::npos) return nullptr;
      if (name) *name = key.substr(kind.size(), dot - kind.size());
      want = kind + "*." + key.substr(dot + 1);
    }
  for (const ParamDef& d : param_defs())
    if (d.key == want) return &d;
  return nullptr;
}

// Throws SceneError unless p has the handle or obstacle that KEY (of
// definition d) names.
void check_named(const Params& p, const std::string& key, const ParamDef& d,
                 const std::string& name) {
  if (d.key.rfind("handle.*.", 0) == 0 && !p.handles.count(name))
    throw SceneError(key + ": the scene has no such handle");
  if (d.key.rfind("obstacle.*.", 0) == 0 && !p.obstacles.count(name))
    throw SceneError(key + ": the scene has no such obstacle");
}

namespace {

std::string value_text(const Params& p, const std::string& key) {
  std::string name;
  const ParamDef* d = def_of(key, &name);
  if (!d) throw SceneError(key + ": unknown key (wetcloth params lists the keys)");
  check_named(p, key, *d, name);
  // Numbers in their shortest exact text (100, not 100.0), strings unquoted.
  return std::visit(
      [](const auto& x) -> std::string {
        using T = std::decay_t<decltype(x)>;
        if constexpr (std::is_same_v<T, std::string>)
          return x;
        else if constexpr (std::is_same_v<T, bool>)
          return x ? "true" : "false";
        else if constexpr (std::is_same_v<T, double>)
          return format_number(x);
        else if constexpr (std::is_same_v<T, long long>)
          return std::to_string(x);
        else {
          std::string o = "[";
          for (const auto& e : x)
            o += (o.size() > 1 ? ", " : "") + format_number(static_cast<double>(e));
          return o + "]";
        }
      },
      d->get(p, name));
}

// A value as part of a folder name: letters, digits and . + -; an array's
// numbers joined by x ([25, 25] -> 25x25).
std::string name_part(const std::string& text) {
  std::string o;
  for (char c : text) {
    if (std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '+' || c == '-')
      o += c;
    else if (c == ',')
      o += 'x';
    else if (c != '[' && c != ']' && c != ' ' && c != '"')
      o += '_';
  }
  return o;
}

// The number of cases; SceneError on no key, a key varied twice, a key
// without values, or too many cases.
std::size_t case_count(const std::vector<Varied>& varied) {
  if (varied.empty())
    throw SceneError("nothing to vary: give --vary KEY=V1,V2,... (or --humidity, --air-models)");
  std::size_t total = 1;
  for (std::size_t k = 0; k < varied.size(); ++k) {
    for (std::size_t j = 0; j < k; ++j)
      if (varied[j].key == varied[k].key)
        throw SceneError(varied[k].option + ": " + varied[k].key + " is varied twice");
    if (varied[k].values.empty()) throw SceneError(varied[k].option + ": no values");
    total *= varied[k].values.size();
    if (total > 100000) throw SceneError("--vary: more than 100000 cases");
  }
  return total;
}

// Case c's value of each key, by index (the first key outermost).
std::vector<std::size_t> value_indices(const std::vector<Varied>& varied, std::size_t c) {
  std::vector<std::size_t> at(varied.size(), 0);
  for (std::size_t k = varied.size(); k-- > 0;) {
    at[k] = c % varied[k].values.size();
    c /= varied[k].values.size();
  }
  return at;
}

// Each value of each key as read back from the cases' scenes ("0.50" ->
// 0.5), and a humidity's as a number.
struct ReadBack {
  std::vector<std::vector<std::string>> text;
  std::vector<std::vector<double>> omega;
};

bool is_extra_key(const std::string& key) { return key != "cloth.humidity" && key != "air.model"; }

// The decimals that tell the humidities apart, 2 at least.
int humidity_decimals(std::vector<double> w) {
  std::sort(w.begin(), w.end());
  const auto distinct = [&](int d) {
    char a[32], b[32];
    for (std::size_t i = 1; i < w.size(); ++i) {
      std::snprintf(a, sizeof a, "%.*f", d, w[i - 1]);
      std::snprintf(b, sizeof b, "%.*f", d, w[i]);
      if (std::strcmp(a, b) == 0) return false;
    }
    return true;
  };
  int decimals = 2;
  while (!distinct(decimals)) ++decimals;  // ends by 17: the doubles differ
  return decimals;
}

// The names: a part for each key with several values (humidity always, as
// omega_0.70 with the decimals that tell the values apart; an air model as
// its name; any other key as NAME=VALUE, NAME its last part unless two keys
// share it); with no such key, every key's part.
void name_cases(const std::vector<Varied>& varied, const ReadBack& read, Plan& plan) {
  std::vector<std::string> shorts;
  for (const auto& v : varied) shorts.push_back(v.key.substr(v.key.rfind('.') + 1));
  std::vector<bool> named(varied.size());
  bool any = false;
  for (std::size_t k = 0; k < varied.size(); ++k) {
    named[k] = varied[k].values.size() > 1 || varied[k].key == "cloth.humidity";
    any = any || named[k];
  }
  if (!any) named.assign(varied.size(), true);
  std::vector<int> decimals(varied.size(), 2);
  for (std::size_t k = 0; k < varied.size(); ++k)
    if (varied[k].key == "cloth.humidity") decimals[k] = humidity_decimals(read.omega[k]);
  for (std::size_t c = 0; c < plan.cases.size(); ++c) {
    const std::vector<std::size_t> at = value_indices(varied, c);
    std::string name;
    for (std::size_t k = 0; k < varied.size(); ++k) {
      if (!named[k]) continue;
      std::string part;
      if (varied[k].key == "cloth.humidity") {
        char buf[64];
        std::snprintf(buf, sizeof buf, "omega_%.*f", decimals[k], read.omega[k][at[k]]);
        part = buf;
      } else if (varied[k].key == "air.model") {
        part = read.text[k][at[k]];
      } else {
        const bool shared = std::count(shorts.begin(), shorts.end(), shorts[k]) > 1;
        part = (shared ? varied[k].key : shorts[k]) + "=" + name_part(read.text[k][at[k]]);
      }
      name += (name.empty() ? "" : "_") + part;
    }
    plan.cases[c].name = name;
  }
}

}  // namespace

// Every case, in the order of the cartesian product (the first key outermost).
// load(sets) gives the scene with the base overrides and then `sets`; it
// throws SceneError on a bad value. Throws SceneError on a key given twice, a
// value given twice (after reading: 0.5 and 0.50 are one) or no key at all.
Plan plan(const std::vector<Varied>& varied,
          const std::function<Params(const std::vector<std::string>&)>& load) {
  const std::size_t total = case_count(varied);
  Plan plan;
  ReadBack read{std::vector<std::vector<std::string>>(varied.size()),
                std::vector<std::vector<double>>(varied.size())};
  for (std::size_t k = 0; k < varied.size(); ++k) {
    read.text[k].resize(varied[k].values.size());
    read.omega[k].resize(varied[k].values.size());
    if (is_extra_key(varied[k].key)) plan.extra_keys.push_back(varied[k].key);
  }
  for (std::size_t c = 0; c < total; ++c) {
    const std::vector<std::size_t> at = value_indices(varied, c);
    Case cs;
    for (std::size_t k = 0; k < varied.size(); ++k)
      cs.sets.push_back(varied[k].key + "=" + varied[k].values[at[k]]);
    cs.params = load(cs.sets);
    for (std::size_t k = 0; k < varied.size(); ++k) {
      const std::string text = value_text(cs.params, varied[k].key);
      read.text[k][at[k]] = text;
      if (varied[k].key == "cloth.humidity") read.omega[k][at[k]] = cs.params.cloth.humidity;
      if (is_extra_key(varied[k].key)) cs.columns.push_back(text);
    }
    cs.humidity = cs.params.cloth.humidity;
    cs.air_model = to_string(cs.params.air.model);
    plan.cases.push_back(std::move(cs));
  }
  for (std::size_t k = 0; k < varied.size(); ++k) {
    std::vector<std::string> sorted = read.text[k];
    std::sort(sorted.begin(), sorted.end());
    if (const auto twice = std::adjacent_find(sorted.begin(), sorted.end()); twice != sorted.end())
      throw SceneError(varied[k].option + ": " + *twice + " is given twice");
  }
  name_cases(varied, read, plan);
  std::set<std::string> names;
  for (const Case& cs : plan.cases)
    if (!names.insert(cs.name).second)
      throw SceneError("two cases would share the folder " + cs.name);
  return plan;
}

// A CSV field, quoted when it holds a comma, a quote or a line break.
std::string csv_field(const std::string& s) {
  if (s.find_first_of(",\"\n\r") == std::string::npos) return s;
  std::string o = "\"";
  for (char c : s) o += c == '"' ? std::string("\"\"") : std::string(1, c);
  return o + "\"";
}

std::string csv_header(const Plan& plan) {
  std::string o = "case";
  for (const auto& k : plan.extra_keys) o += "," + csv_field(k);
  o += ",air_model,humidity,status,peak_deficit_pa,frame_peak_deficit_pa,time_to_5cm_s";
  for (const auto& c : metrics_columns()) o += "," + c;
  return o + "\n";
}

std::string csv_row(const Case& c, const Outcome& r) {
  std::string o = csv_field(c.name);
  for (const auto& v : c.columns) o += "," + csv_field(v);
  o += "," + csv_field(c.air_model) + "," + format_number(c.humidity) + "," +
       (r.ok            ? "ok"
        : r.interrupted ? "interrupted"
                        : "blew_up") +
       "," + format_number(r.peak_deficit_pa) + "," + format_number(r.frame_peak_deficit_pa) + "," +
       format_number(r.time_to_5cm_s);
  for (double v : metrics_values(r.final)) o += "," + format_number(v);
  return o + "\n";
}

Outcome outcome_of(const RunResult& r) {
  Outcome o;
  o.ok = r.code == kOk;
  o.interrupted = r.code > 128;
  o.peak_deficit_pa = r.peak_deficit_pa;
  o.frame_peak_deficit_pa = r.frame_peak_deficit_pa;
  o.time_to_5cm_s = r.time_to_5cm_s;
  o.final = r.final;
  return o;
}

std::string cases_csv(const Plan& plan) {
  std::string o = "index,case,overrides\n";
  for (std::size_t i = 0; i < plan.cases.size(); ++i) {
    std::string sets;
    for (const auto& s : plan.cases[i].sets) sets += (sets.empty() ? "" : " ") + s;
    o += std::to_string(i) + "," + csv_field(plan.cases[i].name) + "," + csv_field(sets) + "\n";
  }
  return o;
}

std::string finish_case(const Plan& plan, std::size_t i, const RunResult& r, const fs::path& dir) {
  if (!(r.code == kOk || r.code == kBlowUp || (r.code > 128 && r.started))) return {};
  std::string row = csv_row(plan.cases[i], outcome_of(r));
  if (!dir.empty()) write_shared(dir / kRowFile, csv_header(plan) + row);
  return row;
}

void run_cases(const Plan& plan, const std::vector<std::size_t>& chosen, const fs::path& out,
               unsigned jobs, const RunHooks& hooks,
               const std::function<void(std::size_t, const RunResult&, const std::string&)>& done) {
  std::vector<std::pair<Params, fs::path>> runs;
  for (std::size_t i : chosen)
    runs.emplace_back(plan.cases[i].params, out.empty() ? fs::path() : out / plan.cases[i].name);
  run_all(runs, jobs, hooks, [&](std::size_t k, const RunResult& r) {
    done(chosen[k], r, finish_case(plan, chosen[k], r, runs[k].second));
  });
}

void write_shared(const fs::path& path, const std::string& contents) {
  const fs::path tmp = path.string() + "." + std::to_string(getpid()) + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    out << contents;
    if (!out.flush()) throw std::runtime_error(tmp.string() + ": cannot write");
  }
  fs::rename(tmp, path);
}

namespace {

std::string read_text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// A case's name from its line of cases.csv (index,case,overrides).
std::string case_name(const std::string& line) {
  std::string name = line.substr(line.find(',') + 1);
  if (name.empty() || name[0] != '"') return name.substr(0, name.find(','));
  std::string unq;
  for (std::size_t k = 1; k < name.size(); ++k) {
    if (name[k] == '"' && k + 1 < name.size() && name[k + 1] == '"')
      unq += name[++k];
    else if (name[k] == '"')
      break;
    else
      unq += name[k];
  }
  return unq;
}

}  // namespace

Gathered gather(const fs::path& dir) {
  if (!fs::exists(dir / kCasesFile))
    throw SceneError(
        "--gather " + dir.string() + ": no " + kCasesFile +
        " (not a sweep folder: `wetcloth sweep ... --out DIR` or `--list`/`--case` writes it)");
  std::istringstream in(read_text(dir / kCasesFile));
  std::string line, header, rows;
  Gathered g;
  std::getline(in, line);  // its header
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    ++g.total;
    const std::string name = case_name(line);
    std::istringstream row(read_text(dir / name / kRowFile));
    std::string h, r;
    if (!std::getline(row, h) || !std::getline(row, r) || r.empty()) {
      g.missing.push_back(line.substr(0, line.find(',')) + " " + name);
      continue;
    }
    if (header.empty()) header = h;
    if (h != header)
      throw SceneError(dir.string() + "/" + name + "/" + kRowFile +
                       ": its header differs from the other cases'");
    rows += r + "\n";
    ++g.found;
  }
  if (g.found == 0)
    throw SceneError("--gather " + dir.string() + ": none of its " + std::to_string(g.total) +
                     " cases has finished");
  write_file_atomic(dir / "sweep.csv", header + "\n" + rows);
  return g;
}

fs::path plot_script() {
  if (const char* env = std::getenv("WETCLOTH_PLOT_SCRIPT")) return env;
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  const fs::path installed = exe.parent_path().parent_path() / "share/wetcloth/plot_sweep.py";
  if (!ec && fs::exists(installed)) return installed;
  return fs::path(WETCLOTH_SOURCE_DIR) / "tools/plot_sweep.py";
}

bool plot(const fs::path& dir, std::string* why) {
  const std::string python = fs::exists("/usr/bin/python3") ? "/usr/bin/python3" : "python3";
  const std::string cmdline = python + " '" + plot_script().string() + "' '" + dir.string() + "'";
  if (std::system(cmdline.c_str()) == 0) return true;
  if (why) *why = cmdline;
  return false;
}

}  // namespace wetcloth::sweep
