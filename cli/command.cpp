#include "cli/command.h"

#include <spdlog/spdlog.h>

#include "core/logging.h"
#include "core/runtime.h"

namespace cgsr::cli {

GlobalOptions& globals() {
  static GlobalOptions options;
  return options;
}

void add_global_options(CLI::App& app) {
  auto& g = globals();
  app.add_option("--config", g.config_file, "YAML config file for the command")->check(CLI::ExistingFile);
  app.add_option("--set", g.sets, "override a config value: key.path=value (repeatable)");
  app.add_option("--out", g.out, "run directory for config.yaml, log.txt, results.json and artifacts");
  app.add_option("--log-level", g.log_level, "trace, debug, info, warn, error or off")->capture_default_str();
  app.add_option("--threads", g.threads, "LibTorch and TBB threads (0 = all hardware threads)");
  app.add_option("--seed", g.seed, "seed for every random number generator");
  app.add_flag("--print-config", g.print_config, "print the resolved config of the command and exit");
  app.add_flag("--force", g.force,
               "write into a run directory that belongs to another command; --resume: go on despite differences "
               "from the checkpoint");
  app.add_flag("--verbose", g.verbose, "internal errors: with LibTorch's backtrace");
  app.add_flag("--check", g.check,
               "check the config and exit without running or writing anything (cgsr run: every stage's section "
               "and every scene config it names too)");
}

config::Document build_document(const std::vector<FlagAssignment>& flags) {
  const auto& g = globals();
  config::Document doc = g.config_file.empty() ? config::Document() : config::Document::load_file(g.config_file);
  for (const auto& assignment : g.sets) doc.apply_override(assignment);
  for (const auto& flag : flags) doc.apply_override(flag.assignment, flag.origin);
  if (g.seed) doc.apply_override("seed=" + std::to_string(*g.seed), "--seed");
  if (g.threads) doc.apply_override("threads=" + std::to_string(*g.threads), "--threads");
  return doc;
}

void begin_command(const RunSettings& run) {
  init_logging(globals().log_level);
  const int threads = set_threads(run.threads);
  seed_everything(static_cast<uint64_t>(run.seed));
  spdlog::debug("threads {}, seed {}", threads, run.seed);
}

void flag_to_key(CLI::App& sub, std::vector<FlagAssignment>& assignments, const std::string& flag,
                 const std::string& key, const std::string& description) {
  sub.add_option_function<std::string>(
      flag,
      [&assignments, flag, key](const std::string& value) {
        assignments.push_back({key + "=" + value, flag + " " + value});
      },
      description + " (config key '" + key + "')");
}

void list_to_key(CLI::App& sub, std::vector<FlagAssignment>& assignments, const std::string& name,
                 const std::string& key, const std::string& description, const std::string& origin) {
  sub.add_option_function<std::vector<std::string>>(
      name,
      [&assignments, key, origin](const std::vector<std::string>& values) {
        std::string list = "[";
        for (size_t i = 0; i < values.size(); ++i) list += (i ? ", " : "") + ("'" + values[i] + "'");
        assignments.push_back({key + "=" + list + "]", origin});
      },
      description);
}

void switch_to_key(CLI::App& sub, std::vector<FlagAssignment>& assignments, const std::string& flag,
                   const std::string& key, const std::string& description) {
  sub.add_flag_function(
      flag, [&assignments, flag, key](int64_t) { assignments.push_back({key + "=true", flag}); },
      description + " (config key '" + key + "')");
}

void add_distributed_flags(CLI::App& sub, std::vector<FlagAssignment>& flags) {
  flag_to_key(sub, flags, "--world-size", "distributed.world_size", "processes in a distributed run");
  flag_to_key(sub, flags, "--rank", "distributed.rank", "this process's rank (0 coordinates)");
  flag_to_key(sub, flags, "--store", "distributed.store", "HOST:PORT of the store rank 0 hosts");
}

}  // namespace cgsr::cli
