// Multiply-accumulate counts against the published numbers at 1280x720 output, and the
// counting convention itself.
#include <gtest/gtest.h>

#include <cmath>

#include "models/complexity.h"
#include "models/sr_network.h"
#include "tests/models/model_cases.h"

using namespace cgsr;

namespace {
// MACs of a network at 1280x720 output, in units of 10^-digits G (so 70.52G -> 7052 with digits 2).
int64_t macs_at_720p(const ArchSpec& spec, int digits) {
  SRNetwork net(spec);
  const auto [w, h] = lr_size_for_output(1280, 720, spec.scale);
  const auto c = complexity(*net, w, h);
  return std::llround(static_cast<double>(c.macs) / std::pow(10.0, 9 - digits));
}
}  // namespace

TEST(Complexity, PanMatchesPublishedMacs) {
  EXPECT_EQ(macs_at_720p(default_spec("pan", 2), 2), 7052);  // 70.52G
  EXPECT_EQ(macs_at_720p(default_spec("pan", 3), 2), 3899);  // 38.99G
  EXPECT_EQ(macs_at_720p(default_spec("pan", 4), 2), 2816);  // 28.16G
}

TEST(Complexity, EdsrBaselineMatchesPublishedMacs) {
  EXPECT_EQ(macs_at_720p(default_spec("edsr", 2), 1), 3163);  // 316.3G
  EXPECT_EQ(macs_at_720p(default_spec("edsr", 3), 1), 1601);  // 160.1G
  EXPECT_EQ(macs_at_720p(default_spec("edsr", 4), 1), 1142);  // 114.2G
}

TEST(Complexity, SrcnnLumaMatchesPublishedMacs) {
  ArchSpec s = default_spec("srcnn", 2);
  s.colors = Colors::Y;
  EXPECT_EQ(macs_at_720p(s, 1), 527);  // 52.7G
}

TEST(Complexity, LrSizeFloorsTheOutput) {
  EXPECT_EQ(lr_size_for_output(1280, 720, 3), (std::pair<int64_t, int64_t>{426, 240}));
  SRNetwork net(default_spec("pan", 3));
  const auto c = complexity(*net, 426, 240);
  EXPECT_EQ(c.hr_width, 1278);
  EXPECT_EQ(c.hr_height, 720);
}

TEST(Complexity, ConvCostIsWeightsTimesOutputPixels) {
  SRNetwork net(default_spec("pan", 2));
  const auto c = complexity(*net, 10, 6);
  int64_t sum = 0;
  for (const auto& l : c.layers) {
    sum += l.macs;
    if (l.name == "backbone.conv_first") {
      EXPECT_EQ(l.macs, 40 * 3 * 9 * 10 * 6);
      EXPECT_EQ(l.params, 40 * 3 * 9 + 40);
    }
    if (l.name == "backbone.conv_last") {
      EXPECT_EQ(l.macs, 3 * 24 * 9 * 20 * 12);  // at HR
    }
  }
  EXPECT_EQ(sum, c.macs);
  // MACs scale with the pixel count.
  EXPECT_EQ(complexity(*net, 20, 12).macs, 4 * c.macs);
}

TEST(Complexity, GeometryHeadIsNotCountedButRitIs) {
  const ArchSpec base = default_spec("pan", 2);
  const ArchSpec cg = cgsr::test::with_rit(base, "lr", "concat", /*geometry=*/true);
  SRNetwork plain(base), enhanced(cg);
  const auto a = complexity(*plain, 16, 16), b = complexity(*enhanced, 16, 16);
  // RIT: gate (6) + conv 6->16 3x3 + fuse (40+16)->40 1x1.
  const int64_t rit_params = 6 + (6 * 16 * 9 + 16) + (56 * 40 + 40);
  EXPECT_EQ(b.params - a.params, rit_params);
  EXPECT_EQ(b.macs - a.macs, (6 * 16 * 9 + 56 * 40) * 16 * 16);
  EXPECT_GT(total_parameter_count(*enhanced), inference_parameter_count(*enhanced));
  EXPECT_EQ(inference_parameter_count(*enhanced), b.params);
}

TEST(Complexity, FormatsCounts) {
  EXPECT_EQ(format_count(70.52e9), "70.52G");
  EXPECT_EQ(format_count(316.26e9), "316.3G");
  EXPECT_EQ(format_count(261403), "261.4K");
  EXPECT_EQ(format_count(12), "12");
}
