#include "render_data/visualize.h"

#include <torch/torch.h>

#include "core/error.h"
#include "core/text.h"

namespace cgsr {

const std::vector<std::string>& preview_channel_names() {
  static const std::vector<std::string> n = {"color", "depth", "normal", "normal_angle", "edge", "motion"};
  return n;
}

PreviewChannel preview_channel_from_name(const std::string& name) {
  const auto& names = preview_channel_names();
  for (size_t i = 0; i < names.size(); ++i)
    if (names[i] == name) return static_cast<PreviewChannel>(i);
  throw Error("preview", "unknown channel '" + name + "'" + did_you_mean(name, names) + "; valid: " + join(names));
}

namespace {
torch::Tensor require(const torch::Tensor& t, const char* name) {
  if (!t.defined()) throw Error("preview", std::string("the frame has no '") + name + "' channel");
  return t;
}

bool shows(const Frame& f, PreviewChannel channel) {
  switch (channel) {
    case PreviewChannel::Color: return f.color.defined();
    case PreviewChannel::Depth: return f.has(RenderChannel::Depth);
    case PreviewChannel::Normal: return f.has(RenderChannel::Normal);
    case PreviewChannel::NormalAngle: return f.has(RenderChannel::NormalAngle);
    case PreviewChannel::Edge: return f.has(RenderChannel::Edge);
    case PreviewChannel::Motion: return f.has(RenderChannel::Motion);
  }
  return false;
}
}  // namespace

torch::Tensor visualize(const Frame& f, PreviewChannel channel, double motion_scale) {
  switch (channel) {
    case PreviewChannel::Color: return f.color_float();
    case PreviewChannel::Depth: {
      // Log depth over the frame's own range, near bright, far grey, sky black. (The z-buffer
      // form the network sees, normalize_depth, is nearly 1 beyond a few metres and shows nothing.)
      const auto z = require(f.depth, "depth").to(torch::kFloat32);
      const auto geometry = torch::isfinite(z) & (z > 0);
      if (!geometry.any().item<bool>()) return torch::zeros({3, f.height, f.width});
      const auto log_z = torch::log(torch::where(geometry, z, torch::ones({})));
      const auto seen = log_z.masked_select(geometry);
      const float lo = seen.min().item<float>(), range = std::max(seen.max().item<float>() - lo, 1e-6f);
      const auto v = torch::where(geometry, 1.0f - 0.8f * (log_z - lo) / range, torch::zeros({}));
      return v.expand({3, f.height, f.width}).contiguous();
    }
    case PreviewChannel::Normal: {
      const auto n = require(f.normal, "normal").to(torch::kFloat32);
      const auto sky = (n.abs().sum(0, true) == 0);
      return torch::where(sky, torch::zeros({}), (n + 1) * 0.5f);
    }
    case PreviewChannel::NormalAngle:
      return require(f.normal_angle, "normal_angle").to(torch::kFloat32).expand({3, f.height, f.width}).contiguous();
    case PreviewChannel::Edge: return require(f.edge, "edge").to(torch::kFloat32).expand({3, f.height, f.width}).contiguous();
    case PreviewChannel::Motion: {
      const auto m = require(f.motion, "motion");
      const auto angle = torch::atan2(m[1], m[0]);  // hue from direction
      const auto mag = (m.norm(2, 0) / motion_scale).clamp(0, 1);
      const float third = 2.0943951f;
      auto r = (torch::cos(angle) * 0.5f + 0.5f) * mag;
      auto g = (torch::cos(angle - third) * 0.5f + 0.5f) * mag;
      auto b = (torch::cos(angle + third) * 0.5f + 0.5f) * mag;
      return torch::stack({r, g, b}, 0);
    }
  }
  return {};
}

torch::Tensor montage(const Frame& lr, const Frame& hr, const std::vector<PreviewChannel>& channels) {
  if (hr.width % lr.width != 0 || hr.width / lr.width != hr.height / lr.height || hr.height % lr.height != 0)
    throw Error("preview", "the HR frame is not an integer multiple of the LR frame");
  const int s = hr.width / lr.width, gap = 4;
  const int W = hr.width, H = hr.height;
  auto canvas = torch::ones({3, static_cast<int64_t>(channels.size()) * (H + gap) - gap, 2 * W + gap});
  for (size_t row = 0; row < channels.size(); ++row) {
    // A capture may hold a channel at one resolution only: the other cell stays black.
    if (!shows(lr, channels[row]) && !shows(hr, channels[row]))
      throw Error("preview", "neither resolution has the '" + preview_channel_names()[static_cast<size_t>(channels[row])] +
                                 "' channel");
    const int64_t y = static_cast<int64_t>(row) * (H + gap);
    auto cells = canvas.slice(1, y, y + H);
    // Motion is in pixels of its own resolution: scale the LR colour wheel like the HR one.
    if (shows(lr, channels[row]))
      cells.slice(2, 0, W).copy_(visualize(lr, channels[row], 8.0 / s).repeat_interleave(s, 1).repeat_interleave(s, 2));
    else
      cells.slice(2, 0, W).zero_();
    if (shows(hr, channels[row]))
      cells.slice(2, W + gap, 2 * W + gap).copy_(visualize(hr, channels[row], 8.0));
    else
      cells.slice(2, W + gap, 2 * W + gap).zero_();
  }
  return canvas;
}

torch::Tensor tile_frames(const std::vector<Frame>& frames, PreviewChannel channel, int columns) {
  if (frames.empty() || columns < 1) throw Error("preview", "a grid needs at least one frame and one column");
  const int W = frames[0].width, H = frames[0].height, gap = 4;
  const int cols = std::min<int>(columns, static_cast<int>(frames.size()));
  const int rows = (static_cast<int>(frames.size()) + cols - 1) / cols;
  auto canvas = torch::ones({3, static_cast<int64_t>(rows) * (H + gap) - gap, static_cast<int64_t>(cols) * (W + gap) - gap});
  for (size_t i = 0; i < frames.size(); ++i) {
    if (frames[i].width != W || frames[i].height != H)
      throw Error("preview", "frame " + std::to_string(i) + " of the grid is " + std::to_string(frames[i].width) + "x" +
                                 std::to_string(frames[i].height) + ", the first is " + std::to_string(W) + "x" +
                                 std::to_string(H));
    if (!shows(frames[i], channel))
      throw Error("preview", "a frame of the grid has no '" + preview_channel_names()[static_cast<size_t>(channel)] + "' channel");
    const int64_t y = static_cast<int64_t>(i / cols) * (H + gap), x = static_cast<int64_t>(i % cols) * (W + gap);
    canvas.slice(1, y, y + H).slice(2, x, x + W).copy_(visualize(frames[i], channel));
  }
  return canvas;
}

}  // namespace cgsr
