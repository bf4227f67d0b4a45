// The `bsp` rendering channel: the sub-pixel BSP border image resolved at HR, derived on load.
// It is the BSP border upsampler's output number for number, cropped with the other HR channels,
// a clear error where the data set has no BSP files, and a CG network reading it trains,
// evaluates and exports (ONNX verified).
#include <gtest/gtest.h>

#include <torch/torch.h>

#include <filesystem>

#include "core/error.h"
#include "eval/baselines/bsp_border_upsampler.h"
#include "render_data/augment.h"
#include "render_data/bsp_border.h"
#include "render_data/bsp_border_file.h"
#include "render_data/dataset.h"
#include "render_data/patch_sampler.h"
#include "tests/support/cli_runner.h"
#include "tests/support/tiny_data.h"

namespace cgsr {
namespace bsp_channel_test {  // named: the tests compile as one unity translation unit
using test::with_channels;

// The tiny procedural room (64x48 and 128x96) with BSP border files, rendered once per process.
const std::filesystem::path& tiny_bsp_data() {
  static const std::filesystem::path dir = [] {
    const auto d = test::scratch_dir("tiny-bsp-data") / "data";
    const auto r = test::run_cgsr("render --config " + std::string(CGSR_SOURCE_DIR) +
                                  "/configs/scenes/tiny.yaml --set frames=3 --set bsp_border.depth=2 --threads 1 --out " +
                                  d.string());
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return d;
  }();
  return dir;
}

TEST(BspChannel, IsTheUpsamplersOutputAndItsBorderCoverage) {
  const Dataset data = Dataset::open(tiny_bsp_data(), with_channels({"edge", "bsp"}));
  ASSERT_TRUE(data.info().bsp_border);
  const auto [lo, hi] = resolution_pair(data, 2);
  int64_t covered = 0;
  for (int f = 0; f < data.frame_count(); ++f) {
    const auto lr = data.frame(f, lo), hr = data.frame(f, hi);
    ASSERT_TRUE(lr->bsp_border);
    ASSERT_TRUE(hr->has(RenderChannel::Bsp));
    ASSERT_EQ(hr->bsp.sizes(), (std::vector<int64_t>{4, 96, 128}));
    const auto upsampled = upscale_bsp_border(lr->color_float().unsqueeze(0), {lr->bsp_border.get()}, 2)[0];
    EXPECT_TRUE(torch::equal(hr->bsp.slice(0, 0, 3), upsampled)) << "frame " << f;
    // Coverage: the HR pixels whose centres lie in an LR pixel that has a tree.
    auto expected = torch::zeros({96, 128});
    for (int y = 0; y < 96; ++y)
      for (int x = 0; x < 128; ++x)
        if (lr->bsp_border->at(x / 2, y / 2)) expected[y][x] = 1.0f;
    EXPECT_TRUE(torch::equal(hr->bsp[3], expected)) << "frame " << f;
    covered += expected.sum().item<int64_t>();
    // At the BSP resolution itself: the colour, each border pixel taking its centre's leaf.
    const auto own = upscale_bsp_border(lr->color_float().unsqueeze(0), {lr->bsp_border.get()}, 1)[0];
    EXPECT_TRUE(torch::equal(lr->bsp.slice(0, 0, 3), own));
    // A frame batch (what eval and training's validation feed a network) carries the same numbers.
    const Batch b = frame_batch(data, f, 2, {RenderChannel::Bsp}, DepthEncoding::Log);
    EXPECT_TRUE(torch::equal(b.hr_info[0], hr->bsp));
  }
  EXPECT_GT(covered, 0) << "the tiny room has border pixels";
}

// Patches crop the bsp channel where they crop the colour: LR window (x, y) <-> HR (2x, 2y).
TEST(BspChannel, PatchesCropItWithTheOtherChannels) {
  const Dataset data = Dataset::open(tiny_bsp_data(), with_channels({"edge", "bsp"}));
  PatchSamplerOptions o;
  o.patch_size = 12;
  o.batch_size = 4;
  o.augment = false;
  o.split = Split::All;
  o.channels = {RenderChannel::Edge, RenderChannel::Bsp};
  o.prefetch = 0;
  PatchSampler sampler(data, o);
  const Batch b = sampler.next();
  const auto [lo, hi] = resolution_pair(data, 2);
  for (int i = 0; i < o.batch_size; ++i) {
    const auto lr = data.frame(b.frames[i], lo), hr = data.frame(b.frames[i], hi);
    const auto colour = lr->color_float();
    // Find the LR window of this patch by its colour and edges (the first that matches).
    bool found = false;
    for (int y = 0; y + o.patch_size <= lr->height && !found; ++y)
      for (int x = 0; x + o.patch_size <= lr->width && !found; ++x) {
        const auto window = [&](const torch::Tensor& t, int s) {
          return t.slice(1, s * y, s * (y + o.patch_size)).slice(2, s * x, s * (x + o.patch_size));
        };
        if (!torch::equal(window(colour, 1), b.lr_color[i]) ||
            !torch::equal(window(lr->edge.to(torch::kFloat32), 1), b.lr_info[i].slice(0, 0, 1)))
          continue;
        found = true;
        EXPECT_TRUE(torch::equal(window(lr->bsp, 1), b.lr_info[i].slice(0, 1, 5)));
        EXPECT_TRUE(torch::equal(window(hr->bsp, 2), b.hr_info[i].slice(0, 1, 5)));
        EXPECT_TRUE(torch::equal(window(hr->color_float(), 2), b.hr_color[i]));
      }
    EXPECT_TRUE(found) << "item " << i;
  }
}

// Colour augmentation permutes and scales the bsp colour as it does the frame's colour; the
// coverage and the other channels stay.
TEST(BspChannel, ColourAugmentationReachesItsColourOnly) {
  const std::vector<RenderChannel> channels = {RenderChannel::Edge, RenderChannel::Bsp};
  const auto info = torch::rand({6, 5, 7});
  const ColorAugmentation a{/*permutation=*/4, /*gain=*/0.8f};
  const auto out = augment_info_color(info, channels, a);
  EXPECT_TRUE(torch::equal(out.slice(0, 1, 4), augment_color(info.slice(0, 1, 4), a)));
  EXPECT_TRUE(torch::equal(out[0], info[0]));
  EXPECT_TRUE(torch::equal(out[4], info[4]));
  EXPECT_FALSE(torch::equal(out.slice(0, 1, 4), info.slice(0, 1, 4)));
  const auto plain = torch::rand({1, 5, 7});
  EXPECT_TRUE(torch::equal(augment_info_color(plain, {RenderChannel::Edge}, a), plain));
}

TEST(BspChannel, WithoutBspFilesItIsAClearError) {
  // A data set rendered without bsp_border: the error names it and says how to render the files.
  try {
    Dataset::open(test::tiny_data(), with_channels({"depth", "bsp"}));
    FAIL() << "opened the bsp channel of a data set without BSP files";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(test::tiny_data().string()), std::string::npos) << what;
    EXPECT_NE(what.find("bsp_border: {depth: 2}"), std::string::npos) << what;
  }
  // Without the channel asked for, the data set opens as before and lacks it.
  EXPECT_EQ(Dataset::open(test::tiny_data()).info().derived.size(), 0u);

