#include "pruning/hybrid_model.h"

#include <torch/torch.h>

#include <cmath>
#include <set>

#include "core/error.h"
#include "core/tensor_checks.h"
#include "models/layers.h"

namespace cgsr {

namespace {
constexpr const char* kKey = "dynamic_pruning";
constexpr int kFormat = 3;
const std::string kPrefix = std::string(kExtraTensorPrefix) + "dpc.";
}  // namespace

bool is_hybrid_model(const Provenance& provenance) {
  return provenance.extra.is_object() && provenance.extra.contains(kKey);
}

void save_hybrid_model(const std::filesystem::path& path, const HybridModel& model) {
  ModelFileContents contents;
  contents.spec = model.network->spec();
  contents.provenance = model.provenance;
  const auto& options = model.samplers->options();
  contents.provenance.extra[kKey] = {{"format", kFormat},
                                     {"sampler", {{"channels", options.channels},
                                                  {"grid", options.grid},
                                                  {"width", options.width}}},
                                     {"pool", to_json(model.pool)},
                                     {"latency", {{"lr_size", {model.latency.lr_width, model.latency.lr_height}},
                                                  {"median_ms", model.latency.median_ms}}}};
  for (const auto& p : model.network->named_parameters(/*recurse=*/true)) contents.tensors.emplace_back(p.key(), p.value());
  for (const auto& p : model.samplers->named_parameters(/*recurse=*/true))
    contents.tensors.emplace_back(kPrefix + p.key(), p.value());
  write_model_file(path, contents);
}

HybridModel load_hybrid_model(const std::filesystem::path& path) {
  const std::string where = path.string();
  Model base = load_model(path);
  if (!is_hybrid_model(base.provenance))
    throw Error(where, "not a hybrid-pruned model (no dynamic pruning components; made by cgsr prune?)");
  const ModelFileContents contents = read_model_file(path);
  HybridModel model;
  model.network = base.network;
  model.network->eval();
  model.provenance = base.provenance;
  const auto& j = base.provenance.extra[kKey];
  SamplerOptions options;
  try {
    if (j.at("format").get<int>() != kFormat)
      throw Error(where, "dynamic pruning data format " + j.at("format").dump() + " is not supported (this cgsr reads format " +
                             std::to_string(kFormat) + ": run cgsr prune again)");
    options.channels = j.at("sampler").at("channels").get<std::vector<std::string>>();
    options.grid = j.at("sampler").at("grid").get<int>();
    options.width = j.at("sampler").at("width").get<int>();
    const auto& latency = j.at("latency");
    model.latency.lr_width = latency.at("lr_size").at(0).get<int64_t>();
    model.latency.lr_height = latency.at("lr_size").at(1).get<int64_t>();
    model.latency.median_ms = latency.at("median_ms").get<std::vector<double>>();
  } catch (const nlohmann::json::exception& e) {
    throw Error(where, std::string("malformed dynamic pruning data: ") + e.what());
  }
  try {
    options.render_channels();
  } catch (const Error& e) {
    throw e.within(where);
  }
  if (options.grid < 2 || options.width < 1) throw Error(where, "invalid dynamic sampler settings");
  model.pool = pool_from_json(j.at("pool"), model.network->spec(), where);
  if (model.latency.median_ms.size() != static_cast<size_t>(model.pool.size()))
    throw Error(where, "the latency table has " + std::to_string(model.latency.median_ms.size()) +
                           " entries, the pool " + std::to_string(model.pool.size()) + " patterns");
  for (double ms : model.latency.median_ms)
    if (!std::isfinite(ms) || ms < 0) throw Error(where, "the latency table holds an invalid time");
  {
    // The samplers' width comes from the metadata: bounded by what the file stores for them (as in
    // load_model, twice that plus 4 MiB, so near misses get the per-tensor message below).
    int64_t stored = 0;
    for (const auto& [name, value] : contents.tensors)
      if (name.rfind(kPrefix, 0) == 0) stored += value.numel();
    const ParameterBudget budget(2 * stored + (int64_t{1} << 20), where);
    model.samplers = DynamicSamplers(options, std::vector<int>{model.pool.size()});
  }
  auto params = model.samplers->named_parameters(/*recurse=*/true);
  std::set<std::string> seen;
  torch::NoGradGuard no_grad;
  for (const auto& [name, value] : contents.tensors) {
    if (name.rfind(kPrefix, 0) != 0) continue;
    const std::string key = name.substr(kPrefix.size());
    torch::Tensor* target = params.find(key);
    if (!target || target->sizes() != value.sizes())
      throw Error(where, "dynamic sampler tensor " + name + " " + shape_string(value) + " does not fit the samplers");
    require_finite(value, where + ": " + name);
    target->copy_(value);
    seen.insert(key);
  }
  for (const auto& p : params)
    if (!seen.count(p.key())) throw Error(where, "missing dynamic sampler tensor " + kPrefix + p.key());
  model.samplers->eval();
  return model;
}

}  // namespace cgsr
