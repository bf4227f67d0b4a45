// The graph description is faithful: interpreting it reproduces forward() bit for bit, for
// every backbone with and without the RIT, and the builder rejects inconsistent layouts.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>

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
  for (const char* b : {"srcnn", "edsr", "pan", "srpo"})
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

// ---- the Sample op -----------------------------------------------------------------------------

namespace {

// The Sample op written out independently, in double: output pixel (i, j) reads the source at
// x = (j + 0.5) / r - 0.5 + dx, y likewise; nearest rounds half to even and clamps the index,
// bilinear clamps the position to [0, size - 1] and interpolates, bicubic (a = -0.75) weighs the
// 4x4 pixels around the unclamped position, each index clamped.
torch::Tensor reference_sample(const torch::Tensor& source, const torch::Tensor& offsets, int64_t r,
                               graph::ResizeMode mode) {
  const auto s = source.to(torch::kDouble).contiguous();
  const auto o = offsets.to(torch::kDouble).contiguous();
  const int64_t n = s.size(0), c = s.size(1), h = s.size(2), w = s.size(3), oh = o.size(2), ow = o.size(3);
  auto out = torch::zeros({n, c, oh, ow}, torch::kDouble);
  const auto sa = s.accessor<double, 4>();
  const auto oa = o.accessor<double, 4>();
  auto ya = out.accessor<double, 4>();
  const auto cubic = [](double t) {
    const double a = -0.75;
    const auto near = [&](double d) { return ((a + 2) * d - (a + 3)) * d * d + 1; };
    const auto far = [&](double d) { return ((a * d - 5 * a) * d + 8 * a) * d - 4 * a; };
    return std::array<double, 4>{far(t + 1), near(t), near(1 - t), far(2 - t)};
  };
  const auto at = [&](int64_t b, int64_t ch, int64_t yi, int64_t xi) {
    return sa[b][ch][std::clamp<int64_t>(yi, 0, h - 1)][std::clamp<int64_t>(xi, 0, w - 1)];
  };
  for (int64_t b = 0; b < n; ++b)
    for (int64_t i = 0; i < oh; ++i)
      for (int64_t j = 0; j < ow; ++j) {
        const double x = (j + 0.5) / r - 0.5 + oa[b][0][i][j], y = (i + 0.5) / r - 0.5 + oa[b][1][i][j];
        for (int64_t ch = 0; ch < c; ++ch) {
          if (mode == graph::ResizeMode::Nearest) {
            ya[b][ch][i][j] = at(b, ch, static_cast<int64_t>(std::nearbyint(y)), static_cast<int64_t>(std::nearbyint(x)));
          } else if (mode == graph::ResizeMode::Bilinear) {
            const double cx = std::clamp(x, 0.0, static_cast<double>(w - 1)), cy = std::clamp(y, 0.0, static_cast<double>(h - 1));
            const auto x0 = static_cast<int64_t>(std::floor(cx)), y0 = static_cast<int64_t>(std::floor(cy));
            const double fx = cx - x0, fy = cy - y0;
            ya[b][ch][i][j] = (1 - fy) * ((1 - fx) * at(b, ch, y0, x0) + fx * at(b, ch, y0, x0 + 1)) +
                              fy * ((1 - fx) * at(b, ch, y0 + 1, x0) + fx * at(b, ch, y0 + 1, x0 + 1));
          } else {
            const double x0 = std::floor(x), y0 = std::floor(y);
            const auto wx = cubic(x - x0), wy = cubic(y - y0);
            double sum = 0;
            for (int64_t u = 0; u < 4; ++u)
              for (int64_t v = 0; v < 4; ++v)
                sum += wy[u] * wx[v] * at(b, ch, static_cast<int64_t>(y0) - 1 + u, static_cast<int64_t>(x0) - 1 + v);
            ya[b][ch][i][j] = sum;
          }
        }
      }
  return out.to(torch::kFloat);
}

// torch's grid_sampler with the grid written the textbook way (normalized in double).
torch::Tensor torch_grid_sample(const torch::Tensor& source, const torch::Tensor& offsets, int64_t r, bool nearest) {
  const int64_t h = source.size(2), w = source.size(3), oh = offsets.size(2), ow = offsets.size(3);
  const auto o = offsets.to(torch::kDouble);
  const auto j = torch::arange(ow, torch::kDouble).view({1, 1, ow});
  const auto i = torch::arange(oh, torch::kDouble).view({1, oh, 1});
  const auto x = (j + 0.5) / r - 0.5 + o.select(1, 0);
  const auto y = (i + 0.5) / r - 0.5 + o.select(1, 1);
  const auto grid = torch::stack({(2 * x + 1) / w - 1, (2 * y + 1) / h - 1}, -1).to(torch::kFloat);
  return torch::grid_sampler(source, grid, nearest ? 1 : 0, /*border*/ 1, /*align_corners=*/false);
}

}  // namespace

