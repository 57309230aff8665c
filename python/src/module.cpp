// wetcloth as a Python module (pybind11): scenes, a Simulation stepped from
// Python with its state as NumPy arrays, a run into its folder (wetcloth.run)
// and what wetcloth.sweep plans and runs per case. It binds the public API of
// include/wetcloth as it is: the run and the sweep are the library's, as the
// command line's are.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <atomic>
#include <charconv>
#include <chrono>
#include <cmath>
#include <csignal>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "wetcloth/checkpoint.hpp"
#include "wetcloth/output.hpp"
#include "wetcloth/run.hpp"
#include "wetcloth/scene.hpp"
#include "wetcloth/simulation.hpp"
#include "wetcloth/sweep.hpp"

namespace py = pybind11;
using namespace wetcloth;

namespace {

struct BlowUpError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// The loader names an override "--set 'KEY=VALUE'": from Python it is the key.
std::string clean_message(std::string m) {
  if (m.rfind("--set '", 0) == 0)
    if (const auto end = m.find("': "); end != std::string::npos) m = m.substr(end + 3);
  if (m.rfind("Params: ", 0) == 0) m = m.substr(8);
  // Python's exception takes a C string: a NUL in a path would end it.
  for (std::size_t at; (at = m.find('\0')) != std::string::npos;) m.replace(at, 1, "\\x00");
  return m;
}

// A key from Python: dotted ("cloth.humidity"), or a keyword with "__" for the
// dots (cloth__humidity); humidity, duration, threads stand for their keys.
std::string normal_key(std::string key) {
  if (key == "humidity") return "cloth.humidity";
  if (key == "duration") return "run.duration";
  if (key == "threads") return "integrator.threads";
  for (std::size_t at; (at = key.find("__")) != std::string::npos;) key.replace(at, 2, ".");
  const bool ok = !key.empty() && std::all_of(key.begin(), key.end(), [](unsigned char c) {
    return std::isalnum(c) || c == '_' || c == '-' || c == '.';
  });
  if (!ok) throw SceneError("'" + key + "': not a parameter key (wetcloth.params() lists them)");
  return key;
}

std::string shortest(double v) {
  if (std::isnan(v)) return "nan";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  std::string s(buf, r.ptr);
  if (s.find_first_of(".eE") == std::string::npos) s += ".0";
  return s;
}

// A Python value as TOML text: bool, int, float (NumPy scalars too), str, or a
// flat sequence of numbers. Anything else is a TypeError naming the key.
std::string toml_value(const std::string& key, py::handle v, bool top = true) {
  const py::module_ np = py::module_::import("numpy");
  py::object value = py::reinterpret_borrow<py::object>(v);
  if (py::isinstance(value, np.attr("generic"))) value = value.attr("item")();
  if (py::isinstance<py::bool_>(value)) return value.cast<bool>() ? "true" : "false";
  if (PyLong_Check(value.ptr())) return py::str(value).cast<std::string>();
  if (PyFloat_Check(value.ptr())) return shortest(value.cast<double>());
  if (py::isinstance<py::str>(value)) {
    std::string s = "\"";
    for (unsigned char c : value.cast<std::string>()) {
      if (c == '"' || c == '\\') {
        s += '\\';
        s += static_cast<char>(c);
      } else if (c < 0x20 || c == 0x7f) {
        char buf[8];
        std::snprintf(buf, sizeof buf, "\\u%04x", c);
        s += buf;
      } else {
        s += static_cast<char>(c);
      }
    }
    return s + "\"";
  }
  if (top && (py::isinstance<py::list>(value) || py::isinstance<py::tuple>(value) ||
              py::isinstance<py::array>(value))) {
    if (py::isinstance<py::array>(value) && value.cast<py::array>().ndim() != 1)
      throw SceneError(key + ": expected a flat list of numbers, got an array of " +
                       std::to_string(value.cast<py::array>().ndim()) + " dimensions");
    std::string s = "[";
    for (py::handle e : value) s += (s.size() > 1 ? ", " : "") + toml_value(key, e, false);
    return s + "]";
  }
  throw py::type_error(
      key + ": a value of type " +
      py::str(py::type::of(value).attr("__name__")).cast<std::string>() +
      " cannot be a parameter (a number, a string, True/False or a list of numbers)");
}

// Overrides from a dict and keywords, as KEY=VALUE texts (later ones win);
// "grid" is taken out (it is not a parameter: the same cloth, G wide).
std::vector<std::string> override_texts(const py::object& overrides, const py::dict& kw,
                                        std::optional<long long>* grid) {
  std::vector<std::string> sets;
  const auto add = [&](py::handle k, py::handle v) {
    if (!py::isinstance<py::str>(k)) throw py::type_error("a parameter key must be a str");
    const std::string raw = k.cast<std::string>();
    if (raw == "grid" && grid) {
      if (!PyLong_Check(v.ptr()) || py::isinstance<py::bool_>(v))
        throw py::type_error("grid: expected an int");
      try {
        *grid = v.cast<long long>();
      } catch (const py::cast_error&) {
        throw SceneError("grid: " + py::repr(v).cast<std::string>() +
                         " is not a cloth's width in particles (2 to 2001)");
      }
      return;
    }
    const std::string key = normal_key(raw);
    sets.push_back(key + "=" + toml_value(key, v));
  };
  if (!overrides.is_none()) {
    if (!py::isinstance<py::dict>(overrides))
      throw py::type_error("overrides: expected a dict of {\"key\": value}");
    for (auto [k, v] : overrides.cast<py::dict>()) add(k, v);
  }
  for (auto [k, v] : kw) add(k, v);
  return sets;
}

// A scene loaded (wetcloth.load_scene): its parameters, resolved.
struct Scene {
  Params params;
};

// SCENE (a built-in name, a path, or a Scene) with overrides; with a grid, the
// same cloth G particles wide, as `wetcloth run --grid` makes it.
Params load(const py::object& scene, const std::vector<std::string>& sets,
            std::optional<long long> grid) {
  Params p;
  if (py::isinstance<Scene>(scene)) {
    p = reparse_scene(scene.cast<const Scene&>().params, sets);
  } else if (py::isinstance<py::str>(scene) || py::hasattr(scene, "__fspath__")) {
    const std::string name =
        py::str(py::module_::import("os").attr("fspath")(scene)).cast<std::string>();
    if (name.find('\0') != std::string::npos)
      throw SceneError("scene: " + py::repr(scene).cast<std::string>() +
                       " holds a NUL character: no file or built-in scene is named so");
    p = load_scene(name, sets);
  } else {
    throw py::type_error("scene: expected a built-in scene's name, a path or a wetcloth.Scene");
  }
  if (!grid) return p;
  const double dt = p.integrator.dt;
  try {
    p = at_resolution(p, *grid);
  } catch (const SceneError& e) {
    throw SceneError(std::string("grid: ") + e.what());
  }
  if (std::any_of(sets.begin(), sets.end(),
                  [](const std::string& s) { return s.rfind("integrator.dt=", 0) == 0; }))
    p.integrator.dt = dt;
  validate(p);
  return p;
}

py::object to_python(const ParamValue& v) {
  return std::visit(
      [](const auto& x) -> py::object {
        using T = std::decay_t<decltype(x)>;
        if constexpr (std::is_same_v<T, double>)
          return std::isnan(x) ? py::object(py::none()) : py::object(py::float_(x));
        else if constexpr (std::is_same_v<T, bool> || std::is_same_v<T, long long> ||
                           std::is_same_v<T, std::string>)
          return py::cast(x);
        else
          return py::cast(std::vector<typename T::value_type>(x.begin(), x.end()));  // a list
      },
      v);
}

py::object get_value(const Params& p, const std::string& raw) {
  const std::string key = normal_key(raw);
  std::string name;  // of the handle or obstacle
  const ParamDef* d = sweep::def_of(key, &name);
  if (!d) throw SceneError(key + ": unknown key (wetcloth.params() lists the keys)");
  sweep::check_named(p, key, *d, name);
  return to_python(d->get(p, name));
}

py::dict metrics_dict(const Metrics& m) {
  py::dict d;
  const auto cols = metrics_columns();
  const auto vals = metrics_values(m);
  for (std::size_t i = 0; i < cols.size(); ++i) d[py::str(cols[i])] = vals[i];
  return d;
}

class PySimulation {
 public:
  explicit PySimulation(const Params& p) : sim_(p) {}

