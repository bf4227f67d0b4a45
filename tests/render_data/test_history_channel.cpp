// The `history` rendering channel (history_channel.h): zero-upsampling places each jittered LR
// sample at the point it sampled, warping through motion reproduces the frame better than
// bicubic and the depth test rejects disoccluded samples, the history resets at a scene cut, loads
// are deterministic, data without motion is a clear error, a jittered game capture gives the same
// history (its jitter from a file; depth and motion at LR only are upsampled), and a network
// reading it trains.
// Real frames of the tiny scene (configs/scenes/tiny.yaml), rendered once per process.
#include <gtest/gtest.h>

#include <torch/torch.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iomanip>
#include <limits>
#include <sstream>
#include <thread>

#include "core/error.h"
#include "core/image_io.h"
#include "render_data/dataset.h"
#include "render_data/frame.h"
#include "render_data/history_channel.h"
#include "render_data/jitter.h"
#include "test_scenes.h"
#include "tests/support/cli_runner.h"
#include "tests/support/tiny_data.h"

namespace cgsr {
namespace history_channel_test {  // named: the tests compile as one unity translation unit
using test::with_channels;
namespace fs = std::filesystem;

std::string tiny_config() { return std::string(CGSR_SOURCE_DIR) + "/configs/scenes/tiny.yaml"; }

JitterSettings halton16() {
  JitterSettings j;
  j.sequence = "halton";
  j.phases = 16;
  return j;
}

// The tiny scene jittered by 16 Halton phases (64x48 and 128x96), its camera walk spread over
// 24 frames (6 would move it 45 pixels a frame at 128x96: hardly anything stays in view).
const fs::path& jittered_data() {
  static const fs::path dir = [] {
    const auto d = test::scratch_dir("history-data") / "data";
    const auto r = test::run_cgsr("render --config " + tiny_config() +
                                   " --set frames=24 --set jitter.sequence=halton --set jitter.phases=16 --threads 1 --out " + d.string());
    EXPECT_EQ(r.exit_code, 0) << r.all();
    return d;
  }();
  return dir;
}

// Frame t's chain as the data set gathers it: frames[k] = frame t-k (k <= kHistoryFrames).
std::vector<HistoryFrame> chain_of(const Dataset& all, int t, size_t hr) {
  std::vector<HistoryFrame> chain;
  for (int k = 0; k <= kHistoryFrames && t - k >= 0; ++k) {
    const Frame lr = all.load(t - k, 0), h = k < kHistoryFrames ? all.load(t - k, hr) : Frame();
    chain.push_back({lr.color, lr.depth, lr.jitter, h.depth, h.motion});  // the oldest gives its LR samples only
  }
  return chain;
}

double psnr(const torch::Tensor& a, const torch::Tensor& b) {
  const double mse = (a - b).pow(2).mean().item<double>();
  return 10 * std::log10(1.0 / mse);
}

// The colour of `image` [3,H,W] at the pixels of `mask` [H,W]: [3, n].
torch::Tensor at(const torch::Tensor& image, const torch::Tensor& mask) { return image.index({torch::indexing::Slice(), mask}); }

int age_of(float recency) { return static_cast<int>(std::lround((1 - recency) * (kHistoryFrames + 1))); }

// A still camera over the tiny scene: frame f's LR sample x lands in the HR pixel containing
// s * (x + 0.5 - jitter_f), with its colour and recency 1 - age/(K+1).
TEST(HistoryChannel, ZeroUpsamplingPlacesEachSampleAtItsJitteredPosition) {
  const auto doc = config::Document::load_file(tiny_config());
  const SceneBundle b = make_scene(config::Block{doc.root()["scene"], std::make_shared<config::Document>(doc), "scene"}, 1);
  const SceneRenderer renderer(b.scene, test::unshadowed());
  const CameraPose pose = b.camera.at_frame(2, 6);
  const int w = 64, h = 48, s = 2, t = kHistoryFrames;
  const float near_plane = b.camera.near_plane, far_plane = b.camera.far_plane;
  const Frame hr = frame_from_gbuffer(renderer.render(pose, pose, s * w, s * h, near_plane, far_plane));
  ASSERT_LT(hr.motion.abs().max().item<float>(), 1e-4f);  // still
  std::vector<HistoryFrame> chain;
  std::vector<Frame> lr;
  for (int k = 0; k <= kHistoryFrames; ++k) {
    const Vec2 j = jitter_offset(halton16(), t - k);
    lr.push_back(frame_from_gbuffer(renderer.render(pose, pose, w, h, near_plane, far_plane, j)));
    chain.push_back({lr.back().color, lr.back().depth, {j.x, j.y}, hr.depth, hr.motion});
  }
  const torch::Tensor history = history_channel(chain, s, "still");
  ASSERT_EQ(history.sizes(), (std::vector<int64_t>{4, s * h, s * w}));
  auto H = history.accessor<float, 3>();
  std::vector<int> per_age(kHistoryFrames + 1, 0);
  for (int i = 0; i < s * h; ++i)
    for (int jj = 0; jj < s * w; ++jj) {
      const float recency = H[3][i][jj];
      if (recency == 0) {
        for (int c = 0; c < 3; ++c) ASSERT_EQ(H[c][i][jj], 0.0f);
        continue;
      }
      const int k = age_of(recency);
      ASSERT_GE(k, 0);
      ASSERT_LE(k, kHistoryFrames);
      ASSERT_NEAR(recency, 1.0f - static_cast<float>(k) / (kHistoryFrames + 1), 1e-6f);
      ++per_age[k];
      // The sample of frame t-k whose jittered position lies in this pixel holds its colour.
      const auto& jit = chain[k].jitter;
      const int x = static_cast<int>(std::floor((jj + 0.5) / s + jit[0])), y = static_cast<int>(std::floor((i + 0.5) / s + jit[1]));
      const double px = s * (x + 0.5 - jit[0]), py = s * (y + 0.5 - jit[1]);
      ASSERT_TRUE(px >= jj && px <= jj + 1 && py >= i && py <= i + 1) << i << "," << jj << " age " << k;
      for (int c = 0; c < 3; ++c) ASSERT_EQ(H[c][i][jj], lr[k].color[c][y][x].item<uint8_t>() / 255.0f);
    }
  // Every sample of the current frame lands in the pixel containing its position, but where the
  // LR depth there disagrees with the HR depth (a silhouette).
  const auto& j0 = chain[0].jitter;
  int placed = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const int px = static_cast<int>(std::floor(s * (x + 0.5 - j0[0]))), py = static_cast<int>(std::floor(s * (y + 0.5 - j0[1])));
      if (H[3][py][px] != 1.0f) continue;
      ++placed;
      for (int c = 0; c < 3; ++c) ASSERT_EQ(H[c][py][px], lr[0].color[c][y][x].item<uint8_t>() / 255.0f);
    }
  EXPECT_GT(placed, 0.9 * w * h);
  // At s = 2 the Halton offsets of four consecutive frames fall in the four quadrants of an LR
  // pixel: frames t .. t-3 fill the HR grid and t-4's samples all land on taken pixels.
  for (int k = 0; k < 4; ++k) EXPECT_GT(per_age[k], 0.9 * w * h) << "age " << k;
  EXPECT_GT(per_age[0] + per_age[1] + per_age[2] + per_age[3], 0.99 * s * s * w * h);
}

// A moving camera: the samples warped from older frames match the HR ground truth far better
// than bicubic does on the same pixels, the data set's channel is the function of its stored
// frames, and the depth test rejects samples the warp would take from the wrong surface.
TEST(HistoryChannel, WarpingReproducesTheFrameAndRejectsDisocclusions) {
  const Dataset all = Dataset::open(jittered_data());
  const Dataset data = Dataset::open(jittered_data(), with_channels({"history"}));
  const size_t hr = 1;
  const int s = 2;
  namespace F = torch::nn::functional;
  std::vector<torch::Tensor> warped_history, warped_truth, warped_bicubic, extra_history, extra_truth;
  std::vector<torch::Tensor> own_history, own_truth, flipped_history, flipped_truth;
  int64_t covered = 0, pixels = 0;
  for (int t = kHistoryFrames; t < data.frame_count(); ++t) {
    const auto chain = chain_of(all, t, hr);
    const torch::Tensor history = data.frame(t, hr)->history;
    ASSERT_TRUE(torch::equal(history, history_channel(chain, s, "frame " + std::to_string(t))));
    const torch::Tensor truth = all.load(t, hr).color_float();
    const torch::Tensor bicubic =
        F::interpolate(all.load(t, 0).color_float().unsqueeze(0),
                       F::InterpolateFuncOptions().scale_factor(std::vector<double>{2.0, 2.0}).mode(torch::kBicubic).align_corners(false))[0]
            .clamp(0, 1);
    const torch::Tensor recency = history[3];
    // The current frame's samples against the truth, and placed with the jitter's sign flipped
    // (at s * (x + 0.5 + jitter)): jitter.h's convention puts them nearer the truth.
    auto flipped = chain;
    for (auto& f : flipped) f.jitter = {-f.jitter[0], -f.jitter[1]};
    const torch::Tensor wrong = history_channel(flipped, s, "flipped");
    own_history.push_back(at(history.slice(0, 0, 3), recency == 1));
    own_truth.push_back(at(truth, recency == 1));
    flipped_history.push_back(at(wrong.slice(0, 0, 3), wrong[3] == 1));
    flipped_truth.push_back(at(truth, wrong[3] == 1));
    const torch::Tensor older = (recency > 0) & (recency < 1);  // age >= 1
    warped_history.push_back(at(history.slice(0, 0, 3), older));
    warped_truth.push_back(at(truth, older));
    warped_bicubic.push_back(at(bicubic, older));
    covered += (recency > 0).sum().item<int64_t>();
    pixels += recency.numel();
    // Without the depth test: what it rejected.
    const double none = std::numeric_limits<double>::max();
    const torch::Tensor loose = history_channel(chain, s, "loose", {none, none, none});
    const torch::Tensor extra = (loose[3] > 0) & (recency == 0);
    extra_history.push_back(at(loose.slice(0, 0, 3), extra));
    extra_truth.push_back(at(truth, extra));
  }
  const torch::Tensor wh = torch::cat(warped_history, 1), wt = torch::cat(warped_truth, 1), wb = torch::cat(warped_bicubic, 1);
  ASSERT_GT(wh.size(1), 1000);
  const double history_psnr = psnr(wh, wt), bicubic_psnr = psnr(wb, wt);
  const torch::Tensor eh = torch::cat(extra_history, 1), et = torch::cat(extra_truth, 1);
  const double rejected_psnr = eh.size(1) > 0 ? psnr(eh, et) : 0;
  std::cout << "warped pixels " << wh.size(1) << ": history " << history_psnr << " dB, bicubic " << bicubic_psnr
            << " dB; covered " << static_cast<double>(covered) / pixels << "; rejected by depth " << eh.size(1) << " at "
            << rejected_psnr << " dB\n";
  // Measured (depth tests 0.1): 29.2 dB against bicubic's 26.8 on 25164 warped pixels, 36% of the
  // pixels covered, 74077 samples rejected at 25.7 dB.
  const double own_psnr = psnr(torch::cat(own_history, 1), torch::cat(own_truth, 1));
  const double flipped_psnr = psnr(torch::cat(flipped_history, 1), torch::cat(flipped_truth, 1));
  std::cout << "current frame's samples " << own_psnr << " dB, with the jitter flipped " << flipped_psnr << " dB\n";
  EXPECT_GT(own_psnr, flipped_psnr + 2.0);  // measured 29.5 against 25.3
  EXPECT_GT(history_psnr, bicubic_psnr + 1.5);
  EXPECT_GT(static_cast<double>(covered) / pixels, 0.3);
  // The depth test rejects something, and what it rejects is farther from the truth.
  EXPECT_GT(eh.size(1), 1000);
  EXPECT_LT(rejected_psnr, history_psnr - 2.0);
}

// The tiny scene twice, jittered (unjittered, a frame's own samples fill every HR pixel at s = 2):
// 6 frames, then a slower walk of 24 so that samples stay in view. The cut is at frame 6.
const fs::path& two_scene_data() {
  static const fs::path set = test::two_scene_walk("history-scenes", "\njitter: {sequence: halton, phases: 16}\n");
  return set;
}

// A two-scene data set: the second scene's first frame holds its own samples only (recency 1 or
// 0), its next one gathers one frame back at most, and later ones more.
TEST(HistoryChannel, ResetsAtASceneCut) {
  const Dataset data = Dataset::open(two_scene_data(), with_channels({"history"}));
  ASSERT_EQ(data.scenes().size(), 2u);
  const int first = data.scenes()[1].first_frame;
  ASSERT_FALSE(data.has_previous(first));
  const torch::Tensor cut = data.frame(first, 1)->history[3];
  EXPECT_TRUE(((cut == 0) | (cut == 1)).all().item<bool>());
  EXPECT_GT((cut == 1).sum().item<int64_t>(), 0);
  const torch::Tensor next = data.frame(first + 1, 1)->history[3];
  const float one_back = 1.0f - 1.0f / (kHistoryFrames + 1);
  EXPECT_TRUE(((next == 0) | (next == 1) | (next == one_back)).all().item<bool>());
  int64_t older = 0;
  for (int f = first + 6; f < first + 12; ++f) {
    const torch::Tensor later = data.frame(f, 1)->history[3];
    older += ((later > 0) & (later < 1)).sum().item<int64_t>();
  }
  EXPECT_GT(older, 100);
  // The LR resolution (s = 1) has it too.
  EXPECT_EQ(data.frame(first + 1, 0)->history.size(0), 4);
}

// Two loads give the same tensor, also loaded from several threads; a capture without motion asked for `history` names the data
// set, each resolution and what it lacks; the channel is not derived unless asked for.
TEST(HistoryChannel, IsDeterministicAndAClearErrorWithoutMotion) {
  const Dataset a = Dataset::open(jittered_data(), with_channels({"history"}));
  const Dataset b = Dataset::open(jittered_data(), with_channels({"depth", "history"}));
  EXPECT_TRUE(torch::equal(a.load(5, 1).history, b.load(5, 1).history));
  EXPECT_TRUE(torch::equal(a.load(3, 0).history, a.load(3, 0).history));
  // Frames derived from several threads at once (the patch sampler's prefetch) are the same: a
  // frame's history reads its predecessors' stored channels, never the cache it is being added to.
  const Dataset shared = Dataset::open(jittered_data(), with_channels({"history"}));
  std::vector<torch::Tensor> parallel(8);
  std::vector<std::thread> threads;
  for (int i = 0; i < 8; ++i) threads.emplace_back([&, i] { parallel[i] = shared.frame(4 + i % 4, 1)->history; });
  for (auto& t : threads) t.join();
  for (int i = 0; i < 8; ++i) EXPECT_TRUE(torch::equal(parallel[i], a.load(4 + i % 4, 1).history)) << i;
  const auto defaults = Dataset::open(jittered_data()).info().channels;
  EXPECT_EQ(std::find(defaults.begin(), defaults.end(), RenderChannel::History), defaults.end());
  EXPECT_TRUE(open_for_channels(jittered_data(), {RenderChannel::History}).frame(2, 1)->has(RenderChannel::History));

  const fs::path root = test::scratch_dir("history_no_motion");
  fs::create_directories(root / "lr");
  fs::create_directories(root / "hr");
  for (int f = 0; f < 2; ++f) {
    write_image(root / "lr" / ("color_" + std::to_string(f) + ".png"), torch::rand({3, 24, 32}));
    write_image(root / "lr" / ("depth_" + std::to_string(f) + ".png"), torch::full({1, 24, 32}, 0.5f));
    write_image(root / "hr" / ("color_" + std::to_string(f) + ".png"), torch::rand({3, 48, 64}));
  }
  std::ofstream(root / "capture.yaml") << "layout: glob\nresolutions:\n"
                                          "  - {size: 32x24, color: lr/color_*.png, depth: lr/depth_*.png}\n"
                                          "  - {size: 64x48, color: hr/color_*.png}\n";
  try {
    Dataset::open(root / "capture.yaml", with_channels({"history"}));
    FAIL() << "derived history without motion";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find((root / "capture.yaml").string()), std::string::npos) << what;
    EXPECT_NE(what.find("'history'"), std::string::npos) << what;
    EXPECT_NE(what.find("32x24: the data set has no motion at 32x24"), std::string::npos) << what;
    EXPECT_NE(what.find("64x48: the data set has no motion at 64x48 or 32x24"), std::string::npos) << what;
  }
  fs::remove_all(root);
}

