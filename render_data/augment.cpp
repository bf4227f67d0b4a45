#include "render_data/augment.h"

#include <torch/torch.h>

#include <cmath>

#include "core/error.h"

namespace cgsr {

Augmentation Augmentation::from_index(int index) {
  CGSR_CHECK(index >= 0 && index < 8, "augmentation index must be in [0, 8)");
  return {index >= 4, index % 4};
}

ColorAugmentation ColorAugmentation::from_uniform(double u_permutation, double u_gain) {
  CGSR_CHECK(u_permutation >= 0 && u_permutation < 1 && u_gain >= 0 && u_gain < 1, "uniform draws must be in [0, 1)");
  return {static_cast<int>(u_permutation * 6), static_cast<float>(std::pow(kMaxGain, 2 * u_gain - 1))};
}

torch::Tensor augment_color(const torch::Tensor& color, const ColorAugmentation& a) {
  static constexpr int64_t kOrders[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  CGSR_CHECK(a.permutation >= 0 && a.permutation < 6, "colour permutation index must be in [0, 6)");
  const int64_t cdim = color.dim() - 3;
  CGSR_CHECK(color.size(cdim) == 3, "colour augmentation needs 3 colour channels");
  const auto& order = kOrders[a.permutation];
  torch::Tensor t = a.permutation ? color.index_select(cdim, torch::tensor({order[0], order[1], order[2]})) : color;
  return a.gain == 1.0f ? t.contiguous() : t.mul(a.gain).clamp_(0, 1);
}

torch::Tensor augment_info_color(const torch::Tensor& info, const std::vector<RenderChannel>& channels,
                                 const ColorAugmentation& a) {
  const int64_t cdim = info.dim() - 3;
  int64_t offset = 0;
  torch::Tensor out = info;
  for (auto c : channels) {
    if (c == RenderChannel::Bsp || c == RenderChannel::History) {
      if (out.is_same(info)) out = info.clone();
      out.narrow(cdim, offset, 3).copy_(augment_color(info.narrow(cdim, offset, 3), a));
    }
    offset += channel_width(c);
  }
  return out;
}

torch::Tensor augment_image(const torch::Tensor& image, const Augmentation& a) {
  const int64_t h = image.dim() - 2, w = image.dim() - 1;
  torch::Tensor t = a.flip ? image.flip({w}) : image;
  // torch.rot90 with dims (H, W) turns the first axis towards the second: counter-clockwise as
  // displayed (rows run down the screen).
  if (a.rotations % 4) t = torch::rot90(t, a.rotations % 4, {h, w});
  return t.contiguous();
}

torch::Tensor augment_info(const torch::Tensor& info, const std::vector<RenderChannel>& channels, const Augmentation& a) {
  torch::Tensor t = augment_image(info, a);
  const int64_t cdim = info.dim() - 3;
  int64_t offset = 0;
  for (auto c : channels) {
    const int width = channel_width(c);
    if (c == RenderChannel::Normal || c == RenderChannel::Motion || c == RenderChannel::Jitter ||
        c == RenderChannel::HistoryOut) {
      // Components in image orientation: motion and jitter are (x right, y down); normals (x right, y up).
      const bool y_up = c == RenderChannel::Normal;
      const int64_t at = offset + (c == RenderChannel::HistoryOut ? 4 : 0);  // history_out: its motion
      auto x = t.select(cdim, at).clone(), y = t.select(cdim, at + 1).clone();
      if (a.flip) x = -x;
      for (int r = 0; r < a.rotations % 4; ++r) {
        // Counter-clockwise: y-down (dx, dy) -> (dy, -dx); y-up (x, y) -> (-y, x).
        auto nx = y_up ? -y : y, ny = y_up ? x : -x;
        x = nx;
        y = ny;
      }
      t.select(cdim, at).copy_(x);
      t.select(cdim, at + 1).copy_(y);
    }
    offset += width;
  }
  CGSR_CHECK(offset == info.size(cdim), "info tensor width does not match its channel list");
  return t;
}

}  // namespace cgsr
