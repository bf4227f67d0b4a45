#pragma once
// Pictures of frames for people: each channel as an RGB image, and montages that put a low
// resolution frame (nearest-neighbour enlarged, so its pixels stay visible) beside its high
// resolution render. Used by `cgsr data preview` and for the README figures.

#include <torch/types.h>

#include <vector>

#include "render_data/frame.h"

namespace cgsr {

enum class PreviewChannel { Color, Depth, Normal, NormalAngle, Edge, Motion };
const std::vector<std::string>& preview_channel_names();  // color, depth, normal, normal_angle, edge, motion
PreviewChannel preview_channel_from_name(const std::string& name);

// float32 [3,H,W] in [0,1]: colour as is; depth as grey of log depth over the frame's range
// (near white, far grey, sky black); normals as (n + 1) / 2 with black sky; normal angle and edges as grey;
// motion as hue = direction, brightness = magnitude (relative to `motion_scale` pixels).
torch::Tensor visualize(const Frame& frame, PreviewChannel channel, double motion_scale = 8.0);

// Rows = channels; columns = LR enlarged to the HR size by pixel replication, then HR. A 4-pixel
// gap separates cells; a channel one resolution lacks leaves its cell black. Requires hr = s x lr
// for an integer s.
torch::Tensor montage(const Frame& lr, const Frame& hr, const std::vector<PreviewChannel>& channels);

// A grid of frames of one size (e.g. many scenes of a multi-scene data set), row by row,
// `columns` per row, one channel each, 4-pixel white gaps.
torch::Tensor tile_frames(const std::vector<Frame>& frames, PreviewChannel channel, int columns);

}  // namespace cgsr