// Trains PAN x2 with an HR RIT (hr_fuse, width 4) reading `rit` (--set options) for 2 steps on
// the jittered frames into `out`.
test::CliResult train_two_steps(const fs::path& out, const std::string& rit) {
  return test::run_cgsr("train --data " + jittered_data().string() +
                        " --model pan --steps 2 --threads 1 --set schedule.batch_size=2 --set schedule.patch_size=16"
                        " --set schedule.val_frames=1 --set schedule.color_augment=true --set enhance.enabled=true " +
                        rit + " --set enhance.rit.source=hr_fuse --set enhance.rit.hr_width=4"
                        " --set enhance.geometry.enabled=false --out " + out.string());
}

// The best temporal network's RIT options: `channels` (with history and jitter) read, the
// samples blended, the whole output taken at the jitter.
std::string output_at_jitter(const std::string& channels) {
  return "--set 'enhance.rit.channels=" + channels + "' --set enhance.rit.history_blend=true"
         " --set enhance.rit.skip_at_jitter=true --set enhance.rit.residual_at_jitter=true";
}

// A jittered sequence as an engine would capture it (the glob layout: PNG colour, float EXR depth
// and motion at both resolutions) with its jitter in a text file: every frame's jitter and history
// are the rendered data set's; without the file the frames load unjittered and their history
// moves; the classic history fill and a trained temporal network score on it as on the rendered
// frames. A bad jitter file is an error naming the file and line.
TEST(HistoryChannel, AJitteredCaptureWithItsJitterFileGivesTheRenderedHistory) {
  const Dataset rendered = Dataset::open(jittered_data(), with_channels({"depth", "motion", "history"}));
  const fs::path root = test::scratch_dir("history_capture");
  const int frames = 8;
  std::ofstream jitter(root / "jitter.txt");
  jitter << "# x y, LR pixels\n" << std::setprecision(17);
  std::string layout = "layout: glob\ndepth_encoding: linear\nresolutions:\n", hr_colour;
  for (size_t res : {0, 1}) {
    const std::string dir = res == 0 ? "lr" : "hr", size = rendered.info().resolutions[res].name();
    fs::create_directories(root / dir);
    layout += "  - {size: " + size + ", color: " + dir + "/color_*.png, depth: " + dir + "/depth_*.exr, motion: " + dir +
              "/mv_*.exr}\n";
    if (res == 1) hr_colour = "  - {size: " + size + ", color: hr/color_*.png}\n";
    for (int f = 0; f < frames; ++f) {
      const Frame fr = rendered.load(f, res);
      const std::string n = std::to_string(f);
      write_image(root / dir / ("color_" + n + ".png"), fr.color_float());
      write_image(root / dir / ("depth_" + n + ".exr"), torch::where(torch::isinf(fr.depth), torch::zeros({}), fr.depth), {32});
      const auto motion = torch::cat({fr.motion.to(torch::kFloat32), torch::zeros({1, fr.height, fr.width})});
      write_image(root / dir / ("mv_" + n + ".exr"), motion, {32});
      if (res == 0) jitter << fr.jitter[0] << " " << fr.jitter[1] << "\n";
    }
  }
  jitter.close();
  std::ofstream(root / "capture.yaml") << layout << "jitter: jitter.txt\n";
  std::ofstream(root / "unjittered.yaml") << layout;
  const Dataset capture = Dataset::open(root / "capture.yaml", with_channels({"history"}));
  const Dataset unjittered = Dataset::open(root / "unjittered.yaml", with_channels({"history"}));
  int moved = 0;
  for (int f = 0; f < frames; ++f) {
    SCOPED_TRACE("frame " + std::to_string(f));
    EXPECT_EQ(capture.load(f, 0).jitter, rendered.load(f, 0).jitter);
    EXPECT_TRUE(torch::equal(capture.load(f, 1).history, rendered.load(f, 1).history));
    EXPECT_EQ(unjittered.load(f, 0).jitter, (std::array<double, 2>{0, 0}));
    moved += !torch::equal(unjittered.load(f, 1).history, rendered.load(f, 1).history);
  }
  EXPECT_GE(moved, frames - 1);  // (a frame jittered by exactly 0 would load the same)
  // With depth and motion at the render size only, upsampled as an engine passes them: the same
  // samples wherever the motion is flat over an LR pixel's block.
  const std::string lr_only = layout.substr(0, layout.rfind("  - {size")) + hr_colour + "jitter: jitter.txt\n";
  std::ofstream(root / "lr_only.yaml") << lr_only;
  const Dataset from_lr = Dataset::open(root / "lr_only.yaml", with_channels({"history"}));
  double same = 0;
  for (int f = 0; f < frames; ++f) {
    const auto a = from_lr.load(f, 1).history, b = rendered.load(f, 1).history;
    same += (a == b).all(0).to(torch::kFloat64).mean().item<double>() / frames;
  }
  EXPECT_GE(same, 0.97);  // 98.97% at commit time
  EXPECT_LT(same, 1.0);   // silhouettes move otherwise than their LR pixel's centre
  // cgsr eval runs temporal upscalers on them: the classic history fill, and a network trained on
  // the rendered frames that reads the history and the jitter (blended, output at the jitter; 2
  // steps). On the jittered capture each gives the rendered data set's PSNR to the last digit;
  // from LR depth and motion within 0.05 dB.
  const auto train = train_two_steps(root / "train", output_at_jitter("[history, jitter]"));
  ASSERT_EQ(train.exit_code, 0) << train.all();
  const fs::path data[3] = {jittered_data(), root / "capture.yaml", root / "lr_only.yaml"};
  for (const std::string& model : {std::string("history"), (root / "train" / "model.cgsr").string()}) {
    SCOPED_TRACE(model);
    double psnr[3];
    for (int i = 0; i < 3; ++i) {
      const fs::path out = root / ("eval" + std::to_string(i));
      const auto r = test::run_cgsr("eval --data " + data[i].string() + " --model " + model + " --frames 0:" +
                                    std::to_string(frames) + " --split all --latency-runs 0 --out " + out.string());
      ASSERT_EQ(r.exit_code, 0) << r.all();
      const std::string summary = test::slurp(out / "results.json");
      const auto at = summary.find("\"psnr\": ");
      ASSERT_NE(at, std::string::npos) << summary;
      psnr[i] = std::stod(summary.substr(at + 8, 24));
      fs::remove_all(out);
    }
    EXPECT_EQ(psnr[1], psnr[0]);
    EXPECT_NEAR(psnr[2], psnr[0], 0.05);  // at commit time: history -0.005 dB, the network -0.00005 dB
  }

  auto open_error = [&](const std::string& lines) {
    std::ofstream(root / "bad.txt") << lines;
    std::ofstream(root / "bad.yaml") << layout << "jitter: bad.txt\n";
    try {
      Dataset::open(root / "bad.yaml");
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find((root / "bad.txt").string()), std::string::npos) << e.what();
      return std::string(e.what());
    }
    return std::string("no error");
  };
  std::string all;
  for (int f = 0; f < frames; ++f) all += "0.25 -0.25\n";
  EXPECT_NE(open_error("0.25 -0.25\n").find("has 1 offsets for the capture's 8 frames"), std::string::npos);
  EXPECT_NE(open_error(all + "\n0 0\n").find("line 10: more offsets than the capture's 8 frames"), std::string::npos);
  EXPECT_NE(open_error("# x y\n0.25\n" + all).find("line 2: expected two numbers 'x y', got '0.25'"), std::string::npos);
  EXPECT_NE(open_error("0.25 -0.25 1\n" + all).find("line 1: expected two numbers"), std::string::npos);
  EXPECT_NE(open_error("nan 0\n" + all).find("line 1: expected two numbers"), std::string::npos);
  EXPECT_NE(open_error("0.5 0\n" + all).find("line 1: offset 0.5000 is outside [-0.5, 0.5) pixels"), std::string::npos);
  std::ofstream(root / "missing.yaml") << layout << "jitter: missing.txt\n";
  try {
    Dataset::open(root / "missing.yaml");
    ADD_FAILURE() << "opened a capture whose jitter file is missing";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find((root / "missing.txt").string() + ": cannot open the jitter file"), std::string::npos)
        << e.what();
  }
  fs::remove_all(root);
}

