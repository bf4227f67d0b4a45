#include "pruning/dynamic_pruning.h"

#include <spdlog/spdlog.h>
#include <torch/torch.h>

#include <cmath>
#include <numeric>

#include "core/error.h"
#include "core/metrics.h"
#include "core/progress.h"
#include "render_data/patch_sampler.h"

namespace cgsr {

const std::vector<std::string>& EnumNames<PatternCost>::names() {
  static const std::vector<std::string> n{"macs", "latency", "predicted"};
  return n;
}

config::Schema<SelectorOptions> selector_schema() {
  config::Schema<SelectorOptions> s;
  s.field("cost", &SelectorOptions::cost,
          "what a pattern costs: predicted (the latency table's, reproducible), latency (measured here) or macs");
  s.field("budget", &SelectorOptions::budget,
          "mean per-frame cost the choices aim at, as a fraction of the widest pattern's (0: the pick's)")
      .check([](double v) { return v >= 0 && v <= 1; }, "must be in [0, 1]");
  s.field("temperature", &SelectorOptions::temperature,
          "dB: cost differences below this count as near-ties when the sampler is fitted")
      .range(1e-6, 100.0);
  s.field("steps", &SelectorOptions::steps, "optimizer steps fitting the sampler").range(0, 1000000);
  s.field("learning_rate", &SelectorOptions::learning_rate, "sampler learning rate").range(1e-9, 10.0);
  s.field("frames", &SelectorOptions::frames, "training frames measured and fitted on (0 = all)").at_least(0);
  s.field("latency_runs", &SelectorOptions::latency_runs, "rounds timing every pattern for the latency table")
      .range(1, 1000);
  return s;
}

nlohmann::ordered_json to_json(const SelectorFit& fit) {
  nlohmann::ordered_json j;
  j["frames"] = fit.frames;
  j["latency_ms"] = fit.latency_ms;
  j["cost"] = fit.cost;
  j["price_db"] = fit.price;
  j["best"] = fit.best;
  j["chosen"] = fit.chosen;
  j["agreement"] = fit.agreement;
  j["mean_cost"] = fit.mean_cost;
  auto mean_loss = nlohmann::ordered_json::array();
  for (size_t k = 0; k < fit.latency_ms.size(); ++k) {
    double sum = 0;
    for (const auto& f : fit.loss_db) sum += f[k];
    mean_loss.push_back(fit.loss_db.empty() ? 0.0 : sum / static_cast<double>(fit.loss_db.size()));
  }
  j["mean_loss_db"] = mean_loss;
  return j;
}

DynamicPruning::DynamicPruning(SRNetwork network, const Dataset& data, PatternPool pool, const SamplerOptions& options)
    : network_(std::move(network)), data_(data), pool_(std::move(pool)) {
  channels_ = options.render_channels();
  for (auto c : channels_)
    if (std::find(data.info().channels.begin(), data.info().channels.end(), c) == data.info().channels.end())
      throw Error(data.info().root.string(), "the dynamic sampler reads rendering channel '" + channel_name(c) +
                                                 "', which the data set does not have");
  samplers_ = DynamicSamplers(options, std::vector<int>{pool_.size()});
}

torch::Tensor DynamicPruning::sampler_input(int frame) {
  auto it = inputs_.find(frame);
  if (it != inputs_.end()) return it->second;
  const int scale = network_->spec().scale;
  // The sampler sees depth as the network does: at inference both read the one batch.
  const DepthEncoding depth = network_->depth_encoding();
  const auto info = frame_batch(data_, frame, scale, channels_, depth).lr_info;
  torch::Tensor previous;
  if (data_.has_previous(frame)) previous = frame_batch(data_, frame - 1, scale, channels_, depth).lr_info;
  const auto input = cgsr::sampler_input(info, previous, channels_, samplers_->options().grid);
  return inputs_.emplace(frame, input).first->second;
}

torch::Tensor DynamicPruning::sampler_inputs(const std::vector<int>& frames) {
  std::vector<torch::Tensor> parts;
  for (int f : frames) parts.push_back(sampler_input(f));
  return torch::cat(parts, 0);
}

namespace {
// Per frame, the pattern of least loss_db + price * latency fraction (ties: the wider one).
std::vector<int> cheapest(const std::vector<std::vector<double>>& loss_db, const std::vector<double>& fraction,
                          double price) {
  std::vector<int> best;
  for (const auto& f : loss_db) {
    int b = 0;
    for (int k = 1; k < static_cast<int>(f.size()); ++k)
      if (f[k] + price * fraction[k] < f[b] + price * fraction[b]) b = k;
    best.push_back(b);
  }
  return best;
}

double mean_fraction(const std::vector<int>& choice, const std::vector<double>& fraction) {
  double sum = 0;
  for (int k : choice) sum += fraction[k];
  return choice.empty() ? 1.0 : sum / static_cast<double>(choice.size());
}
}  // namespace

SelectorFit DynamicPruning::fit_selector(const std::vector<int>& frames, const SelectorOptions& options,
                                         const LatencyTable* table) {
  if (frames.empty()) throw Error("dynamic pruning", "no frames to fit the pattern choice on");
  SelectorFit fit;
  fit.frames = frames;
  const int scale = network_->spec().scale;
  const int patterns = pool_.size();
  network_->eval();
  PatternNetworks networks(*network_, pool_);

  // The latency table and the costs, on the first frame.
  {
    const Batch b = frame_batch(data_, frames.front(), scale, network_->input_channels(), network_->depth_encoding());
    const auto info = network_->info_input(b);
    for (const auto& l : networks.measure_latency(b.lr_color, info, options.latency_runs))
      fit.latency_ms.push_back(l.median_ms);
    std::vector<double> macs, predicted;
    for (int k = 0; k < patterns; ++k) {
      macs.push_back(static_cast<double>(networks.cost(k, b.lr_color.size(3), b.lr_color.size(2)).macs));
      if (options.cost == PatternCost::Predicted) {
        if (!table) throw Error("dynamic pruning", "selector.cost is predicted, but there is no latency table");
        predicted.push_back(table->predict(networks.graph(k)));
      }
    }
    const auto& measure = options.cost == PatternCost::Macs        ? macs
                          : options.cost == PatternCost::Predicted ? predicted
                                                                   : fit.latency_ms;
    for (double v : measure) fit.cost.push_back(v / measure.front());
  }
  const std::vector<double>& fraction = fit.cost;

  // Each pattern's PSNR on every frame.
  {
    Progress progress("pattern losses", static_cast<int64_t>(frames.size()));
    for (int f : frames) {
      const Batch b = frame_batch(data_, f, scale, network_->input_channels(), network_->depth_encoding());
      const auto info = network_->info_input(b);
      std::vector<double> psnr_k;
      for (int k = 0; k < patterns; ++k) {
        const auto sr = networks.run(k, b.lr_color, info);
        if (!torch::isfinite(sr).all().item<bool>())
          throw Error("dynamic pruning: frame " + std::to_string(f), "pattern " + std::to_string(k) +
                                                                         " produced NaN or infinite values");
        psnr_k.push_back(psnr(sr.clamp(0.0, 1.0), b.hr_color).item<double>());
      }
      std::vector<double> loss;
      for (double p : psnr_k) loss.push_back(std::isinf(psnr_k[0]) && std::isinf(p) ? 0.0 : psnr_k[0] - p);
      fit.loss_db.push_back(loss);
      progress.advance();
    }
    progress.finish();
  }

  // The price of latency that meets the budget on average.
  double low = 0, high = 1;
  const double budget = options.budget > 0 ? options.budget : 1.0;
  if (mean_fraction(cheapest(fit.loss_db, fraction, 0), fraction) <= budget) {
    high = 0;
  } else {
    while (mean_fraction(cheapest(fit.loss_db, fraction, high), fraction) > budget && high < 1e6)
      high *= 2;
    for (int i = 0; i < 60; ++i) {
      const double mid = 0.5 * (low + high);
      (mean_fraction(cheapest(fit.loss_db, fraction, mid), fraction) > budget ? low : high) = mid;
    }
  }
  fit.price = high;
  fit.best = cheapest(fit.loss_db, fraction, fit.price);

  // Fit the sampler to the per-frame cost distributions.
  const int64_t n = static_cast<int64_t>(frames.size());
  auto cost = torch::empty({n, patterns}, torch::kFloat);
  for (int64_t i = 0; i < n; ++i)
    for (int k = 0; k < patterns; ++k)
      cost[i][k] = static_cast<float>(fit.loss_db[i][k] + fit.price * fraction[k]);
  const auto target = torch::softmax(-cost / options.temperature, 1);
  const auto input = sampler_inputs(frames);
  samplers_->train();
  torch::optim::Adam optimizer(samplers_->parameters(), torch::optim::AdamOptions(options.learning_rate));
  for (int step = 0; step < options.steps; ++step) {
    const auto scores = samplers_->forward(input).select(1, 0);  // [N, K]
    const auto loss = -(target * torch::log_softmax(scores, 1)).sum(1).mean();
    optimizer.zero_grad();
    loss.backward();
    optimizer.step();
  }
  samplers_->eval();
  int agree = 0;
  for (int64_t i = 0; i < n; ++i) {
    fit.chosen.push_back(samplers_->choose(input.slice(0, i, i + 1)).front().front());
    agree += fit.chosen.back() == fit.best[i];
  }
  fit.agreement = static_cast<double>(agree) / static_cast<double>(n);
  fit.mean_cost = mean_fraction(fit.chosen, fraction);
  return fit;
}

std::vector<int64_t> DynamicPruning::selection_counts(const std::vector<int>& frames) {
  std::vector<int64_t> counts(pool_.size(), 0);
  samplers_->eval();
  for (int f : frames) ++counts[samplers_->choose(sampler_input(f)).front().front()];
  return counts;
}

}  // namespace cgsr