  // One thread in the simulation at a time: advance_to lets go of the GIL.
  struct Busy {
    explicit Busy(PySimulation& s) : s(s) {
      if (s.busy_.exchange(true))
        throw std::runtime_error("this Simulation is busy in another thread (advance_to)");
    }
    ~Busy() { s.busy_ = false; }
    PySimulation& s;
  };

  void check_blow_up() const {
    if (const std::string why = sim_.blow_up_reason(); !why.empty()) throw BlowUpError(why);
  }

  void step() {
    Busy busy(*this);
    check_blow_up();
    {
      py::gil_scoped_release free;
      sim_.step();
    }
    check_blow_up();
  }

  // As Simulation::advance_to (the same steps), in slices of about 0.1 s
  // between which Ctrl-C is heard.
  void advance_to(double t) {
    Busy busy(*this);
    const double dt = sim_.model().params.integrator.dt;
    if (!std::isfinite(t) || t < 0 || t / dt > 1e15)
      throw SceneError("advance_to: t = " + shortest(t) +
                       " s is not a time to reach (finite, >= 0)");
    check_blow_up();
    const auto target = static_cast<long long>(std::llround(t / dt));
    // Backwards is no direction a simulation goes: doing nothing would hide it.
    if (target < sim_.state().steps)
      throw SceneError("advance_to: t = " + shortest(t) + " s is before the simulation's time, " +
                       shortest(sim_.state().time) +
                       " s (a Simulation goes forward only: make a new one, or load a saved one)");
    while (sim_.state().steps < target) {
      bool blew = false;
      {
        py::gil_scoped_release free;
        const auto start = std::chrono::steady_clock::now();
        while (sim_.state().steps < target) {
          sim_.step();
          if (!sim_.blow_up_reason().empty()) {
            blew = true;
            break;
          }
          if (std::chrono::steady_clock::now() - start > std::chrono::milliseconds(100)) break;
        }
      }
      if (blew) check_blow_up();
      if (PyErr_CheckSignals() != 0) throw py::error_already_set();
    }
  }