// `cgsr train` with history in the RIT channels at HR (hr_unshuffle+hr_fuse), colour augmentation
// on: the channel flows through patch sampling and augmentation into a training step.
TEST(HistoryChannel, ANetworkReadingItTrains) {
  const auto dir = test::scratch_dir("history-train");
  const auto train = test::run_cgsr(
      "train --data " + jittered_data().string() +
      " --model pan --steps 2 --threads 1 --set schedule.batch_size=2 --set schedule.patch_size=16"
      " --set schedule.val_frames=1 --set schedule.color_augment=true --set enhance.enabled=true"
      " --set 'enhance.rit.channels=[depth, history]' --set enhance.rit.source=hr_unshuffle+hr_fuse"
      " --set enhance.rit.width=4 --set enhance.rit.hr_width=4 --set enhance.geometry.enabled=false --out " +
      (dir / "train").string());
  ASSERT_EQ(train.exit_code, 0) << train.all();
  EXPECT_TRUE(fs::exists(dir / "train" / "model.cgsr"));
  fs::remove_all(dir);
}

// A network with `rit` trains 2 steps (train_two_steps) and exports to ONNX, `hr_info` the shape of its HR input, and the runtimes reproduce it:
// on random inputs and on `verify_frames` (export flags; "": the jittered set's first test frame).
// Returns the export's output.
std::string expect_trains_and_exports(const std::string& scratch, const std::string& rit, const std::string& hr_info,
                                      const std::string& verify_frames = "") {
  const auto dir = test::scratch_dir(scratch);
  const auto train = train_two_steps(dir / "train", rit);
  EXPECT_EQ(train.exit_code, 0) << train.all();
  if (train.exit_code != 0) return "";
  const auto exported = test::run_cgsr(
      "export --model " + (dir / "train" / "model.cgsr").string() + " --format onnx --input 64x48 --verify --data " +
      (verify_frames.empty() ? jittered_data().string() : verify_frames) + " --out " + (dir / "model.onnx").string());
  EXPECT_EQ(exported.exit_code, 0) << exported.all();
  EXPECT_NE(exported.out.find("hr_render_info " + hr_info), std::string::npos) << exported.out;
  EXPECT_NE(exported.out.find("0 failed"), std::string::npos) << exported.out;
  EXPECT_EQ(exported.out.find(" 0 passed"), std::string::npos) << exported.out;
  fs::remove_all(dir);
  return exported.out;
}

