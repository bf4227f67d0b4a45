// Fitting the per-frame choice on rendered frames: the cheapest patterns at the fitted price meet
// the budget on average, whether patterns are priced by MACs or by the latency table.
#include <gtest/gtest.h>

#include <algorithm>

#include "core/error.h"
#include "models/latency_table.h"
#include "pruning/dynamic_pruning.h"
#include "tests/pruning/pruning_cases.h"
#include "tests/support/elastic_options.h"
#include "tests/support/tiny_data.h"

using namespace cgsr;
using namespace cgsr::test;

TEST(DynamicPruning, TheFittedChoiceMeetsTheBudgetOnAverage) {
  torch::manual_seed(21);
  const Dataset data = Dataset::open(tiny_data());
  SRNetwork net(small_spec("pan", 2, 2, 6, 8));
  randomize(*net);
  net->eval();
  const PatternPool pool = random_pool(*net, 3, 4);
  SamplerOptions sampler;
  sampler.grid = 4;
  sampler.width = 2;
  DynamicPruning dynamic(net, data, pool, sampler);
  const auto frames = data.frames(Split::Train);
  LatencyTableOptions latency;
  latency.runs = 1;
  latency.calibration_subnets = 2;
  latency.check_subnets = 0;
  latency.subnet_runs = 1;
  const ElasticSpace space(net->spec(), test::elastic_options(2, 0.25, 1));
  const LatencyTable table = measure_latency_table(*net, space, 32, 24, latency);
  for (const PatternCost cost : {PatternCost::Macs, PatternCost::Predicted}) {
    SCOPED_TRACE(enum_name(cost));
    SelectorOptions options;
    options.cost = cost;
    options.budget = 1;
    options.steps = 20;
    const auto costs = dynamic.fit_selector(frames, options, &table).cost;
    // Halfway between the narrowest pattern's cost and the widest's: a budget that binds.
    options.budget = 0.5 * (1 + *std::min_element(costs.begin(), costs.end()));
    const SelectorFit fit = dynamic.fit_selector(frames, options, &table);
    ASSERT_EQ(fit.cost.size(), 3u);
    EXPECT_DOUBLE_EQ(fit.cost[0], 1.0);
    double mean = 0;
    for (int k : fit.best) mean += fit.cost[k] / static_cast<double>(fit.best.size());
    EXPECT_LE(mean, options.budget + 1e-9);
    EXPECT_EQ(fit.chosen.size(), frames.size());
  }
  SelectorOptions predicted;
  predicted.cost = PatternCost::Predicted;
  EXPECT_THROW(dynamic.fit_selector(frames, predicted, nullptr), Error);
}