// Bicubic reads 4x4 pixels, each index clamped: at whole-pixel offsets the pixel itself, between
// them an overshooting interpolation (a = -0.75), far outside a border pixel.
TEST(SampleOp, BicubicMatchesTheDefinition) {
  torch::manual_seed(43);
  for (int64_t r : {1, 2}) {
    SCOPED_TRACE("ratio " + std::to_string(r));
    const auto source = torch::rand({2, 3, 6, 7});
    auto offsets = torch::randn({2, 2, 6 * r, 7 * r}) * 2;
    offsets.slice(2, 0, 2) *= 40;
    const auto got = graph::apply_sample(source, offsets, r, graph::ResizeMode::Bicubic);
    EXPECT_TRUE(torch::allclose(got, reference_sample(source, offsets, r, graph::ResizeMode::Bicubic), 1e-5, 1e-5));
  }
  const auto source = torch::rand({1, 1, 6, 7});
  const auto shifted = graph::apply_sample(source, torch::ones({1, 2, 6, 7}), 1, graph::ResizeMode::Bicubic);
  EXPECT_TRUE(torch::allclose(shifted.slice(2, 0, 5).slice(3, 0, 6), source.slice(2, 1, 6).slice(3, 1, 7), 1e-6, 1e-6));
}

TEST(SampleOp, MatchesGridSamplerAndTheDefinitionOnRandomAndFarOutsideOffsets) {
  torch::manual_seed(41);
  for (int64_t r : {1, 2, 3, 4}) {
    SCOPED_TRACE("ratio " + std::to_string(r));
    const auto source = torch::rand({2, 3, 5, 7});
    auto offsets = torch::randn({2, 2, 5 * r, 7 * r}) * 2;
    offsets.slice(2, 0, 2) *= 40;  // far outside the image: the border clamps
    const auto nearest = graph::apply_sample(source, offsets, r, graph::ResizeMode::Nearest);
    const auto bilinear = graph::apply_sample(source, offsets, r, graph::ResizeMode::Bilinear);
    EXPECT_EQ(nearest.sizes().vec(), (std::vector<int64_t>{2, 3, 5 * r, 7 * r}));
    EXPECT_TRUE(torch::equal(nearest, reference_sample(source, offsets, r, graph::ResizeMode::Nearest)));
    EXPECT_TRUE(torch::equal(nearest, torch_grid_sample(source, offsets, r, true)));
    EXPECT_TRUE(torch::allclose(bilinear, reference_sample(source, offsets, r, graph::ResizeMode::Bilinear), 1e-5, 1e-5));
    EXPECT_TRUE(torch::allclose(bilinear, torch_grid_sample(source, offsets, r, false), 1e-5, 1e-5));
    // Clamped, not zero-padded: every far-outside sample is a border pixel.
    EXPECT_GT(nearest.slice(2, 0, 2).abs().min().item<float>(), 0.f);
  }
}

TEST(SampleOp, NearestRoundsExactHalvesToEven) {
  // Power-of-two sizes keep the normalized grid exact, so positions land on .5 exactly.
  const int64_t w = 8, h = 8, r = 2;
  const auto source = torch::arange(w, torch::kFloat).view({1, 1, 1, w}).expand({1, 1, h, w}).contiguous();
  // Output column j sits at j / 2 - 0.25; this offset moves it to floor(j / 2) + 0.5.
  auto offsets = torch::zeros({1, 2, h * r, w * r});
  for (int64_t j = 0; j < w * r; ++j) offsets[0][0].select(1, j).fill_(static_cast<double>(j / 2) + 0.75 - j / 2.0);
  const auto got = graph::apply_sample(source, offsets, r, graph::ResizeMode::Nearest);
  EXPECT_TRUE(torch::equal(got, reference_sample(source, offsets, r, graph::ResizeMode::Nearest)));
  EXPECT_TRUE(torch::equal(got, torch_grid_sample(source, offsets, r, true)));
  for (int64_t j = 0; j < w * r; ++j) {
    const int64_t m = j / 2;                              // position m + 0.5
    const int64_t even = std::min<int64_t>(m % 2 == 0 ? m : m + 1, w - 1);  // half to even, clamped
    EXPECT_EQ(got[0][0][0][j].item<float>(), static_cast<float>(even)) << "column " << j;
  }
}

