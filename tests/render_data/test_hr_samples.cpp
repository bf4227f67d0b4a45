// Anti-aliased targets (render config `hr_samples`): the resolve against a supersampled render
// averaged here in linear light, a render job's files against the one-sample render (only the
// targets' colour changes, and only near geometry edges), the manifest and the loader's target,
// and the errors a bad value gets.
#include <gtest/gtest.h>

#include <torch/torch.h>

#include <fstream>
#include <utility>

#include "core/error.h"
#include "render_data/dataset.h"
#include "render_data/dataset_manifest.h"
#include "render_data/frame_files.h"
#include "render_data/hr_samples.h"
#include "render_data/render_job.h"
#include "render_data/renderer.h"
#include "render_data/scene_source.h"
#include "test_scenes.h"
#include "tests/support/cli_runner.h"

namespace cgsr {
namespace {
namespace fs = std::filesystem;

std::string tiny_scene_config() { return std::string(CGSR_SOURCE_DIR) + "/configs/scenes/tiny.yaml"; }

RenderJobOptions hr_tiny_job(int frames, int hr_samples) {
  static const auto doc = std::make_shared<config::Document>(config::Document::load_file(tiny_scene_config()));
  RenderJobOptions job;
  job.frames = frames;
  job.resolutions = {"64x48", "128x96"};
  job.shadows = true;
  job.shadow_map_size = 128;
  job.hr_samples = hr_samples;
  job.scene = config::Block{doc->root()["scene"], doc, "scene"};
  return job;
}

// sRGB <-> linear light, written out here rather than taken from the renderer.
torch::Tensor decode_srgb_test(const torch::Tensor& c) {
  return torch::where(c <= 0.04045, c / 12.92, torch::pow((c + 0.055) / 1.055, 2.4));
}
torch::Tensor encode_srgb_test(const torch::Tensor& l) {
  return torch::where(l <= 0.0031308, l * 12.92, 1.055 * torch::pow(l, 1.0 / 2.4) - 0.055);
}
// The n x n blocks of an sRGB [3, nH, nW] image averaged in linear light, [3, H, W].
torch::Tensor linear_box_resolve(const torch::Tensor& srgb, int n) {
  const auto linear = decode_srgb_test(srgb.to(torch::kFloat64));
  return encode_srgb_test(torch::avg_pool2d(linear.unsqueeze(0), {n, n}).squeeze(0));
}

torch::Tensor file_bytes(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  return torch::from_blob(const_cast<char*>(text.data()), {static_cast<int64_t>(text.size())}, torch::kUInt8).clone();
}
bool same_file_bytes(const fs::path& a, const fs::path& b) { return torch::equal(file_bytes(a), file_bytes(b)); }

TEST(HrSamples, OnlySquaresUpToFourPerSide) {
  EXPECT_EQ(hr_samples_per_side(1), 1);
  EXPECT_EQ(hr_samples_per_side(4), 2);
  EXPECT_EQ(hr_samples_per_side(9), 3);
  EXPECT_EQ(hr_samples_per_side(16), 4);
  for (int bad : {0, -4, 2, 3, 8, 25, 64}) EXPECT_EQ(hr_samples_per_side(bad), 0) << bad;
  EXPECT_EQ(hr_target_description(1, ""), "aliased (1 sample per pixel)");
  EXPECT_EQ(hr_target_description(4, "box"), "supersampled (4 samples per pixel, box filter)");
}

// A resolved pixel is the linear-light mean of its n x n samples: the view rendered at n x the
// size (one sample per pixel, render()) and averaged here, for n = 2 and 3; n = 1 is render().
TEST(HrSamples, AResolvedPixelIsTheLinearMeanOfItsSupersampledBlock) {
  const SceneBundle b = make_scene(hr_tiny_job(3, 4).scene, 1);
  const SceneRenderer renderer(b.scene, RenderSettings{});
  const CameraPose pose = b.camera.at_frame(1, 3);
  const float near = b.camera.near_plane, far = b.camera.far_plane;
  EXPECT_TRUE(torch::equal(renderer.render_color(pose, 64, 48, near, far, 1),
                           renderer.render(pose, pose, 64, 48, near, far).color));
  for (int n : {2, 3}) {
    SCOPED_TRACE("n = " + std::to_string(n));
    const torch::Tensor resolved = renderer.render_color(pose, 64, 48, near, far, n);
    const torch::Tensor super = renderer.render(pose, pose, 64 * n, 48 * n, near, far).color;
    ASSERT_EQ(resolved.sizes(), (std::vector<int64_t>{3, 48, 64}));
    const torch::Tensor expected = linear_box_resolve(super, n).to(torch::kFloat32);
    EXPECT_LT((resolved - expected).abs().max().item<float>(), 2e-5f);
    // Averaging the sRGB values instead would be another image: the test tells them apart.
    const torch::Tensor srgb_mean = torch::avg_pool2d(super.unsqueeze(0), {n, n}).squeeze(0);
    EXPECT_GT((resolved - srgb_mean).abs().max().item<float>(), 0.01f);
  }
}

// Two flat, evenly lit surfaces, a tilted dark square before a white wall: inside each the
// supersampled colour is the one-sample colour (within float rounding), along the square's
// edges (the one-sample edge map grown by a pixel) it is the mix of both.
TEST(HrSamples, OnlyPixelsAtGeometryEdgesChange) {
  Scene s = test::empty_scene();
  Material dark;
  dark.name = "dark";
  dark.tint = {0.05f, 0.1f, 0.6f};
  s.materials.push_back(dark);
  test::add_quad(s, {0, 0, -5}, {50, 0, 0}, {0, 50, 0}, 1);
  test::add_quad(s, {0.2f, 0.1f, -3}, {0.8f, 0.35f, 0}, {-0.35f, 0.8f, 0}, 2);
  s.meshes.back().material = 1;
  const SceneRenderer renderer(s, test::unshadowed());
  const CameraPose pose;
  const GBuffer g = renderer.render(pose, pose, 96, 72, 0.1f, 100.0f);
  const torch::Tensor resolved = renderer.render_color(pose, 96, 72, 0.1f, 100.0f, 4);
  const torch::Tensor diff = (resolved - g.color).abs().amax(0);
  const torch::Tensor edge = g.edge.unsqueeze(0);
  const torch::Tensor near_edge = torch::max_pool2d(edge, 3, 1, 1).squeeze(0).squeeze(0) > 0;
  const torch::Tensor away = near_edge.logical_not();
  ASSERT_GT(near_edge.sum().item<int64_t>(), 40);
  ASSERT_GT(away.sum().item<int64_t>(), 3000);
  EXPECT_LT(diff.masked_select(away).max().item<float>(), 1e-5f);
  EXPECT_GT(diff.masked_select(near_edge).max().item<float>(), 0.3f);
  // The grown edge is about four pixels across the outline, which crosses one or two of them.
  EXPECT_GT((diff.masked_select(near_edge) > 0.02f).sum().item<int64_t>(), near_edge.sum().item<int64_t>() / 5);
}

// Rendered with hr_samples 4 against 1: the LR frames and every G-buffer are byte for byte the
// same, the targets' colour is render_color's. hr_samples 1 is the render without the key: same
// fingerprint, no manifest key, the same bytes as render().
TEST(HrSamples, SupersamplingChangesOnlyTheTargetsColour) {
  const fs::path root = test::scratch_dir("hr_samples_render");
  RenderJobOptions one = hr_tiny_job(2, 1), four = hr_tiny_job(2, 4);
  one.name = "one";
  four.name = "four";
  RenderJobOptions plain = hr_tiny_job(2, 1);
  EXPECT_EQ(render_fingerprint(one, 1), render_fingerprint(plain, 1));
  EXPECT_NE(render_fingerprint(four, 1), render_fingerprint(one, 1));
  RenderJobOptions nine = hr_tiny_job(2, 9);
  EXPECT_NE(render_fingerprint(nine, 1), render_fingerprint(four, 1));
  finish_render(root / "one", run_render_job(one, 1, root / "one").manifest);
  finish_render(root / "four", run_render_job(four, 1, root / "four").manifest);

  std::ifstream in(root / "one" / "manifest.yaml");
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(text.find("hr_"), std::string::npos) << text;

  const DatasetManifest m = read_manifest(root / "four");
  EXPECT_EQ(m.hr_samples, 4);
  EXPECT_EQ(m.hr_filter, "box");
  const Resolution lr = m.resolutions[0], hr = m.resolutions[1];
  for (int f = 0; f < 2; ++f) {
    SCOPED_TRACE("frame " + std::to_string(f));
    for (FileKind k : all_file_kinds()) {
      EXPECT_TRUE(same_file_bytes(frame_file(root / "one", lr, k, f), frame_file(root / "four", lr, k, f)))
          << "LR " << file_kind_name(k);
      if (k != FileKind::Color) {
        EXPECT_TRUE(same_file_bytes(frame_file(root / "one", hr, k, f), frame_file(root / "four", hr, k, f)))
            << "HR " << file_kind_name(k);
      }
    }
    // Only the targets' colour changes (where it changes is the next test's business).
    EXPECT_FALSE(torch::equal(read_color_file(frame_file(root / "one", hr, FileKind::Color, f), f, hr),
                              read_color_file(frame_file(root / "four", hr, FileKind::Color, f), f, hr)));
  }
  // The LR input of both sets is the same one-sample render; the one-sample set's targets too.
  const SceneBundle b = make_scene(one.scene, 1);
  const SceneRenderer renderer(b.scene, [] {
    RenderSettings s;
    s.shadow.map_size = 128;
    return s;
  }());
  const GBuffer g = renderer.render(b.camera.at_frame(1, 2), b.camera.at_frame(0, 2), hr.width, hr.height,
                                    b.camera.near_plane, b.camera.far_plane);
  const auto as_u8 = [](const torch::Tensor& c) { return (c.clamp(0, 1) * 255.0f).round().to(torch::kUInt8); };
  EXPECT_TRUE(torch::equal(read_color_file(frame_file(root / "one", hr, FileKind::Color, 1), 1, hr), as_u8(g.color)));
  const torch::Tensor resolved = renderer.render_color(b.camera.at_frame(1, 2), hr.width, hr.height,
                                                       b.camera.near_plane, b.camera.far_plane, 2);
  EXPECT_TRUE(torch::equal(read_color_file(frame_file(root / "four", hr, FileKind::Color, 1), 1, hr), as_u8(resolved)));

  // The loader names the target; a render of one config cannot resume into the other's directory.
  EXPECT_EQ(Dataset::open(root / "four").info().target, "supersampled (4 samples per pixel, box filter)");
  EXPECT_EQ(Dataset::open(root / "four").info().hr_samples, 4);
  EXPECT_EQ(Dataset::open(root / "one").info().target, "aliased (1 sample per pixel)");
  EXPECT_EQ(Dataset::open(root / "one").info().hr_samples, 1);
  // A set merged from both names each scene's target, and a view of one scene its own.
  write_manifest(root / "mixed", merge_manifests(root / "mixed", "mixed", {root / "one", root / "four"}, {}));
  const Dataset mixed = Dataset::open(root / "mixed");
  EXPECT_EQ(mixed.info().target,
            "mixed: one aliased (1 sample per pixel), four supersampled (4 samples per pixel, box filter)");
  EXPECT_EQ(mixed.info().hr_samples, 0);
  EXPECT_EQ(mixed.scene("four").info().target, "supersampled (4 samples per pixel, box filter)");
  EXPECT_EQ(mixed.scene("one").info().hr_samples, 1);
  try {
    run_render_job(four, 1, root / "one");
    ADD_FAILURE() << "resumed an aliased render with hr_samples 4";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("different configuration"), std::string::npos) << e.what();
  }
}

TEST(HrSamples, ManifestRoundTripAndMalformedValuesNameTheKey) {
  const fs::path dir = test::scratch_dir("hr_samples_manifest");
  DatasetManifest m;
  m.name = "aa";
  m.fingerprint = "0123456789abcdef";
  m.frames = 2;
  m.resolutions = {{32, 24}, {64, 48}};
  m.split = make_split(2);
  m.hr_samples = 16;
  m.hr_filter = "box";
  write_manifest(dir, m);
  const DatasetManifest back = read_manifest(dir);
  EXPECT_EQ(back.hr_samples, 16);
  EXPECT_EQ(back.hr_filter, "box");

  test::expect_manifest_errors(dir, {
      {"hr_samples: 8\nhr_filter: box", "hr_samples: is 8, must be a square n x n with n in 1..4 (1, 4, 9 or 16)"},
      {"hr_samples: 4", "missing required key 'hr_filter'"},
      {"hr_samples: 4\nhr_filter: gauss", "unknown filter 'gauss'"},
      {"hr_filter: box", "a filter without hr_samples above 1"},
      {"hr_samples: many\nhr_filter: box", "hr_samples"},
  }, "manifest.yaml:1", "hr_");
}

TEST(HrSamples, BadValuesAreErrorsNamingTheKey) {
  for (int bad : {2, 0, 25}) {
    try {
      run_render_job(hr_tiny_job(1, bad), 1, test::scratch_dir("hr_samples_bad"));
      ADD_FAILURE() << bad;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("hr_samples: is " + std::to_string(bad) + ", must be a square"),
                std::string::npos)
          << e.what();
    }
  }
  RenderJobOptions single = hr_tiny_job(1, 4);
  single.resolutions = {"64x48"};
  try {
    run_render_job(single, 1, test::scratch_dir("hr_samples_single"));
    ADD_FAILURE() << "supersampled a render with no target resolution";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("there is only 64x48"), std::string::npos) << e.what();
  }
  // The config: the key is checked before anything renders.
  const fs::path out = test::scratch_dir("hr_samples_cli") / "set";
  const test::CliResult r = test::run_cgsr("render --config " + tiny_scene_config() + " --set hr_samples=3 --out " + out.string());
  EXPECT_EQ(r.exit_code, 2) << r.all();
  EXPECT_NE(r.all().find("hr_samples"), std::string::npos) << r.all();
  EXPECT_NE(r.all().find("1, 4, 9 or 16"), std::string::npos) << r.all();
  EXPECT_FALSE(fs::exists(out / "manifest.yaml"));
  // hr_samples=1 is the config without the key: the resolved config (and so the stage hash of
  // `cgsr run`) is the same.
  const test::CliResult plain = test::run_cgsr("render --config " + tiny_scene_config() + " --print-config");
  const test::CliResult one = test::run_cgsr("render --config " + tiny_scene_config() + " --set hr_samples=1 --print-config");
  const test::CliResult four = test::run_cgsr("render --config " + tiny_scene_config() + " --set hr_samples=4 --print-config");
  ASSERT_EQ(plain.exit_code, 0) << plain.all();
  EXPECT_EQ(one.out, plain.out);
  EXPECT_EQ(plain.out.find("hr_samples"), std::string::npos) << plain.out;
  EXPECT_NE(four.out.find("hr_samples: 4"), std::string::npos) << four.out;
}

}  // namespace
}  // namespace cgsr
