// Weight inheritance: an identical child is bit-identical, shrunk children keep consistent
// shapes, the most important channels survive, and impossible children are clear errors.
#include <gtest/gtest.h>

#include "core/error.h"
#include "models/importance/block_importance.h"
#include "models/inherit.h"
#include "tests/models/model_cases.h"

using namespace cgsr;
using namespace cgsr::test;

namespace {
// Half of every group (at least 1), the first 2 blocks.
ArchSpec shrunk(const ArchSpec& parent) {
  ArchSpec child = parent;
  if (child.blocks > 2) child.blocks = 2;
  child.widths = GroupWidths();
  child = resolve_spec(child);  // the groups of the shallower network
  GroupWidths w;
  for (const auto& [group, width] : child.widths.entries()) w.set(group, std::max(1, parent.widths.at(group) / 2));
  child.widths = w;
  if (child.rit.enabled) {
    child.rit.width = std::max(1, parent.rit.width / 2);
    child.rit.channels = {"depth", "edge"};
  }
  return resolve_spec(child);
}

// Randomizes every parameter (including the zero-initialized RIT fusion) so copies are visible.
void randomize(SRNetworkImpl& net) {
  torch::NoGradGuard no_grad;
  for (auto& p : net.parameters()) p.normal_(0, 0.05);
}
}  // namespace

TEST(Inherit, IdenticalChildIsBitIdentical) {
  torch::manual_seed(6);
  for (const auto& c : all_backbone_cases()) {
    for (bool rit : {false, true}) {
      SCOPED_TRACE(case_name(c) + (rit ? " with rit" : ""));
      const ArchSpec spec =
          rit ? with_rit(spec_for(c), "hr_pooled", "concat", has_hr_features(c.backbone)) : spec_for(c);
      SRNetwork parent(spec);
      randomize(*parent);
      auto child = inherit(*parent, spec);
      EXPECT_TRUE(child.fresh.empty());
      EXPECT_EQ(child.network->spec(), parent->spec());
      const auto [color, info] = random_inputs(spec, 5, 4);
      torch::NoGradGuard no_grad;
      const auto a = parent->forward_train(color, info), b = child.network->forward_train(color, info);
      EXPECT_TRUE(torch::equal(a.image, b.image));
      if (rit && has_hr_features(c.backbone)) {
        EXPECT_TRUE(torch::equal(a.geometry, b.geometry));
      }
    }
  }
}

TEST(Inherit, ShrunkChildrenHaveConsistentShapes) {
  torch::manual_seed(7);
  for (const auto& c : all_backbone_cases()) {
    SCOPED_TRACE(case_name(c));
    const ArchSpec spec =
        with_rit(spec_for(c), "lr", c.scale == 3 ? "add" : "concat", has_hr_features(c.backbone));
    SRNetwork parent(spec);
    randomize(*parent);
    const ArchSpec child_spec = shrunk(spec);
    auto child = inherit(*parent, child_spec);
    EXPECT_TRUE(child.fresh.empty());
    EXPECT_EQ(child.network->spec(), child_spec);
    // kept is by parent group: SPAN's second child block is its parent's last (a fixed block).
    const auto in_parent = [&](const std::string& group) {
      const auto block = parse_block_group(group);
      if (!block || block->first == 0 || c.backbone != "span") return group;
      return block_group(spec.blocks - 1, block->second);
    };
    for (const auto& [group, width] : child_spec.widths.entries()) {
      ASSERT_TRUE(child.kept.count(in_parent(group))) << group;
      EXPECT_EQ(static_cast<int>(child.kept.at(in_parent(group)).size()), width);
    }
    const auto [color, info] = random_inputs(child_spec, 5, 4);
    torch::NoGradGuard no_grad;
    const auto out = child.network->forward_train(color, info);
    EXPECT_EQ(out.image.sizes().vec(), (std::vector<int64_t>{1, 3, 4 * c.scale, 5 * c.scale}));
    if (has_hr_features(c.backbone)) {
      EXPECT_EQ(out.geometry.size(1), 2);  // depth + edge
    }
  }
}

