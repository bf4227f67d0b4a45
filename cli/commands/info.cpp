#include "cli/commands/info.h"

#include <cstdio>

#include "core/system_info.h"
#include "core/yaml_json.h"
#include "core/text.h"
#include "models/complexity.h"
#include "models/model_source.h"

namespace cgsr::cli {

config::Schema<InfoOptions> info_schema() {
  config::Schema<InfoOptions> s;
  s.field("json", &InfoOptions::json, "print JSON instead of a table");
  s.field("model", &InfoOptions::model, "backbone name, spec YAML file or model file to describe");
  s.field("scale", &InfoOptions::scale, "scale for a backbone name (0: 2, or the file's)").check(
      [](int v) { return v == 0 || (v >= 2 && v <= 4); }, "must be 0, 2, 3 or 4");
  s.field("input", &InfoOptions::input, "LR input size WxH for MAC counts (default: 1280x720 output)");
  add_run_settings(s);
  return s;
}

void setup_info(CLI::App& app) {
  add_command<InfoOptions>(
      app, "info", "Show library versions, threads, SIMD level and build type; with --model, a network's layers, "
      "parameters and MACs", info_schema,
      [](CLI::App& sub, std::vector<FlagAssignment>& flags) {
        switch_to_key(sub, flags, "--json", "json", "print JSON instead of a table");
        flag_to_key(sub, flags, "--model", "model", "backbone name, spec YAML file or model file");
        flag_to_key(sub, flags, "--scale", "scale", "scale for a backbone name");
        flag_to_key(sub, flags, "--input", "input", "LR input size WxH (default: 1280x720 output)");
      },
      [](const InfoOptions& options, const YAML::Node&, RunDir*) { return run_info(options); },
      /*always_run_dir=*/false);
}

namespace {

const char* source_kind(ModelSource::Kind kind) {
  switch (kind) {
    case ModelSource::Kind::Name: return "default spec";
    case ModelSource::Kind::SpecFile: return "spec file";
    case ModelSource::Kind::ModelFile: return "model file";
  }
  return "?";
}

// "1,369,859"
std::string grouped(int64_t n) {
  std::string digits = std::to_string(n < 0 ? -n : n), out;
  for (size_t i = 0; i < digits.size(); ++i) {
    if (i > 0 && (digits.size() - i) % 3 == 0) out += ',';
    out += digits[i];
  }
  return n < 0 ? "-" + out : out;
}

nlohmann::ordered_json describe_model(const InfoOptions& options) {
  const ModelSource source = resolve_model(options.model, options.scale);
  const ArchSpec& spec = source.spec;
  int64_t w = 0, h = 0;
  if (options.input.empty()) {
    std::tie(w, h) = lr_size_for_output(1280, 720, spec.scale);
  } else {
    std::tie(w, h) = parse_size(options.input, "--input");
  }
  const Complexity cost = complexity(*source.network, w, h);
  nlohmann::ordered_json j;
  j["origin"] = source.origin;
  j["source"] = source_kind(source.kind);
  j["summary"] = spec_summary(spec);
  j["spec"] = yaml_to_json(spec_to_node(spec));
  j["channels"] = channel_names(spec.input_channels());
  j["training_only_params"] = total_parameter_count(*source.network) - cost.params;
  if (source.provenance) j["provenance"] = *source.provenance;
  j["complexity"] = to_json(cost);
  return j;
}

void print_model(const nlohmann::ordered_json& model) {
  std::printf("\nmodel              %s (%s: %s)\n", model["summary"].get<std::string>().c_str(),
              model["source"].get<std::string>().c_str(), model["origin"].get<std::string>().c_str());
  const auto channels = model["channels"].get<std::vector<std::string>>();
  std::printf("rendering channels %s\n", channels.empty() ? "none" : join(channels).c_str());
  if (model.contains("provenance")) {
    const auto& p = model["provenance"];
    std::printf("stage              %s\n", p["stage"].get<std::string>().c_str());
    if (!p["parent"].get<std::string>().empty()) std::printf("parent             %s\n", p["parent"].get<std::string>().c_str());
    if (!p["metrics"].empty()) std::printf("metrics            %s\n", p["metrics"].dump().c_str());
  }
  const auto& c = model["complexity"];
  std::printf("input              %s -> output %s\n\n", c["input"].get<std::string>().c_str(),
              c["output"].get<std::string>().c_str());
  std::printf("%-44s %-6s %5s %5s %3s %11s %11s %10s\n", "layer", "kind", "in", "out", "k", "output", "params", "MACs");
  for (const auto& l : c["layers"]) {
    std::printf("%-44s %-6s %5lld %5lld %3lld %11s %11s %10s\n", l["name"].get<std::string>().c_str(),
                l["kind"] == "conv" ? (l["trainable"].get<bool>() ? "conv" : "fixed") : "gate",
                static_cast<long long>(l["in"].get<int64_t>()), static_cast<long long>(l["out"].get<int64_t>()),
                static_cast<long long>(l["kernel"].get<int64_t>()), l["output"].get<std::string>().c_str(),
                grouped(l["params"].get<int64_t>()).c_str(), format_count(static_cast<double>(l["macs"].get<int64_t>())).c_str());
  }
  std::printf("\n%-44s %42s %10s\n", "total (inference)", grouped(c["params"].get<int64_t>()).c_str(),
              format_count(static_cast<double>(c["macs"].get<int64_t>())).c_str());
  if (model["training_only_params"].get<int64_t>() > 0)
    std::printf("%-44s %42s\n", "training-only (geometry head)", grouped(model["training_only_params"].get<int64_t>()).c_str());
}

}  // namespace

nlohmann::ordered_json run_info(const InfoOptions& options) {
  nlohmann::ordered_json results;
  results["system"] = system_info();
  if (!options.model.empty()) results["model"] = describe_model(options);
  if (options.json) {
    std::printf("%s\n", results.dump(2).c_str());
    return results;
  }
  for (const auto& [key, value] : results["system"].items())
    std::printf("%-18s %s\n", key.c_str(), value.is_string() ? value.get<std::string>().c_str() : value.dump().c_str());
  if (results.contains("model")) print_model(results["model"]);
  return results;
}

}  // namespace cgsr::cli
