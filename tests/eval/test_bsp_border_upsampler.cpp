// The BSP border upsampler: leaves on each side of a known line, bicubic elsewhere, clear errors
// without BSP images, and on rendered frames better than bicubic on the geometry edges.
#include <gtest/gtest.h>

#include <torch/torch.h>

#include <algorithm>

#include "core/config.h"
#include "core/error.h"
#include "core/metrics.h"
#include "eval/baselines/bsp_border_upsampler.h"
#include "eval/baselines/interpolation.h"
#include "eval/upscaler.h"
#include "render_data/bsp_border_builder.h"
#include "render_data/edges.h"
#include "render_data/frame.h"
#include "render_data/renderer.h"
#include "render_data/scene_source.h"
#include "tests/support/cli_runner.h"
#include "tests/support/tiny_data.h"

namespace cgsr {
namespace bsp_upsampler_test {  // named: the tests compile as one unity translation unit

// A 4x4 grey image whose pixel (1, 1) is split by the vertical line x = 1.5: red right of it
// (the side a*x + b*y + c >= 0), blue left.
BspBorderImage one_vertical_line() {
  BspBorderImage image(4, 4, 1);
  BspTree t;
  t.shape = 1;
  t.lines = {BspLine{1, 0, -1.5f}};
  t.leaves = {Rgb8{255, 0, 0}, Rgb8{0, 0, 255}};
  image.add(1 * 4 + 1, t);
  return image;
}

TEST(BspBorderUpsampler, OutputPixelsReadTheLeafTheirCentreFallsIn) {
  const auto lr = torch::full({1, 3, 4, 4}, 0.5f);
  const BspBorderImage image = one_vertical_line();
  for (const int s : {2, 4}) {
    const auto out = upscale_bsp_border(lr, {&image}, s);
    ASSERT_EQ(out.sizes(), (std::vector<int64_t>{1, 3, 4 * s, 4 * s}));
    // Pixel (1, 1) covers output columns and rows s .. 2s - 1; its centre column is x = 1.5.
    for (int Y = s; Y < 2 * s; ++Y)
      for (int X = s; X < 2 * s; ++X) {
        const bool right = (X + 0.5) / s >= 1.5;
        EXPECT_FLOAT_EQ(out[0][0][Y][X].item<float>(), right ? 1.0f : 0.0f) << "s " << s << " at " << X << "," << Y;
        EXPECT_FLOAT_EQ(out[0][2][Y][X].item<float>(), right ? 0.0f : 1.0f) << "s " << s << " at " << X << "," << Y;
      }
    // Everywhere else bicubic, the border pixel's tap reading its leaf on the output centre's
    // side of the line: the bicubic of the input with that pixel blue left of x = 1.5, red right.
    auto left = lr.clone(), right = lr.clone();
    left[0][0][1][1] = 0.0f;
    left[0][1][1][1] = 0.0f;
    left[0][2][1][1] = 1.0f;
    right[0][0][1][1] = 1.0f;
    right[0][1][1][1] = 0.0f;
    right[0][2][1][1] = 0.0f;
    const auto on_left = upscale_bicubic(left, s), on_right = upscale_bicubic(right, s);
    for (int Y = 0; Y < 4 * s; ++Y)
      for (int X = 0; X < 4 * s; ++X) {
        if (Y >= s && Y < 2 * s && X >= s && X < 2 * s) continue;
        const auto& expected = (X + 0.5) / s < 1.5 ? on_left : on_right;
        for (int c = 0; c < 3; ++c)
          ASSERT_NEAR(out[0][c][Y][X].item<float>(), expected[0][c][Y][X].item<float>(), 1e-5)
              << "s " << s << " channel " << c << " at " << X << "," << Y;
      }
    // Far from the border pixel (no tap reaches it) the grey stays exactly grey.
    EXPECT_FLOAT_EQ(out[0][1][4 * s - 1][4 * s - 1].item<float>(), 0.5f);
  }
}

TEST(BspBorderUpsampler, RefusesMissingOrMismatchedImages) {
  const auto lr = torch::full({1, 3, 4, 4}, 0.5f);
  const BspBorderImage image = one_vertical_line();
  const BspBorderImage other(8, 4, 1);
  const auto message = [&](const std::vector<const BspBorderImage*>& bsp) {
    try {
      upscale_bsp_border(lr, bsp, 2);
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("(accepted)");
  };
  EXPECT_NE(message({}).find("0 BSP border image(s) for 1 frame(s)"), std::string::npos) << message({});
  EXPECT_NE(message({nullptr}).find("no BSP border image"), std::string::npos);
  EXPECT_NE(message({&other}).find("8x4 for a frame of 4x4"), std::string::npos) << message({&other});

  // Registered with the classic upscalers; a batch without BSP images is an error saying how to get them.
  auto up = classic_upscalers().get("bsp_border")(2);
  EXPECT_TRUE(up->reads_bsp_border());
  Batch b;
  b.lr_color = lr;
  try {
    up->upscale(b);
    ADD_FAILURE() << "a batch without BSP border images was upscaled";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("bsp_border: {depth"), std::string::npos) << e.what();
  }
  b.lr_bsp_border = {std::make_shared<const BspBorderImage>(one_vertical_line())};
  EXPECT_EQ(up->upscale(b).size(3), 8);
}

// Rendered frames of the tiny procedural room (configs/scenes/tiny.yaml) at 64x48 and 128x96:
// on the HR geometry-edge pixels (grown by one pixel, as evaluation measures them) the BSP border
// upsampler beats bicubic.
TEST(BspBorderUpsampler, BeatsBicubicOnGeometryEdgesOfRenderedFrames) {
  const auto doc = config::Document::load_file(std::string(CGSR_SOURCE_DIR) + "/configs/scenes/tiny.yaml");
  const SceneBundle b = make_scene(config::Block{doc.root()["scene"], std::make_shared<config::Document>(doc), "scene"}, 1);
  RenderSettings settings;
  settings.shadow.map_size = 128;
  const SceneRenderer r(b.scene, settings);
  const float near_plane = b.camera.near_plane, far_plane = b.camera.far_plane;
  double bsp_sum = 0, bicubic_sum = 0, bsp_rest = 0, bicubic_rest = 0;
  const std::vector<int> frames = {1, 3, 5};
  for (int f : frames) {
    const CameraPose pose = b.camera.at_frame(f, 6);
    // Colour as a data set stores it: 8 bits.
    const Frame lr = frame_from_gbuffer(r.render(pose, pose, 64, 48, near_plane, far_plane));
    const Frame hr = frame_from_gbuffer(r.render(pose, pose, 128, 96, near_plane, far_plane));
    const BspBorderImage bsp = r.render_bsp_border(pose, 64, 48, near_plane, far_plane, {2, 4});
    const auto lr_color = lr.color_float().unsqueeze(0), hr_color = hr.color_float().unsqueeze(0);
    const auto mask = dilate_edges(hr.edge);
    const MaskedPsnr with_bsp = masked_psnr(upscale_bsp_border(lr_color, {&bsp}, 2).clamp(0, 1), hr_color, mask).at(0);
    const MaskedPsnr bicubic = masked_psnr(upscale_bicubic(lr_color, 2).clamp(0, 1), hr_color, mask).at(0);
    ASSERT_TRUE(with_bsp.inside && bicubic.inside);
    bsp_sum += *with_bsp.inside;
    bicubic_sum += *bicubic.inside;
    bsp_rest += *with_bsp.outside;
    bicubic_rest += *bicubic.outside;
  }
  const double n = static_cast<double>(frames.size());
  const double gain = (bsp_sum - bicubic_sum) / n;
  RecordProperty("edge_gain_db", std::to_string(gain));
  // Measured +4.5 dB (frames 1, 3 and 5, depth 2, 4 samples per side); the bound leaves headroom.
  EXPECT_GT(gain, 3.0) << "BSP " << bsp_sum / n << " dB against bicubic " << bicubic_sum / n << " dB on geometry edges";
  // Off the edges they differ only around border pixels that the dilated edge map misses.
  EXPECT_GT((bsp_rest - bicubic_rest) / n, -0.1);
}

// `cgsr eval`: 'classic' includes bsp_border on a data set with BSP border files and leaves it out
// elsewhere, where naming it is a user error saying how to render them; it never lists the
// upscalers that read the jitter.
TEST(BspBorderUpsampler, EvalListsItOnlyWhereTheDataHasTheFiles) {
  const auto dir = test::scratch_dir("bsp-border-eval");
  const auto render = test::run_cgsr("render --config " + std::string(CGSR_SOURCE_DIR) +
                                     "/configs/scenes/tiny.yaml --set frames=3 --set bsp_border.depth=2 --threads 1 --out " +
                                     (dir / "data").string());
  ASSERT_EQ(render.exit_code, 0) << render.err;
  const auto names = [](const nlohmann::json& results) {
    std::vector<std::string> out;
    for (const auto& e : results.at("evaluations")) out.push_back(e.at("name").get<std::string>());
    return out;
  };
  const std::string common = " --model classic --split all --latency-runs 0 --threads 1 --out ";
  const auto with = test::run_cgsr("eval --data " + (dir / "data").string() + common + (dir / "with").string());
  ASSERT_EQ(with.exit_code, 0) << with.err;
  const auto listed = names(test::read_json(dir / "with" / "results.json"));
  EXPECT_NE(std::find(listed.begin(), listed.end(), "bsp_border"), listed.end());
  const auto without = test::run_cgsr("eval --data " + test::tiny_data().string() + common + (dir / "without").string());
  ASSERT_EQ(without.exit_code, 0) << without.err;
  const auto plain = names(test::read_json(dir / "without" / "results.json"));
  EXPECT_EQ(std::find(plain.begin(), plain.end(), "bsp_border"), plain.end());
  EXPECT_EQ(plain.size() + 1, listed.size());
  // Nor does it list the upscalers that read the jitter (they are named on their own).
  for (const char* temporal : {"bicubic_at_jitter", "history"})
    EXPECT_EQ(std::find(listed.begin(), listed.end(), temporal), listed.end()) << temporal;
  const auto named = test::run_cgsr("eval --data " + test::tiny_data().string() +
                                    " --model bsp_border --latency-runs 0 --threads 1 --out " + (dir / "named").string());
  EXPECT_EQ(named.exit_code, 2);
  EXPECT_NE(named.all().find("render it with bsp_border: {depth: 2}"), std::string::npos) << named.all();
}

}  // namespace bsp_upsampler_test
}  // namespace cgsr
