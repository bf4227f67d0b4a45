#pragma once
// The dynamic pruning component of a network with a pattern pool (pattern_pool.h): it learns to
// choose a pattern per frame from the rendering information of that frame and the one before
// (the sampler, dynamic_sampler.h). fit_selector() measures, on every training frame, each
// pattern's PSNR loss against the widest on the full frame, and each pattern's cost: its latency
// predicted by the latency table (reproducible), its latency measured on this machine, or its
// MACs, as a fraction of the widest pattern's. A frame's cost of pattern k is
// loss_dB[k] + lambda * cost[k], with lambda the smallest price for which the frames' cheapest
// patterns meet the budget on average: easy frames (little geometry, little motion) take narrow
// patterns, hard ones wide. The sampler is fitted to the softmax of -cost / temperature per frame
// (cross-entropy): Eq. 4's image term plus a latency term, made a distribution so that frames
// where patterns cost about the same do not pull hard either way.

#include <map>
#include <memory>
#include <vector>

#include "core/config.h"
#include "core/enum_names.h"
#include "models/latency_table.h"
#include "models/sr_network.h"
#include "pruning/dynamic_sampler.h"
#include "pruning/pattern_networks.h"
#include "pruning/pattern_pool.h"
#include "render_data/dataset.h"

namespace cgsr {

// What a pattern costs when the choice is fitted. Predicted latency (the latency table) and MACs
// make the choice reproducible; latency measured on a shared machine can differ between two runs,
// and the choice with it.
enum class PatternCost { Macs, Latency, Predicted };
template <>
struct EnumNames<PatternCost> {
  static constexpr const char* kind = "pattern cost";
  static const std::vector<std::string>& names();  // macs, latency, predicted
};

struct SelectorOptions {
  PatternCost cost = PatternCost::Predicted;
  double budget = 0;             // mean per-frame cost, as a fraction of the widest pattern's (0: the pick's)
  double temperature = 0.02;     // dB: cost differences below this are near-ties
  int steps = 400;               // optimizer steps (full batch of the training frames)
  double learning_rate = 1e-2;
  int frames = 0;                // training frames measured and fitted on (0 = all)
  int latency_runs = 5;          // rounds of the latency table
};
config::Schema<SelectorOptions> selector_schema();

// What fit_selector measured and chose.
struct SelectorFit {
  std::vector<int> frames;
  std::vector<std::vector<double>> loss_db;  // [frame][pattern]: PSNR below the widest pattern's
  std::vector<double> latency_ms;            // [pattern], the latency table at the frames' size
  std::vector<double> cost;                  // [pattern], fraction of the widest pattern's
  double price = 0;                          // lambda: dB per widest-pattern cost
  std::vector<int> best;                     // [frame]: the pattern of least cost
  std::vector<int> chosen;                   // [frame]: the sampler's choice after fitting
  double agreement = 0;                      // fraction of frames where chosen == best
  double mean_cost = 0;                      // of the chosen patterns, against the widest
};
nlohmann::ordered_json to_json(const SelectorFit& fit);

class DynamicPruning {
 public:
  DynamicPruning(SRNetwork network, const Dataset& data, PatternPool pool, const SamplerOptions& options);

  // The sampler input of a frame (its rendering information and that of the frame before),
  // computed once per frame.
  torch::Tensor sampler_input(int frame);
  torch::Tensor sampler_inputs(const std::vector<int>& frames);

  // The choice fitted on `frames` with the network as it is now; `table` prices the patterns
  // when options.cost is predicted. A budget of 0 reads as 1 (the caller sets the pick's).
  SelectorFit fit_selector(const std::vector<int>& frames, const SelectorOptions& options,
                           const LatencyTable* table = nullptr);

  // [pattern]: frames among `frames` for which the sampler chooses it.
  std::vector<int64_t> selection_counts(const std::vector<int>& frames);

  SRNetwork network() const { return network_; }
  DynamicSamplers samplers() const { return samplers_; }
  const PatternPool& pool() const { return pool_; }

 private:
  SRNetwork network_;
  const Dataset& data_;
  PatternPool pool_;
  DynamicSamplers samplers_{nullptr};
  std::vector<RenderChannel> channels_;
  std::map<int, torch::Tensor> inputs_;
};

}  // namespace cgsr