  // A data set whose frame lost its .bsp file: loading the channel names the file.
  const auto copy = test::scratch_dir("bsp-missing") / "data";
  std::filesystem::copy(tiny_bsp_data(), copy, std::filesystem::copy_options::recursive);
  const Dataset data = Dataset::open(copy, with_channels({"bsp"}));
  const auto file = bsp_border_file(copy, data.resolutions()[0], 1);
  ASSERT_TRUE(std::filesystem::exists(file));
  std::filesystem::remove(file);
  const auto hr = data.resolution_index(data.resolutions()[1]);
  try {
    data.load(1, hr);
    FAIL() << "loaded the bsp channel without its file";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(file.string()), std::string::npos) << what;
    EXPECT_NE(what.find("missing sub-pixel BSP border file"), std::string::npos) << what;
  }
  EXPECT_NO_THROW(data.load(0, hr));
  std::filesystem::remove_all(copy.parent_path());
}

// `cgsr train` with the bsp channel through hr_unshuffle+hr_fuse, then `cgsr eval` and `cgsr export
// --verify` (ONNX Runtime and OpenCV against our forward pass) of the trained model; training on
// a data set without the files fails saying how to render them.
TEST(BspChannel, ACgNetworkWithItTrainsEvaluatesAndExports) {
  const auto dir = test::scratch_dir("bsp-channel-cli");
  const std::string rit = " --set enhance.enabled=true --set 'enhance.rit.channels=[depth, edge, bsp]'"
                          " --set enhance.rit.source=hr_unshuffle+hr_fuse --set enhance.rit.width=4"
                          " --set enhance.rit.hr_width=4 --set enhance.geometry.enabled=false";
  const std::string common = " --model pan --steps 2 --threads 1 --set schedule.batch_size=2 --set schedule.patch_size=16"
                             " --set schedule.val_frames=1 --set schedule.color_augment=true" + rit;
  const auto train = test::run_cgsr("train --data " + tiny_bsp_data().string() + common + " --out " + (dir / "train").string());
  ASSERT_EQ(train.exit_code, 0) << train.all();
  const auto model = dir / "train" / "model.cgsr";
  ASSERT_TRUE(std::filesystem::exists(model));

  const auto eval = test::run_cgsr("eval --data " + tiny_bsp_data().string() + " --model " + model.string() +
                                   " --split all --latency-runs 0 --threads 1 --out " + (dir / "eval").string());
  ASSERT_EQ(eval.exit_code, 0) << eval.all();
  const auto results = test::read_json(dir / "eval" / "results.json");
  ASSERT_FALSE(results.at("evaluations").empty());
  EXPECT_GT(results.at("evaluations").at(0).at("psnr").get<double>(), 15.0) << results.dump();

  const auto exported = test::run_cgsr("export --model " + model.string() + " --format onnx --input 64x48 --verify --out " +
                                       (dir / "model.onnx").string());
  ASSERT_EQ(exported.exit_code, 0) << exported.all();
  // depth 1 + edge 1 + bsp 4 = 6 channels at HR.
  EXPECT_NE(exported.out.find("hr_render_info [1, 6, 96, 128]"), std::string::npos) << exported.out;
  EXPECT_NE(exported.out.find("0 failed"), std::string::npos) << exported.out;
  EXPECT_EQ(exported.out.find(" 0 passed"), std::string::npos) << exported.out;

  const auto without = test::run_cgsr("train --data " + test::tiny_data().string() + common + " --out " +
                                      (dir / "without").string());
  EXPECT_EQ(without.exit_code, 2) << without.all();
  EXPECT_NE(without.all().find("bsp_border: {depth: 2}"), std::string::npos) << without.all();
  std::filesystem::remove_all(dir);
}

