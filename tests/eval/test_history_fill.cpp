// The history-fill upscaler (eval/baselines/history_fill.h): each output pixel is the history
// channel's sample where it has one and bicubic elsewhere, it beats bicubic on rendered jittered
// frames, and wrong shapes are a clear error. On the same frames, PAN's image skip taken at the
// jitter channel (rit.skip_at_jitter) beats the unjittered one.
#include <gtest/gtest.h>

#include <torch/torch.h>

#include <cmath>

#include "core/error.h"
#include "eval/baselines/history_fill.h"
#include "eval/baselines/interpolation.h"
#include "eval/upscaler.h"
#include "models/sr_network.h"
#include "render_data/dataset.h"
#include "render_data/history_channel.h"
#include "render_data/patch_sampler.h"
#include "tests/support/cli_runner.h"
#include "tests/support/tiny_data.h"

namespace cgsr {
namespace history_fill_test {  // named: the tests compile as one unity translation unit

double psnr(const torch::Tensor& a, const torch::Tensor& b) {
  return 10 * std::log10(1.0 / (a - b).pow(2).mean().item<double>());
}

// The tiny scene jittered, its walk spread over 24 frames so that samples survive a few frames;
// rendered once per process.
const std::filesystem::path& jittered_tiny() {
  static const std::filesystem::path dir = [] {
    const auto d = test::scratch_dir("history-fill") / "data";
    const auto r = test::run_cgsr("render --config " + std::string(CGSR_SOURCE_DIR) +
                                  "/configs/scenes/tiny.yaml --set frames=24 --set jitter.sequence=halton "
                                  "--set jitter.phases=16 --threads 1 --out " + d.string());
    EXPECT_EQ(r.exit_code, 0) << r.all();
    return d;
  }();
  return dir;
}

TEST(HistoryFill, TakesTheSamplesAndBicubicElsewhereAndBeatsBicubic) {
  const Dataset data = Dataset::open(jittered_tiny(), test::with_channels({"history"}));
  auto upscaler = classic_upscalers().get("history")(2);
  ASSERT_EQ(upscaler->channels(), std::vector<RenderChannel>{RenderChannel::History});
  std::vector<torch::Tensor> filled, bicubic, plain_bicubic, truth;
  for (int t = kHistoryFrames; t < data.frame_count(); ++t) {
    const Batch b = frame_batch(data, t, 2, upscaler->channels(), upscaler->depth_encoding());
    const torch::Tensor out = upscaler->upscale(b);
    const torch::Tensor sampled = (b.hr_info.narrow(1, 3, 1) > 0).expand_as(out);
    ASSERT_EQ(b.lr_jitter.size(), 1u);
    EXPECT_NE(b.lr_jitter[0], (std::array<double, 2>{0, 0}));
    const torch::Tensor cubic = upscale_bicubic_jittered(b.lr_color, 2, b.lr_jitter);
    EXPECT_TRUE(torch::equal(classic_upscalers().get("bicubic_at_jitter")(2)->upscale(b), cubic));
    ASSERT_GT(sampled.sum().item<int64_t>(), 0);
    EXPECT_TRUE(torch::equal(out.masked_select(sampled), b.hr_info.narrow(1, 0, 3).masked_select(sampled)));
    EXPECT_TRUE(torch::equal(out.masked_select(~sampled), cubic.masked_select(~sampled)));
    filled.push_back(out.clamp(0, 1));
    bicubic.push_back(cubic.clamp(0, 1));
    plain_bicubic.push_back(upscale_bicubic(b.lr_color, 2).clamp(0, 1));
    truth.push_back(b.hr_color);
  }
  const double fill_psnr = psnr(torch::cat(filled), torch::cat(truth));
  const double bicubic_psnr = psnr(torch::cat(bicubic), torch::cat(truth));
  const double plain_psnr = psnr(torch::cat(plain_bicubic), torch::cat(truth));
  std::cout << "history fill " << fill_psnr << " dB, bicubic at the jitter " << bicubic_psnr
            << " dB, bicubic unaware of it " << plain_psnr << " dB\n";
  EXPECT_GT(bicubic_psnr, plain_psnr + 0.5);  // measured 27.91 against 26.73: knowing the jitter puts the samples where they belong
  EXPECT_GT(fill_psnr, bicubic_psnr + 0.05);  // measured 28.03 against 27.91 (the walk is fast here)
}

// The jitter channel carries each frame's LR jitter at the output resolution, and rit.skip_at_jitter
// reads it: with the body's last conv at zero, PAN's output is its image skip alone, which at the
// jitter beats the unjittered skip on the rendered frames (a wrong sign or axis would lose).
TEST(SkipAtJitter, TheJitterChannelPutsPansSkipWhereTheSamplesAre) {
  const Dataset data = Dataset::open(jittered_tiny(), test::with_channels({"jitter"}));
  ArchSpec spec = default_spec("pan", 2);
  spec.rit.enabled = true;
  spec.rit.channels = {"jitter"};
  spec.rit.source = RitSource::HrFuse;
  spec.rit.hr_width = 4;
  ArchSpec plain_spec = spec;
  spec.rit.skip_at_jitter = true;
  SRNetwork net(resolve_spec(spec)), plain(resolve_spec(plain_spec));
  torch::NoGradGuard no_grad;
  for (auto& p : net->named_parameters())
    if (p.key().find("conv_last") != std::string::npos) p.value().zero_();
  auto theirs = plain->named_parameters();
  for (auto& p : net->named_parameters()) theirs[p.key()].copy_(p.value());  // the option adds no parameter
  std::vector<torch::Tensor> at_jitter, unjittered, truth;
  for (int t = 0; t < data.frame_count(); t += 3) {
    const Batch b = frame_batch(data, t, 2, net->input_channels(), net->depth_encoding());
    ASSERT_EQ(b.lr_jitter.size(), 1u);
    // Two planes, the LR frame's jitter everywhere at the output resolution.
    const auto planes = b.hr_info;
    ASSERT_EQ(planes.sizes(), (std::vector<int64_t>{1, 2, b.hr_color.size(2), b.hr_color.size(3)}));
    EXPECT_TRUE(torch::equal(planes.select(1, 0), torch::full_like(planes.select(1, 0), static_cast<float>(b.lr_jitter[0][0]))));
    EXPECT_TRUE(torch::equal(planes.select(1, 1), torch::full_like(planes.select(1, 1), static_cast<float>(b.lr_jitter[0][1]))));
    at_jitter.push_back(net->forward(b.lr_color, planes).clamp(0, 1));
    unjittered.push_back(plain->forward(b.lr_color, planes).clamp(0, 1));
    EXPECT_TRUE(torch::allclose(net->forward(b.lr_color, torch::zeros_like(planes)), plain->forward(b.lr_color, planes),
                                1e-5, 1e-5));  // at jitter 0 the skip is PAN's own
    truth.push_back(b.hr_color);
  }
  const double jitter_psnr = psnr(torch::cat(at_jitter), torch::cat(truth));
  const double plain_psnr = psnr(torch::cat(unjittered), torch::cat(truth));
  std::cout << "bilinear skip at the jitter " << jitter_psnr << " dB, unjittered " << plain_psnr << " dB\n";
  EXPECT_GT(jitter_psnr, plain_psnr + 0.3);  // measured 27.50 against 26.96
}

TEST(HistoryFill, WrongShapesAreAClearError) {
  const auto lr = torch::rand({1, 3, 4, 6});
  EXPECT_EQ(upscale_history_fill(lr, torch::zeros({1, 4, 8, 12}), 2, {}).sizes(), (std::vector<int64_t>{1, 3, 8, 12}));
  for (const auto& history : {torch::zeros({1, 3, 8, 12}), torch::zeros({1, 4, 8, 8}), torch::zeros({2, 4, 8, 12})}) {
    try {
      upscale_history_fill(lr, history, 2, {});
      ADD_FAILURE() << "accepted a history of shape " << history.sizes();
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("[1,4,8,12]"), std::string::npos) << e.what();
    }
  }
}

}  // namespace history_fill_test
}  // namespace cgsr
