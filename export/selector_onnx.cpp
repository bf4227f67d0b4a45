#include "export/selector_onnx.h"

#include <torch/torch.h>

#include <functional>

#include "core/error.h"
#include "core/text.h"
#include "export/onnx_builder.h"
#include "render_data/render_channels.h"

namespace cgsr {

namespace {

torch::Tensor box_matrix(int64_t in, int64_t out, const std::function<std::pair<int64_t, int64_t>(int64_t)>& window) {
  auto m = torch::zeros({out, in}, torch::kDouble);
  for (int64_t i = 0; i < out; ++i) {
    const auto [begin, end] = window(i);
    CGSR_CHECK(begin >= 0 && end <= in && end > begin, "box pooling: empty window");
    m[i].slice(0, begin, end).fill_(1.0 / static_cast<double>(end - begin));
  }
  return m.to(torch::kFloat);
}

// Tensor names: inputs and outputs as in the header; everything else "<step>.<role>".
class SelectorWriter {
 public:
  SelectorWriter(const DynamicSamplersImpl& s, int64_t width, int64_t height,
                 const std::vector<std::pair<std::string, std::string>>& metadata)
      : s_(s), width_(width), height_(height), b_("cgsr_selector", metadata) {}

  std::string build() {
    const auto channels = s_.options().render_channels();
    const int64_t c = total_width(channels), g = s_.options().grid;
    const std::string doc = "rendering information (" + join(channel_names(channels)) +
                            ") at the LR size, motion in pixels";
    b_.declare_input(b_.claim(kSelectorInfoInput), onnx::TensorProto::FLOAT, {1, c, height_, width_},
                     "this frame's " + doc);
    b_.declare_input(b_.claim(kSelectorPreviousInput), onnx::TensorProto::FLOAT, {1, c, height_, width_},
                     "the previous frame's " + doc + "; this frame's again on a first frame");
    const std::string current = pooled(kSelectorInfoInput, "current", channels);
    const std::string previous = pooled(kSelectorPreviousInput, "previous", channels);
    const std::string change = b_.claim("change");
    b_.node("Sub", "change", {current, previous}, {change});
    const std::string input = b_.claim("sampler_input");
    OnnxBuilder::attr(b_.node("Concat", "sampler_input", {current, change}, {input}), "axis", int64_t{1});

    std::string x = relu(conv("conv1", input, *s_.conv1), "conv1.relu");
    x = box_pool("pool2", x, g, g, ceil_pool_matrix(g, 2), ceil_pool_matrix(g, 2));
    x = relu(conv("conv2", x, *s_.conv2), "conv2.relu");
    const std::string global = b_.claim("global");
    b_.node("GlobalAveragePool", "global", {x}, {global});
    x = conv("head", global, *s_.head);  // [1, K, 1, 1]
    const int64_t k = s_.head->weight.size(0);
    const std::string flat = b_.claim("head.flat");
    b_.node("Reshape", "head.flat", {x, b_.int64_initializer("head.shape", {1, k})}, {flat});
    b_.node("Add", "scores", {flat, b_.initializer("invalid_mask", s_.invalid_mask(), {1, k})},
            {b_.claim(kSelectorScores)});
    auto* argmax = b_.node("ArgMax", "pattern", {kSelectorScores}, {b_.claim(kSelectorPattern)});
    OnnxBuilder::attr(argmax, "axis", int64_t{1});
    OnnxBuilder::attr(argmax, "keepdims", int64_t{0});
    OnnxBuilder::attr(argmax, "select_last_index", int64_t{0});  // ties: the first, as torch's argmax
    b_.declare_output(kSelectorScores, onnx::TensorProto::FLOAT, {1, k},
                      "score per pattern (invalid patterns -1e9); the highest is chosen");
    b_.declare_output(kSelectorPattern, onnx::TensorProto::INT64, {1}, "the pattern to run: argmax of scores");
    return b_.serialize("selector export");
  }

 private:
  // sampler_input's per-frame part: motion to frame fractions, clipped, then pooled to the grid.
  std::string pooled(const std::string& in, const std::string& prefix, const std::vector<RenderChannel>& channels) {
    std::vector<std::string> parts;
    int64_t at = 0, run_start = 0;
    const auto slice = [&](int64_t from, int64_t to, const std::string& name) {
      const std::string out = b_.claim(name);
      b_.node("Slice", name, {in, b_.int64_initializer(name + ".starts", {from}), b_.int64_initializer(name + ".ends", {to}),
                              b_.int64_initializer(name + ".axes", {1})},
              {out});
      return out;
    };
    bool has_motion = false;
    for (auto ch : channels) {
      if (ch == RenderChannel::Motion) {
        has_motion = true;
        const std::string base = prefix + ".motion";
        if (at > run_start) parts.push_back(slice(run_start, at, prefix + ".before_motion"));
        const std::string raw = slice(at, at + 2, base);
        // The same float factors sampler_input multiplies by: 1/W for dx, 1/H for dy.
        const auto factors = torch::tensor({1.0 / static_cast<double>(width_), 1.0 / static_cast<double>(height_)},
                                           torch::kDouble)
                                 .to(torch::kFloat);
        const std::string scaled = b_.claim(base + ".scaled");
        b_.node("Mul", base + ".scale", {raw, b_.initializer(base + ".factors", factors, {1, 2, 1, 1})}, {scaled});
        const std::string clipped = b_.claim(base + ".clipped");
        b_.node("Clip", base + ".clip",
                {scaled, b_.initializer(base + ".min", torch::tensor(-1.0f), {}),
                 b_.initializer(base + ".max", torch::tensor(1.0f), {})},
                {clipped});
        parts.push_back(clipped);
        run_start = at + 2;
      }
      at += channel_width(ch);
    }
    std::string x = in;
    if (has_motion) {
      if (at > run_start) parts.push_back(slice(run_start, at, prefix + ".after_motion"));
      x = b_.claim(prefix + ".normalized");
      if (parts.size() == 1) {
        b_.node("Identity", prefix + ".normalized", {parts.front()}, {x});
      } else {
        OnnxBuilder::attr(b_.node("Concat", prefix + ".normalized", parts, {x}), "axis", int64_t{1});
      }
    }
    const int64_t g = s_.options().grid;
    return box_pool(prefix + ".grid", x, height_, width_, adaptive_pool_matrix(height_, g),
                    adaptive_pool_matrix(width_, g));
  }

