#pragma once
// The rendering information a network can use, as named channels in one fixed order.
// This file is the contract between the data side (renderers, loaders) and the models: a model
// records the channel names it uses, and every tensor of rendering information is stacked in
// this order, each channel with the width given here.
//
//   name          width  range     meaning
//   depth           1    [0,1]    depth in the encoding the consumer asks for (DepthEncoding below;
//                                 0 at the near plane (near/far for linear), 1 at the far
//                                 plane and for sky)
//   normal          3    [-1,1]   view-space unit normal (x right, y up, z towards the camera);
//                                 0 where there is no geometry (sky)
//   normal_angle    1    [0,1]    angle between the normal and the direction to the camera,
//                                 0 deg -> 0, 90 deg -> 1 (as in the CGSR data release); 0 for sky
//   edge            1    {0,1}    object edges (depth discontinuities, id changes, normal creases)
//   motion          2    pixels   screen-space motion to the previous frame, (dx, dy) in pixels of
//                                 this resolution: a pixel at p was at p + motion in the previous frame.
//                                 A point that was not in front of the previous camera's near plane
//                                 (the sky: the far plane) has no previous pixel: motion 0 (its
//                                 projection would diverge); the render counts those pixels.
//                                 A previous position beyond one image size outside the frame is
//                                 cut there along the motion (still outside: no history), so
//                                 |motion| stays within two image sizes per axis; also counted.
//                                 Motion excludes the sub-pixel jitter (jitter.h, the FSR 2
//                                 convention): both positions are the unjittered ones, so a still
//                                 camera over a static scene has motion 0 although the samples move
//   bsp             4    [0,1]    the sub-pixel BSP border image (bsp_border.h) resolved at this
//                                 resolution: (r, g, b) the BSP border upsampler's output from the
//                                 LR colour (sRGB-encoded like the colour image), then coverage, 1
//                                 where the pixel's centre lies in an LR pixel that has a tree.
//                                 Derived on load (bsp_channel.h) at every resolution that is an
//                                 integer multiple of the data set's BSP resolution (at that one:
//                                 the colour with each border pixel's centre leaf); only cgsr data
//                                 sets rendered with bsp_border have it
//   history         4    [0,1]    the jittered LR samples of this frame and of its K = 4 previous
//                                 frames of the same scene (never across a scene cut), each on this
//                                 resolution's grid at the point it sampled (LR pixel x of frame f:
//                                 s * (x + 0.5 - jitter_f), s = this resolution / the LR one, an
//                                 integer), reprojected to this frame by gathering through the
//                                 motion vectors and rejected where its depth disagrees
//                                 (disocclusion): (r, g, b) the sample's colour (sRGB-encoded like
//                                 the colour image), then recency 1 for this frame's sample,
//                                 1 - k/(K+1) for frame t-k's, 0 where none lands (colour 0); the
//                                 most recent sample wins. Derived on load (history_channel.h) only
//                                 when asked for by name, at every integer multiple of the LR
//                                 resolution, from LR depth and the depth and motion stored
//                                 there or at LR (upsampled: upsample_channel); docs/temporal.md
//   jitter          2    pixels   the LR frame's sub-pixel jitter (jitter.h), (x, y) in LR pixels
//                                 (x right, y down, each in [-0.5, 0.5)), the same at every pixel
//                                 and at every resolution: what an engine passes a temporal
//                                 upscaler each frame, as two constant planes. 0 for unjittered
//                                 data. Derived on load only when asked for by name
//   history_out     6    [0,1]    the recurrent state (docs/temporal.md): (r, g, b) the upscaler's
//                   ..   pixels   own output for the previous frame, as the runner passes it (not
//                                 warped: the network warps it; 0 in a data set, which cannot know
//                                 it), then validity, 1 where this frame's pixel was seen by the
//                                 previous frame of the same scene (p + 0.5 + motion inside that
//                                 frame, and its depth there within 50% of here: history_channel.h's
//                                 history_out_channel), 0 at disocclusions, outside it and at a
//                                 scene's first frame; then the motion (dx, dy) as the motion channel
//                                 at this resolution. A runner without a previous output sets the
//                                 validity to 0. Derived on load only when asked for by name, at
//                                 every integer multiple of the LR resolution (as history)

#include <torch/types.h>

#include <string>
#include <vector>

#include "core/enum_names.h"

namespace cgsr {

enum class RenderChannel { Depth, Normal, NormalAngle, Edge, Motion, Bsp, History, Jitter, HistoryOut };

const std::vector<RenderChannel>& all_render_channels();  // in the fixed order above
const std::string& channel_name(RenderChannel channel);
RenderChannel channel_from_name(const std::string& name);  // cgsr::Error listing valid names
int channel_width(RenderChannel channel);
int total_width(const std::vector<RenderChannel>& channels);

// Names <-> channels, sorted into the fixed order; duplicates are an error.
std::vector<RenderChannel> parse_channels(const std::vector<std::string>& names);
std::vector<std::string> channel_names(const std::vector<RenderChannel>& channels);

// A channel stored at the render (LR) size, at `scale` times that size the way an engine passes
// it to a pass at the output size: nearest (each LR pixel over its s x s block), and motion also
// times s (pixels of the larger resolution). `t` is [..., h, w].
torch::Tensor upsample_channel(const torch::Tensor& t, RenderChannel channel, int scale);

// The rows of `info` ([N, total_width(available), H, W], channels stacked in `available` order)
// that hold `wanted`, in `wanted` order. Errors name the tensor (`what`, e.g. "lr_info") and who
// needs the channels (`reader`, e.g. "the model").
torch::Tensor pick_channels(const torch::Tensor& info, const std::vector<RenderChannel>& available,
                            const std::vector<RenderChannel>& wanted, const std::string& what,
                            const std::string& reader);

// How linear view depth z becomes the [0,1] value a network sees. A model records its encoding
// (rit.depth_encoding); data sets always store linear depth, so any encoding can be made.
//   log      log(z/near) / log(far/near): equal steps per octave of distance, so a room and a
//            horizon both get a usable range (the default for new networks)
//   linear   z / far
//   zbuffer  the z-buffer value (normalize_depth); above 0.95 for most of a scene with a near
//            plane of a few centimetres, so it carries little signal (kept for older model files)
// All clamp to [0,1] and give 1 at the far plane and beyond (sky); log and zbuffer give 0 at (and
// before) the near plane, linear gives near/far there.
enum class DepthEncoding { Log, Linear, ZBuffer };
template <>
struct EnumNames<DepthEncoding> {
  static constexpr const char* kind = "depth encoding";
  static const std::vector<std::string>& names();  // log, linear, zbuffer
};
torch::Tensor encode_depth(const torch::Tensor& linear_depth, double near, double far, DepthEncoding encoding);

// The z-buffer value of a perspective projection, (1/near - 1/z) / (1/near - 1/far), clamped to [0,1]. 0 at the near
// plane, 1 at the far plane and beyond (sky, z = inf). Finite for any near > 0, far <= inf.
torch::Tensor normalize_depth(const torch::Tensor& linear_depth, double near, double far);
// Inverse of normalize_depth for values in [0,1) (1 maps to far).
torch::Tensor linearize_depth(const torch::Tensor& normalized_depth, double near, double far);

}  // namespace cgsr
