#include "render_data/capture_format.h"

#include <torch/torch.h>

#include <cmath>
#include <limits>

#include "core/error.h"
#include "render_data/render_channels.h"

namespace cgsr {
namespace {

torch::Tensor no_geometry_where(const torch::Tensor& clear, const torch::Tensor& depth) {
  return torch::where(clear, torch::full({}, std::numeric_limits<float>::infinity()), depth);
}

}  // namespace

const std::vector<std::string>& EnumNames<ColorAlpha>::names() {
  static const std::vector<std::string> names = {"ignore", "premultiplied"};
  return names;
}

const std::vector<std::string>& EnumNames<CaptureDepth>::names() {
  static const std::vector<std::string> names = {"normalized", "reversed", "linear", "linear_normalized"};
  return names;
}

const std::vector<std::string>& EnumNames<MotionUnits>::names() {
  static const std::vector<std::string> names = {"pixels", "uv"};
  return names;
}

config::Schema<MotionFormat> motion_format_schema() {
  config::Schema<MotionComponent> c;
  c.field("channels", &MotionComponent::channels, "one channel, or [high, low] channels of one code").range(0, 3)
      .check([](const std::vector<int>& v) { return v.size() == 1 || v.size() == 2; }, "needs one or two channels");
  c.field("scale", &MotionComponent::scale, "value = (code / max code - offset) x scale");
  c.field("offset", &MotionComponent::offset, "subtracted from the normalized code (or float value)");
  config::Schema<MotionFormat> s;
  s.section("x", &MotionFormat::x, c, "horizontal component");
  s.section("y", &MotionFormat::y, c, "vertical component");
  s.field("units", &MotionFormat::units, "pixels, or uv (fractions of width and height)");
  return s;
}

torch::Tensor decode_capture_color(const ImageFile& image, ColorAlpha alpha) {
  const auto& v = image.pixels;
  const int64_t c = v.size(0);
  if (c != 1 && c != 3 && c != 4)
    throw Error("color", "has " + std::to_string(c) + " channel(s); colour must be grey, RGB or RGBA");
  if (image.is_float()) {
    const int64_t outside = ((v < 0) | (v > 1.0f + 1.0f / 512)).sum().item<int64_t>();
    if (outside > 0)
      throw Error("color", std::to_string(outside) +
                               " float value(s) outside [0,1]: colour must be display-referred (tone-map HDR captures first)");
  }
  torch::Tensor rgb = c == 1 ? v.expand({3, v.size(1), v.size(2)}) : v.slice(0, 0, 3);
  if (c == 4 && alpha == ColorAlpha::Premultiplied) {
    const auto a = v.slice(0, 3, 4);
    rgb = torch::where(a > 0, rgb / a.clamp_min(1e-12f), torch::zeros({}));
  }
  return (rgb.clamp(0.0, 1.0) * 255.0f).round_().to(torch::kUInt8).contiguous();
}

CaptureDepthMap decode_capture_depth(const ImageFile& image, const DepthFormat& f) {
  const auto v = image.pixels.slice(0, 0, 1);
  if ((v < 0).any().item<bool>()) throw Error("depth", "negative depth values");
  const bool integer = !image.is_float();
  const double levels = image.max_code();
  const double inv_near = 1.0 / f.near_plane, inv_far = std::isinf(f.far_plane) ? 0.0 : 1.0 / f.far_plane;
  CaptureDepthMap out;
  switch (f.encoding) {
    case CaptureDepth::Normalized:
    case CaptureDepth::Reversed: {
      if ((v > 1.0f + 1e-6f).any().item<bool>()) throw Error("depth", "z-buffer values above 1");
      const auto d = f.encoding == CaptureDepth::Normalized ? v : 1.0f - v;
      out.depth = no_geometry_where(d >= 1.0f, linearize_depth(d, f.near_plane, f.far_plane));
      if (integer) out.precision.inverse_step = (inv_near - inv_far) / levels;
      break;
    }
    case CaptureDepth::Linear: {
      const auto z = v * static_cast<float>((integer ? levels : 1.0) * f.scale);
      out.depth = no_geometry_where((v == 0) | torch::isinf(v), z);
      if (integer) out.precision.linear_step = f.scale;
      break;
    }
    case CaptureDepth::LinearNormalized: {
      if (std::isinf(f.far_plane)) throw Error("depth", "linear_normalized depth needs a finite far plane");
      if ((v > 1.0f + 1e-6f).any().item<bool>()) throw Error("depth", "linear_normalized values above 1");
      out.depth = no_geometry_where((v == 0) | (v >= 1.0f), v * static_cast<float>(f.far_plane));
      if (integer) out.precision.linear_step = f.far_plane / levels;
      break;
    }
  }
  return out;
}

torch::Tensor decode_capture_motion(const ImageFile& image, const MotionFormat& format) {
  const auto& v = image.pixels;
  const int64_t H = v.size(1), W = v.size(2);
  if (!image.is_float() && !format.declared)
    throw Error("motion", std::to_string(image.bits) +
                              "-bit integer motion vectors need a motion_format block (channels, scale, offset) "
                              "saying how codes map to pixels");
  auto component = [&](const MotionComponent& c, const char* axis, int64_t size) {
    for (int ch : c.channels)
      if (ch >= v.size(0))
        throw Error("motion", std::string(axis) + " reads channel " + std::to_string(ch) + " but the image has " +
                                  std::to_string(v.size(0)));
    torch::Tensor value;
    if (image.is_float()) {
      if (c.channels.size() != 1) throw Error("motion", std::string(axis) + ": float images hold a component in one channel");
      value = v[c.channels[0]];
    } else {
      // Integer codes: the high channel's code times (max code + 1) plus the low channel's.
      const double levels = image.max_code();
      const auto code = [&](int ch) { return (v[ch].to(torch::kFloat64) * levels).round(); };
      const auto raw = c.channels.size() == 1 ? code(c.channels[0]) : code(c.channels[0]) * (levels + 1) + code(c.channels[1]);
      const double max_code = c.channels.size() == 1 ? levels : (levels + 1) * (levels + 1) - 1;
      value = raw / max_code;
    }
    auto px = (value.to(torch::kFloat64) - c.offset) * c.scale;
    if (format.units == MotionUnits::Uv) px = px * static_cast<double>(size);
    return px.to(torch::kFloat32);
  };
  return torch::stack({component(format.x, "x", W), component(format.y, "y", H)}, 0).contiguous();
}

}  // namespace cgsr