  // Separable box pooling of [1, C, h, w] by rows[out_h, h] and cols[out_w, w]. When every window
  // is the same size and they tile the input, AveragePool computes the same (cheaper at 720p);
  // otherwise two MatMuls with the fixed matrices: rows @ x @ cols^T.
  std::string box_pool(const std::string& name, const std::string& x, int64_t h, int64_t w,
                       const torch::Tensor& rows, const torch::Tensor& cols) {
    const int64_t oh = rows.size(0), ow = cols.size(0);
    const std::string out = b_.claim(name);
    const bool tiles = h % oh == 0 && w % ow == 0 && torch::equal(rows, adaptive_pool_matrix(h, oh)) &&
                       torch::equal(cols, adaptive_pool_matrix(w, ow));
    if (tiles) {
      auto* n = b_.node("AveragePool", name, {x}, {out});
      OnnxBuilder::attr(n, "kernel_shape", std::vector<int64_t>{h / oh, w / ow});
      OnnxBuilder::attr(n, "strides", std::vector<int64_t>{h / oh, w / ow});
      return out;
    }
    const std::string across = b_.claim(name + ".columns");
    b_.node("MatMul", name + ".columns", {x, b_.initializer(name + ".cols_t", cols.t().contiguous(), {w, ow})},
            {across});
    b_.node("MatMul", name, {b_.initializer(name + ".rows", rows, {oh, h}), across}, {out});
    return out;
  }

  std::string conv(const std::string& name, const std::string& x, const torch::nn::Conv2dImpl& conv) {
    const auto& w = conv.weight;
    const auto& o = conv.options;
    CGSR_CHECK(c10::holds_alternative<torch::ExpandingArray<2>>(o.padding()), "selector export: " + name +
                                                                                  " has a padding mode, not sizes");
    const int64_t pad = (*c10::get<torch::ExpandingArray<2>>(o.padding()))[0];
    std::vector<std::string> inputs = {x, b_.initializer(name + ".weight", w, w.sizes().vec())};
    if (conv.bias.defined()) inputs.push_back(b_.initializer(name + ".bias", conv.bias, {w.size(0)}));
    const std::string out = b_.claim(name);
    auto* n = b_.node("Conv", name, inputs, {out});
    OnnxBuilder::attr(n, "kernel_shape", std::vector<int64_t>{w.size(2), w.size(3)});
    OnnxBuilder::attr(n, "pads", std::vector<int64_t>{pad, pad, pad, pad});
    OnnxBuilder::attr(n, "strides", std::vector<int64_t>{(*o.stride())[0], (*o.stride())[1]});
    OnnxBuilder::attr(n, "dilations", std::vector<int64_t>{(*o.dilation())[0], (*o.dilation())[1]});
    OnnxBuilder::attr(n, "group", o.groups());
    return out;
  }

  std::string relu(const std::string& x, const std::string& name) {
    const std::string out = b_.claim(name);
    b_.node("Relu", name, {x}, {out});
    return out;
  }

  const DynamicSamplersImpl& s_;
  int64_t width_, height_;
  OnnxBuilder b_;
};

}  // namespace

torch::Tensor adaptive_pool_matrix(int64_t in, int64_t out) {
  CGSR_CHECK(in > 0 && out > 0, "adaptive pooling needs positive sizes");
  return box_matrix(in, out, [&](int64_t i) {
    return std::make_pair(i * in / out, ((i + 1) * in + out - 1) / out);
  });
}

torch::Tensor ceil_pool_matrix(int64_t in, int64_t k) {
  CGSR_CHECK(in > 0 && k > 0, "pooling needs positive sizes");
  const int64_t out = (in + k - 1) / k;
  return box_matrix(in, out, [&](int64_t i) { return std::make_pair(i * k, std::min(i * k + k, in)); });
}

std::string selector_onnx_bytes(const DynamicSamplersImpl& samplers, int64_t width, int64_t height,
                                const std::vector<std::pair<std::string, std::string>>& metadata) {
  if (samplers.patterns().size() != 1)
    throw Error("selector export", "a hybrid model's sampler has one head; this one has " +
                                       std::to_string(samplers.patterns().size()) + " units");
  if (width <= 0 || height <= 0)
    throw Error("selector export", "needs a positive LR size, got " + std::to_string(width) + "x" +
                                       std::to_string(height));
  return SelectorWriter(samplers, width, height, metadata).build();
}

}  // namespace cgsr
