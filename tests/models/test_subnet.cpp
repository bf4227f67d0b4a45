// Subnets of a network (models/subnet.h) and the elastic space (models/elastic.h).

#include <gtest/gtest.h>
#include <torch/torch.h>

#include <random>
#include <set>

#include "core/error.h"
#include "models/elastic.h"
#include "models/importance/channel_importance.h"
#include "models/subnet.h"
#include "tests/models/model_cases.h"
#include "tests/support/elastic_options.h"

namespace cgsr {
namespace {

// PAN x2 with 4 blocks and a RIT on both branches, small enough to run every case quickly.
ArchSpec small_pan(int scale = 2) {
  ArchSpec s = default_spec("pan", scale);
  s.blocks = 4;
  s.widths = {};
  return test::with_rit(resolve_spec(s), "hr_unshuffle+hr_fuse");
}

// SPAN x2 with 3 blocks (the last one fixed) and a RIT on the LR grid.
ArchSpec small_span() {
  ArchSpec s = default_spec("span", 2);
  s.blocks = 3;
  s.widths = {};
  s = resolve_spec(s);
  for (const auto& [group, width] : s.widths.entries()) s.widths.set(group, 16);
  return test::with_rit(resolve_spec(s), "hr_unshuffle");
}

ArchSpec small_edsr() {
  ArchSpec s = default_spec("edsr", 2);
  s.blocks = 3;
  s.widths = {};
  s = resolve_spec(s);
  s.widths.set("features", 16);
  s.widths.set("up1", 16);
  for (int b = 0; b < 3; ++b) s.widths.set(block_group(b, "mid"), 16);
  return resolve_spec(s);
}

torch::Tensor run_image(const graph::Graph& g, const torch::Tensor& color, const torch::Tensor& info,
                        const graph::OpObserver& observer = {}) {
  torch::NoGradGuard no_grad;
  return graph::run(g, network_inputs(g, color, info), nullptr, observer).front().second;
}

// The full graph (branches unfolded) with the subnet's dropped channels zeroed after every op,
// and a skipped block's output replaced by its input: what the subnet must compute.
torch::Tensor masked_full(const SRNetworkImpl& net, const SubnetConfig& sub, const torch::Tensor& color,
                          const torch::Tensor& info) {
  const graph::Graph g = net.describe_branches();
  std::vector<int> block_of(g.ops.size(), -1);
  std::map<int, size_t> last_op;  // block -> its last op (its output)
  std::map<int, int> block_input;  // block -> the value it reads from before it
  for (size_t i = 0; i < g.ops.size(); ++i) {
    const std::string prefix = "backbone.blocks.";
    if (g.ops[i].name.rfind(prefix, 0) != 0) continue;
    block_of[i] = std::stoi(g.ops[i].name.substr(prefix.size()));
    last_op[block_of[i]] = i;
    if (!block_input.count(block_of[i])) block_input[block_of[i]] = g.ops[i].inputs[0];
  }
  std::map<int, torch::Tensor> seen;  // value -> what later ops read
  for (const auto& [name, v] : g.inputs) seen[v] = name == "color" ? color : info;
  const auto observer = [&](size_t op, const torch::Tensor& out) -> torch::Tensor {
    const int b = block_of[op];
    const bool skipped = b >= 0 && !std::binary_search(sub.blocks.begin(), sub.blocks.end(), b);
    if (skipped) return seen[g.ops[op].output] = last_op[b] == op ? seen.at(block_input[b]) : torch::zeros_like(out);
    auto masked = out.clone();
    int64_t offset = 0;
    for (const auto& s : g.values[g.ops[op].output].layout) {
      if (s.prunable) {
        const int64_t kept = subnet_width(sub, s.group, s.channels);
        masked.narrow(1, offset + kept * s.repeat, (s.channels - kept) * s.repeat).zero_();
      }
      offset += s.channels * s.repeat;
    }
    return seen[g.ops[op].output] = masked;
  };
  return run_image(g, color, info, observer);
}

TEST(Subnet, EqualsTheFullNetworkWithDroppedChannelsAndBlocksMasked) {
  for (const ArchSpec& spec : {small_pan(2), small_pan(4), small_edsr(), small_span()}) {
    SCOPED_TRACE(spec_summary(spec));
    const SRNetwork net = test::build_network(spec, 3);
    const ElasticSpace space(spec, test::elastic_options(4, 0.25, 1));
    std::mt19937_64 rng(7);
    const auto [color, info] = test::random_inputs(spec, 9, 7);
    for (int i = 0; i < 6; ++i) {
      const SubnetConfig sub = i == 0 ? space.full() : i == 1 ? space.smallest() : space.sample(rng);
      SCOPED_TRACE(subnet_key(sub));
      const auto narrow = run_image(subnet_graph(*net, sub), color, info);
      const auto masked = masked_full(*net, sub, color, info);
      // Relative to the output's size: SPAN scales its input by 255 and a random one keeps that.
      EXPECT_LT((narrow - masked).abs().max().item<double>(), 1e-5 * std::max(1.0, masked.abs().max().item<double>()));
    }
  }
}

TEST(Subnet, SkippingABlockIsNotTheFullNetwork) {
  const ArchSpec spec = small_pan();
  const SRNetwork net = test::build_network(spec, 1);
  SubnetConfig sub = full_subnet(spec);
  const auto [color, info] = test::random_inputs(spec, 8, 8);
  const auto full = run_image(subnet_graph(*net, sub), color, info);
  EXPECT_TRUE(torch::equal(full, run_image(net->describe(false), color, info)));
  sub.blocks = {0, 1, 3};
  EXPECT_GT((run_image(subnet_graph(*net, sub), color, info) - full).abs().max().item<double>(), 1e-6);
}

TEST(Subnet, LeadingChannelsAreViewsOfTheNetworksWeights) {
  const ArchSpec spec = small_pan();
  const SRNetwork net = test::build_network(spec, 2);
  SubnetConfig sub = full_subnet(spec);
  sub.widths["block1_a"] = 8;
  sub.widths["up1"] = 12;
  sub.widths["rit"] = 8;
  const graph::Graph g = subnet_graph(*net, sub);
  std::set<const void*> storages;
  for (const auto& p : net->parameters()) storages.insert(p.storage().data());
  int views = 0, copies = 0;
  for (const auto& op : g.ops) {
    if (op.kind != graph::OpKind::Conv || !op.trainable) continue;
    if (storages.count(op.weight.storage().data())) ++views; else ++copies;
  }
  // Every conv is a view but those reading a concatenation of narrowed groups (block 1's conv3).
  EXPECT_EQ(copies, 1);
  EXPECT_GT(views, 20);
  const auto* k1 = g.find_op("backbone.blocks.1.k1");
  ASSERT_NE(k1, nullptr);
  EXPECT_EQ(k1->weight.size(0), 20);
  EXPECT_EQ(k1->weight.size(1), 8);
}

TEST(Subnet, MaterializedSubnetComputesTheSameAsItsGraph) {
  for (const ArchSpec& spec : {small_pan(), small_span()}) {
    SCOPED_TRACE(spec_summary(spec));
    const SRNetwork net = test::build_network(spec, 4);
    const ElasticSpace space(spec, test::elastic_options(4, 0.25, 2));
    std::mt19937_64 rng(11);
    const auto [color, info] = test::random_inputs(spec, 10, 6);
    for (int i = 0; i < 4; ++i) {
      const SubnetConfig sub = space.sample(rng);
      SRNetwork small = materialize_subnet(*net, sub);
      EXPECT_EQ(small->spec().blocks, static_cast<int>(sub.blocks.size()));
      small->eval();
      torch::NoGradGuard no_grad;
      const auto a = small->forward(color, info);
      const auto b = run_image(subnet_graph(*net, sub), color, info);
      EXPECT_LT((a - b).abs().max().item<double>(), 1e-5 * std::max(1.0, b.abs().max().item<double>()))
          << subnet_key(sub);
    }
  }
}

TEST(ElasticSpace, EverySubnetKeepsTheBackbonesFixedBlocks) {
  const ArchSpec spec = small_span();  // conv_cat reads SPAN's first block and inside its last
  const ElasticSpace space(spec, test::elastic_options(4, 0.25, 1));
  EXPECT_EQ(space.min_blocks(), 2);
  EXPECT_EQ(space.smallest().blocks, (std::vector<int>{0, 2}));
  std::mt19937_64 rng(5);
  int skipped = 0;
  for (int i = 0; i < 20; ++i) {
    const SubnetConfig sub = space.sample(rng);
    EXPECT_TRUE(std::binary_search(sub.blocks.begin(), sub.blocks.end(), 0)) << subnet_key(sub);
    EXPECT_TRUE(std::binary_search(sub.blocks.begin(), sub.blocks.end(), 2)) << subnet_key(sub);
    EXPECT_TRUE(space.contains(sub));
    skipped += sub.blocks.size() == 2;
  }
  EXPECT_GT(skipped, 0);
  SubnetConfig without_last = space.full();
  without_last.blocks = {0, 1};
  EXPECT_FALSE(space.contains(without_last));
  EXPECT_EQ(space.repair(without_last).blocks, (std::vector<int>{0, 1, 2}));
  const SRNetwork net = test::build_network(spec, 1);
  EXPECT_THROW(subnet_graph(*net, without_last), Error);
}

TEST(Subnet, DifferentiableGraphTrainsTheKeptWeightsOnly) {
  const ArchSpec spec = small_pan();
  SRNetwork net = test::build_network(spec, 5);
  SubnetConfig sub = full_subnet(spec);
  sub.blocks = {0, 2, 3};
  sub.widths["block0_a"] = 4;
  const graph::Graph g = subnet_graph(*net, sub, false, /*differentiable=*/true);
  const auto [color, info] = test::random_inputs(spec, 6, 6);
  graph::run(g, network_inputs(g, color, info)).front().second.square().mean().backward();
  const auto params = net->named_parameters();
  const auto& k1 = params["backbone.blocks.0.k1.weight"].grad();  // [a_out, a, 3, 3]
  ASSERT_TRUE(k1.defined());
  EXPECT_GT(k1.narrow(1, 0, 4).abs().sum().item<double>(), 0);
  EXPECT_EQ(k1.narrow(1, 4, 16).abs().sum().item<double>(), 0);
  const auto& skipped = params["backbone.blocks.1.k1.weight"].grad();
  EXPECT_TRUE(!skipped.defined() || skipped.abs().sum().item<double>() == 0);
}

TEST(Subnet, ProblemsAndJsonRoundTrip) {
  const ArchSpec spec = small_pan();
  SubnetConfig sub = full_subnet(spec);
  EXPECT_TRUE(subnet_problems(spec, sub).empty());
  EXPECT_EQ(subnet_from_json(to_json(sub), "test"), sub);
  sub.blocks = {2, 1};
  sub.widths["nope"] = 3;
  sub.widths["features"] = 41;
  EXPECT_EQ(subnet_problems(spec, sub).size(), 3u);
  EXPECT_THROW(subnet_graph(*test::build_network(spec, 0), sub), Error);
  EXPECT_THROW(subnet_from_json(nlohmann::ordered_json{{"blocks", "x"}}, "test"), Error);
}

TEST(ElasticSpace, ChoicesSamplesAndRepair) {
  const ArchSpec spec = small_pan();
  const ElasticSpace space(spec, test::elastic_options(4, 0.5, 2), {3, 1, 0, 2});
  for (const auto& gene : space.genes()) {
    EXPECT_EQ(gene.choices.back(), gene.full) << gene.group;
    EXPECT_GE(gene.choices.front() * 2, gene.full) << gene.group;
    for (size_t i = 0; i + 1 < gene.choices.size(); ++i) EXPECT_EQ(gene.choices[i] % 4, 0) << gene.group;
  }
  EXPECT_EQ(space.smallest().blocks, (std::vector<int>{1, 3}));  // the two most important
  EXPECT_TRUE(space.contains(space.full()));
  EXPECT_TRUE(space.contains(space.smallest()));
  // Limits at 0 give the full network; a limit opens the range progressively.
  EXPECT_EQ(space.smallest(ShrinkLimits{0, 0}), space.full());
  std::mt19937_64 rng(1);
  for (int i = 0; i < 50; ++i) {
    const auto sub = space.sample(rng);
    EXPECT_TRUE(space.contains(sub)) << subnet_key(sub);
    EXPECT_EQ(space.sample(rng, ShrinkLimits{0, 0}), space.full());
  }
  SubnetConfig odd = space.full();
  odd.widths["features"] = 27;
  odd.blocks = {0};
  const auto fixed = space.repair(odd);
  EXPECT_TRUE(space.contains(fixed));
  EXPECT_EQ(fixed.widths.at("features"), 28);
  EXPECT_EQ(fixed.blocks, (std::vector<int>{0, 3}));
}

TEST(ElasticSpace, PrecisionIsAGeneWhenTheOptionsListSeveral) {
  ElasticOptions options = test::elastic_options(4, 0.5, 2);
  options.precisions = {Precision::Fp32, Precision::Int8};
  const ElasticSpace space(small_pan(), options);
  EXPECT_EQ(space.full().precision, Precision::Fp32);
  EXPECT_EQ(space.smallest().precision, Precision::Fp32);
  std::mt19937_64 rng(2);
  std::set<Precision> drawn;
  for (int i = 0; i < 40; ++i) {
    const auto sub = space.sample_candidate(rng);
    EXPECT_TRUE(space.contains(sub)) << subnet_key(sub);
    drawn.insert(sub.precision);
  }
  EXPECT_EQ(drawn.size(), 2u);
  // Training draws the same subnets as without the option: structure only, in float32.
  const ElasticSpace plain(small_pan(), test::elastic_options(4, 0.5, 2));
  std::mt19937_64 a(3), b(3);
  for (int i = 0; i < 10; ++i) EXPECT_EQ(space.sample(a), plain.sample(b));
  // A precision the space does not list is outside it; repair gives the first listed.
  SubnetConfig bf16 = space.full();
  bf16.precision = Precision::Bf16;
  EXPECT_FALSE(space.contains(bf16));
  EXPECT_EQ(space.repair(bf16).precision, Precision::Fp32);
  // Keys and files name a reduced precision; float32 ones read as before.
  SubnetConfig int8 = space.full();
  int8.precision = Precision::Int8;
  EXPECT_EQ(subnet_key(int8), subnet_key(space.full()) + "|int8");
  EXPECT_FALSE(to_json(space.full()).contains("precision"));
  EXPECT_EQ(subnet_from_json(to_json(int8), "test"), int8);
  EXPECT_NE(int8, space.full());
  // The option starts with float32 and lists each format once.
  const auto parse = [](const std::string& yaml) {
    return config::parse_document(config::Document::parse(yaml, "elastic.yaml"), elastic_options_schema());
  };
  EXPECT_EQ(parse("precisions: [fp32, bf16, int8]\n").precisions.size(), 3u);
  EXPECT_THROW(parse("precisions: [int8]\n"), Error);
  EXPECT_THROW(parse("precisions: [fp32, int8, int8]\n"), Error);
  // Metadata written before the option existed reads as float32 only.
  nlohmann::ordered_json old = ElasticOptions{};
  old.erase("precisions");
  EXPECT_EQ(old.get<ElasticOptions>().precisions, std::vector<Precision>{Precision::Fp32});
}

TEST(ElasticSpace, MakeElasticSortsChannelsAndKeepsTheOutput) {
  const ArchSpec spec = small_pan();
  SRNetwork net = test::build_network(spec, 6);
  ElasticNetwork elastic = make_elastic(*net, ElasticOptions{});
  const auto [color, info] = test::random_inputs(spec, 8, 8);
  torch::NoGradGuard no_grad;
  EXPECT_LT((elastic.network->forward(color, info) - net->forward(color, info)).abs().max().item<double>(), 1e-5);
  for (const auto& [group, scores] : channel_importance(*elastic.network)) {
    const auto s = scores.detach();
    for (int64_t i = 0; i + 1 < s.numel(); ++i) EXPECT_GE(s[i].item<double>(), s[i + 1].item<double>()) << group;
  }
  const auto back = elastic_space_from(spec, {{"elastic", elastic_metadata(elastic.space)}}, "test");
  EXPECT_EQ(back.block_order(), elastic.space.block_order());
  EXPECT_THROW(elastic_space_from(spec, nlohmann::ordered_json::object(), "test"), Error);
}

}  // namespace
}  // namespace cgsr