// rit.bsp_composite through the command line: a CG network whose output is the bsp image on the
// covered pixels trains, evaluates and exports (ONNX Runtime and OpenCV verified against our
// forward pass, the composite included); asked for without the bsp channel, training refuses it
// naming the key.
TEST(BspChannel, ACgNetworkCompositingItTrainsEvaluatesAndExports) {
  const auto dir = test::scratch_dir("bsp-composite-cli");
  const std::string common = " --model pan --steps 2 --threads 1 --set schedule.batch_size=2 --set schedule.patch_size=16"
                             " --set schedule.val_frames=1 --set schedule.color_augment=true --set enhance.enabled=true"
                             " --set enhance.rit.source=hr_fuse --set enhance.rit.hr_width=4"
                             " --set enhance.geometry.enabled=false --set enhance.rit.bsp_composite=true";
  const auto train = test::run_cgsr("train --data " + tiny_bsp_data().string() + common +
                                    " --set 'enhance.rit.channels=[edge, bsp]' --out " + (dir / "train").string());
  ASSERT_EQ(train.exit_code, 0) << train.all();
  const auto model = dir / "train" / "model.cgsr";
  ASSERT_TRUE(std::filesystem::exists(model));

  const auto eval = test::run_cgsr("eval --data " + tiny_bsp_data().string() + " --model " + model.string() +
                                   " --model bsp_border --split all --latency-runs 0 --threads 1 --out " +
                                   (dir / "eval").string());
  ASSERT_EQ(eval.exit_code, 0) << eval.all();
  const auto results = test::read_json(dir / "eval" / "results.json");
  ASSERT_EQ(results.at("evaluations").size(), 2u) << results.dump();
  EXPECT_GT(results.at("evaluations").at(0).at("psnr").get<double>(), 15.0) << results.dump();

  const auto exported = test::run_cgsr("export --model " + model.string() + " --format onnx --input 64x48 --verify --out " +
                                       (dir / "model.onnx").string());
  ASSERT_EQ(exported.exit_code, 0) << exported.all();
  EXPECT_NE(exported.out.find("hr_render_info [1, 5, 96, 128]"), std::string::npos) << exported.out;
  EXPECT_NE(exported.out.find("0 failed"), std::string::npos) << exported.out;
  EXPECT_EQ(exported.out.find(" 0 passed"), std::string::npos) << exported.out;

  const auto without = test::run_cgsr("train --data " + tiny_bsp_data().string() + common +
                                      " --set 'enhance.rit.channels=[depth, edge]' --out " + (dir / "without").string());
  EXPECT_EQ(without.exit_code, 2) << without.all();
  EXPECT_NE(without.all().find("bsp_composite"), std::string::npos) << without.all();
  EXPECT_NE(without.all().find("add bsp"), std::string::npos) << without.all();
  std::filesystem::remove_all(dir);
}

}  // namespace bsp_channel_test
}  // namespace cgsr
