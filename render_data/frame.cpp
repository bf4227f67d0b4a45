#include "render_data/frame.h"

#include <torch/torch.h>

#include "core/error.h"
#include "render_data/bsp_border.h"

namespace cgsr {

bool Frame::has(RenderChannel c) const {
  switch (c) {
    case RenderChannel::Depth: return depth.defined();
    case RenderChannel::Normal: return normal.defined();
    case RenderChannel::NormalAngle: return normal_angle.defined();
    case RenderChannel::Edge: return edge.defined();
    case RenderChannel::Motion: return motion.defined();
    case RenderChannel::Bsp: return bsp.defined();
    case RenderChannel::History: return history.defined();
    case RenderChannel::Jitter: return lr_jitter.defined();
    case RenderChannel::HistoryOut: return history_out.defined();
  }
  return false;
}

std::vector<RenderChannel> Frame::channels() const {
  std::vector<RenderChannel> out;
  for (auto c : all_render_channels())
    if (has(c)) out.push_back(c);
  return out;
}

torch::Tensor Frame::color_float() const { return color.to(torch::kFloat32).div_(255.0f); }

torch::Tensor Frame::info(const std::vector<RenderChannel>& channels, DepthEncoding depth_encoding, double near_plane,
                          double far_plane) const {
  std::vector<torch::Tensor> parts;
  for (auto c : channels) {
    if (!has(c)) throw Error("frame", "has no '" + channel_name(c) + "' channel");
    switch (c) {
      case RenderChannel::Depth: parts.push_back(encode_depth(depth, near_plane, far_plane, depth_encoding)); break;
      case RenderChannel::Normal: parts.push_back(normal.to(torch::kFloat32)); break;
      case RenderChannel::NormalAngle: parts.push_back(normal_angle.to(torch::kFloat32)); break;
      case RenderChannel::Edge: parts.push_back(edge.to(torch::kFloat32)); break;
      case RenderChannel::Motion: parts.push_back(motion.to(torch::kFloat32)); break;
      case RenderChannel::Bsp: parts.push_back(bsp); break;
      case RenderChannel::History: parts.push_back(history); break;
      case RenderChannel::Jitter: parts.push_back(lr_jitter.expand({2, height, width}).contiguous()); break;
      case RenderChannel::HistoryOut: parts.push_back(history_out); break;
    }
  }
  if (parts.empty()) return torch::zeros({0, height, width}, torch::kFloat32);
  return torch::cat(parts, 0);
}

size_t Frame::bytes() const {
  size_t n = 0;
  for (const auto* t : {&color, &depth, &normal, &normal_angle, &edge, &motion, &bsp, &history, &lr_jitter, &history_out})
    if (t->defined()) n += t->numel() * t->element_size();
  if (bsp_border) n += bsp_border->bytes();
  return n;
}

Frame crop(const Frame& f, int x, int y, int w, int h) {
  CGSR_CHECK(x >= 0 && y >= 0 && w > 0 && h > 0 && x + w <= f.width && y + h <= f.height, "crop outside the frame");
  Frame out;
  out.width = w;
  out.height = h;
  out.jitter = f.jitter;
  out.lr_jitter = f.lr_jitter;
  const Frame* src = &f;
  for (auto [dst, from] : {std::pair{&out.color, &src->color}, std::pair{&out.depth, &src->depth},
                           std::pair{&out.normal, &src->normal}, std::pair{&out.normal_angle, &src->normal_angle},
                           std::pair{&out.edge, &src->edge}, std::pair{&out.motion, &src->motion},
                           std::pair{&out.bsp, &src->bsp}, std::pair{&out.history, &src->history},
                           std::pair{&out.history_out, &src->history_out}})
    if (from->defined()) *dst = from->slice(1, y, y + h).slice(2, x, x + w);
  return out;
}

Frame frame_from_gbuffer(const GBuffer& g) {
  Frame f;
  f.width = g.width;
  f.height = g.height;
  f.color = (g.color.clamp(0, 1) * 255.0f).round().to(torch::kUInt8);
  f.depth = g.depth.clone();
  f.normal = g.normal.to(torch::kFloat16);
  f.normal_angle = g.normal_angle.to(torch::kFloat16);
  f.edge = g.edge.to(torch::kUInt8);
  f.motion = g.motion.clone();
  return f;
}

}  // namespace cgsr
