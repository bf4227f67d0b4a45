#include "cli/commands/info.h"

#include <cstdio>

#include "core/system_info.h"

namespace cgsr::cli {

config::Schema<InfoOptions> info_schema() {
  config::Schema<InfoOptions> s;
  s.field("json", &InfoOptions::json, "print JSON instead of a table");
  add_run_settings(s);
  return s;
}

void setup_info(CLI::App& app) {
  add_command<InfoOptions>(
      app, "info", "Show library versions, threads, SIMD level and build type", info_schema,
      [](CLI::App& sub, std::vector<FlagAssignment>& flags) {
        switch_to_key(sub, flags, "--json", "json", "print JSON instead of a table");
      },
      [](const InfoOptions& options, RunDir*) { return run_info(options); },
      /*always_run_dir=*/false);
}

nlohmann::ordered_json run_info(const InfoOptions& options) {
  nlohmann::ordered_json results;
  results["system"] = system_info();
  if (options.json) {
    std::printf("%s\n", results.dump(2).c_str());
    return results;
  }
  for (const auto& [key, value] : results["system"].items())
    std::printf("%-18s %s\n", key.c_str(), value.is_string() ? value.get<std::string>().c_str() : value.dump().c_str());
  return results;
}

}  // namespace cgsr::cli
