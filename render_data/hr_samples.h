#pragma once
// Anti-aliased targets (render config `hr_samples: N`): the colour of every resolution but the
// smallest (the ground truth; the smallest is the network's input and keeps one sample per pixel)
// is rendered with N = n x n samples per pixel on a regular grid, the view rasterized at n x the
// resolution, and resolved with a box filter in linear light (SceneRenderer::render_color). The
// G-buffers keep one sample per pixel. N = 1 is today's aliased target.

#include <string>

namespace cgsr {

constexpr int kMaxHrSamplesPerSide = 4;
// The one resolve filter: the mean of a pixel's n x n samples in linear light.
constexpr const char* kHrFilterBox = "box";

// n with n * n == hr_samples and 1 <= n <= kMaxHrSamplesPerSide; 0 when there is none.
int hr_samples_per_side(int hr_samples);

// What a mistaken value should be instead (for the errors that name the key).
std::string hr_samples_expected();

// The target a data set's HR colour is, for reports: "aliased (1 sample per pixel)" or
// "supersampled (4 samples per pixel, box filter)".
std::string hr_target_description(int hr_samples, const std::string& filter);

// What a data set's target is when cgsr did not render it (a game capture or the CGSR release).
constexpr const char* kCapturedTarget = "as captured";

}  // namespace cgsr
