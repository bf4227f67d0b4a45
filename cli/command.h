#pragma once
// What every subcommand shares: the global options, turning --config/--set/flags into a typed
// options struct, and the run directory with config.yaml, log.txt and results.json.

#include <CLI/CLI.hpp>

#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/config.h"
#include "core/run_dir.h"
#include "core/run_dir_lock.h"
#include "core/utf8.h"
#include "models/memory_layout.h"
#include "pipeline/run_settings.h"

namespace cgsr::cli {

struct GlobalOptions {
  std::string config_file;         // --config FILE
  std::vector<std::string> sets;   // --set key.path=value, repeatable
  std::string out;                 // --out DIR
  std::string log_level = "info";  // --log-level
  std::optional<int> threads;      // --threads N (0 = all hardware threads)
  std::optional<int64_t> seed;     // --seed N
  bool print_config = false;       // --print-config
  bool check = false;              // --check
  bool force = false;              // --force
  bool verbose = false;            // --verbose
};

GlobalOptions& globals();
void add_global_options(CLI::App& app);

// A command flag recorded as a config assignment, e.g. {"model=pan", "--model pan"}.
struct FlagAssignment {
  std::string assignment;
  std::string origin;
};

// The document a command parses: --config, then --set, then the command's own flags, then
// --seed/--threads.
config::Document build_document(const std::vector<FlagAssignment>& flags);

// Applies logging, threads and seed for a command about to run.
void begin_command(const RunSettings& run);

// Registers `name` as a subcommand that parses its options with `schema` and runs `body`.
// `flags` registers the command's own CLI flags; each flag appends assignments to the vector.
// The run directory exists when --out is given, or always when `always_run_dir` is true
// (default runs/<name>-<time>); it records the memory layouts the command chose (layouts.json). `body` gets the options, the resolved config and the run
// directory, and returns the results written to results.json. `place_run_dir`, when given, moves
// the run directory (e.g. a distributed rank's own subdirectory). `check`, when given, is what
// --check does beyond parsing the options (e.g. cgsr run parses every stage's section), and
// returns what it found to print.
template <class T>
CLI::App* add_command(CLI::App& app, const std::string& name, const std::string& description,
                      std::function<config::Schema<T>()> schema,
                      std::function<void(CLI::App&, std::vector<FlagAssignment>&)> flags,
                      std::function<nlohmann::ordered_json(const T&, const YAML::Node&, RunDir*)> body,
                      bool always_run_dir,
                      std::function<std::filesystem::path(const T&, const std::filesystem::path&)> place_run_dir = {},
                      std::function<std::string(const T&)> check = {}) {
  CLI::App* sub = app.add_subcommand(name, description);
  auto assignments = std::make_shared<std::vector<FlagAssignment>>();
  if (flags) flags(*sub, *assignments);
  // The command as its run directory records it: "train", "data merge".
  const std::string command = app.get_name().empty() ? name : app.get_name() + " " + name;
  sub->callback([=]() {
    // Before any work: paths reach JSON files, which must be UTF-8 (core/utf8.h).
    require_utf8(globals().out, "--out", "the path");
    require_utf8(globals().config_file, "--config", "the path");
    const auto the_schema = schema();
    const config::Document doc = build_document(*assignments);
    const T options = config::parse_document(doc, the_schema);
    const YAML::Node resolved = the_schema.emit(options);
    if (globals().print_config) {
      std::fputs(config::to_yaml(resolved).c_str(), stdout);
      return;
    }
    if (globals().check) {  // nothing runs, nothing is written
      if (check) std::fputs(check(options).c_str(), stdout);
      std::printf("cgsr %s: the config is valid\n", name.c_str());
      return;
    }
    begin_command(options);
    std::unique_ptr<RunDirLock> lock;  // released after the run directory's log is finished
    std::unique_ptr<RunDir> run_dir;
    if (!globals().out.empty() || always_run_dir) {
      std::filesystem::path dir = globals().out.empty() ? default_run_dir(name) : std::filesystem::path(globals().out);
      if (place_run_dir) dir = place_run_dir(options, dir);
      lock = std::make_unique<RunDirLock>(dir, command, globals().force);
      run_dir = std::make_unique<RunDir>(dir);
    }
    if (run_dir) run_dir->write_config(resolved);
    // The memory layouts `auto` chose, so that a rerun of the directory uses them (memory_layout.h).
    std::optional<LayoutRecordScope> layouts;
    if (run_dir) layouts.emplace(run_dir->file("layouts.json"));
    const nlohmann::ordered_json results = body(options, resolved, run_dir.get());
    if (run_dir) run_dir->write_results(results);
  });
  return sub;
}

// Adds `--name VALUE` to `sub`, recorded as the assignment "key=VALUE".
void flag_to_key(CLI::App& sub, std::vector<FlagAssignment>& assignments, const std::string& flag,
                 const std::string& key, const std::string& description);
// Adds a repeatable option or positional list `name` to `sub`, recorded as the assignment
// "key=['a', 'b']" (quoted, so paths stay strings) with `origin` as where it came from.
void list_to_key(CLI::App& sub, std::vector<FlagAssignment>& assignments, const std::string& name,
                 const std::string& key, const std::string& description, const std::string& origin);
// Adds a boolean `--name` flag to `sub`, recorded as "key=true".
void switch_to_key(CLI::App& sub, std::vector<FlagAssignment>& assignments, const std::string& flag,
                   const std::string& key, const std::string& description);

// --world-size N --rank R --store HOST:PORT of a command that runs as several processes (cgsr
// train, cgsr search: pipeline/distributed_run.h), recorded as distributed.world_size/rank/store.
void add_distributed_flags(CLI::App& sub, std::vector<FlagAssignment>& flags);

}  // namespace cgsr::cli