  void set(const std::string& raw, py::handle value) {
    Busy busy(*this);
    const std::string key = normal_key(raw);
    const Params& now = sim_.model().params;
    const Params p = reparse_scene(now, {key + "=" + toml_value(key, value)});
    if (p.cloth.resolution != now.cloth.resolution)
      throw SceneError(key + ": the grid cannot change in a running Simulation (make a new one)");
    if (key == "cloth.humidity")
      sim_.set_humidity(p.cloth.humidity);  // live: mass, permeability, adhesion
    else
      sim_.set_params(p);
  }

  // x or v as the State keeps them, every x, then y, then z: a C-contiguous
  // 3 x n view, no copy, that follows the simulation as it steps. Read-only:
  // assign positions or velocities to set them.
  py::array columns(py::object self, bool velocities) {
    const Vec3Array& a = velocities ? sim_.state().v : sim_.state().x;
    const auto n = static_cast<py::ssize_t>(a.size());
    py::array out(py::dtype::of<double>(), {py::ssize_t{3}, n},
                  {static_cast<py::ssize_t>(n * sizeof(double)), py::ssize_t{sizeof(double)}},
                  a.column(0), self);
    out.attr("setflags")(py::arg("write") = false);
    return out;
  }

  // x or v as n x 3 rows, C-contiguous (what most array code and C
  // libraries take): a copy, made at each read. Read-only, as assigning to
  // it would change nothing: assign the property to set them.
  py::array rows(bool velocities) const {
    const Vec3Array& a = velocities ? sim_.state().v : sim_.state().x;
    const auto n = static_cast<py::ssize_t>(a.size());
    py::array_t<double> out({n, py::ssize_t{3}});
    auto r = out.mutable_unchecked<2>();
    for (py::ssize_t i = 0; i < n; ++i)
      for (int k = 0; k < 3; ++k) r(i, k) = a.column(k)[i];
    out.attr("setflags")(py::arg("write") = false);
    return out;
  }

  void assign(py::handle value, bool velocities, const char* what) {
    Busy busy(*this);
    const auto arr = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(value);
    if (!arr) throw py::type_error(std::string(what) + ": expected an array of numbers");
    const auto n = static_cast<py::ssize_t>(sim_.model().n);
    if (arr.ndim() != 2 || arr.shape(0) != n || arr.shape(1) != 3) {
      std::string shape;
      for (py::ssize_t k = 0; k < arr.ndim(); ++k)
        shape += (k ? ", " : "") + std::to_string(arr.shape(k));
      throw SceneError(std::string(what) + ": expected shape (" + std::to_string(n) +
                       ", 3), got (" + shape + ")");
    }
    Vec3Array a(static_cast<std::size_t>(n));
    const auto r = arr.unchecked<2>();
    for (py::ssize_t i = 0; i < n; ++i)
      for (int k = 0; k < 3; ++k) a.column(k)[i] = r(i, k);
    if (velocities)
      sim_.set_velocities(a);
    else
      sim_.set_positions(a);
  }

  Simulation sim_;

 private:
  std::atomic<bool> busy_{false};
};

template <class T, class U>
py::array_t<T> copy_of(const std::vector<U>& v) {
  py::array_t<T> out(static_cast<py::ssize_t>(v.size()));
  std::copy(v.begin(), v.end(), out.mutable_data());
  return out;
}

// A run's hooks from Python: Ctrl-C (KeyboardInterrupt, or any exception a
// signal handler raises) is heard every 0.1 s of the run and stops it at the
// end of that step, whole, as SIGINT stops `wetcloth run`; the exception is
// kept to be raised once the run has written its checkpoint. progress(t,
// duration), where given, is called after each frame. The run's thread holds
// no GIL: each call takes it.
struct PyRunHooks {
  RunHooks hooks;
  std::optional<py::error_already_set> raised;
  std::chrono::steady_clock::time_point heard = std::chrono::steady_clock::now();

