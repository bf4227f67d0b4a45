#include "cli/commands/data_merge.h"

#include <algorithm>
#include <cstdio>

#include "render_data/dataset_manifest.h"

namespace cgsr::cli {

config::Schema<DataMergeOptions> data_merge_schema() {
  config::Schema<DataMergeOptions> s;
  s.field("data", &DataMergeOptions::data, "data set directories to merge (each single- or multi-scene)")
      .check([](const std::vector<std::string>& v) { return !v.empty(); }, "needs at least one data set");
  s.field("weights", &DataMergeOptions::weights,
          "sampling weight per data set (none: scenes in proportion to their training frames)")
      .check([](const std::vector<double>& v) { return std::all_of(v.begin(), v.end(), [](double w) { return w > 0; }); },
             "weights must be positive");
  s.field("name", &DataMergeOptions::name, "name of the merged data set (default: the scene names joined by '+')");
  s.validate([](const DataMergeOptions& o, const config::Cursor& at, const YAML::Node& node) {
    if (!o.weights.empty() && o.weights.size() != o.data.size())
      at.child("weights").fail(node["weights"] ? node["weights"] : node,
                               "give one weight per data set (" + std::to_string(o.data.size()) + ")");
  });
  add_run_settings(s);
  return s;
}

void setup_data_merge(CLI::App& data) {
  add_command<DataMergeOptions>(
      data, "merge", "One multi-scene data set from existing data sets (a manifest that refers to them, no copies)",
      data_merge_schema,
      [](CLI::App& sub, std::vector<FlagAssignment>& flags) {
        list_to_key(sub, flags, "data", "data", "data set directories", "DATA");
      },
      [](const DataMergeOptions& options, const YAML::Node&, RunDir* run_dir) {
        return run_data_merge(options, *run_dir);
      },
      /*always_run_dir=*/true);
}

nlohmann::ordered_json run_data_merge(const DataMergeOptions& options, RunDir& run_dir) {
  const std::filesystem::path& out = run_dir.path();
  std::vector<std::filesystem::path> dirs(options.data.begin(), options.data.end());
  const DatasetManifest m = merge_manifests(out, options.name, dirs, options.weights);
  // The manifest makes the directory a data set: written last, so a failed merge leaves none.
  run_dir.after_results([out, m] { write_manifest(out, m); });
  nlohmann::ordered_json j;
  j["dataset"] = out.string();
  j["name"] = m.name;
  j["frames"] = m.frames;
  j["split"] = {{"train", m.split.train.size()}, {"val", m.split.val.size()}, {"test", m.split.test.size()}};
  j["scenes"] = nlohmann::ordered_json::array();
  std::printf("merged %zu scene(s), %d frames, into '%s' in %s\n", m.scenes.size(), m.frames, m.name.c_str(),
              out.string().c_str());
  for (const auto& s : m.scenes) {
    j["scenes"].push_back({{"name", s.name}, {"path", s.path}, {"first_frame", s.first_frame}, {"frames", s.frames},
                           {"weight", s.weight}});
    std::printf("  %-16s frames %d..%d from %s", s.name.c_str(), s.first_frame, s.first_frame + s.frames - 1, s.path.c_str());
    if (s.weight > 0) std::printf(", weight %g", s.weight);
    std::printf("\n");
  }
  return j;
}

}  // namespace cgsr::cli
