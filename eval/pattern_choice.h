#pragma once
// What a hybrid-pruned model chose per frame, read back from its evaluation: every frame of an
// upscaler that chooses a pattern per frame (pruning/hybrid_upscaler.h) carries its
// PatternChoice (upscaler.h, FrameScore::choice). The report shows the choice next to the frame's
// geometry-edge density, how hard the rendering information says the frame is, as a table and
// a plot; the verdict counts the patterns in use.
//
//   if (auto c = pattern_choices(result)) write_scatter_plot("choice.svg", pattern_choice_plot(result.name, *c));

#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "core/plot.h"
#include "eval/evaluation.h"

namespace cgsr {

struct FrameChoice {
  int frame = 0;
  int pattern = 0;
  double channel_fraction = 1;          // of the widest pattern's unit channels
  std::optional<double> edge_fraction;  // share of the frame's pixels on geometry edges
  double psnr = 0;
};

struct PatternChoices {
  std::vector<FrameChoice> frames;  // in evaluation order
  std::map<int, int> usage;         // pattern -> frames that chose it
};

// None when no frame of `result` records a pattern.
std::optional<PatternChoices> pattern_choices(const EvalResult& result);

// "pattern 0: 3 frames (30%), pattern 2: 7 frames (70%)"
std::string usage_text(const PatternChoices& choices);

// A Markdown section: the usage shares and, per frame, edge density, pattern, channels kept and
// PSNR; `plot` (a file name next to the Markdown) is linked when not empty.
std::string pattern_choice_markdown(const std::string& model, const PatternChoices& choices,
                                    const std::string& plot = "");

// Per frame, the chosen pattern's channel fraction against the frame's edge density, each point
// named by its frame. Throws cgsr::Error when no frame has an edge density (the data set has no
// edge channel).
ScatterPlot pattern_choice_plot(const std::string& model, const PatternChoices& choices);

}  // namespace cgsr
