#include "render_data/render_channels.h"

#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "core/tensor_checks.h"
#include "core/text.h"

namespace cgsr {
namespace {
struct ChannelInfo {
  RenderChannel channel;
  std::string name;
  int width;
};
const std::vector<ChannelInfo>& table() {
  static const std::vector<ChannelInfo> t = {
      {RenderChannel::Depth, "depth", 1},   {RenderChannel::Normal, "normal", 3},
      {RenderChannel::NormalAngle, "normal_angle", 1}, {RenderChannel::Edge, "edge", 1},
      {RenderChannel::Motion, "motion", 2}, {RenderChannel::Bsp, "bsp", 4},
      {RenderChannel::History, "history", 4},   {RenderChannel::Jitter, "jitter", 2},
      {RenderChannel::HistoryOut, "history_out", 6},
  };
  return t;
}
const ChannelInfo& info(RenderChannel c) { return table()[static_cast<size_t>(c)]; }
}  // namespace

const std::vector<RenderChannel>& all_render_channels() {
  static const std::vector<RenderChannel> all = [] {
    std::vector<RenderChannel> v;
    for (const auto& i : table()) v.push_back(i.channel);
    return v;
  }();
  return all;
}

const std::string& channel_name(RenderChannel channel) { return info(channel).name; }
int channel_width(RenderChannel channel) { return info(channel).width; }

torch::Tensor upsample_channel(const torch::Tensor& t, RenderChannel channel, int scale) {
  const auto nearest = t.repeat_interleave(scale, -2).repeat_interleave(scale, -1);
  return channel == RenderChannel::Motion ? nearest * static_cast<float>(scale) : nearest;
}

RenderChannel channel_from_name(const std::string& name) {
  std::vector<std::string> names;
  for (const auto& i : table()) {
    if (i.name == name) return i.channel;
    names.push_back(i.name);
  }
  throw Error("render channels", "unknown channel '" + name + "'" + did_you_mean(name, names) + "; valid: " + join(names));
}

int total_width(const std::vector<RenderChannel>& channels) {
  int w = 0;
  for (auto c : channels) w += channel_width(c);
  return w;
}

std::vector<RenderChannel> parse_channels(const std::vector<std::string>& names) {
  std::vector<RenderChannel> out;
  for (const auto& n : names) {
    const RenderChannel c = channel_from_name(n);
    if (std::find(out.begin(), out.end(), c) != out.end())
      throw Error("render channels", "channel '" + n + "' is listed twice");
    out.push_back(c);
  }
  std::sort(out.begin(), out.end());
  return out;
}

std::vector<std::string> channel_names(const std::vector<RenderChannel>& channels) {
  std::vector<std::string> out;
  for (auto c : channels) out.push_back(channel_name(c));
  return out;
}

torch::Tensor normalize_depth(const torch::Tensor& linear_depth, double near, double far) {
  if (!(near > 0) || !(far > near)) throw Error("depth", "need 0 < near < far, got near " + std::to_string(near) +
                                                            ", far " + std::to_string(far));
  const double inv_near = 1.0 / near, inv_far = std::isinf(far) ? 0.0 : 1.0 / far;
  // 1/z of +inf is 0, so sky lands at (or beyond) the far plane without special cases.
  const auto inv_z = torch::reciprocal(linear_depth.clamp_min(near));
  return ((inv_near - inv_z) / (inv_near - inv_far)).clamp(0.0, 1.0);
}

const std::vector<std::string>& EnumNames<DepthEncoding>::names() {
  static const std::vector<std::string> names = {"log", "linear", "zbuffer"};
  return names;
}

torch::Tensor encode_depth(const torch::Tensor& linear_depth, double near, double far, DepthEncoding encoding) {
  if (encoding == DepthEncoding::ZBuffer) return normalize_depth(linear_depth, near, far);
  if (!(near > 0) || !(far > near) || std::isinf(far))
    throw Error("depth", std::string("the ") + enum_name(encoding) +
                             " encoding needs 0 < near < far < inf, got near " + std::to_string(near) + ", far " +
                             std::to_string(far));
  // Clamping first keeps log() finite (z = 0) and maps sky (z = +inf) to exactly 1.
  const auto z = linear_depth.clamp(near, far);
  if (encoding == DepthEncoding::Linear) return (z / far).clamp(0.0, 1.0);
  return (torch::log(z / near) / std::log(far / near)).clamp(0.0, 1.0);
}

torch::Tensor linearize_depth(const torch::Tensor& normalized_depth, double near, double far) {
  if (!(near > 0) || !(far > near)) throw Error("depth", "need 0 < near < far");
  const double inv_near = 1.0 / near, inv_far = std::isinf(far) ? 0.0 : 1.0 / far;
  const auto inv_z = inv_near - normalized_depth.clamp(0.0, 1.0) * (inv_near - inv_far);
  return torch::reciprocal(inv_z.clamp_min(1e-30));
}

torch::Tensor pick_channels(const torch::Tensor& info, const std::vector<RenderChannel>& available,
                            const std::vector<RenderChannel>& wanted, const std::string& what,
                            const std::string& reader) {
  if (!info.defined() || info.dim() != 4 || info.size(1) != total_width(available))
    throw Error("batch", what + " must be [N, " + std::to_string(total_width(available)) + ", H, W] for channels " +
                             join(channel_names(available)) + ", got " +
                             (info.defined() ? shape_string(info) : std::string("nothing")));
  std::vector<torch::Tensor> parts;
  for (auto c : wanted) {
    int64_t offset = 0;
    bool found = false;
    for (auto a : available) {
      if (a == c) {
        found = true;
        break;
      }
      offset += channel_width(a);
    }
    if (!found)
      throw Error("batch", reader + " needs rendering channel '" + channel_name(c) + "' but the batch has only " +
                               (available.empty() ? std::string("none") : join(channel_names(available))));
    parts.push_back(info.slice(1, offset, offset + channel_width(c)));
  }
  return torch::cat(parts, 1);
}

}  // namespace cgsr
