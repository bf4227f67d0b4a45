// Pruning units: block-internal groups tied by convolutions, never a residual stream.
#include <gtest/gtest.h>

#include "pruning/prunable_units.h"
#include "tests/pruning/pruning_cases.h"

using namespace cgsr;
using namespace cgsr::test;

namespace {
std::vector<std::string> names(const std::vector<PrunableUnit>& units) {
  std::vector<std::string> out;
  for (const auto& u : units) out.push_back(u.name);
  return out;
}
}  // namespace

TEST(PrunableUnits, PanBlocksAndUpsampler) {
  SRNetwork net(small_spec("pan", 4, 2, 6, 8, /*rit=*/true));
  const auto units = find_units(net->describe(false));
  EXPECT_EQ(names(units), (std::vector<std::string>{"block0", "block1", "rit", "up1+hr1+up2+hr2"}));
  EXPECT_EQ(units[0].groups, (std::vector<std::string>{"block0_a", "block0_b", "block0_a_out", "block0_att",
                                                        "block0_b_out"}));
  EXPECT_EQ(units[0].total_width(), 30);
  // conv1_a, conv1_b, k1, pa_conv.k2/k3/k4, conv3 of block 0.
  EXPECT_EQ(units[0].ops.size(), 7u);
  for (const auto& u : units)
    for (const auto& g : u.groups) EXPECT_NE(g, "features");
}

TEST(PrunableUnits, EdsrAndSrcnn) {
  SRNetwork edsr(small_spec("edsr", 2, 3, 6, 8));
  EXPECT_EQ(names(find_units(edsr->describe(false))), (std::vector<std::string>{"block0", "block1", "block2", "up1"}));
  SRNetwork srcnn(small_spec("srcnn", 2, 0, 7, 7));
  EXPECT_EQ(names(find_units(srcnn->describe(false))), (std::vector<std::string>{"conv1+conv2"}));
}

TEST(PrunableUnits, KeptCount) {
  EXPECT_EQ(kept_count(20, 0.5), 10);
  EXPECT_EQ(kept_count(3, 0.1), 1);
  EXPECT_EQ(kept_count(24, 1.0), 24);
  EXPECT_EQ(kept_count(5, 0.5), 3);
}
