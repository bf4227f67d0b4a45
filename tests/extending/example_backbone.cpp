// The backbone of docs/extending.md, as models/backbones/example.cpp would hold it. The tests compile
// it into their own binary and register it themselves (tests/extending/test_extending.cpp).
//
// example: conv 3x3 (the features) -> residual blocks (conv 3x3, ReLU, conv 3x3, plus the block's
// input) -> plus the features -> conv 3x3 to up x s*s channels, pixel shuffle -> conv 3x3 to RGB.
// Layer groups: features (the first conv and every block's second conv: one residual stream),
// block<i>_mid (a block's inner channels), up (the channels after the pixel shuffle).
#include <torch/nn/modules/container/modulelist.h>
#include <torch/torch.h>

#include "models/backbone.h"
#include "models/backbone_registry.h"
#include "models/layers.h"

namespace cgsr {

// A residual block. Its module is blocks.<i>, so its ops are named backbone.blocks.<i>.*: that
// is how subnets skip a block and how blocks are ranked (models/subnet.h, importance/).
class ToyBlockImpl : public torch::nn::Module {
 public:
  ToyBlockImpl(int index, int64_t features, int64_t mid) : index_(index) {
    conv1 = register_module("conv1", make_conv(features, mid, 3));
    conv2 = register_module("conv2", make_conv(mid, features, 3));
  }
  torch::Tensor forward(const torch::Tensor& x) { return conv2(torch::relu(conv1(x))) + x; }
  // forward() op for op; conv2 writes into the residual stream, so it takes the input's layout.
  int describe(graph::Builder& g, int x) const {
    auto scope = g.scope("blocks." + std::to_string(index_));
    const auto mid = graph::group_layout(block_group(index_, "mid"), conv1->weight.size(0));
    const int y = g.relu(describe_conv(g, "conv1", conv1, x, mid));
    return g.add(describe_conv(g, "conv2", conv2, y, g.value(x).layout), x);
  }
  torch::nn::Conv2d conv1{nullptr}, conv2{nullptr};

 private:
  int index_;
};
TORCH_MODULE(ToyBlock);

class ToyImpl : public BackboneImpl {
 public:
  explicit ToyImpl(const ArchSpec& spec) : scale_(spec.scale) {
    const int64_t features = spec.group_width("features"), up = spec.group_width("up");
    head = register_module("head", make_conv(3, features, 3));
    blocks = register_module("blocks", torch::nn::ModuleList());
    for (int i = 0; i < spec.blocks; ++i)
      blocks->push_back(ToyBlock(i, features, spec.group_width(block_group(i, "mid"))));
    upsample = register_module("upsample", make_conv(features, up * scale_ * scale_, 3));
    tail = register_module("tail", make_conv(up, 3, 3));
  }

  // The RIT joins between these two (models/rit.h).
  ExtractedFeatures extract(const torch::Tensor& lr_color) override {
    const auto features = head(lr_color);
    auto x = features;
    for (const auto& block : *blocks) x = block->as<ToyBlock>()->forward(x);
    return {x + features, {}};
  }
  Reconstruction reconstruct(const torch::Tensor& features, const torch::Tensor&, const HrFusion& at_hr) override {
    auto x = torch::pixel_shuffle(upsample(features), scale_);
    if (at_hr) x = at_hr(x);  // the RIT's HR branch (rit.source: hr_fuse)
    return {tail(x), x};
  }

  // The graph of each part, op for op as above: graph::run of it equals forward() bit for bit.
  ExtractedPorts describe_extract(graph::Builder& g, int color) const override {
    const int features = describe_conv(g, "head", head, color, graph::group_layout("features", head->weight.size(0)));
    int x = features;
    for (const auto& block : *blocks) x = block->as<ToyBlock>()->describe(g, x);
    return {g.add(x, features), -1};
  }
  ReconstructionPorts describe_reconstruct(graph::Builder& g, int features, int,
                                           const HrFusionPort& at_hr) const override {
    const int64_t r2 = scale_ * scale_;  // a pixel-shuffle group: each of its channels r*r times
    int x = describe_conv(g, "upsample", upsample, features,
                          graph::group_layout("up", upsample->weight.size(0) / r2, r2));
    x = g.pixel_shuffle(x, scale_);
    if (at_hr) x = at_hr(x);
    return {describe_conv(g, "tail", tail, x, graph::fixed_layout("rgb", 3)), x};
  }

  std::string feature_group() const override { return "features"; }
  int64_t feature_factor() const override { return 1; }  // the features are at LR
  std::string hr_feature_group() const override { return "up"; }
  std::string hr_fusion_group() const override { return "up"; }

 private:
  int64_t scale_;
  torch::nn::Conv2d head{nullptr}, upsample{nullptr}, tail{nullptr};
  torch::nn::ModuleList blocks{nullptr};
};

// Named for the file: models/backbones/example.cpp defines register_backbone_example.
void register_backbone_example(Registry<BackboneInfo>& registry) {
  BackboneInfo info;
  info.description = "example: a small residual network with a pixel-shuffle upsampler (docs/extending.md)";
  info.default_blocks = 2;
  info.min_blocks = 1;
  info.max_blocks = 16;
  info.block_group_suffixes = {"mid"};
  info.groups = [](int scale, int blocks) {
    std::vector<GroupDefault> groups = {{"features", 16}};
    for (int i = 0; i < blocks; ++i) groups.push_back({block_group(i, "mid"), 16});
    groups.push_back({"up", 8});
    return groups;
  };
  info.build = [](const ArchSpec& spec) -> std::shared_ptr<BackboneImpl> { return std::make_shared<ToyImpl>(spec); };
  registry.add("example", info, info.description);
}

}  // namespace cgsr
