// The sandwich fine-tuning's extra loss: with in-place distillation the narrower patterns learn
// the widest pattern's output, without it the HR frame; Eq. 4's L1 term adds only when asked.
#include <gtest/gtest.h>

#include "pruning/dynamic_pruning.h"
#include "render_data/patch_sampler.h"
#include "tests/pruning/pruning_cases.h"
#include "tests/support/tiny_data.h"
#include "train/losses.h"

using namespace cgsr;
using namespace cgsr::test;

TEST(DynamicPruning, NarrowerPatternsLearnTheWidestOutputWhenDistilling) {
  torch::manual_seed(21);
  const Dataset data = Dataset::open(tiny_data());
  SRNetwork net(small_spec("pan", 2, 2, 6, 8));
  randomize(*net);
  const PatternPool pool = nested_pool(find_units(net->describe(false)), {1.0, 0.5});
  DynamicPruning dynamic(net, data, pool, SamplerOptions{});
  const Batch batch = frame_batch(data, 0, 2, net->input_channels(), net->depth_encoding());

  FinetuneOptions options;
  options.sampled_patterns = 0;  // the narrowest pattern only
  const auto narrow = PatternMasks(*net, pool);
  TrainOutput narrow_output;
  {
    torch::NoGradGuard no_grad;
    narrow_output.image = narrow.forward(batch.lr_color, torch::Tensor(), narrow.group_masks(1, 1));
  }
  torch::NoGradGuard no_grad;
  // Given its own output as the widest's, the narrowest pattern has nothing left to learn.
  options.distill = true;
  EXPECT_LT(dynamic.hooks(options).extra_loss(batch, narrow_output, 0).item<double>(), 1e-12);
  // Without distillation it learns the HR frame.
  options.distill = false;
  const double to_hr = dynamic.hooks(options).extra_loss(batch, narrow_output, 0).item<double>();
  EXPECT_NEAR(to_hr, reconstruction_error(narrow_output.image, batch.hr_color, ErrorNorm::L2).item<double>(), 1e-6);
  EXPECT_GT(to_hr, 1e-6);
  // Eq. 4's L1 term on the weights the pattern leaves out, when asked for.
  options.lambda_pruned = 1e-3;
  const double with_l1 = dynamic.hooks(options).extra_loss(batch, narrow_output, 0).item<double>();
  EXPECT_NEAR(with_l1 - to_hr, 1e-3 * narrow.pruned_weight_l1(narrow.group_masks(1, 1)).item<double>(), 1e-6);
}