// Whether the verification table of `out` has ONNX Runtime passing on `input` ("frame 6 (64x48)").
bool onnxruntime_passed(const std::string& out, const std::string& input) {
  std::istringstream lines(out);
  for (std::string line; std::getline(lines, line);)
    if (line.find(" onnxruntime ") != std::string::npos && line.find(" " + input + " ") != std::string::npos)
      return line.size() >= 3 && line.compare(line.size() - 3, 3, " ok") == 0;
  return false;
}

// rit.history_blend through the command line: ONNX Runtime and OpenCV reproduce the blend.
TEST(HistoryChannel, ANetworkBlendingItTrainsAndExports) {
  expect_trains_and_exports("history-blend", "--set 'enhance.rit.channels=[depth, history]' --set enhance.rit.history_blend=true",
                            "[1, 5, 96, 128]");  // depth 1 + history 4
}

// rit.skip_at_jitter and rit.residual_at_jitter with the blend: the jitter channel is derived for
// the network, and ONNX Runtime reproduces it (both GridSamples included; OpenCV DNN has none).
TEST(HistoryChannel, ANetworkTakingItsOutputAtTheJitterTrainsAndExports) {
  const std::string out =
      expect_trains_and_exports("output-at-jitter", output_at_jitter("[depth, history, jitter]"),
                                "[1, 7, 96, 128]");  // 1 + 4 + 2
  const int first_test = Dataset::open(jittered_data()).frames(Split::Test).at(0);
  EXPECT_TRUE(onnxruntime_passed(out, "frame " + std::to_string(first_test) + " (64x48)")) << out;
}

