// Captures as games write them (capture_format.h): RGBA colour, quantised depth in several
// encodings, motion vectors packed into integer images; and a cgsr-rendered sequence written in
// exactly that form, loaded back through the glob layout and compared with the renderer's own
// channels.
#include <gtest/gtest.h>

#include <torch/torch.h>

#include <fstream>

#include "core/error.h"
#include "core/image_io.h"
#include "render_data/capture_format.h"
#include "render_data/dataset.h"
#include "render_data/edges.h"
#include "render_data/render_channels.h"
#include "test_scenes.h"
#include "tests/support/cli_runner.h"

namespace cgsr {
namespace {
namespace fs = std::filesystem;

ImageFile integer_image(const torch::Tensor& codes, int bits) {
  ImageFile f;
  f.bits = bits;
  f.pixels = codes.to(torch::kFloat32) / static_cast<float>(f.max_code());
  return f;
}

ImageFile float_image(const torch::Tensor& values) {
  ImageFile f;
  f.bits = 32;
  f.pixels = values.to(torch::kFloat32);
  return f;
}

TEST(CaptureFormat, ColourAlphaIsDroppedOrDividedOut) {
  auto rgba = torch::zeros({4, 1, 2});
  rgba.slice(0, 0, 3).fill_(0.25f);
  rgba[3][0][0] = 0.5f;  // premultiplied: the colour is 0.5
  rgba[3][0][1] = 0.0f;  // fully transparent: black
  const auto image = float_image(rgba);
  const auto ignored = decode_capture_color(image, ColorAlpha::Ignore);
  EXPECT_EQ(ignored.sizes(), (std::vector<int64_t>{3, 1, 2}));
  EXPECT_EQ(ignored[0][0][0].item<int>(), 64);
  EXPECT_EQ(ignored[0][0][1].item<int>(), 64);
  const auto straight = decode_capture_color(image, ColorAlpha::Premultiplied);
  EXPECT_EQ(straight[1][0][0].item<int>(), 128);
  EXPECT_EQ(straight[1][0][1].item<int>(), 0);
  // Grey becomes three equal channels; 16-bit codes round to the nearest 8-bit value.
  const auto grey = decode_capture_color(integer_image(torch::full({1, 2, 2}, 32896), 16), ColorAlpha::Ignore);
  EXPECT_TRUE((grey == 128).all().item<bool>());
}

TEST(CaptureFormat, HdrColourIsAnErrorNotAClamp) {
  auto hdr = torch::full({3, 2, 2}, 0.5f);
  hdr[0][1][1] = 4.0f;
  try {
    decode_capture_color(float_image(hdr), ColorAlpha::Ignore);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(e.message().find("1 float value(s) outside [0,1]"), std::string::npos) << e.message();
  }
  EXPECT_THROW(decode_capture_color(float_image(torch::zeros({2, 2, 2})), ColorAlpha::Ignore), Error);
}

// Every encoding decodes its own encoding of a depth ramp to within one storage step, maps its
// clear value to "no geometry", and reports the step.
TEST(CaptureFormat, DepthEncodingsDecodeTheirRampsWithTheirPrecision) {
  const double near = 0.5, far = 40;
  const auto z = torch::linspace(0.6, 25, 50).view({1, 1, 50});  // below the last 8-bit code (clear)
  const auto w = 1.0 / z;
  const auto zbuffer = normalize_depth(z, near, far);
  const std::vector<std::pair<CaptureDepth, torch::Tensor>> stored = {
      {CaptureDepth::Normalized, (zbuffer * 255).round()},
      {CaptureDepth::Reversed, ((1 - zbuffer) * 255).round()},
      {CaptureDepth::Linear, (z / 0.25).round()},  // quarter metres
      {CaptureDepth::LinearNormalized, (z / far * 255).round()},
  };
  for (const auto& [encoding, codes] : stored) {
    DepthFormat f;
    f.encoding = encoding;
    f.near_plane = near;
    f.far_plane = far;
    f.scale = encoding == CaptureDepth::Linear ? 0.25 : 1;
    const auto map = decode_capture_depth(integer_image(codes, 8), f);
    SCOPED_TRACE(enum_name(encoding));
    ASSERT_FALSE(map.precision.exact());
    // Half a step of rounding, in 1/z.
    const auto step = map.precision.inverse_step + map.precision.linear_step * w * w;
    const auto error = (1.0 / map.depth - w).abs();
    EXPECT_TRUE((error <= step * 0.5 + 1e-6).all().item<bool>()) << (error / step).max().item<double>();
  }
  DepthFormat reversed;
  reversed.encoding = CaptureDepth::Reversed;
  reversed.near_plane = near;
  reversed.far_plane = far;
  EXPECT_TRUE(torch::isinf(decode_capture_depth(integer_image(torch::zeros({1, 1, 1}), 8), reversed).depth).all().item<bool>());
  DepthFormat linear;
  linear.encoding = CaptureDepth::Linear;
  const auto exact = decode_capture_depth(float_image(torch::tensor({0.0f, 2.5f}).view({1, 1, 2})), linear);
  EXPECT_TRUE(exact.precision.exact());
  EXPECT_TRUE(std::isinf(exact.depth[0][0][0].item<float>()));
  EXPECT_FLOAT_EQ(exact.depth[0][0][1].item<float>(), 2.5f);
  EXPECT_THROW(decode_capture_depth(float_image(torch::full({1, 1, 1}, -1.0f)), linear), Error);
}

TEST(CaptureFormat, MotionFromPackedCodes) {
  // x: a 16-bit code split into R (high) and G (low) bytes, (code / 65535 - 0.5) * 2 in uv.
  const int code = 40000;
  auto codes = torch::zeros({4, 1, 1}, torch::kInt32);
  codes[0][0][0] = code / 256;
  codes[1][0][0] = code % 256;
  codes[2][0][0] = 128;  // y in one channel: (128 / 255 - 0.5) * -8 px
  MotionFormat f;
  f.declared = true;
  f.x = {{0, 1}, 2.0, 0.5};
  f.y = {{2}, -8.0, 0.5};
  f.units = MotionUnits::Uv;
  const auto m = decode_capture_motion(integer_image(codes, 8), f);
  // uv of x times the width (1 pixel here), y in pixels too (uv of height 1).
  EXPECT_NEAR(m[0][0][0].item<float>(), (code / 65535.0 - 0.5) * 2, 1e-6);
  EXPECT_NEAR(m[1][0][0].item<float>(), (128 / 255.0 - 0.5) * -8, 1e-6);
  // Integer images without a declared mapping, and channels the image does not have, are errors.
  EXPECT_THROW(decode_capture_motion(integer_image(codes, 8), MotionFormat{}), Error);
  f.y = {{5}, 1.0, 0.0};
  EXPECT_THROW(decode_capture_motion(integer_image(codes, 8), f), Error);
}

// A slanted floor stored in 8 bits is a staircase; without its precision every step is an edge.
TEST(CaptureFormat, QuantisedDepthStaircasesAreNotEdges) {
  const double near = 0.5, far = 30;
  const auto z = torch::linspace(1.0, 20.0, 120).view({1, 120, 1}).expand({1, 120, 80}).contiguous();
  DepthFormat f;
  f.encoding = CaptureDepth::Normalized;
  f.near_plane = near;
  f.far_plane = far;
  const auto map = decode_capture_depth(integer_image((normalize_depth(z, near, far) * 255).round(), 8), f);
  const EdgeSettings settings;
  const auto naive = detect_edges(map.depth, {}, {}, settings).sum().item<int64_t>();
  EXPECT_GT(naive, 80 * 5) << "the staircase should fool a detector that ignores quantisation";
  EXPECT_EQ(detect_edges(map.depth, {}, {}, settings, map.precision).sum().item<int64_t>(), 0);
  // A real step (a box 30% nearer) is still found.
  auto boxed = z.clone();
  boxed.slice(2, 40, 80) *= 0.7f;
  const auto box = decode_capture_depth(integer_image((normalize_depth(boxed, near, far) * 255).round(), 8), f);
  // Where the jump is larger than the tolerance (8% plus 2 steps of 1/z), up to about 8 m.
  const auto edges = detect_edges(box.depth, {}, {}, settings, box.precision);
  const auto near_rows = edges.slice(1, 0, 40);
  EXPECT_EQ((near_rows.select(2, 39) + near_rows.select(2, 40)).gt(0).sum().item<int64_t>(), 40);
}

// --- a cgsr-rendered sequence written as a game capture ---------------------------------------

TEST(CaptureFormat, RenderedSequenceAsAGameCaptureLoadsBack) {
  const fs::path dir = test::scratch_dir("capture_roundtrip");
  const auto r = test::run_cgsr("render --config " + std::string(CGSR_SOURCE_DIR) + "/configs/scenes/tiny.yaml --out " +
                                (dir / "render").string() + " --threads 1 --set 'resolutions=[160x120, 320x240]' --set frames=6");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  DatasetOpenOptions all;
  all.channels = {"depth", "normal", "edge", "motion"};
  const Dataset rendered = Dataset::open(dir / "render", all);
  const int W = 160, H = 120, frames = rendered.frame_count();

  // Depth planes that bracket the scene, as a capture tool picks them for an 8-bit image.
  double z_min = 1e30, z_max = 0;
  for (int i = 0; i < frames; ++i) {
    const auto d = rendered.frame(i, 0)->depth;
    const auto finite = d.masked_select(torch::isfinite(d));
    z_min = std::min(z_min, finite.min().item<double>());
    z_max = std::max(z_max, finite.max().item<double>());
  }
  const double near = 0.9 * z_min, far = 1.1 * z_max;
  fs::create_directories(dir / "capture" / "lr");
  fs::create_directories(dir / "capture" / "hr");
  const double motion_scale = 2.0, max16 = 65535;  // uv in [-1, 1] as 16-bit codes around 0.5
  for (int i = 0; i < frames; ++i) {
    const auto lr = rendered.frame(i, 0);
    const std::string n = std::to_string(i);
    auto rgba = torch::cat({lr->color_float(), torch::full({1, H, W}, 0.3f)}, 0);  // alpha means nothing here
    write_image(dir / "capture" / "lr" / ("color_" + n + ".png"), rgba);
    const auto reversed = torch::where(torch::isinf(lr->depth), torch::zeros({}), 1 - normalize_depth(lr->depth, near, far));
    write_image(dir / "capture" / "lr" / ("depth_" + n + ".png"), reversed);
    // Motion as uv, y up, each component a 16-bit code in two 8-bit channels.
    auto pack = [&](const torch::Tensor& uv) {
      const auto code = ((uv / motion_scale + 0.5) * max16).round().clamp(0, max16).to(torch::kInt32);
      return std::make_pair(torch::floor_divide(code, 256), code.remainder(256));
    };
    const auto [xh, xl] = pack(lr->motion[0] / W);
    const auto [yh, yl] = pack(-lr->motion[1] / H);
    write_image(dir / "capture" / "lr" / ("mv_" + n + ".png"), torch::stack({xh, xl, yh, yl}, 0).to(torch::kFloat32) / 255);
    write_image(dir / "capture" / "hr" / ("frame_" + n + ".png"), rendered.frame(i, 1)->color_float());
  }
  std::ofstream(dir / "capture" / "capture.yaml")
      << "layout: glob\nname: game\nnear: " << near << "\nfar: " << far << "\nvfov: 70\n"
      << "color_alpha: ignore\ndepth_encoding: reversed\n"
         "motion_format:\n"
         "  x: {channels: [0, 1], scale: 2, offset: 0.5}\n"
         "  y: {channels: [2, 3], scale: -2, offset: 0.5}\n"
         "  units: uv\n"
         "resolutions:\n"
         "  - {size: 160x120, color: lr/color_*.png, depth: lr/depth_*.png, motion: lr/mv_*.png}\n"
         "  - {size: 320x240, color: hr/frame_*.png}\n";

  DatasetOpenOptions open;
  open.channels = {"depth", "edge", "motion"};
  open.derive = {"edge"};
  const Dataset capture = Dataset::open(dir / "capture" / "capture.yaml", open);
  ASSERT_EQ(capture.frame_count(), frames);
  const double motion_step = motion_scale / max16 * W;  // one code, in pixels (x; y is finer)
  int64_t found = 0, found_on_edges = 0, depth_edges = 0, depth_edges_found = 0;
  for (int i = 0; i < frames; ++i) {
    SCOPED_TRACE("frame " + std::to_string(i));
    const auto truth = rendered.frame(i, 0);
    const auto loaded = capture.frame(i, 0);
    EXPECT_TRUE(torch::equal(loaded->color, truth->color));
    EXPECT_TRUE(torch::equal(capture.frame(i, 1)->color, rendered.frame(i, 1)->color));
    // Within one code where the packing can hold the motion (|uv| < 1).
    const auto representable = (truth->motion[0].abs() < W * 0.99) & (truth->motion[1].abs() < H * 0.99);
    const auto motion_error = (loaded->motion - truth->motion).abs().amax(0);
    EXPECT_LE(motion_error.masked_select(representable).max().item<double>(), motion_step);
    // Edges from 8-bit depth: what they find lies on the renderer's edges, and they find the
    // renderer's depth discontinuities (its creases and id changes need normals and ids).
    const auto f = loaded->edge.squeeze(0) > 0, all = truth->edge.squeeze(0) > 0;
    const auto from_depth = detect_edges(truth->depth, {}, {}, EdgeSettings{}).squeeze(0) > 0;
    found += f.sum().item<int64_t>();
    found_on_edges += (f & dilate_edges(all)).sum().item<int64_t>();
    depth_edges += from_depth.sum().item<int64_t>();
    depth_edges_found += (from_depth & dilate_edges(f)).sum().item<int64_t>();
  }
  ASSERT_GT(depth_edges, 100) << "the sequence should show depth discontinuities";
  EXPECT_GE(static_cast<double>(found_on_edges) / found, 0.9);
  EXPECT_GE(static_cast<double>(depth_edges_found) / depth_edges, 0.9);
  // `cgsr data check` sees the capture, with edges derived from its depth.
  const auto check = test::run_cgsr("data check " + (dir / "capture" / "capture.yaml").string() + " --derive edge");
  EXPECT_EQ(check.exit_code, 0) << check.err;
  EXPECT_EQ(check.out.find("edges        0.00%"), std::string::npos) << check.out;
  EXPECT_NE(check.out.find("edges "), std::string::npos) << check.out;
}

}  // namespace
}  // namespace cgsr