TEST(Inherit, CopiesTheMostImportantChannelsThroughTheGraph) {
  torch::manual_seed(8);
  SRNetwork parent(default_spec("edsr", 2));
  randomize(*parent);
  ArchSpec child_spec = parent->spec();
  child_spec.widths.set("block1_mid", 4);
  child_spec.widths.set("features", 60);
  child_spec.widths.set("up1", 16);
  {
    // Make block1_mid channels 7, 20, 33, 50 by far the most important.
    torch::NoGradGuard no_grad;
    auto w = parent->named_parameters()["backbone.blocks.1.conv1.weight"];
    for (int64_t c : {7, 20, 33, 50}) w[c].mul_(100);
  }
  auto child = inherit(*parent, child_spec);
  EXPECT_EQ(child.kept.at("block1_mid"), (std::vector<int64_t>{7, 20, 33, 50}));
  const auto pp = parent->named_parameters(), cp = child.network->named_parameters();
  const auto& feat = child.kept.at("features");
  ASSERT_EQ(feat.size(), 60u);
  const auto fi = torch::tensor(feat), mi = torch::tensor(std::vector<int64_t>{7, 20, 33, 50});
  // conv1: out = mid kept, in = features kept; conv2: out = features kept, in = mid kept.
  EXPECT_TRUE(torch::equal(cp["backbone.blocks.1.conv1.weight"],
                           pp["backbone.blocks.1.conv1.weight"].index_select(0, mi).index_select(1, fi)));
  EXPECT_TRUE(torch::equal(cp["backbone.blocks.1.conv2.weight"],
                           pp["backbone.blocks.1.conv2.weight"].index_select(0, fi).index_select(1, mi)));
  EXPECT_TRUE(torch::equal(cp["backbone.head.bias"], pp["backbone.head.bias"].index_select(0, fi)));
  // Pixel shuffle: kept channel c brings its 4 sub-channels 4c..4c+3.
  std::vector<int64_t> sub;
  for (int64_t c : child.kept.at("up1"))
    for (int64_t k = 0; k < 4; ++k) sub.push_back(4 * c + k);
  EXPECT_TRUE(torch::equal(cp["backbone.upsample1.weight"],
                           pp["backbone.upsample1.weight"].index_select(0, torch::tensor(sub)).index_select(1, fi)));
}

TEST(Inherit, DeadChannelsCanBeRemovedWithoutChangingTheOutput) {
  // Channels whose producing weights are zero are the least important and carry nothing, so
  // removing them leaves the output unchanged (up to summation order).
  torch::manual_seed(9);
  SRNetwork parent(default_spec("pan", 2));
  randomize(*parent);
  {
    torch::NoGradGuard no_grad;
    auto p = parent->named_parameters();
    for (int64_t c : {1, 5, 6}) {
      p["backbone.blocks.0.conv1_a.weight"][c].zero_();  // block0_a: producer of channel c
      p["backbone.blocks.0.pa_conv.k3.weight"][c].zero_();  // block0_att: k3 * sigmoid(k2) = 0
      p["backbone.blocks.0.pa_conv.k2.weight"][c].zero_();
      p["backbone.blocks.0.pa_conv.k2.bias"][c].zero_();
    }
  }
  ArchSpec child_spec = parent->spec();
  child_spec.widths.set("block0_a", 17);
  child_spec.widths.set("block0_att", 17);
  auto child = inherit(*parent, child_spec);
  EXPECT_EQ(child.kept.at("block0_a").size(), 17u);
  for (int64_t c : {1, 5, 6}) {
    const auto& kept = child.kept.at("block0_a");
    EXPECT_EQ(std::count(kept.begin(), kept.end(), c), 0);
  }
  const auto x = torch::rand({1, 3, 6, 6});
  torch::NoGradGuard no_grad;
  EXPECT_TRUE(torch::allclose(child.network->forward(x), parent->forward(x), 1e-5, 1e-5));
}

TEST(Inherit, ImpossibleChildrenAreErrors) {
  SRNetwork parent(default_spec("pan", 2));
  ArchSpec wider = parent->spec();
  wider.widths.set("features", 48);
  EXPECT_THROW(inherit(*parent, wider), Error);
  ArchSpec deeper = parent->spec();
  deeper.blocks = 17;
  EXPECT_THROW(inherit(*parent, deeper), Error);
  EXPECT_THROW(inherit(*parent, default_spec("pan", 3)), Error);
  EXPECT_THROW(inherit(*parent, default_spec("edsr", 2)), Error);
  SRNetwork cg(with_rit(default_spec("pan", 2), "lr", "concat"));
  ArchSpec other = cg->spec();
  other.rit.fusion = RitFusion::Add;
  try {
    inherit(*cg, other);
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("rit.fusion"), std::string::npos) << e.what();
  }
  ArchSpec more_channels = cg->spec();
  more_channels.rit.channels.push_back("motion");
  EXPECT_THROW(inherit(*cg, more_channels), Error);
}