// The same exported over a sequence: 8 consecutive frames of a two-scene set, the cut at frame 6
// (the history the data set derives starts again there, as the engine resets it), each frame
// reproduced by ONNX Runtime within 1e-4. A frame range the data set does not have is an error
// naming the data set and its size.
TEST(HistoryChannel, ATemporalNetworkExportedMatchesOverASequenceWithASceneCut) {
  const std::string out =
      expect_trains_and_exports("output-at-jitter-sequence", output_at_jitter("[depth, history, jitter]"),
                                "[1, 7, 96, 128]", two_scene_data().string() + " --frames 2:10");
  ASSERT_EQ(Dataset::open(two_scene_data()).scenes().at(1).first_frame, 6);
  for (int f = 2; f < 10; ++f)
    EXPECT_TRUE(onnxruntime_passed(out, "frame " + std::to_string(f) + " (64x48)")) << "frame " << f << "\n" << out;
  EXPECT_FALSE(onnxruntime_passed(out, "frame 10 (64x48)"));

  const auto beyond = test::run_cgsr("export --model pan --format onnx --input 64x48 --verify --data " +
                                     two_scene_data().string() + " --frames 28:31 --out " +
                                     (test::scratch_dir("export-frames") / "pan.onnx").string());
  EXPECT_NE(beyond.exit_code, 0);
  EXPECT_NE(beyond.all().find("frames 28:31: the data set has 30 frames (0:30)"), std::string::npos) << beyond.all();
  EXPECT_NE(beyond.all().find(two_scene_data().string()), std::string::npos) << beyond.all();
  const auto without_data = test::run_cgsr("export --model pan --format onnx --input 64x48 --verify --frames 0:2 --out " +
                                           (test::scratch_dir("export-frames") / "pan.onnx").string());
  EXPECT_NE(without_data.exit_code, 0);
  EXPECT_NE(without_data.all().find("frames"), std::string::npos) << without_data.all();
  EXPECT_NE(without_data.all().find("--data DIR"), std::string::npos) << without_data.all();
}

