#pragma once
// A hybrid-pruned model: the statically pruned network plus its dynamic pruning component (the
// sampler and the pool of patterns, subnets of the network) and the patterns' measured latency,
// in one model file.
//
// The file is an ordinary model file (models/model_file.h): the network's parameters under their
// usual names, the samplers' tensors under "extra.dpc.", and the pool and sampler settings in
// provenance.extra["dynamic_pruning"] (format 3: the patterns as subnets; formats 1 and 2, nested
// channel patterns, are no longer read). load_model() therefore reads the static network alone
// (export, bench and eval of the static part work unchanged); load_hybrid_model() reads all.

#include <filesystem>
#include <nlohmann/json.hpp>

#include "models/model_file.h"
#include "models/sr_network.h"
#include "pruning/dynamic_sampler.h"
#include "pruning/pattern_pool.h"

namespace cgsr {

// Each pattern's latency on the machine that pruned the model, at one input size.
struct PatternLatency {
  int64_t lr_width = 0, lr_height = 0;
  std::vector<double> median_ms;  // [pattern]
};

struct HybridModel {
  SRNetwork network{nullptr};  // statically pruned (the union of the patterns); runs dense on its own
  PatternPool pool;            // the patterns, subnets of the network, widest first
  DynamicSamplers samplers{nullptr};  // one head scoring the pool's patterns
  PatternLatency latency;
  Provenance provenance;
};

void save_hybrid_model(const std::filesystem::path& path, const HybridModel& model);
HybridModel load_hybrid_model(const std::filesystem::path& path);

// Whether a model file's provenance describes dynamic pruning components.
bool is_hybrid_model(const Provenance& provenance);

}  // namespace cgsr
