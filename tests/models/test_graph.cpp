// The graph description is faithful: interpreting it reproduces forward() bit for bit, for
// every backbone with and without the RIT, and the builder rejects inconsistent layouts.
#include <gtest/gtest.h>

#include "core/error.h"
#include "models/graph.h"
#include "models/sr_network.h"
#include "tests/models/model_cases.h"

using namespace cgsr;
using namespace cgsr::test;

TEST(Graph, InterpreterReproducesEveryBackbone) {
  torch::manual_seed(1);
  for (const auto& c : all_backbone_cases()) {
    SCOPED_TRACE(case_name(c));
    expect_graph_matches_forward(spec_for(c));
  }
}

TEST(Graph, InterpreterReproducesRitVariants) {
  torch::manual_seed(2);
  for (const char* b : {"srcnn", "edsr", "pan"})
    for (const auto& source : rit_sources())
      for (const char* fusion : {"concat", "add"}) {
        SCOPED_TRACE(std::string(b) + " " + source + " " + fusion);
        expect_graph_matches_forward(with_rit(default_spec(b, 3), source, fusion, /*geometry=*/true));
      }
}

TEST(Graph, InferenceGraphExcludesTheGeometryHead) {
  SRNetwork net(with_rit(default_spec("pan", 2), "lr", "concat", true));
  const auto g = net->describe(false);
  EXPECT_FALSE(g.has_output("geometry"));
  EXPECT_TRUE(g.has_input("info"));
  for (const auto& op : g.ops) EXPECT_NE(op.name.rfind("geometry.", 0), 0u) << op.name;
  EXPECT_TRUE(net->describe(true).has_output("geometry"));
}

TEST(Graph, OpsHoldTheNetworksOwnTensors) {
  SRNetwork net(default_spec("pan", 2));
  const auto g = net->describe();
  const auto* op = g.find_op("backbone.blocks.3.pa_conv.k2");
  ASSERT_NE(op, nullptr);
  EXPECT_EQ(op->kind, graph::OpKind::Conv);
  EXPECT_EQ(op->weight.sizes().vec(), (std::vector<int64_t>{20, 20, 1, 1}));
  EXPECT_TRUE(op->weight.is_same(net->named_parameters()["backbone.blocks.3.pa_conv.k2.weight"]));
  // Layouts name the layer groups.
  EXPECT_EQ(graph::layout_string(g.values[op->output].layout), "block3_att(20)");
  const auto* up = g.find_op("backbone.upsample1");
  EXPECT_EQ(up, nullptr);  // PAN has no pixel shuffle
  SRNetwork edsr(default_spec("edsr", 3));
  const auto ge = edsr->describe();
  const auto* shuffle_conv = ge.find_op("backbone.upsample1");
  ASSERT_NE(shuffle_conv, nullptr);
  EXPECT_EQ(graph::layout_string(ge.values[shuffle_conv->output].layout), "up1(64x9)");
}

TEST(Graph, BuilderRejectsInconsistentResiduals) {
  graph::Builder g;
  const int a = g.input("a", graph::group_layout("features", 8), 1);
  const int b = g.input("b", graph::group_layout("block0_a", 8), 1);
  EXPECT_THROW(g.add(a, b), Error);
  EXPECT_THROW(g.mul(a, b), Error);
  const int c = g.input("c", graph::group_layout("up1", 4, 4), 1);
  EXPECT_THROW(g.pixel_shuffle(c, 3), Error);  // 4 sub-channels cannot shuffle by 3
  EXPECT_NO_THROW(g.pixel_shuffle(c, 2));
}

TEST(Graph, MissingInputIsAnError) {
  SRNetwork net(with_rit(default_spec("pan", 2)));
  EXPECT_THROW(graph::run(net->describe(), {{"color", torch::rand({1, 3, 4, 4})}}), Error);
}
