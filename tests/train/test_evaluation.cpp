// Evaluation on the tiny scene: frame selection by range, and a consecutive range scoring like
// the same frames evaluated one by one.
#include <gtest/gtest.h>

#include "core/error.h"
#include "tests/support/tiny_data.h"
#include "train/evaluation.h"

using namespace cgsr;
using namespace cgsr::test;

namespace {
EvalOptions all_frames(const std::string& range) {
  EvalOptions o;
  o.split = "all";
  o.frames = range;
  o.latency_runs = 0;
  return o;
}
}  // namespace

TEST(Evaluation, FrameRangeSelectsWithinTheSplit) {
  const Dataset data = Dataset::open(tiny_data());
  EXPECT_EQ(evaluation_frames(data, all_frames("1:4")), (std::vector<int>{1, 2, 3}));
  EXPECT_EQ(evaluation_frames(data, all_frames("")).size(), 6u);
  EXPECT_THROW(evaluation_frames(data, all_frames("4:2")), Error);
  EXPECT_THROW(evaluation_frames(data, all_frames("10:20")), Error);  // no frame there
  EXPECT_THROW(evaluation_frames(data, all_frames("x:2")), Error);
}

TEST(Evaluation, ConsecutiveFramesGiveTheSameScoresAsSingleFrames) {
  const Dataset data = Dataset::open(tiny_data());
  auto upscaler = classic_upscalers().get("bicubic")(2);
  const EvalResult range = evaluate(*upscaler, data, all_frames("1:4"));
  ASSERT_EQ(range.frames.size(), 3u);
  for (const auto& f : range.frames) {
    SCOPED_TRACE(f.frame);
    const EvalResult one = evaluate(*upscaler, data, all_frames(std::to_string(f.frame) + ":" + std::to_string(f.frame + 1)));
    ASSERT_EQ(one.frames.size(), 1u);
    EXPECT_DOUBLE_EQ(one.frames[0].psnr, f.psnr);
    ASSERT_TRUE(one.frames[0].temporal_error && f.temporal_error);
    EXPECT_DOUBLE_EQ(*one.frames[0].temporal_error, *f.temporal_error);
  }
}
