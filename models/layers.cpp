#include "models/layers.h"

#include <torch/torch.h>

#include "core/error.h"

namespace cgsr {

torch::nn::Conv2d make_conv(int64_t in, int64_t out, int64_t kernel, bool bias) {
  CGSR_CHECK(kernel % 2 == 1, "make_conv: kernel size must be odd");
  CGSR_CHECK(in > 0 && out > 0, "make_conv: channel counts must be positive");
  return torch::nn::Conv2d(torch::nn::Conv2dOptions(in, out, kernel).padding(kernel / 2).bias(bias));
}

int describe_conv(graph::Builder& g, const std::string& name, const torch::nn::Conv2d& conv, int x,
                  graph::Layout out) {
  return g.conv(name, x, conv->weight, conv->bias, conv->weight.size(-1) / 2, std::move(out));
}

void zero_conv(torch::nn::Conv2d& conv) {
  torch::NoGradGuard no_grad;
  conv->weight.zero_();
  if (conv->bias.defined()) conv->bias.zero_();
}

}  // namespace cgsr