// `cgsr ablate` with history in a channel set: the data set is opened with the channel though it
// is not derived by default, and the variant trains and evaluates.
TEST(HistoryChannel, AnAblationChannelSetReadsIt) {
  const auto dir = test::scratch_dir("history-ablate");
  const auto plain = test::run_cgsr("train --data " + jittered_data().string() +
                                    " --model pan --steps 1 --threads 1 --set schedule.batch_size=2"
                                    " --set schedule.patch_size=16 --set schedule.val_frames=1 --out " +
                                    (dir / "plain").string());
  ASSERT_EQ(plain.exit_code, 0) << plain.all();
  const auto r = test::run_cgsr(
      "ablate --data " + jittered_data().string() + " --model " + (dir / "plain" / "model.cgsr").string() +
      " --threads 1 --set ablation.sources=[hr_fuse] --set ablation.seeds=[1] --set ablation.leave_out=false"
      " --set ablation.rit.channels=[depth,edge] --set ablation.small_width=0 --set ablation.schedule.steps=2"
      " --set ablation.schedule.batch_size=2 --set ablation.schedule.patch_size=16"
      " --set ablation.schedule.validate_every=0 --set ablation.schedule.val_frames=1"
      " --set ablation.schedule.layout=nchw --set ablation.eval.latency_runs=0 --set ablation.eval.split=all"
      " --set 'ablation.channel_sets=[[depth, history]]' --out " + (dir / "run").string());
  ASSERT_EQ(r.exit_code, 0) << r.all();
  const auto rows = test::read_json(dir / "run" / "results.json").at("rows");
  bool found = false;
  for (const auto& row : rows) found = found || row.at("variant") == "hr_fuse [depth+history]";
  EXPECT_TRUE(found) << rows;
  fs::remove_all(dir);
}

