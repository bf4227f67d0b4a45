// Recurrent networks (the history_out channel, render_channels.h): the channel's reprojection, the
// sampler's sequences, training on them, evaluation in order with a reset at each scene cut, and
// the exported file reproduced by ONNX Runtime over a sequence that crosses the cut.
#include <gtest/gtest.h>

#include <limits>

#include "core/image_io.h"
#include "eval/evaluation.h"
#include "eval/upscaler.h"
#include "models/graph.h"
#include "models/model_file.h"
#include "render_data/history_channel.h"
#include "render_data/patch_sampler.h"
#include "tests/support/cli_runner.h"
#include "tests/support/eval_frames.h"
#include "tests/support/scratch_dir.h"
#include "tests/support/tiny_data.h"

namespace cgsr {
namespace recurrent_network_test {  // named: the tests compile as one unity translation unit

namespace fs = std::filesystem;
using test::run_cgsr;
using test::with_channels;

// The tiny scene, then its walk over 24 frames: the cut is at frame 6.
const fs::path& walk_set() {
  static const fs::path set = test::two_scene_walk("recurrent-scenes");
  return set;
}
constexpr int kCut = 6;

double psnr_of(const torch::Tensor& a, const torch::Tensor& b) {
  return 10 * std::log10(1.0 / (a - b).pow(2).mean().item<double>());
}

// The colour of `image` [3,H,W] at the pixels of `mask` [H,W]: [3, n].
torch::Tensor at(const torch::Tensor& image, const torch::Tensor& mask) {
  return image.index({torch::indexing::Slice(), mask});
}

// The rendered HR frame t-1 read at p + motion (the warp the network applies to its own previous
// output) reproduces frame t where the channel says valid, far better than frame t-1 unwarped;
// what the depth test rejects is farther from the truth; a scene's first frame has no valid pixel.
TEST(RecurrentNetwork, TheChannelsWarpReproducesTheNextFrameWhereValid) {
  const Dataset all = Dataset::open(walk_set());
  const Dataset data = Dataset::open(walk_set(), with_channels({"history_out"}));
  const size_t hr = 1;
  EXPECT_EQ(data.frame(kCut, hr)->history_out[3].sum().item<float>(), 0.0f);
  EXPECT_EQ(data.frame(0, hr)->history_out[3].sum().item<float>(), 0.0f);
  std::vector<torch::Tensor> warped_valid, still_valid, truth_valid, warped_rejected, truth_rejected;
  int64_t valid_pixels = 0, pixels = 0;
  for (int t = kCut + 1; t < data.frame_count(); ++t) {
    const torch::Tensor channel = data.frame(t, hr)->history_out;
    const Frame now = all.load(t, hr), before = all.load(t - 1, hr);
    ASSERT_TRUE(torch::equal(channel.narrow(0, 4, 2), now.motion));
    ASSERT_EQ(channel.narrow(0, 0, 3).abs().sum().item<float>(), 0.0f);  // the runner's part
    const torch::Tensor previous = before.color_float(), truth = now.color_float();
    const torch::Tensor warped =
        graph::apply_sample(previous.unsqueeze(0), now.motion.unsqueeze(0), 1, graph::ResizeMode::Bilinear)[0];
    const torch::Tensor valid = channel[3] == 1;
    warped_valid.push_back(at(warped, valid));
    still_valid.push_back(at(previous, valid));
    truth_valid.push_back(at(truth, valid));
    valid_pixels += valid.sum().item<int64_t>();
    pixels += valid.numel();
    // Without the depth test: what it rejected (inside the frame, not the sky).
    const double none = std::numeric_limits<double>::max();
    const torch::Tensor loose = history_out_channel(now.depth, now.motion, before.depth, "loose", {none, none, none});
    const torch::Tensor rejected = (loose[3] == 1) & ~valid;
    warped_rejected.push_back(at(warped, rejected));
    truth_rejected.push_back(at(truth, rejected));
  }
  const auto tv = torch::cat(truth_valid, 1), tr = torch::cat(truth_rejected, 1);
  const double warped = psnr_of(torch::cat(warped_valid, 1), tv), still = psnr_of(torch::cat(still_valid, 1), tv);
  const double rejected = tr.size(1) ? psnr_of(torch::cat(warped_rejected, 1), tr) : 0;
  const double coverage = static_cast<double>(valid_pixels) / static_cast<double>(pixels);
  std::cout << "valid " << coverage << " of the pixels: warped " << warped << " dB, unwarped " << still
            << " dB; rejected by depth " << tr.size(1) << " at " << rejected << " dB\n";
  // Measured: 90% valid at 31.3 dB against 19.1 unwarped; 3314 pixels rejected at 27.2 dB (at
  // the history channel's 10% bound: 28% valid, and the 63% it rejected at 30.7 dB).
  EXPECT_GT(coverage, 0.8);
  EXPECT_GT(warped, still + 6.0);
  EXPECT_GT(warped, 28.0);
  EXPECT_GT(tr.size(1), 1000);
  EXPECT_LT(rejected, warped - 2.0);
}

// Sequences: T consecutive frames of one scene per item, step t's items at t * N, the drawn frame
// among them; the validity ends where the motion leaves the window; T = 1 draws what it always did.
TEST(RecurrentNetwork, TheSamplerDrawsSequencesInOneScene) {
  const Dataset data = Dataset::open(walk_set(), with_channels({"history_out"}));
  PatchSamplerOptions o;
  o.patch_size = 12;
  o.batch_size = 6;
  o.channels = {RenderChannel::HistoryOut};
  o.seed = 3;
  o.prefetch = 0;
  PatchSampler single(data, o);
  o.sequence_length = 3;
  PatchSampler sequences(data, o);
  for (int k = 0; k < 4; ++k) {
    const Batch one = single.batch(k), b = sequences.batch(k);
    ASSERT_EQ(b.lr_color.size(0), 18);
    ASSERT_EQ(b.frames.size(), 18u);
    for (int i = 0; i < 6; ++i) {
      const SceneInfo& scene = data.scene_of(b.frames[i]);
      bool holds_drawn = false;
      for (int t = 0; t < 3; ++t) {
        const int f = b.frames[static_cast<size_t>(t * 6 + i)];
        EXPECT_EQ(f, b.frames[i] + t);
        EXPECT_TRUE(scene.contains(f)) << f;
        holds_drawn = holds_drawn || f == one.frames[i];
      }
      EXPECT_TRUE(holds_drawn) << i;
    }
    // Valid only where p + 0.5 + motion stays in the 24 x 24 HR window.
    const auto info = b.hr_info;
    const auto x = torch::arange(24, torch::kFloat32).add(0.5).view({1, 1, 24}) + info.select(1, 4);
    const auto y = torch::arange(24, torch::kFloat32).add(0.5).view({1, 24, 1}) + info.select(1, 5);
    const auto outside = (x < 0) | (x >= 24) | (y < 0) | (y >= 24);
    EXPECT_EQ(info.select(1, 3).masked_select(outside).sum().item<float>(), 0.0f);
  }
  o.sequence_length = 0;
  EXPECT_THROW(PatchSampler(data, o), Error);
  o.sequence_length = 7;  // the first scene has 6 frames
  try {
    PatchSampler too_long(data, o);
    FAIL() << "sequences longer than a scene";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("scene 'tiny_a' has 6 frames"), std::string::npos) << e.what();
  }
}

// An upscaler that says it is recurrent and records, in order, the frames it runs and the resets.
class RecordingRecurrent : public Upscaler {
 public:
  std::string name() const override { return "recording"; }
  int scale() const override { return 2; }
  bool recurrent() const override { return true; }
  void reset_history() override { seen.push_back(kReset); }
  torch::Tensor upscale(const Batch& batch) override {
    seen.push_back(batch.frames.front());
    return bicubic_->upscale(batch);
  }
  static constexpr int kReset = -1;
  std::vector<int> seen;