TEST(SampleOp, ZeroOffsetsAreNearestAndBilinearUpsampling) {
  torch::manual_seed(42);
  for (int64_t r : {2, 3, 4}) {
    SCOPED_TRACE("ratio " + std::to_string(r));
    const auto source = torch::rand({1, 3, 7, 5});
    const auto zeros = torch::zeros({1, 2, 7 * r, 5 * r});
    EXPECT_TRUE(torch::equal(graph::apply_sample(source, zeros, r, graph::ResizeMode::Nearest),
                             graph::apply_resize(source, r, graph::ResizeMode::Nearest)));
    EXPECT_TRUE(torch::allclose(graph::apply_sample(source, zeros, r, graph::ResizeMode::Bilinear),
                                graph::apply_resize(source, r, graph::ResizeMode::Bilinear), 1e-5, 1e-6));
  }
}

TEST(SampleOp, BuilderChecksTheOffsetsAndTheFactors) {
  graph::Builder g;
  const int color = g.input("color", graph::fixed_layout("rgb", 3), 1);
  const int hr = g.input("hr", graph::fixed_layout("offsets", 2), 2);
  const int sampled = g.sample(color, hr, graph::ResizeMode::Nearest);
  EXPECT_EQ(g.value(sampled).factor, 2);
  EXPECT_EQ(g.value(sampled).layout, graph::fixed_layout("rgb", 3));
  EXPECT_THROW(g.sample(hr, color, graph::ResizeMode::Nearest), Error);  // 3 channels, factor 1 < 2
  const int odd = g.input("odd", graph::fixed_layout("offsets", 2), 3);
  EXPECT_THROW(g.sample(hr, odd, graph::ResizeMode::Nearest), Error);  // 3 is no multiple of 2
  EXPECT_EQ(g.value(g.sample(color, hr, graph::ResizeMode::Bicubic)).factor, 2);
  const int prunable = g.input("p", graph::group_layout("features", 2), 2);
  EXPECT_THROW(g.sample(color, prunable, graph::ResizeMode::Nearest), Error);
  EXPECT_THROW(graph::apply_sample(torch::rand({1, 3, 4, 4}), torch::zeros({1, 2, 8, 7}), 2,
                                   graph::ResizeMode::Nearest),
               Error);
}

TEST(AnyAbsAboveOp, IsTheIndicatorOfAnOffsetThatRoundsAwayFromZero) {
  const auto dx = torch::tensor({0.5f, -0.5f, 0.5000001f, -0.6f, 0.2f, 0.f, 0.49f, 3.f});
  const auto dy = torch::tensor({0.f, 0.4f, 0.f, 0.f, -0.51f, 0.f, -0.5f, 0.f});
  const auto offsets = torch::stack({dx, dy}).view({1, 2, 1, 8});
  const auto mask = graph::apply_any_abs_above(offsets, 0.5);
  EXPECT_EQ(mask.sizes().vec(), (std::vector<int64_t>{1, 1, 1, 8}));
  EXPECT_TRUE(torch::equal(mask.flatten(), torch::tensor({0.f, 0.f, 1.f, 1.f, 1.f, 0.f, 0.f, 1.f})));
  // The same as round half to even != 0 in either component.
  const auto moved = (torch::round(offsets) != 0).any(1, true).to(torch::kFloat);
  EXPECT_TRUE(torch::equal(mask, moved));
  graph::Builder g;
  const int off = g.input("o", graph::fixed_layout("offsets", 2), 2);
  const int m = g.any_abs_above(off, 0.5);
  EXPECT_EQ(g.value(m).layout, graph::fixed_layout("mask", 1));
  EXPECT_EQ(g.value(m).factor, 2);
}
