#pragma once
// A hybrid-pruned model: the statically pruned network plus its dynamic pruning components
// (the samplers and the pattern pool), in one model file.
//
// The file is an ordinary model file (models/model_file.h): the network's parameters under their
// usual names, the samplers' tensors under "extra.dpc.", and the pool and sampler settings in
// provenance.extra["dynamic_pruning"]. load_model() therefore reads the static network alone
// (export, bench and eval of the static part work unchanged); load_hybrid_model() reads all.

#include <filesystem>
#include <nlohmann/json.hpp>

#include "models/model_file.h"
#include "models/sr_network.h"
#include "pruning/dynamic_sampler.h"
#include "pruning/pattern_pool.h"

namespace cgsr {

struct HybridModel {
  SRNetwork network{nullptr};  // statically pruned; runs dense on its own
  PatternPool pool;            // in the network's channel indices
  DynamicSamplers samplers{nullptr};
  Provenance provenance;
};

void save_hybrid_model(const std::filesystem::path& path, const HybridModel& model);
HybridModel load_hybrid_model(const std::filesystem::path& path);

// Whether a model file's provenance describes dynamic pruning components.
bool is_hybrid_model(const Provenance& provenance);

}  // namespace cgsr
