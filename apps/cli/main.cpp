// wetcloth: the command-line program. Thin: it parses options, loads scenes and
// calls the library.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <functional>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <vector>

#include "cli.hpp"
#include "common/scene_options.hpp"
#ifdef WETCLOTH_VIEWER
#include "../viewer/commands.hpp"
#endif
#include "wetcloth/output.hpp"
#include "wetcloth/scene.hpp"

using namespace wetcloth;

namespace {

// A registered command: runs it when it was chosen, else returns -1.
using Command = std::function<int()>;

Command add_scenes_command(CLI::App& app) {
  auto* cmd = app.add_subcommand("scenes", "list the built-in scenes");
  return [cmd]() -> int {
    if (!*cmd) return -1;
    int width = 0;  // the longest name's: every description starts in one column
    for (const auto& s : builtin_scenes()) width = std::max(width, static_cast<int>(s.name.size()));
    for (const auto& s : builtin_scenes())
      std::printf("%-*s  %s\n", width, s.name.c_str(), s.description.c_str());
    return kOk;
  };
}

Command add_check_command(CLI::App& app) {
  auto o = std::make_shared<cli::SceneOptions>();
  auto* cmd = app.add_subcommand("check", "validate a scene and print every parameter, resolved");
  o->add_to(cmd);
  return [cmd, o]() -> int {
    if (!*cmd) return -1;
    const Params p = o->load();
    std::cout << "# " << o->scene << ": ok\n";
    // The substeps that will run (a mesh cloth counts its own particles).
    if (p.integrator.type == IntegratorType::Xpbd)
      std::cout << "# xpbd: "
                << (p.cloth.mesh.empty() ? xpbd_substeps(p) : xpbd_substeps(build_model(p)))
                << " substeps a step of " << p.integrator.dt << " s\n";
    std::cout << to_toml(p);
    return kOk;
  };
}

// `params --json`: every parameter's definition, for programs.
std::string params_json() {
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
  return all.dump(2) + "\n";
}

// `params --preset [NAME]`: what the preset sets, or (no name) the presets.
int print_preset(const std::string& name) {
  if (name.empty()) {
    std::cout << presets_text();
    return kOk;
  }
  if (const FabricPreset* f = find_preset(name)) {
    std::cout << preset_text(*f);
    return kOk;
  }
  std::fprintf(stderr, "wetcloth: error: params --preset: '%s' is not a preset; the presets:\n%s",
               name.c_str(), presets_text().c_str());
  return kBadInput;
}

Command add_params_command(CLI::App& app) {
  struct Options {
    bool markdown = false, json = false;
    std::string preset;
  };
  auto o = std::make_shared<Options>();
  auto* cmd =
      app.add_subcommand("params", "every scene parameter: key, unit, default, range, meaning");
  auto* markdown =
      cmd->add_flag("--markdown", o->markdown, "as the Markdown table of docs/guide.md");
  auto* json = cmd->add_flag("--json", o->json,
                             "as JSON: key, unit, type, default, min, max, choices, meaning");
  cmd->add_option("--preset", o->preset,
                  "what fabric preset NAME (material.preset) sets: key, value, unit, source; "
                  "without NAME, the presets")
      ->expected(0, 1)
      ->excludes(markdown, json);
  return [cmd, o]() -> int {
    if (!*cmd) return -1;
    if (cmd->count("--preset") > 0) return print_preset(o->preset);
    std::cout << (o->markdown ? params_markdown() : o->json ? params_json() : params_text());
    return kOk;
  };
}

// The first word names the command: CLI11 would answer a misspelt one
// (`runn`, or an option before the command) with "A subcommand is required".
// Returns the exit code when there is no command to run.
std::optional<int> check_command_word(CLI::App& app, int argc, char** argv) {
  if (argc <= 1) {  // no command: what there is to do
    app.name(argv[0]);
    std::cerr << app.help();
    return kBadInput;
  }
  const std::string first = argv[1];
  std::string names;
  bool known = first == "-h" || first == "--help" || first == "--version";
  for (const CLI::App* sub : app.get_subcommands([](const CLI::App*) { return true; })) {
    known = known || sub->check_name(first);
    names += (names.empty() ? "" : ", ") + sub->get_name();
  }
  if (known) return std::nullopt;
  std::fprintf(stderr, "wetcloth: error: unknown %s '%s'%s (the commands: %s; wetcloth --help)\n",
               first[0] == '-' ? "option" : "command", first.c_str(),
               first[0] == '-' ? " before the command" : "", names.c_str());
  return kBadInput;
}

// Runs the chosen command; the library's errors become exit codes.
int run_chosen(const std::vector<Command>& commands) {
  try {
    for (const Command& command : commands)
      if (const int code = command(); code >= 0) return code;
  } catch (const SceneError& e) {
    std::fprintf(stderr, "wetcloth: error: %s\n", e.what());
    return kBadInput;
  } catch (const OutputError& e) {
    std::fprintf(stderr, "wetcloth: error: %s\n", e.what());
    return kOutputError;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "wetcloth: error: %s\n", e.what());
    return kError;
  }
  return kOk;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"wetcloth " WETCLOTH_VERSION
               ": wet cloth on contact surfaces (mass-spring cloth, trapped air, liquid-bridge "
               "adhesion, friction, self-collision). Units are SI throughout."};
  app.require_subcommand(1);
  app.set_version_flag("--version", WETCLOTH_VERSION);

  // In the order `wetcloth --help` lists them.
  std::vector<Command> commands{cli::add_run_command(app),     add_scenes_command(app),
                                add_check_command(app),        add_params_command(app),
                                cli::add_sweep_command(app),   cli::add_bench_command(app),
                                cli::add_converge_command(app)};
#ifdef WETCLOTH_VIEWER
  auto viewer_commands = viewer::add_commands(app);  // view, render
  commands.push_back([viewer_commands] { return viewer_commands().value_or(-1); });
#endif

  if (const auto code = check_command_word(app, argc, argv)) return *code;
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // --help and --version end here with 0; a bad option or value is bad
    // input like any other (CLI11's own codes are 100 and up), said as the
    // loader says it.
    if (e.get_exit_code() == 0) return app.exit(e);
    std::fprintf(stderr, "wetcloth: error: %s\nRun with --help for more information.\n", e.what());
    return kBadInput;
  }
  return run_chosen(commands);
}
