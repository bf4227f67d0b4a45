#include "cli/commands/data_check.h"

#include <cstdio>

#include "cli/commands/data_merge.h"
#include "cli/commands/data_preview.h"
#include "core/error.h"
#include "render_data/data_check.h"

namespace cgsr::cli {

config::Schema<DataCheckOptions> data_check_schema() {
  config::Schema<DataCheckOptions> s;
  s.field("dir", &DataCheckOptions::dir, "dataset directory or glob-layout YAML file").required();
  s.section("open", &DataCheckOptions::open, dataset_open_schema(), "how to open the dataset");
  s.field("max_messages", &DataCheckOptions::max_messages, "problems listed in full").range(0, 100000);
  s.field("json", &DataCheckOptions::json, "print the report as JSON");
  add_run_settings(s);
  return s;
}

void setup_data(CLI::App& app) {
  CLI::App* data = app.add_subcommand("data", "Dataset tools: check, preview, merge");
  data->require_subcommand(1);
  setup_data_check(*data);
  setup_data_preview(*data);
  setup_data_merge(*data);
}

void setup_data_check(CLI::App& data) {
  add_command<DataCheckOptions>(
      data, "check", "Validate a dataset: every frame and resolution, sizes, NaN/Inf, value ranges", data_check_schema,
      [](CLI::App& sub, std::vector<FlagAssignment>& flags) {
        sub.add_option_function<std::string>(
            "dir", [&flags](const std::string& v) { flags.push_back({"dir=" + v, "DIR " + v}); },
            "dataset directory or glob-layout YAML file");
        flag_to_key(sub, flags, "--layout", "open.layout", "dataset layout (auto, cgsr, cgsr-release, glob)");
        sub.add_option_function<std::vector<std::string>>(
               "--derive",
               [&flags](const std::vector<std::string>& channels) {
                 flags.push_back({"open.derive=[" + join(channels) + "]", "--derive"});
               },
               "channels to derive from depth when the data lacks them (edge, normal, normal_angle)")
            ->delimiter(',');
        switch_to_key(sub, flags, "--clean-grid-lines", "open.clean_grid_lines", "remove CGSR tile-grid lines from edges");
        switch_to_key(sub, flags, "--json", "json", "print the report as JSON");
      },
      [](const DataCheckOptions& options, const YAML::Node&, RunDir*) { return run_data_check(options); },
      /*always_run_dir=*/false);
}

nlohmann::ordered_json run_data_check(const DataCheckOptions& options) {
  const DataCheckReport r = check_dataset(options.dir, options.open, static_cast<size_t>(options.max_messages));
  nlohmann::ordered_json j;
  j["dataset"] = options.dir;
  j["name"] = r.name;
  j["layout"] = r.layout;
  j["frames"] = r.frames;
  std::vector<std::string> res;
  for (const auto& x : r.resolutions) res.push_back(x.name());
  j["resolutions"] = res;
  j["channels"] = r.channels;
  j["derived"] = r.derived;
  j["frames_checked"] = r.frames_checked;
  j["files_checked"] = r.files_checked;
  j["split"] = {{"train", r.split_train}, {"val", r.split_val}, {"test", r.split_test}};
  if (!r.scenes.empty()) j["scenes"] = r.scenes;
  j["depth_range"] = {r.depth_min, r.depth_max};
  j["sky_fraction"] = r.sky_fraction;
  j["edge_fraction"] = r.edge_fraction;
  j["motion_max_pixels"] = r.motion_max;
  j["problems"] = r.problems;
  j["problem_count"] = r.problem_count();
  j["messages"] = r.messages;
  if (options.json) {
    std::printf("%s\n", j.dump(2).c_str());
  } else {
    std::printf("dataset      %s (%s layout, '%s')\n", options.dir.c_str(), r.layout.c_str(), r.name.c_str());
    std::printf("frames       %d at %s; split train %d / val %d / test %d\n", r.frames, join(res).c_str(), r.split_train,
                r.split_val, r.split_test);
    if (!r.scenes.empty()) std::printf("scenes       %s\n", join(r.scenes).c_str());
    std::printf("channels     %s%s\n", join(r.channels).c_str(),
                r.derived.empty() ? "" : (" (derived: " + join(r.derived) + ")").c_str());
    std::printf("checked      %lld frame/resolution pairs, %lld files\n", static_cast<long long>(r.frames_checked),
                static_cast<long long>(r.files_checked));
    std::printf("depth        %.4g .. %.4g m, %.1f%% without geometry\n", r.depth_min, r.depth_max, 100 * r.sky_fraction);
    std::printf("edges        %.2f%% of pixels; largest motion %.2f px\n", 100 * r.edge_fraction, r.motion_max);
    if (r.problems.empty()) {
      std::printf("problems     none\n");
    } else {
      std::printf("problems     %lld\n", static_cast<long long>(r.problem_count()));
      for (const auto& [kind, count] : r.problems) std::printf("  %-22s %lld\n", kind.c_str(), static_cast<long long>(count));
      for (const auto& m : r.messages) std::printf("  - %s\n", m.c_str());
    }
  }
  if (r.problem_count() > 0)
    throw Error(options.dir, std::to_string(r.problem_count()) + " problem(s) found (see the summary above)");
  return j;
}

}  // namespace cgsr::cli
