// The cases of a sweep: the cartesian product of the varied keys' values, each
// case's folder name, overrides and sweep.csv row. Header-only and free of the
// command line's parser: `wetcloth sweep` and the Python module's
// wetcloth.sweep both use it, so that both name, order and tabulate cases alike.
#pragma once

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <functional>
#include <set>
#include <string>
#include <variant>
#include <vector>

#include "wetcloth/output.hpp"
#include "wetcloth/scene.hpp"

namespace wetcloth::sweep {

// One varied key and its values as TOML text (a bare word is a string, as
// with --set). `option` names it in errors: "--humidity", "--vary cloth.humidity".
struct Varied {
  std::string key;
  std::vector<std::string> values;
  std::string option;
};

inline std::string trim(const std::string& s) {
  const auto a = s.find_first_not_of(" \t"), b = s.find_last_not_of(" \t");
  return a == std::string::npos ? std::string() : s.substr(a, b - a + 1);
}

// KEY=V1,V2,...: the values split at the commas outside brackets and quotes,
// so that arrays may be varied (cloth.resolution=[25,25],[51,51]).
inline Varied parse_vary(const std::string& text) {
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
inline const ParamDef* def_of(const std::string& key, std::string* name = nullptr) {
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
inline void check_named(const Params& p, const std::string& key, const ParamDef& d,
                        const std::string& name) {
  if (d.key.rfind("handle.*.", 0) == 0 && !p.handles.count(name))
    throw SceneError(key + ": the scene has no such handle");
  if (d.key.rfind("obstacle.*.", 0) == 0 && !p.obstacles.count(name))
    throw SceneError(key + ": the scene has no such obstacle");
}

inline std::string value_text(const Params& p, const std::string& key) {
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

struct Case {
  std::string name;
  std::vector<std::string> sets;     // KEY=VALUE for each varied key
  std::vector<std::string> columns;  // its value of each extra key, as sweep.csv has it
  double humidity = 0;
  std::string air_model;
  Params params;
};

struct Plan {
  std::vector<std::string> extra_keys;  // varied keys other than cloth.humidity and air.model
  std::vector<Case> cases;
};

// A value as part of a folder name: letters, digits and . + -; an array's
// numbers joined by x ([25, 25] -> 25x25).
inline std::string name_part(const std::string& text) {
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
inline std::size_t case_count(const std::vector<Varied>& varied) {
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
inline std::vector<std::size_t> value_indices(const std::vector<Varied>& varied, std::size_t c) {
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

inline bool is_extra_key(const std::string& key) {
  return key != "cloth.humidity" && key != "air.model";
}

// The decimals that tell the humidities apart, 2 at least.
inline int humidity_decimals(std::vector<double> w) {
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
inline void name_cases(const std::vector<Varied>& varied, const ReadBack& read, Plan& plan) {
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

// Every case, in the order of the cartesian product (the first key outermost).
// load(sets) gives the scene with the base overrides and then `sets`; it
// throws SceneError on a bad value. Throws SceneError on a key given twice, a
// value given twice (after reading: 0.5 and 0.50 are one) or no key at all.
inline Plan plan(const std::vector<Varied>& varied,
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
inline std::string csv_field(const std::string& s) {
  if (s.find_first_of(",\"\n\r") == std::string::npos) return s;
  std::string o = "\"";
  for (char c : s) o += c == '"' ? std::string("\"\"") : std::string(1, c);
  return o + "\"";
}

inline std::string csv_header(const Plan& plan) {
  std::string o = "case";
  for (const auto& k : plan.extra_keys) o += "," + csv_field(k);
  o += ",air_model,humidity,status,peak_deficit_pa,frame_peak_deficit_pa,time_to_5cm_s";
  for (const auto& c : metrics_columns()) o += "," + c;
  return o + "\n";
}

// What a case's run gave, as sweep.csv has it.
struct Outcome {
  bool ok = true;
  bool interrupted = false;  // stopped by a signal at a step's end
  double peak_deficit_pa = 0, frame_peak_deficit_pa = 0, time_to_5cm_s = -1;
  Metrics final;
};

inline std::string csv_row(const Case& c, const Outcome& r) {
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

}  // namespace wetcloth::sweep
