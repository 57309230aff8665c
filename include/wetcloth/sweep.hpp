// A sweep: the cases of a scene over the cartesian product of varied keys'
// values (each case's folder name, overrides and sweep.csv row), a case run,
// and the sweep's folder gathered (sweep.csv, the plots). `wetcloth sweep`
// and Python's wetcloth.sweep both use it, so that both name, order and
// tabulate cases alike.
#pragma once

#include <cstddef>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "wetcloth/run.hpp"
#include "wetcloth/scene.hpp"

namespace wetcloth::sweep {

// One varied key and its values as TOML text (a bare word is a string, as
// with --set). `option` names it in errors: "--humidity", "--vary cloth.humidity".
struct Varied {
  std::string key;
  std::vector<std::string> values;
  std::string option;
};

// KEY=V1,V2,...: the values split at the commas outside brackets and quotes,
// so that arrays may be varied (cloth.resolution=[25,25],[51,51]).
Varied parse_vary(const std::string& text);

// The parameter a key names (handle.NAME.KEY: handle.*.KEY; obstacle.NAME.KEY:
// obstacle.*.KEY), and the NAME; null for no parameter.
const ParamDef* def_of(const std::string& key, std::string* name = nullptr);
// Throws SceneError unless p has the handle or obstacle that KEY (of
// definition d) names.
void check_named(const Params& p, const std::string& key, const ParamDef& d,
                 const std::string& name);

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

// Every case, in the order of the cartesian product (the first key outermost),
// named from its values (omega_0.70, sealed_omega_0.70, ..._stretch_stiffness=100).
// load(sets) gives the scene with the base overrides and then `sets`; it
// throws SceneError on a bad value. Throws SceneError on a key given twice, a
// value given twice (after reading: 0.5 and 0.50 are one) or no key at all.
Plan plan(const std::vector<Varied>& varied,
          const std::function<Params(const std::vector<std::string>&)>& load);

// A CSV field, quoted when it holds a comma, a quote or a line break.
std::string csv_field(const std::string& s);
// sweep.csv's header: the case, a column per extra key, air model, humidity,
// status, the peaks, time to 5 cm and the final metrics.
std::string csv_header(const Plan& plan);

// What a case's run gave, as sweep.csv has it.
struct Outcome {
  bool ok = true;
  bool interrupted = false;  // stopped by a signal at a step's end
  double peak_deficit_pa = 0, frame_peak_deficit_pa = 0, time_to_5cm_s = -1;
  Metrics final;
};
Outcome outcome_of(const RunResult& r);
std::string csv_row(const Case& c, const Outcome& r);

// --- the sweep's folder: DIR/<case>/ a run each, DIR/cases.csv, DIR/sweep.csv ---

inline constexpr const char* kCasesFile = "cases.csv";    // the cases in order (for --gather)
inline constexpr const char* kRowFile = "sweep_row.csv";  // in a case's folder: header and row

// cases.csv: index, case and overrides, a case a line.
std::string cases_csv(const Plan& plan);

// A case's row of sweep.csv where it ran (ended, blew up, or was stopped after
// it started), else empty; with a folder, written into DIR/sweep_row.csv
// beside its header, as the case ends (gather reads it).
std::string finish_case(const Plan& plan, std::size_t i, const RunResult& r,
                        const std::filesystem::path& dir);

// Runs the cases `chosen` (indices in the plan) `jobs` at a time, each into
// OUT/<case> (nothing written where OUT is empty), as run_all; done(i, result,
// row) for each as it ends, one call at a time, i its index in the plan.
void run_cases(const Plan& plan, const std::vector<std::size_t>& chosen,
               const std::filesystem::path& out, unsigned jobs, const RunHooks& hooks,
               const std::function<void(std::size_t, const RunResult&, const std::string&)>& done);

// Writes PATH through a temporary file of this process's own: several
// processes (`--case` on a cluster) may write the same file at once.
void write_shared(const std::filesystem::path& path, const std::string& contents);

// `--gather DIR`: DIR/sweep.csv from the case folders that have finished, in
// the sweep's order. Throws SceneError where DIR is no sweep folder, a case's
// header differs, or none has finished.
struct Gathered {
  std::size_t found = 0, total = 0;
  std::vector<std::string> missing;  // "index name" of each case not run
};
Gathered gather(const std::filesystem::path& dir);

// The plotting script (tools/plot_sweep.py): $WETCLOTH_PLOT_SCRIPT, next to an
// installed program, or in the source tree.
std::filesystem::path plot_script();
// Runs it on DIR (it writes the plots that mean something for the scene);
// false, with the command line in `why`, when it failed.
bool plot(const std::filesystem::path& dir, std::string* why = nullptr);

}  // namespace wetcloth::sweep
