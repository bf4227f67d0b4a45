// The per-frame pattern choices of a hybrid-pruned model, read back from its evaluation: usage,
// the report's table and plot.
#include <gtest/gtest.h>

#include <filesystem>

#include "core/error.h"
#include "core/image_io.h"
#include "eval/pattern_choice.h"
#include "tests/support/scratch_dir.h"

using namespace cgsr;

namespace {
FrameScore frame(int index, std::optional<int> pattern, double fraction, std::optional<double> edges) {
  FrameScore f;
  f.frame = index;
  f.psnr = 30 + index;
  f.edge_fraction = edges;
  if (pattern) f.choice = PatternChoice{*pattern, fraction};
  return f;
}
}  // namespace

TEST(PatternChoice, CountsThePatternsEachFrameChose) {
  EvalResult r;
  r.name = "hybrid";
  r.frames = {frame(4, 0, 1.0, 0.08), frame(5, 2, 0.5, 0.01), frame(6, 2, 0.5, 0.02), frame(7, 1, 0.75, 0.05)};
  const auto choices = pattern_choices(r);
  ASSERT_TRUE(choices);
  ASSERT_EQ(choices->frames.size(), 4u);
  EXPECT_EQ(choices->usage, (std::map<int, int>{{0, 1}, {1, 1}, {2, 2}}));
  EXPECT_EQ(choices->frames[1].frame, 5);
  EXPECT_DOUBLE_EQ(choices->frames[1].channel_fraction, 0.5);
  EXPECT_EQ(usage_text(*choices), "pattern 0: 1 frames (25%), pattern 1: 1 frames (25%), pattern 2: 2 frames (50%)");

  const std::string md = pattern_choice_markdown(r.name, *choices, "choice.png");
  EXPECT_NE(md.find("| 5 | 1.00 | 2 | 50 | 35.00 |"), std::string::npos) << md;
  EXPECT_NE(md.find("(choice.png)"), std::string::npos);

  const auto dir = test::scratch_dir("pattern-choice");
  write_scatter_plot(dir / "choice.png", pattern_choice_plot(r.name, *choices));
  EXPECT_GT(read_image(dir / "choice.png").numel(), 0);
  std::filesystem::remove_all(dir);
}

TEST(PatternChoice, ModelsThatDoNotChooseHaveNone) {
  EvalResult r;
  r.name = "pan";
  r.frames = {frame(0, std::nullopt, 1, 0.1), frame(1, std::nullopt, 1, 0.1)};
  EXPECT_FALSE(pattern_choices(r));
}

TEST(PatternChoice, APlotNeedsEdgeDensities) {
  EvalResult r;
  r.name = "hybrid";
  r.frames = {frame(0, 1, 0.5, std::nullopt)};
  const auto choices = pattern_choices(r);
  ASSERT_TRUE(choices);
  EXPECT_EQ(pattern_choice_markdown(r.name, *choices).find("!["), std::string::npos);
  EXPECT_THROW(pattern_choice_plot(r.name, *choices), Error);
}

TEST(PatternChoice, TravelsThroughResultsFilesInItsOwnShape) {
  EvalResult r;
  r.name = "hybrid";
  r.frames = {frame(3, 2, 0.5, 0.04), frame(4, std::nullopt, 1, 0.04)};
  r.frames[0].choice->previous_frame = true;
  r.frames[0].choice->choose_ms = 0.25;
  const nlohmann::ordered_json j = to_json(r);
  // The record results files have always had: the frame's "details", keys in this order.
  EXPECT_EQ(j["frames"][0]["details"].dump(),
            R"({"previous_frame":true,"pattern":2,"channel_fraction":0.5,"choose_ms":0.25})");
  EXPECT_FALSE(j["frames"][1].contains("details"));
  const EvalResult back = eval_result_from_json(j, "test");
  ASSERT_TRUE(back.frames[0].choice);
  EXPECT_EQ(back.frames[0].choice->pattern, 2);
  EXPECT_DOUBLE_EQ(back.frames[0].choice->channel_fraction, 0.5);
  EXPECT_TRUE(back.frames[0].choice->previous_frame);
  EXPECT_DOUBLE_EQ(back.frames[0].choice->choose_ms, 0.25);
  EXPECT_FALSE(back.frames[1].choice);
  EXPECT_EQ(to_json(back).dump(), j.dump());
}