 private:
  std::unique_ptr<Upscaler> bicubic_ = classic_upscalers().get("bicubic")(2);
};


// Evaluation runs a recurrent upscaler over every frame of a scene from its first, in order,
// though it scores only the range; at the cut it starts again.
TEST(RecurrentNetwork, EvaluationRunsEachSceneInOrderFromItsFirstFrame) {
  const Dataset data = Dataset::open(walk_set());
  RecordingRecurrent recording;
  const EvalResult r = evaluate(recording, data, test::all_frames("3:9"));
  const int reset = RecordingRecurrent::kReset;
  EXPECT_EQ(recording.seen, (std::vector<int>{reset, 0, 1, 2, 3, 4, 5, reset, 6, 7, 8}));
  ASSERT_EQ(r.frames.size(), 6u);
  EXPECT_EQ(r.frames.front().frame, 3);
}

// A recurrent PAN x2 (depth and history_out, its convolution reading depth alone through hr_fuse,
// its previous output blended in) trains 2 steps on sequences and is evaluated twice to the same
// outputs; the frame after the cut is what the network gives that frame alone, a frame inside a
// scene is not; ONNX Runtime reproduces the exported file over 8 frames across the cut, each fed
// cgsr's previous output.
TEST(RecurrentNetwork, TrainsEvaluatesAndExportsOverASequenceWithACut) {
  const auto dir = test::scratch_dir("recurrent-train");
  const auto train = run_cgsr("train --data " + walk_set().string() +
                              " --model pan --steps 2 --threads 1 --set schedule.batch_size=2 --set schedule.patch_size=16"
                              " --set schedule.val_frames=1 --set enhance.enabled=true"
                              " --set 'enhance.rit.channels=[depth, history_out]' --set enhance.rit.history_blend=true"
                              " --set 'enhance.rit.feature_channels=[depth]'"
                              " --set enhance.rit.source=hr_fuse --set enhance.rit.hr_width=4"
                              " --set enhance.geometry.enabled=false --out " + (dir / "train").string());
  ASSERT_EQ(train.exit_code, 0) << train.all();
  const fs::path model = dir / "train" / "model.cgsr";

  const Dataset data = open_for_channels(walk_set(), {RenderChannel::Depth, RenderChannel::HistoryOut});
  const auto saved = [&](const std::string& name) {
    EvalOptions o = test::all_frames("4:12");
    o.temporal = false;
    o.save_frames = (dir / name).string();
    NetworkUpscaler net("recurrent", load_model(model).network);
    EXPECT_TRUE(net.recurrent());
    return evaluate(net, data, o);
  };
  const EvalResult first = saved("a"), second = saved("b");
  ASSERT_EQ(first.frames.size(), 8u);
  for (size_t i = 0; i < first.frames.size(); ++i) EXPECT_EQ(first.frames[i].psnr, second.frames[i].psnr) << i;
  // Each frame alone: a fresh upscaler's first frame has no previous output.
  const auto alone = [&](int frame) {
    NetworkUpscaler net("alone", load_model(model).network);
    return net.upscale(frame_batch(data, frame, 2, net.channels(), net.depth_encoding()));
  };
  const auto read = [&](const std::string& name, int frame) {
    char file[64];
    std::snprintf(file, sizeof file, "recurrent_frame%04d.png", frame);
    return read_image(dir / name / file);
  };
  const auto quantized = [](const torch::Tensor& t) { return t.clamp(0, 1).mul(255).round().div(255)[0]; };
  EXPECT_TRUE(torch::allclose(read("a", kCut), quantized(alone(kCut)), 0, 1.5 / 255));
  EXPECT_FALSE(torch::equal(read("a", kCut + 3), quantized(alone(kCut + 3))));

  const auto exported = run_cgsr("export --model " + model.string() + " --format onnx --input 64x48 --verify --data " +
                                 walk_set().string() + " --frames 2:10 --out " + (dir / "model.onnx").string());
  ASSERT_EQ(exported.exit_code, 0) << exported.all();
  EXPECT_NE(exported.out.find("0 failed"), std::string::npos) << exported.out;
  EXPECT_NE(exported.out.find("frame 9 (64x48)"), std::string::npos) << exported.out;
  fs::remove_all(dir);
}

// A recurrent network needs sequences and no other network takes them; a source at LR cannot warp
// an HR output: each a clear error naming the key.
TEST(RecurrentNetwork, ItsSettingsAreCheckedWithClearErrors) {
  const auto dir = test::scratch_dir("recurrent-errors");
  const std::string base = "train --data " + walk_set().string() +
                           " --model pan --steps 1 --threads 1 --set schedule.batch_size=2 --set schedule.patch_size=16"
                           " --set schedule.val_frames=1 --set enhance.enabled=true --set enhance.geometry.enabled=false ";
  const auto one = run_cgsr(base + "--set 'enhance.rit.channels=[history_out]' --set enhance.rit.source=hr_fuse"
                                   " --set enhance.rit.hr_width=4 --set schedule.sequence_length=1 --out " +
                            (dir / "a").string());
  EXPECT_NE(one.exit_code, 0);
  EXPECT_NE(one.all().find("schedule.sequence_length"), std::string::npos) << one.all();
  const auto plain = run_cgsr(base + "--set 'enhance.rit.channels=[depth]' --set schedule.sequence_length=3 --out " +
                              (dir / "b").string());
  EXPECT_NE(plain.exit_code, 0);
  EXPECT_NE(plain.all().find("only a recurrent network"), std::string::npos) << plain.all();
  const auto lr = run_cgsr(base + "--set 'enhance.rit.channels=[history_out]' --set enhance.rit.source=lr --out " +
                           (dir / "c").string());
  EXPECT_NE(lr.exit_code, 0);
  EXPECT_NE(lr.all().find("rit.source"), std::string::npos) << lr.all();
  fs::remove_all(dir);
}

}  // namespace recurrent_network_test
}  // namespace cgsr