  explicit PyRunHooks(const py::object& progress) {
    hooks.stop = [this]() -> int {
      const auto now = std::chrono::steady_clock::now();
      if (now - heard < std::chrono::milliseconds(100)) return 0;
      heard = now;
      py::gil_scoped_acquire gil;
      if (PyErr_CheckSignals() == 0) return 0;
      raised.emplace();  // takes the exception set
      return SIGINT;
    };
    if (!progress.is_none())
      hooks.progress = [progress](double t, double duration, double) {
        py::gil_scoped_acquire gil;
        progress(t, duration);
      };
  }
  // After the run, the GIL held: the exception a signal raised, raised now.
  void raise_if_stopped() {
    if (raised) {
      py::error_already_set e = std::move(*raised);
      raised.reset();
      throw e;
    }
  }
};

py::dict outcome_dict(const RunResult& r) {
  const sweep::Outcome o = sweep::outcome_of(r);
  py::dict d;
  d["status"] = o.ok ? "ok" : o.interrupted ? "interrupted" : "blew_up";
  d["message"] = r.message;
  d["peak_deficit_pa"] = o.peak_deficit_pa;
  d["frame_peak_deficit_pa"] = o.frame_peak_deficit_pa;
  d["time_to_5cm_s"] = o.time_to_5cm_s;
  d["final"] = metrics_dict(o.final);
  return d;
}

// One case of wetcloth.sweep, run by the library's run: into OUT/<case> with
// its row of sweep.csv beside it (case: its name, columns, humidity and air
// model from _plan_sweep; extra: the extra keys), or, without OUT, in memory.
py::dict run_case(const py::object& scene, const std::vector<std::string>& sets,
                  std::optional<long long> grid, const py::object& out, const py::object& extra,
                  const py::object& case_info) {
  sweep::Plan plan;  // this case alone: its row of sweep.csv
  sweep::Case c;
  c.params = load(scene, sets, grid);
  std::filesystem::path dir;
  if (!out.is_none()) {
    plan.extra_keys = extra.cast<std::vector<std::string>>();
    const py::dict info = case_info.cast<py::dict>();
    c.name = info["name"].cast<std::string>();
    c.columns = info["columns"].cast<std::vector<std::string>>();
    c.humidity = info["humidity"].cast<double>();
    c.air_model = info["air_model"].cast<std::string>();
    dir = std::filesystem::path(py::str(out).cast<std::string>()) / c.name;
  }
  plan.cases.push_back(c);
  PyRunHooks hooks{py::none()};
  RunResult r;
  {
    py::gil_scoped_release free;
    r = run_scene(plan.cases[0].params, dir, hooks.hooks);
  }
  hooks.raise_if_stopped();
  py::dict d = outcome_dict(r);
  d["row"] = dir.empty() ? std::string() : sweep::finish_case(plan, 0, r, dir);
  return d;
}

// wetcloth.run: SCENE (with the overrides of load_scene) into OUT, as
// `wetcloth run` writes it, or the run in RESUME continued; the summary.
py::object run(const py::object& scene, const py::object& out, const py::object& exports,
               const py::object& up, const py::object& checkpoint_every, const py::object& resume,
               bool force, const py::object& progress, const py::object& overrides,
               const py::kwargs& kw) {
  std::optional<double> every;
  if (!checkpoint_every.is_none()) {
    every = checkpoint_every.cast<double>();
    const ParamDef* d = sweep::def_of("run.checkpoint_every");
    if (!(*every >= d->min && *every <= d->max))  // as the option checks it
      throw SceneError("checkpoint_every: value " + shortest(*every) + " is out of range " +
                       d->range_text() + " (run.checkpoint_every)");
  }
  Params p;
  std::filesystem::path dir;
  std::optional<ResumePoint> from;
  if (!resume.is_none()) {
    // The scene is the checkpoint's: what would change it is refused.
    std::optional<unsigned> threads;
    for (auto [k, v] : kw)
      if (k.cast<std::string>() == "threads")
        threads = v.cast<unsigned>();
      else
        throw SceneError("resume: the run continues with its checkpoint's scene; " +
                         k.cast<std::string>() +
                         " would change it (threads, checkpoint_every "
                         "and force may be given)");
    if (!scene.is_none() || !overrides.is_none() || !out.is_none() || !exports.is_none() ||
        !up.is_none())
      throw SceneError(
          "resume: the run continues in that folder with its checkpoint's scene; "
          "scene, overrides, out, export and up would change it");
    dir = py::str(py::module_::import("os").attr("fspath")(resume)).cast<std::string>();
    from = resume_run(dir, threads, every, force);
    if (!from)
      return py::module_::import("json").attr("load")(
          py::module_::import("builtins").attr("open")((dir / "summary.json").string()));
    p = from->params;
  } else {
    if (scene.is_none()) throw SceneError("run: a scene is needed, or resume=DIR");
    std::optional<long long> grid;
    std::vector<std::string> sets = override_texts(overrides, kw, &grid);
    if (!exports.is_none()) {
      std::string list;
      if (py::isinstance<py::str>(exports))
        list = exports.cast<std::string>();
      else
        for (py::handle e : exports) list += (list.empty() ? "" : ",") + e.cast<std::string>();
      sets.push_back("run.export=" + toml_value("export", py::str(list)));
    }
    if (!up.is_none()) sets.push_back("run.up=" + toml_value("up", up));
    if (every) sets.push_back("run.checkpoint_every=" + format_number(*every));
    p = load(scene, sets, grid);
    // As `wetcloth run`: the step's threads all the cores unless chosen.
    if (!overrides_key(sets, "integrator.threads")) p.integrator.threads = 0;
    dir = out.is_none()
              ? std::filesystem::path("out") / folder_name(p.name)
              : std::filesystem::path(
                    py::str(py::module_::import("os").attr("fspath")(out)).cast<std::string>());
    prepare_run(p, dir, force,
                py::isinstance<Scene>(scene) ? p.name : py::str(scene).cast<std::string>(), "out");
  }
  PyRunHooks hooks(progress);
  RunResult r;
  {
    py::gil_scoped_release free;
    r = run_scene(p, dir, hooks.hooks, from ? &*from : nullptr);
  }
  hooks.raise_if_stopped();
  if (r.code == kBlowUp) throw BlowUpError(r.message + " (results so far: " + dir.string() + ")");
  return py::module_::import("json").attr("loads")(r.summary);
}

// SceneError and BlowUp: the library's errors as Python exceptions.
void bind_errors(py::module_& m) {
  static py::exception<SceneError> scene_error(m, "SceneError", PyExc_ValueError);
  static py::exception<BlowUpError> blow_up(m, "BlowUp", PyExc_RuntimeError);
  static py::exception<OutputError> output_error(m, "OutputError", PyExc_OSError);
  scene_error.doc() = "A bad scene, key or value (a ValueError); the message names the key.";
  blow_up.doc() = "The simulation blew up; the message names the parameter to look at.";
  output_error.doc() = "An output could not be written (an OSError): the file and the reason.";
  py::register_exception_translator([](std::exception_ptr e) {
    try {
      if (e) std::rethrow_exception(e);
    } catch (const SceneError& x) {
      scene_error(clean_message(x.what()).c_str());
    } catch (const BlowUpError& x) {
      blow_up(x.what());
    } catch (const OutputError& x) {
      output_error(x.what());
    }
  });
}

// What there is to choose from: the built-in scenes and every parameter.
void bind_catalogue(py::module_& m) {
  m.def(
      "scenes",
      [] {
        py::dict d;
        for (const auto& s : builtin_scenes()) d[py::str(s.name)] = s.description;
        return d;
      },
      "The built-in scenes: {name: description}.");

  m.def(
      "params",
      [] {
        py::list rows;
        for (const ParamDef& d : param_defs()) {
          py::dict r;
          r["key"] = d.key;
          r["type"] = d.type_name();
          r["unit"] = d.unit;
          r["default"] = d.default_text();
          r["range"] = d.range_text();
          r["meaning"] = d.meaning;
          rows.append(r);
        }
        return rows;
      },
      "Every scene parameter, as `wetcloth params` lists them: dicts of key, type, unit, default, "
      "range, meaning.");
}

void bind_scene(py::module_& m) {
  py::class_<Scene>(m, "Scene", "A scene's parameters, resolved (wetcloth.load_scene).")
      .def_property_readonly("name", [](const Scene& s) { return s.params.name; })
      .def_property_readonly("description", [](const Scene& s) { return s.params.description; })
      .def(
          "get", [](const Scene& s, const std::string& key) { return get_value(s.params, key); },
          py::arg("key"), "A parameter's value: get('cloth.humidity').")
      .def(
          "toml", [](const Scene& s) { return to_toml(s.params); },
          "Every parameter as TOML (as scene.toml).")
      .def("__repr__", [](const Scene& s) { return "<wetcloth.Scene '" + s.params.name + "'>"; });

  m.def(
      "load_scene",
      [](const py::object& scene, const py::object& overrides, const py::kwargs& kw) {
        std::optional<long long> grid;
        const auto sets = override_texts(overrides, kw, &grid);
        return Scene{load(scene, sets, grid)};
      },
      py::arg("scene"), py::arg("overrides") = py::none(),
      "A built-in scene's name or a TOML file's path, with overrides by dotted key "
      "({'cloth.humidity': 0.7}) or keyword (humidity=0.7, cloth__humidity=0.7; grid=G: the "
      "same cloth G particles wide). Raises SceneError naming the key.");
}

using SimulationClass = py::class_<PySimulation>;

// Time, size and parameters of a Simulation, read and set between steps.
void bind_simulation_params(SimulationClass& cls) {
  cls.def_property_readonly(
         "time", [](const PySimulation& s) { return s.sim_.state().time; }, "Simulated time, s.")
      .def_property_readonly("steps", [](const PySimulation& s) { return s.sim_.state().steps; })
      .def_property_readonly(
          "dt", [](const PySimulation& s) { return s.sim_.model().params.integrator.dt; })
      .def_property_readonly(
          "n", [](const PySimulation& s) { return s.sim_.model().n; }, "Particles.")
      .def_property_readonly(
          "grid",
          [](const PySimulation& s) {
            return py::make_tuple(s.sim_.model().nu, s.sim_.model().nv);
          },
          "(nu, nv): particle i + nu j is grid point (i, j).")
      .def_property_readonly("name",
                             [](const PySimulation& s) { return s.sim_.model().params.name; })
      .def(
          "metrics",
          [](PySimulation& s) {
            PySimulation::Busy busy(s);
            return metrics_dict(s.sim_.metrics());
          },
          "The metrics now: a dict of metrics.csv's columns.")
      .def("set", &PySimulation::set, py::arg("key"), py::arg("value"),
           "Sets a parameter between steps (cloth.humidity live; handle.NAME.force, "
           "obstacle.NAME.translate ...). The grid cannot change.")
      .def(
          "get",
          [](const PySimulation& s, const std::string& key) {
            return get_value(s.sim_.model().params, key);
          },
          py::arg("key"))
      .def("toml", [](const PySimulation& s) { return to_toml(s.sim_.model().params); })
      .def_property_readonly(
          "peak_deficit", [](const PySimulation& s) { return s.sim_.state().peak_deficit; },
          "Largest p_atm - p_in over every step so far, Pa.")
      .def_property_readonly(
          "handles",
          [](const PySimulation& s) {
            py::dict d;
            for (const Handle& h : s.sim_.model().handles) {
              py::dict e;
              e["type"] = to_string(h.type);
              e["particles"] = copy_of<int>(h.particles);
              e["force"] = py::make_tuple(h.force.x(), h.force.y(), h.force.z());
              e["velocity"] = py::make_tuple(h.velocity.x(), h.velocity.y(), h.velocity.z());
              d[py::str(h.name)] = e;
            }
            return d;
          },
          "The handles by name: {name: {type, particles, force, velocity}} (set one with "
          "set('handle.NAME.force', [fx, fy, fz])).");
}

// The state as NumPy arrays: copies, and the positions' and velocities' columns as views.
void bind_simulation_arrays(SimulationClass& cls) {
  cls.def_property(
         "positions", [](const PySimulation& s) { return s.rows(false); },
         [](PySimulation& s, py::handle v) { s.assign(v, false, "positions"); },
         "n x 3 positions, m: a C-contiguous read-only copy (positions_columns: a view).")
      .def_property(
          "velocities", [](const PySimulation& s) { return s.rows(true); },
          [](PySimulation& s, py::handle v) { s.assign(v, true, "velocities"); },
          "n x 3 velocities, m/s: a C-contiguous read-only copy (velocities_columns: a view).")
      .def_property_readonly(
          "positions_columns",
          [](py::object self) { return self.cast<PySimulation&>().columns(self, false); },
          "3 x n positions (x, y, z rows), m: a read-only view of the state, no copy, that "
          "follows the simulation as it steps.")
      .def_property_readonly(
          "velocities_columns",
          [](py::object self) { return self.cast<PySimulation&>().columns(self, true); },
          "3 x n velocities (x, y, z rows), m/s: a read-only view of the state, no copy.")
      .def_property_readonly(
          "triangles",
          [](const PySimulation& s) {
            const auto& t = s.sim_.model().triangles;
            py::array_t<int> out({static_cast<py::ssize_t>(t.size()), py::ssize_t{3}});
            std::copy_n(t.empty() ? nullptr : t[0].data(), 3 * t.size(), out.mutable_data());
            return out;
          },
          "m x 3 particle indices (int32), a copy.")
      .def_property_readonly(
          "normals",
          [](const PySimulation& s) {
            const Model& m = s.sim_.model();
            Vec3Array normal(m.n);
            compute_normals(m, s.sim_.state().x, normal);
            py::array_t<double> out({static_cast<py::ssize_t>(m.n), py::ssize_t{3}});
            for (int i = 0; i < m.n; ++i)
              for (int k = 0; k < 3; ++k) out.mutable_data()[3 * i + k] = normal[i][k];
            return out;
          },
          "n x 3 unit normals at the particles (as the OBJ frames have them), a C-contiguous "
          "copy.")
      .def_property_readonly(
          "uvs",
          [](const PySimulation& s) {
            const auto& uv = s.sim_.model().uv;
            py::array_t<double> out({static_cast<py::ssize_t>(uv.size()), py::ssize_t{2}});
            for (std::size_t i = 0; i < uv.size(); ++i)
              for (int k = 0; k < 2; ++k) out.mutable_data()[2 * i + k] = uv[i][k];
            return out;
          },
          "n x 2 texture coordinates (u, v): the grid's (i, j) / (nu - 1, nv - 1), a mesh "
          "cloth's from its file; a C-contiguous copy.")
      .def_property_readonly(
          "rest_positions",
          [](const PySimulation& s) {
            const auto& x = s.sim_.model().rest_position;
            py::array_t<double> out({static_cast<py::ssize_t>(x.size()), py::ssize_t{3}});
            for (std::size_t i = 0; i < x.size(); ++i)
              for (int k = 0; k < 3; ++k) out.mutable_data()[3 * i + k] = x[i][k];
            return out;
          },
          "n x 3 rest positions, m (the cloth as it starts, unstretched), a C-contiguous copy.")
      .def_property_readonly(
          "in_contact",
          [](const PySimulation& s) {
            const auto& c = s.sim_.state().contact;
            py::array_t<bool> out(static_cast<py::ssize_t>(c.size()));
            for (std::size_t i = 0; i < c.size(); ++i) out.mutable_data()[i] = c[i] != 0;
            return out;
          },
          "n booleans: within the liquid-bridge height of the surface, a copy.")
      .def_property_readonly(
          "pressure",
          [](const PySimulation& s) { return copy_of<double>(s.sim_.state().pocket_pressure); },
          "n inner pressures P_in under each particle, Pa (p_atm where no pocket), a copy.")
      .def_property_readonly(
          "adhesion", [](const PySimulation& s) { return copy_of<double>(s.sim_.adhesion()); },
          "n adhesion forces |F|, N, of the last step, a copy.")
      .def_property(
          "humidity",
          [](const PySimulation& s) { return copy_of<double>(s.sim_.state().humidity); },
          [](PySimulation& s,
             const py::array_t<double, py::array::c_style | py::array::forcecast>& v) {
            if (v.ndim() != 1) throw py::value_error("humidity: expected n values, one a particle");
            const std::vector<double> omega(v.data(), v.data() + v.size());
            try {
              s.sim_.set_humidity_field(omega);
            } catch (const std::invalid_argument& e) {
              throw py::value_error(e.what());
            }
          },
          "n humidities ω, one a particle (the humidity field: wicking, drying and uptake "
          "change it), a copy; set it to an array of n values in [0, 1] (mass, adhesion and "
          "permeability follow).");
}

// A Simulation written to a file and continued from it, with the same bits.
void bind_simulation_files(SimulationClass& cls) {
  cls.def(
         "save",
         [](const PySimulation& s, const std::string& path) {
           // It replaces a file, and nothing else (a link, a device, a folder).
           std::error_code ec;
           const auto st = std::filesystem::symlink_status(path, ec);
           if (std::filesystem::exists(st) && !std::filesystem::is_regular_file(st))
             throw SceneError("save: " + path +
                              ": not a regular file: save writes a new file or replaces one");
           save_checkpoint(path, s.sim_.model().params, s.sim_.state());
         },
         py::arg("path"),
         "Write the whole state with its scene to PATH (a versioned binary file with a checksum); "
         "Simulation.load(PATH) continues it with the same bits.")
      .def_static(
          "load",
          [](const std::string& path) {
            const Checkpoint c = load_checkpoint(path);
            auto sim = std::make_unique<PySimulation>(c.params);
            sim->sim_.restore(c.state);
            return sim;
          },
          py::arg("path"), "A Simulation continued from a file Simulation.save wrote.");
}

void bind_simulation(py::module_& m) {
  SimulationClass cls(m, "Simulation", R"doc(A wet cloth stepped from Python.

Simulation(scene, overrides=None, **keywords): scene is a built-in name, a
path or a wetcloth.Scene; overrides by dotted key ({"cloth.humidity": 0.7})
or keyword (humidity=0.7, cloth__humidity=0.7, duration=, threads=; grid=G
is the same cloth G particles wide). A bad key or value raises SceneError.

positions and velocities are n x 3 float64 arrays, C-contiguous, copied at
each read; assign the property to set them (a copy in). positions_columns and
velocities_columns are 3 x n read-only views of the state as the library keeps
it (x, y, z rows), no copy: they follow the simulation as it steps.
triangles, in_contact, pressure and adhesion are copies, made at each read.
save(path) writes the whole state of the run (a checkpoint), and the static
Simulation.load(path) continues it with the same numbers.)doc");
  cls.def(py::init([](const py::object& scene, const py::object& overrides, const py::kwargs& kw) {
            std::optional<long long> grid;
            const auto sets = override_texts(overrides, kw, &grid);
            const Params p = load(scene, sets, grid);
            return std::make_unique<PySimulation>(p);
          }),
          py::arg("scene"), py::arg("overrides") = py::none())
      .def("step", &PySimulation::step, "One time step. Raises BlowUp if the state blew up.")
      .def("advance_to", &PySimulation::advance_to, py::arg("t"),
           "Steps until time t (s), releasing the GIL while it steps. Raises BlowUp.");
  bind_simulation_params(cls);
  bind_simulation_arrays(cls);
  bind_simulation_files(cls);
  cls.def("__repr__", [](const PySimulation& s) {
    return "<wetcloth.Simulation '" + s.sim_.model().params.name +
           "' t=" + shortest(s.sim_.state().time) + " s>";
  });
}

// wetcloth.sweep's cases as `wetcloth sweep` plans them: (the keys varied
// besides air model and humidity, a dict per case).
py::tuple plan_sweep(const py::object& scene, const py::list& varied,
                     const std::vector<std::string>& base, std::optional<long long> grid) {
  std::vector<sweep::Varied> vs;
  for (py::handle item : varied) {
    const auto pair = item.cast<py::tuple>();
    sweep::Varied v;
    v.key = normal_key(pair[0].cast<std::string>());
    v.option = v.key;
    const py::object values = pair[1];
    if (py::isinstance<py::str>(values) || !py::hasattr(values, "__iter__"))
      throw py::type_error(v.key + ": expected a list of values");
    for (py::handle e : values) v.values.push_back(toml_value(v.key, e));
    vs.push_back(v);
  }
  const sweep::Plan plan = sweep::plan(vs, [&](const std::vector<std::string>& sets) {
    std::vector<std::string> all = base;
    all.insert(all.end(), sets.begin(), sets.end());
    return load(scene, all, grid);
  });
  py::list cases;
  for (const auto& c : plan.cases) {
    py::dict d;
    d["name"] = c.name;
    d["sets"] = c.sets;
    d["columns"] = c.columns;
    d["humidity"] = c.humidity;
    d["air_model"] = c.air_model;
    cases.append(d);
  }
  return py::make_tuple(plan.extra_keys, cases, sweep::csv_header(plan), sweep::cases_csv(plan));
}

// wetcloth.run, and for wetcloth.sweep: the cases as `wetcloth sweep` plans
// them, one case run, and the sweep's folder.
void bind_run(py::module_& m) {
  m.def("run", &run, py::arg("scene") = py::none(), py::kw_only(), py::arg("out") = py::none(),
        py::arg("export") = py::none(), py::arg("up") = py::none(),
        py::arg("checkpoint_every") = py::none(), py::arg("resume") = py::none(),
        py::arg("force") = false, py::arg("progress") = py::none(),
        py::arg("overrides") = py::none(),
        R"doc(Runs SCENE into the folder OUT as `wetcloth run` does, and returns its summary.

scene: a built-in name, a path or a wetcloth.Scene, with overrides as
load_scene takes them (humidity=0.7, duration=0.5, grid=G, threads=N,
cloth__humidity=..., or overrides={"cloth.humidity": 0.7}). out: the folder
(default out/<scene name>); export: caches, any of "usd", "pc2", "vtk" (a
list or "usd,pc2"); up: "z" or "y"; checkpoint_every: seconds of simulated
time between checkpoints; force: run where the estimated memory or disk is
short, or into a folder of files no wetcloth run wrote. resume=DIR continues
the run in DIR from its checkpoint (threads and checkpoint_every may be
given). progress: progress(t, duration) after each frame.

The folder is byte for byte the command line's (but for summary.json's
timings). Ctrl-C stops the run at the end of a step with its outputs whole and
a checkpoint, then raises KeyboardInterrupt: wetcloth.run(resume=DIR) or
`wetcloth run --resume DIR` continues it. Raises SceneError on a bad scene or
folder, BlowUp (the outputs so far kept), OutputError where a file cannot be
written.)doc");
  // A sweep's folder: made, where it is not a system folder and (unless
  // force) holds nothing but an earlier sweep's outputs (its `marks`).
  m.def("_make_sweep_folder",
        [](const std::string& out, const std::vector<std::string>& marks, bool force) {
          if (!force) {
            refuse_system_folder(out, "out");
            refuse_foreign_folder(out, "out", "sweep", marks);
          }
          make_output_folder(out, "out");
        });
  m.def("_write_shared",
        [](const std::string& path, const std::string& text) { sweep::write_shared(path, text); });
  m.def("_write_file",
        [](const std::string& path, const std::string& text) { write_file_atomic(path, text); });
  m.def("_plot_sweep", [](const std::string& dir) {
    py::gil_scoped_release free;
    std::string why;
    return sweep::plot(dir, &why) ? std::string() : why;
  });
  m.def("_plan_sweep", &plan_sweep);
  m.def("_override_texts", [](const py::object& overrides) {
    std::optional<long long> grid;
    auto sets = override_texts(overrides, py::dict(), &grid);
    return py::make_tuple(sets, grid);
  });
  m.def("_run_case", &run_case, py::arg("scene"), py::arg("sets"), py::arg("grid"),
        py::arg("out") = py::none(), py::arg("extra") = py::none(), py::arg("case") = py::none());
  m.def("_metrics_columns", &metrics_columns);
}

}  // namespace

PYBIND11_MODULE(_wetcloth, m) {
  m.doc() = "wetcloth's C++ core (see the wetcloth package's docstring)";
  m.attr("__version__") = WETCLOTH_VERSION;
  bind_errors(m);
  bind_catalogue(m);
  bind_scene(m);
  bind_simulation(m);
  bind_run(m);
}
