#pragma once
// The `history` rendering channel (render_channels.h): the jittered LR samples of a frame and of
// its kHistoryFrames predecessors placed on a resolution `scale` times the LR one, each at the
// point it sampled, reprojected to the current frame through the motion vectors (NSRR's
// "zero-upsampling" and backward warping; docs/temporal.md). A pure function on tensors: the data
// set gathers the frames (dataset.cpp), an engine would pass its own.
//
// For an r-pixel p of frame t (pixel-centre convention: its centre p + 0.5, unjittered as motion
// is), the chain of positions q_t = p + 0.5, q_{f-1} = q_f + motion_f(q_f) follows the point back
// through the previous frames; motion is read at the r-pixel containing q_f (nearest: exact on
// flat motion, and a chain of bilinear reads would blur across silhouettes). LR pixel x of frame
// f sampled the unjittered LR position x + 0.5 - jitter_f (jitter.h: content sits at p + jitter),
// i.e. r-position scale * (x + 0.5 - jitter_f). Frame f's nearest sample to q_f counts when it lies
// within p's footprint (|offset| <= 0.5 r-pixel per axis, inclusive: an unjittered sample on a
// pixel border fills both pixels) and its LR depth agrees with the point's depth. The chain stops
// where it leaves the image or where frame f's depth at q_f disagrees with the previous link's
// (disocclusion: the point was hidden in frame f, and its motion there is the occluder's).
// The most recent accepted sample wins.

#include <torch/types.h>

#include "render_data/render_channels.h"

#include <array>
#include <string>
#include <vector>

namespace cgsr {

// Previous frames gathered (K): the current frame's samples and K older ones.
constexpr int kHistoryFrames = 4;
// The depth tests (relative differences of linear view depth). A sample is compared with the
// chain's depth in its own frame's view; a link compares two frames' views of one point, nearer in
// the older frame where the point was hidden there (disocclusion), farther where the chain jumped
// to a surface behind. The bounds are separate so that they can be measured apart
// (docs/results/history.md): looser ones, either way, add samples barely better than bicubic.
constexpr double kHistoryDepthTolerance = 0.1;
struct HistoryDepthTest {
  double sample = kHistoryDepthTolerance;       // |LR depth - chain depth| above this: another surface
  double link_nearer = kHistoryDepthTolerance;  // older frame nearer by more: occluded there, the chain ends
  double link_farther = kHistoryDepthTolerance; // older frame farther by more: another surface, the chain ends
};

// One frame of the chain, all as the data set stores them.
struct HistoryFrame {
  torch::Tensor lr_color;  // [3,h,w] sRGB-encoded: uint8, or float in [0,1]
  torch::Tensor lr_depth;  // [1,h,w] linear view depth (+inf for the sky)
  std::array<double, 2> jitter{0, 0};  // of the LR frame, LR pixels (Frame::jitter)
  torch::Tensor depth;   // [1,H,W] linear view depth at r; may be undefined for the oldest frame
  torch::Tensor motion;  // [2,H,W] at r (render_channels.h); may be undefined for the oldest frame
};

// Whether two linear depths are one surface: both the sky, or within `tolerance` of the nearer.
bool same_surface_depth(float a, float b, double tolerance);
// Whether a chain link holds: `older`, the point's depth in the older frame, against `newer`.
bool history_link_holds(float older, float newer, const HistoryDepthTest& test);

// `frames[0]` is frame t, `frames[k]` frame t-k (at most kHistoryFrames + 1; fewer at a scene's
// start). Returns float32 [4, scale*h, scale*w]: (r, g, b) of the sample in [0,1], then recency
// 1 - k/(kHistoryFrames+1) for frame t-k's sample, 0 (and colour 0) where no frame has one.
// Throws cgsr::Error naming `what` (e.g. the data set and frame) when a tensor is missing or of
// the wrong size.
torch::Tensor history_channel(const std::vector<HistoryFrame>& frames, int scale, const std::string& what,
                              const HistoryDepthTest& depth_test = {});

// The history_out channel's depth test: a looser link than the history's. A point's view depth
// changes from frame to frame as the camera moves (10% in a frame of the tiny scene's walk), and
// one link per frame has no chain to share the error with: on that walk the 10% bound kept 28% of
// the pixels and rejected the rest at 30.7 dB against the kept ones' 32.7; 50% keeps 90% and
// rejects 1% at 27.2 dB against 31.3 (tests/eval/test_recurrent_network.cpp).
constexpr double kHistoryOutDepthTolerance = 0.5;

// The history_out channel's data part (render_channels.h) at one resolution: float32 [6, H, W],
// colour 0 (the runner passes its previous output there), validity, motion. Pixel p is valid where
// p + 0.5 + motion(p) lies inside the frame and `previous_depth` there (nearest) passes the link
// test against depth(p); the sky (no previous pixel: motion 0) and every pixel of a frame without a
// previous one (`previous_depth` undefined) are not. `depth` and `previous_depth` are [1, H, W]
// linear view depth, `motion` [2, H, W] at the same resolution. Errors name `what`.
torch::Tensor history_out_channel(const torch::Tensor& depth, const torch::Tensor& motion,
                                  const torch::Tensor& previous_depth, const std::string& what,
                                  const HistoryDepthTest& depth_test = {kHistoryOutDepthTolerance,
                                                                        kHistoryOutDepthTolerance,
                                                                        kHistoryOutDepthTolerance});

// A batch's rendering information `info` [N, C, H, W] (stacked as `channels` says) with the
// previous output [N, 3, H, W] in history_out's colour, clamped to [0, 1] as a displayed frame is:
// what a runner of a recurrent network passes each frame. Undefined `previous` (a sequence's first frame, or after a scene cut): validity 0
// instead, so the network runs on this frame alone. `info` itself when `channels` has no
// history_out. Out of place: training's gradients flow through `previous`.
torch::Tensor with_previous_output(const torch::Tensor& info, const std::vector<RenderChannel>& channels,
                                   const torch::Tensor& previous);
// Whether `channels` hold history_out: the network reads its own previous output.
bool reads_previous_output(const std::vector<RenderChannel>& channels);

// `info` [C, H, W] (channels stacked as `channels` says) with history_out's validity set to 0
// where p + 0.5 + motion leaves the H x W window: a training patch's previous output ends there.
// In place; nothing when `channels` has no history_out.
void restrict_history_out_to_window(torch::Tensor& info, const std::vector<RenderChannel>& channels);

}  // namespace cgsr