TEST(Inherit, DroppingBlocksKeepsTheFirstOnes) {
  torch::manual_seed(10);
  SRNetwork parent(default_spec("edsr", 3));
  randomize(*parent);
  ArchSpec child_spec = parent->spec();
  child_spec.blocks = 4;
  child_spec.widths = GroupWidths();
  child_spec = resolve_spec(child_spec);
  auto child = inherit(*parent, child_spec);
  EXPECT_TRUE(torch::equal(child.network->named_parameters()["backbone.blocks.3.conv2.weight"],
                           parent->named_parameters()["backbone.blocks.3.conv2.weight"]));
  EXPECT_EQ(child.network->forward(torch::rand({1, 3, 4, 4})).size(2), 12);
}

// A block whose branch writes nothing into the stream is the least important, and a child that
// drops it (inheriting parent blocks 0 and 2) computes what the parent computes.
TEST(Inherit, DroppingTheLeastImportantBlockKeepsTheOutput) {
  torch::manual_seed(11);
  for (const std::string backbone : {"pan", "edsr"}) {
    SCOPED_TRACE(backbone);
    ArchSpec spec = default_spec(backbone, 2);
    spec.blocks = 3;
    spec.widths = GroupWidths();
    spec = resolve_spec(spec);
    SRNetwork parent(spec);
    randomize(*parent);
    {
      torch::NoGradGuard no_grad;
      const std::string out_conv = backbone == "pan" ? "backbone.blocks.1.conv3." : "backbone.blocks.1.conv2.";
      const auto params = parent->named_parameters();
      params[out_conv + "weight"].zero_();
      if (params.contains(out_conv + "bias")) params[out_conv + "bias"].zero_();
    }
    const auto importance = block_importance(*parent);
    ASSERT_EQ(importance.size(), 3u);
    EXPECT_EQ(importance[1], 0.0);
    EXPECT_GT(importance[0], 0.0);
    const auto order = block_drop_order(*parent);
    EXPECT_EQ(order.front(), 1);
    const auto kept = kept_blocks(order, 2);
    EXPECT_EQ(kept, (std::vector<int>{0, 2}));

    ArchSpec child_spec = spec;
    child_spec.blocks = 2;
    child_spec.widths = GroupWidths();
    child_spec = resolve_spec(child_spec);
    auto child = inherit(*parent, child_spec, {}, kept);
    EXPECT_TRUE(child.fresh.empty());
    const auto params = child.network->named_parameters();
    const auto parent_params = parent->named_parameters();
    for (const auto& p : params) {
      std::string in_parent = p.key();
      const std::string prefix = "backbone.blocks.1.";
      if (in_parent.rfind(prefix, 0) == 0) in_parent = "backbone.blocks.2." + in_parent.substr(prefix.size());
      EXPECT_TRUE(torch::equal(p.value(), parent_params[in_parent])) << p.key() << " <- " << in_parent;
    }
    torch::NoGradGuard no_grad;
    const auto color = torch::rand({1, 3, 6, 5});
    EXPECT_TRUE(torch::allclose(child.network->forward(color), parent->forward(color), 1e-5, 1e-6));
  }
}

TEST(Inherit, BlockChoicesMustBeAscendingParentBlocks) {
  SRNetwork parent(default_spec("edsr", 2));
  ArchSpec child_spec = parent->spec();
  child_spec.blocks = 2;
  child_spec.widths = GroupWidths();
  child_spec = resolve_spec(child_spec);
  EXPECT_THROW(inherit(*parent, child_spec, {}, {3, 1}), Error);
  EXPECT_THROW(inherit(*parent, child_spec, {}, {0, 1, 2}), Error);
  EXPECT_THROW(inherit(*parent, child_spec, {}, {0, parent->spec().blocks}), Error);
  EXPECT_NO_THROW(inherit(*parent, child_spec, {}, {1, 5}));
}
