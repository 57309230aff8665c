// wetcloth: the command-line program. Thin: it parses options, loads scenes and
// calls the library.
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>

#include "bench.hpp"
#include "common/scene_options.hpp"
#include "converge.hpp"
#include "run.hpp"
#include "sweep.hpp"
#ifdef WETCLOTH_VIEWER
#include "../viewer/commands.hpp"
#endif
#include "wetcloth/output.hpp"
#include "wetcloth/scene.hpp"

using namespace wetcloth;
namespace fs = std::filesystem;

int main(int argc, char** argv) {
  CLI::App app{"wetcloth " WETCLOTH_VERSION
               ": wet cloth on contact surfaces (mass-spring cloth, trapped air, liquid-bridge "
               "adhesion, friction, self-collision). Units are SI throughout."};
  app.require_subcommand(1);
  app.set_version_flag("--version", WETCLOTH_VERSION);

  cli::SceneOptions run_opts;
  std::string out_dir;
  bool quiet = false, force = false;
  auto* run = app.add_subcommand("run", "run a scene and write its results into a folder");
  run_opts.add_to(run, false);  // no SCENE with --resume
  std::optional<double> checkpoint_every;
  run->add_option("--checkpoint-every", checkpoint_every,
                  "write the whole state into DIR/checkpoint.state every S of simulated time, "
                  "for --resume (= --set run.checkpoint_every=S)")
      ->check(cli::in_range_of("run.checkpoint_every"));
  std::string resume_dir;
  run->add_option("--resume", resume_dir,
                  "continue the run in DIR from its checkpoint.state, with the same bits as a run "
                  "never stopped (no SCENE: it comes from the checkpoint; --threads and "
                  "--checkpoint-every may be given)")
      ->check(cli::a_path());
  run->add_option("--out", out_dir, "output folder (default out/<scene name>)")
      ->check(cli::a_path());
  run->add_flag("--quiet", quiet, "no progress bar");
  std::optional<std::string> exports, up;
  run->add_option("--export", exports,
                  "animation caches, any of usd,pc2,vtk (= --set run.export=LIST): DIR/cloth.usda; "
                  "DIR/cloth.pc2 with DIR/cloth_rest.obj; DIR/vtk/*.vtp with DIR/cloth.pvd");
  run->add_option("--up", up, "up axis of every file written, z (default) or y (= --set run.up=A)")
      ->check(CLI::IsMember({"z", "y"}));
  run->add_flag("--force", force,
                "run even where the memory or disk the run needs (estimated) is more than the "
                "machine has");
  run->footer(
      "Writes DIR/metrics.csv (one row per frame, SI units in the header), DIR/frames/*.obj,\n"
      "DIR/obstacles.obj, DIR/scene.toml (every parameter, resolved) and DIR/summary.json.\n"
      "Exit codes: 0 ok, 2 bad input (nothing written; or DIR is in use by another run),\n"
      "3 the simulation blew up (outputs so far kept), 4 an output could not be written\n"
      "(full disk, read-only folder: the file and the reason named), 130 / 143 stopped by\n"
      "SIGINT / SIGTERM at the end of a step (outputs whole, summary.json \"interrupted\",\n"
      "DIR/checkpoint.state written: `wetcloth run --resume DIR` continues the run).");

  auto* scenes = app.add_subcommand("scenes", "list the built-in scenes");

  cli::SceneOptions check_opts;
  auto* check = app.add_subcommand("check", "validate a scene and print every parameter, resolved");
  check_opts.add_to(check);

  bool markdown = false;
  auto* params =
      app.add_subcommand("params", "every scene parameter: key, unit, default, range, meaning");
  params->add_flag("--markdown", markdown, "as the Markdown table of docs/guide.md");
  bool json = false;
  params->add_flag("--json", json, "as JSON: key, unit, type, default, min, max, choices, meaning");

  auto sweep_command = cli::add_sweep_command(app);
  auto bench_command = cli::add_bench_command(app);
  auto converge_command = cli::add_converge_command(app);
#ifdef WETCLOTH_VIEWER
  auto viewer_command = viewer::add_commands(app);  // view, render
#endif

  // The first word names the command: CLI11 would answer a misspelt one
  // (`runn`, or an option before the command) with "A subcommand is required".
  if (argc > 1) {
    const std::string first = argv[1];
    std::string names;
    bool known = first == "-h" || first == "--help" || first == "--version";
    for (const CLI::App* sub : app.get_subcommands([](const CLI::App*) { return true; })) {
      known = known || sub->check_name(first);
      names += (names.empty() ? "" : ", ") + sub->get_name();
    }
    if (!known) {
      std::fprintf(stderr,
                   "wetcloth: error: unknown %s '%s'%s (the commands: %s; wetcloth --help)\n",
                   first[0] == '-' ? "option" : "command", first.c_str(),
                   first[0] == '-' ? " before the command" : "", names.c_str());
      return cli::kBadInput;
    }
  } else {  // no command: what there is to do
    app.name(argv[0]);
    std::cerr << app.help();
    return cli::kBadInput;
  }

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // --help and --version end here with 0; a bad option or value is bad
    // input like any other (CLI11's own codes are 100 and up), said as the
    // loader says it.
    if (e.get_exit_code() == 0) return app.exit(e);
    std::fprintf(stderr, "wetcloth: error: %s\nRun with --help for more information.\n", e.what());
    return cli::kBadInput;
  }

  try {
#ifdef WETCLOTH_VIEWER
    if (auto code = viewer_command()) return *code;
#endif
    if (const int code = sweep_command(); code >= 0) return code;
    if (const int code = bench_command(); code >= 0) return code;
    if (const int code = converge_command(); code >= 0) return code;
    if (*scenes) {
      for (const auto& s : builtin_scenes())
        std::printf("%-14s %s\n", s.name.c_str(), s.description.c_str());
      return 0;
    }
    if (*params) {
      if (markdown) {
        std::cout << params_markdown();
      } else if (json) {
        nlohmann::json all = nlohmann::json::array();
        for (const auto& d : param_defs()) {
          nlohmann::json j = {{"key", d.key},
                              {"unit", d.unit},
                              {"type", d.type_name()},
                              {"default", d.default_text()},
                              {"meaning", d.meaning}};
          if (d.min <= d.max) j["min"] = d.min, j["max"] = d.max;
          if (!d.choices.empty()) j["choices"] = d.choices;
          all.push_back(j);
        }
        std::cout << all.dump(2) << "\n";
      } else {
        std::cout << params_text();
      }
      return 0;
    }
    if (*check) {
      const Params p = check_opts.load();
      std::cout << "# " << check_opts.scene << ": ok\n" << to_toml(p);
      return 0;
    }
    if (*run) {
      Params p;
      fs::path out;
      std::optional<cli::ResumePoint> resume;
      if (!resume_dir.empty()) {
        // The scene is the checkpoint's: what would change it is refused.
        std::string given;
        const auto refuse = [&](bool set, const char* what) {
          if (set) given += (given.empty() ? "" : ", ") + std::string(what);
        };
        refuse(!run_opts.scene.empty(), "a SCENE");
        refuse(!run_opts.sets.empty(), "--set");
        refuse(run_opts.humidity.has_value(), "--humidity");
        refuse(run_opts.duration.has_value(), "--duration");
        refuse(run_opts.grid.has_value(), "--grid");
        refuse(exports.has_value(), "--export");
        refuse(up.has_value(), "--up");
        refuse(!out_dir.empty(), "--out");
        if (!given.empty())
          throw SceneError("--resume " + resume_dir +
                           ": the run continues in that folder with its checkpoint's scene; " +
                           given +
                           " would change it (--threads, --checkpoint-every, --quiet and --force "
                           "may be given)");
        out = resume_dir;
        if (cli::run_ended_whole(out)) {
          // Killed in its last moment, between removing the checkpoint and
          // the USD samples: the samples go now.
          std::error_code ec;
          std::filesystem::remove_all(out / ".cloth.usda.samples", ec);
          if (!quiet)
            std::printf("%s: the run ended whole (summary.json); nothing to resume\n", out.c_str());
          return 0;
        }
        resume = cli::load_resume_point(out);
        p = resume->params;
        if (run_opts.threads) p.integrator.threads = *run_opts.threads;
        if (checkpoint_every) p.run.checkpoint_every = *checkpoint_every;
        if (!force) cli::check_resources(p, out, resume->file.string());
      } else {
        if (run_opts.scene.empty())
          throw SceneError(
              "run: a SCENE is needed (a TOML file or a built-in name: wetcloth scenes), or "
              "--resume DIR");
        if (exports) run_opts.sets.push_back("run.export=\"" + *exports + "\"");
        if (up) run_opts.sets.push_back("run.up=" + *up);
        if (checkpoint_every)
          run_opts.sets.push_back("run.checkpoint_every=" + format_number(*checkpoint_every));
        p = run_opts.load();
        out = out_dir.empty() ? fs::path("out") / cli::folder_name(p.name) : fs::path(out_dir);
        if (!force) cli::check_resources(p, out, run_opts.scene);
        cli::make_output_folder(out);
      }
      const bool progress = !quiet && isatty(STDERR_FILENO);
      cli::install_stop_handlers();
      const auto r = cli::run_scene(p, out, progress, resume ? &*resume : nullptr);
      if (r.code > 128) {
        std::fprintf(stderr,
                     "wetcloth: %s\nresults so far (whole): %s; `wetcloth run --resume %s` "
                     "continues the run\n",
                     r.message.c_str(), out.c_str(), out.c_str());
        return r.code;
      }
      if (r.code != cli::kOk) {
        std::fprintf(stderr, "wetcloth: %s\nresults so far: %s\n", r.message.c_str(), out.c_str());
        return r.code;
      }
      if (!quiet)
        std::printf("%s: %lld steps in %.2f s wall (%.2fx real time); results in %s\n",
                    p.name.c_str(), r.steps, r.wall_seconds,
                    r.wall_seconds > 0 ? r.final.time_s / r.wall_seconds : 0.0, out.c_str());
      return 0;
    }
  } catch (const SceneError& e) {
    std::fprintf(stderr, "wetcloth: error: %s\n", e.what());
    return cli::kBadInput;
  } catch (const OutputError& e) {
    std::fprintf(stderr, "wetcloth: error: %s\n", e.what());
    return cli::kOutputError;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "wetcloth: error: %s\n", e.what());
    return cli::kError;
  }
  return 0;
}