// The measurement of docs/results/history.md, on a data set named by CGSR_HISTORY_DATA (disabled:
// run with --gtest_also_run_disabled_tests): per age, the PSNR of the history's samples against
// the HR ground truth and of bicubic on the same pixels; the fraction of HR pixels covered.
TEST(HistoryChannel, DISABLED_MeasureByAge) {
  const char* path = std::getenv("CGSR_HISTORY_DATA");
  if (!path) GTEST_SKIP() << "set CGSR_HISTORY_DATA to a jittered data set";
  const Dataset all = Dataset::open(path, with_channels({"history"}));
  const size_t hr = all.resolutions().size() - 1;
  const int s = lr_multiple(all.info(), hr);
  namespace F = torch::nn::functional;
  std::vector<double> se(kHistoryFrames + 1, 0), bicubic_se(kHistoryFrames + 1, 0);
  std::vector<int64_t> count(kHistoryFrames + 1, 0);
  int64_t pixels = 0;
  for (int t : all.frames(Split::All)) {
    const torch::Tensor history = all.frame(t, hr)->history;
    const torch::Tensor truth = all.load(t, hr).color_float();
    const torch::Tensor bicubic =
        F::interpolate(all.load(t, 0).color_float().unsqueeze(0),
                       F::InterpolateFuncOptions().scale_factor(std::vector<double>{double(s), double(s)}).mode(torch::kBicubic).align_corners(false))[0]
            .clamp(0, 1);
    pixels += history[3].numel();
    for (int k = 0; k <= kHistoryFrames; ++k) {
      const torch::Tensor mask = (history[3] - (1.0f - static_cast<float>(k) / (kHistoryFrames + 1))).abs() < 1e-6;
      const torch::Tensor truth_here = at(truth, mask);
      se[k] += (at(history.slice(0, 0, 3), mask) - truth_here).pow(2).sum().item<double>();
      bicubic_se[k] += (at(bicubic, mask) - truth_here).pow(2).sum().item<double>();
      count[k] += mask.sum().item<int64_t>();
    }
  }
  int64_t covered = 0;
  std::cout << "age | pixels | share of HR pixels | history PSNR | bicubic PSNR (same pixels)\n";
  for (int k = 0; k <= kHistoryFrames; ++k) {
    covered += count[k];
    const auto db = [&](double e) { return count[k] ? 10 * std::log10(3.0 * count[k] / e) : 0.0; };
    std::cout << k << " | " << count[k] << " | " << static_cast<double>(count[k]) / pixels << " | " << db(se[k]) << " | "
              << db(bicubic_se[k]) << "\n";
  }
  std::cout << "covered " << static_cast<double>(covered) / pixels << " of " << pixels << " HR pixels\n";
  // CGSR_HISTORY_SWEEP="sample,nearer,farther;...": the warped samples (age >= 1) under other depth tests.
  const char* sweep = std::getenv("CGSR_HISTORY_SWEEP");
  if (!sweep) return;
  std::stringstream variants(sweep);
  std::string variant;
  const Dataset stored = Dataset::open(path);  // depth and motion, for the chains
  std::cout << "sample | link nearer | link farther | warped pixels | history PSNR | bicubic PSNR (same pixels)\n";
  while (std::getline(variants, variant, ';')) {
    HistoryDepthTest test;
    ASSERT_EQ(std::sscanf(variant.c_str(), "%lf,%lf,%lf", &test.sample, &test.link_nearer, &test.link_farther), 3) << variant;
    double warped_se = 0, warped_bicubic_se = 0;
    int64_t warped = 0;
    for (int t : all.frames(Split::All)) {
      std::vector<HistoryFrame> chain;
      for (int k = 0, f = t; k <= kHistoryFrames; ++k, --f) {
        if (k > 0 && !all.has_previous(f + 1)) break;
        const Frame lr = stored.load(f, 0), h = k < kHistoryFrames ? stored.load(f, hr) : Frame();
        chain.push_back({lr.color, lr.depth, lr.jitter, h.depth, h.motion});
      }
      const torch::Tensor history = history_channel(chain, s, "sweep", test);
      const torch::Tensor mask = (history[3] > 0) & (history[3] < 1);
      const torch::Tensor truth = at(all.load(t, hr).color_float(), mask);
      const torch::Tensor bicubic =
          F::interpolate(all.load(t, 0).color_float().unsqueeze(0),
                         F::InterpolateFuncOptions().scale_factor(std::vector<double>{double(s), double(s)}).mode(torch::kBicubic).align_corners(false))[0]
              .clamp(0, 1);
      warped_se += (at(history.slice(0, 0, 3), mask) - truth).pow(2).sum().item<double>();
      warped_bicubic_se += (at(bicubic, mask) - truth).pow(2).sum().item<double>();
      warped += mask.sum().item<int64_t>();
    }
    std::cout << test.sample << " | " << test.link_nearer << " | " << test.link_farther << " | " << warped << " | "
              << 10 * std::log10(3.0 * warped / warped_se) << " | " << 10 * std::log10(3.0 * warped / warped_bicubic_se) << "\n";
  }
}

}  // namespace history_channel_test
}  // namespace cgsr
