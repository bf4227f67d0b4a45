// Sub-pixel BSP border images: the trees the renderer builds (their lines against the HR render's
// edge), the builder on hand-made samples, the file format and its validation, and the render job
// that writes them without changing what it wrote before.
#include <gtest/gtest.h>

#include <oneapi/tbb/global_control.h>
#include <torch/torch.h>

#include <cmath>
#include <cstring>
#include <functional>

#include "core/atomic_file.h"
#include "core/error.h"
#include "render_data/bsp_border_builder.h"
#include "render_data/bsp_border_file.h"
#include "render_data/data_check.h"
#include "render_data/dataset.h"
#include "render_data/frame_files.h"
#include "render_data/render_job.h"
#include "render_data/renderer.h"
#include "render_data/scene_source.h"
#include "test_scenes.h"

namespace cgsr {
namespace bsp_test {  // named: the tests compile as one unity translation unit

// A plane much larger than the view at z = -5 whose left edge runs through the view at `degrees`
// from the vertical; sky on its left.
Scene slanted_edge_scene(double degrees) {
  Scene s = test::empty_scene();
  s.sky.horizon = {0.1f, 0.2f, 0.6f};
  s.sky.zenith = {0.1f, 0.2f, 0.6f};
  const float t = static_cast<float>(degrees * kPi / 180);
  const Vec3 u{50 * std::cos(t), 50 * std::sin(t), 0}, v{-50 * std::sin(t), 50 * std::cos(t), 0};
  test::add_quad(s, Vec3{0.37f, 0.0f, -5.0f} + u, u, v, 7);
  return s;
}

// Where the HR render's coverage flips along each HR row: the midpoint between the last sky pixel
// centre and the first plane pixel centre, in LR pixel coordinates (x, y of the row's centre).
std::vector<std::pair<double, double>> hr_flips(const GBuffer& hr, int scale) {
  std::vector<std::pair<double, double>> out;
  auto id = hr.object_id.accessor<int32_t, 3>();
  for (int Y = 0; Y < hr.height; ++Y)
    for (int X = 0; X + 1 < hr.width; ++X)
      if (id[0][Y][X] != id[0][Y][X + 1]) {
        out.emplace_back((X + 1.0) / scale, (Y + 0.5) / scale);
        break;
      }
  return out;
}

TEST(BspBorder, RenderedLineReproducesTheHrEdgeWithinATenthOfAnLrPixel) {
  for (const double degrees : {17.0, -31.0}) {
    SCOPED_TRACE("edge at " + std::to_string(degrees) + " degrees");
    const SceneRenderer r(slanted_edge_scene(degrees), test::unshadowed());
    CameraPose pose;
    pose.vfov = 60;
    const int W = 64, H = 48, s = 2;
    const GBuffer hr = r.render(pose, pose, W * s, H * s, 0.1f, 100.0f);
    const BspBorderImage bsp = r.render_bsp_border(pose, W, H, 0.1f, 100.0f, {/*depth=*/2, /*samples=*/4});

    // The HR edge: a least-squares line x = alpha * y + beta through the rows' flip points (each
    // known to half an HR pixel; the fit averages that over the rows).
    const auto flips = hr_flips(hr, s);
    ASSERT_GT(flips.size(), 80u);
    double sy = 0, sx = 0, syy = 0, sxy = 0;
    for (const auto& [x, y] : flips) {
      sx += x;
      sy += y;
      syy += y * y;
      sxy += x * y;
    }
    const double n = static_cast<double>(flips.size());
    const double alpha = (n * sxy - sx * sy) / (n * syy - sy * sy), beta = (sx - alpha * sy) / n;

    // Every LR row the edge crosses has border pixels, each a single line (one other surface),
    // also where the edge runs between two pixels' samples (the ring of neighbour samples sees it).
    int rows_with_border = 0;
    double worst = 0;
    for (int i = 0; i < H; ++i) {
      bool any = false;
      for (int j = 0; j < W; ++j) {
        const BspTree* tree = bsp.at(j, i);
        if (!tree) continue;
        any = true;
        ASSERT_EQ(tree->lines.size(), 1u) << "pixel " << j << "," << i;
        const BspLine& l = tree->lines[0];
        // Where the line crosses the pixel's centre row, against the HR edge there.
        const double y = i + 0.5, x = -(l.b * y + l.c) / l.a;
        worst = std::max(worst, std::abs(x - (alpha * y + beta)));
        // And every HR row through the pixel flips where the line says, to half an HR pixel.
        for (const auto& [fx, fy] : flips) {
          if (fy > i && fy < i + 1 && std::abs(fx - j - 0.5) < 1.5) {
            EXPECT_NEAR(-(l.b * fy + l.c) / l.a, fx, 0.5 / s + 1e-3) << "pixel " << j << "," << i;
          }
        }
      }
      rows_with_border += any;
      EXPECT_TRUE(any) << "row " << i << ": the edge runs from x " << alpha * i + beta << " to " << alpha * (i + 1) + beta;
    }
    EXPECT_EQ(rows_with_border, H);
    EXPECT_LT(worst, 0.1) << worst << " LR pixels between a BSP line and the HR render's edge";
    RecordProperty("worst_line_error_lr_px_" + std::to_string(static_cast<int>(degrees)), std::to_string(worst));
    // A straight edge crosses one or two pixels per row.
    EXPECT_LE(bsp.size(), static_cast<size_t>(2 * H + 2));
  }
}

TEST(BspBorder, LeavesHoldTheColoursOfEachSide) {
  const SceneRenderer r(slanted_edge_scene(17), test::unshadowed());
  CameraPose pose;
  pose.vfov = 60;
  const int W = 64, H = 48;
  const GBuffer lr = r.render(pose, pose, W, H, 0.1f, 100.0f);
  const BspBorderImage bsp = r.render_bsp_border(pose, W, H, 0.1f, 100.0f, {1, 4});
  ASSERT_GT(bsp.size(), 0u);
  auto color = lr.color.accessor<float, 3>();
  auto id = lr.object_id.accessor<int32_t, 3>();
  const int i = H / 2;
  int j = 0;
  while (j < W && !bsp.at(j, i)) ++j;
  ASSERT_LT(j + 3, W);
  const BspTree& tree = *bsp.at(j, i);
  // The sky two pixels left, the (flat, evenly lit) plane two pixels right of the border pixel.
  ASSERT_EQ(id[0][i][j - 2], -1);
  ASSERT_EQ(id[0][i][j + 3], 7);
  // Either side of where the line crosses the pixel's centre row.
  const BspLine& l = tree.lines[0];
  const double y = i + 0.5, x = -(l.b * y + l.c) / l.a;
  const Rgb8& sky = tree.leaves[tree.leaf_at(x - 0.3, y)];
  const Rgb8& plane = tree.leaves[tree.leaf_at(x + 0.3, y)];
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(sky[c], color[c][i][j - 2] * 255, 1.0);
    EXPECT_NEAR(plane[c], color[c][i][j + 3] * 255, 3.0);  // lit: shading varies a little across pixels
  }
}

TEST(BspBorder, NoBorderInsideOneSurface) {
  // A plane filling the view, made of two triangles: the diagonal between them is no border.
  Scene s = test::empty_scene();
  test::add_quad(s, {0, 0, -5}, {50, 0, 0}, {0, 50, 0}, 3);
  const SceneRenderer r(s, test::unshadowed());
  CameraPose pose;
  const BspBorderImage bsp = r.render_bsp_border(pose, 32, 24, 0.1f, 100.0f, {2, 4});
  EXPECT_EQ(bsp.size(), 0u);
}

TEST(BspBorder, RefusesSettingsOutOfRange) {
  Scene s = test::empty_scene();
  test::add_quad(s, {0, 0, -5}, {50, 0, 0}, {0, 50, 0}, 3);
  const SceneRenderer r(s, test::unshadowed());
  CameraPose pose;
  const auto message = [&](int width, int height, BspBorderSettings settings) {
    try {
      r.render_bsp_border(pose, width, height, 0.1f, 100.0f, settings);
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("(accepted)");
  };
  EXPECT_NE(message(32, 24, {0, 4}).find("depth"), std::string::npos);
  EXPECT_NE(message(32, 24, {5, 4}).find("depth"), std::string::npos);
  EXPECT_NE(message(32, 24, {2, 1}).find("samples"), std::string::npos);
  const std::string big = message(4096, 2160, {2, 16});
  EXPECT_NE(big.find("65536x34560 samples"), std::string::npos) << big;
  EXPECT_NE(big.find("use fewer samples"), std::string::npos) << big;
}

SceneBundle tiny_scene() {
  const auto doc = config::Document::load_file(std::string(CGSR_SOURCE_DIR) + "/configs/scenes/tiny.yaml");
  const config::Block block{doc.root()["scene"], std::make_shared<config::Document>(doc), "scene"};
  return make_scene(block, 1);
}

TEST(BspBorder, SameBytesWithOneThreadAndMany) {
  const SceneBundle b = tiny_scene();
  const SceneRenderer r(b.scene, test::unshadowed());
  const CameraPose pose = b.camera.at_frame(2, 6);
  const float near_plane = b.camera.near_plane, far_plane = b.camera.far_plane;
  const std::string many = encode_bsp_border(r.render_bsp_border(pose, 64, 48, near_plane, far_plane, {2, 4}));
  std::string one;
  {
    tbb::global_control single(tbb::global_control::max_allowed_parallelism, 1);
    one = encode_bsp_border(r.render_bsp_border(pose, 64, 48, near_plane, far_plane, {2, 4}));
  }
  EXPECT_EQ(many, one);
  const BspBorderImage image = decode_bsp_border(many, "tiny", 2, {64, 48});
  EXPECT_GT(image.size(), 50u);  // a room with props has borders
  EXPECT_LT(image.border_fraction(), 0.5);
  int deeper = 0;
  for (size_t k = 0; k < image.size(); ++k) deeper += image.tree(k).depth() == 2;
  EXPECT_GT(deeper, 0) << "corners and thin props need a second line somewhere";
}

// ---- the builder on hand-made samples ----

std::vector<BspSample> grid_samples(int px, int py, int m, const std::function<int32_t(double, double)>& surface) {
  std::vector<BspSample> out;
  for (int b = 0; b < m; ++b)
    for (int a = 0; a < m; ++a) {
      BspSample s;
      s.x = px + (a + 0.5) / m;
      s.y = py + (b + 0.5) / m;
      s.surface = surface(s.x, s.y);
      const float v = s.surface == 0 ? 0.2f : 0.8f;
      s.color = {v, v, v};
      out.push_back(s);
    }
  return out;
}

TEST(BspBorderBuilder, PicksTheSeparatingLineAndColoursTheLeaves) {
  // Surface 1 right of x = 10.3 in pixel (10, 4); three candidates, only one separates.
  const auto samples = grid_samples(10, 4, 4, [](double x, double) { return x > 10.3 ? 1 : 0; });
  std::vector<BspCandidate> candidates = {{*line_through(10.9, 0, 10.9, 9), 0},
                                          {*line_through(0, 4.5, 20, 4.5), 0},
                                          {*line_through(10.3, 0, 10.3, 9), 1}};
  const auto tree = build_pixel_bsp(samples, candidates, 2);
  ASSERT_TRUE(tree.has_value());
  ASSERT_EQ(tree->lines.size(), 1u);
  EXPECT_NEAR(-tree->lines[0].c / tree->lines[0].a, 10.3, 1e-5);
  const Rgb8& left = tree->leaves[tree->leaf_at(10.1, 4.5)];
  const Rgb8& right = tree->leaves[tree->leaf_at(10.8, 4.5)];
  EXPECT_EQ(left[0], std::lround(0.2 * 255));
  EXPECT_EQ(right[0], std::lround(0.8 * 255));
}

TEST(BspBorderBuilder, SecondLineForACornerAndNoneForOneSurface) {
  // Surface 1 in the corner x > 10.5, y > 4.5: one line cannot separate it, two can.
  const auto corner = grid_samples(10, 4, 4, [](double x, double y) { return x > 10.5 && y > 4.5 ? 1 : 0; });
  const std::vector<BspCandidate> candidates = {{*line_through(10.5, 0, 10.5, 9), 0}, {*line_through(0, 4.5, 20, 4.5), 0}};
  const auto two = build_pixel_bsp(corner, candidates, 2);
  ASSERT_TRUE(two.has_value());
  EXPECT_EQ(two->lines.size(), 2u);
  EXPECT_EQ(two->depth(), 2);
  EXPECT_EQ(two->leaves[two->leaf_at(10.9, 4.9)][0], std::lround(0.8 * 255));
  EXPECT_EQ(two->leaves[two->leaf_at(10.1, 4.9)][0], std::lround(0.2 * 255));
  EXPECT_EQ(two->leaves[two->leaf_at(10.9, 4.1)][0], std::lround(0.2 * 255));
  const auto one = build_pixel_bsp(corner, candidates, 1);  // depth 1: the best single line
  ASSERT_TRUE(one.has_value());
  EXPECT_EQ(one->lines.size(), 1u);
  const auto flat = grid_samples(10, 4, 4, [](double, double) { return 0; });
  EXPECT_FALSE(build_pixel_bsp(flat, candidates, 2).has_value());
}

// ---- the file format ----

BspBorderImage sample_image() {
  BspBorderImage image(8, 6, 2);
  BspTree a;
  a.shape = 1;
  a.lines = {*line_through(3.4, 0, 3.6, 6)};
  a.leaves = {Rgb8{10, 20, 30}, Rgb8{200, 210, 220}};
  image.add(1 * 8 + 3, a);
  BspTree b;
  b.shape = 0b011;  // split, split, leaf, leaf, leaf
  b.lines = {*line_through(5.5, 0, 5.5, 6), *line_through(0, 4.5, 8, 4.5)};
  b.leaves = {Rgb8{1, 2, 3}, Rgb8{4, 5, 6}, Rgb8{7, 8, 9}};
  image.add(4 * 8 + 5, b);
  return image;
}

TEST(BspBorderFile, RoundTrips) {
  const auto dir = test::scratch_dir("bsp_round_trip");
  const BspBorderImage image = sample_image();
  const auto path = bsp_border_file(dir, {8, 6}, 3);
  EXPECT_EQ(path, dir / "8x6" / "bsp_border" / "000003.bsp");
  write_bsp_border_file(path, image);
  const BspBorderImage back = read_bsp_border_file(path, 3, {8, 6});
  ASSERT_EQ(back.size(), 2u);
  EXPECT_EQ(back.max_depth(), 2);
  EXPECT_EQ(encode_bsp_border(back), encode_bsp_border(image));
  EXPECT_EQ(std::filesystem::file_size(path), 28u + (12 + 15 * 1) + (12 + 15 * 2));
  ASSERT_NE(back.at(5, 4), nullptr);
  EXPECT_EQ(back.at(5, 4)->shape, 0b011u);
  EXPECT_EQ(back.at(5, 4)->leaves[2], (Rgb8{7, 8, 9}));
  EXPECT_EQ(back.at(0, 0), nullptr);
  std::filesystem::remove_all(dir);
}

// The message of decoding `bytes` as frame 3 of an 8x6 image.
std::string problem_with(const std::string& bytes, Resolution expected = {8, 6}) {
  try {
    decode_bsp_border(bytes, "f.bsp", 3, expected);
  } catch (const Error& e) {
    return e.what();
  }
  return "(accepted)";
}

void put_f32_at(std::string& bytes, size_t at, float f) { std::memcpy(&bytes[at], &f, 4); }

TEST(BspBorderFile, RefusesCorruptFilesNamingTheProblem) {
  const std::string good = encode_bsp_border(sample_image());
  // Record 0 starts at 28: pixel (4), line count (1), shape (4), line (12), leaves (6).
  const auto has = [](const std::string& message, const std::string& part) {
    return message.find(part) != std::string::npos;
  };
  std::string m = problem_with("CGSRBSP");
  EXPECT_TRUE(has(m, "f.bsp") && has(m, "frame 3") && has(m, "header") && has(m, "truncated")) << m;
  std::string bad = good;
  bad[0] = 'X';
  m = problem_with(bad);
  EXPECT_TRUE(has(m, "not a sub-pixel BSP border file")) << m;
  m = problem_with(good, {16, 12});
  EXPECT_TRUE(has(m, "width/height") && has(m, "8x6") && has(m, "16x12")) << m;
  bad = good;
  bad[8] = 9;  // version
  m = problem_with(bad);
  EXPECT_TRUE(has(m, "version") && has(m, "unsupported version 9")) << m;
  bad = good;
  bad[28 + 4] = 0;  // line count of record 0
  m = problem_with(bad);
  EXPECT_TRUE(has(m, "record 0 (pixel 11) line count") && has(m, "0 is outside 1 .. 3")) << m;
  bad = good;
  bad[28 + 5] = 3;  // shape of record 0: two splits for one line
  m = problem_with(bad);
  EXPECT_TRUE(has(m, "record 0 (pixel 11)") && has(m, "1 line(s) for a shape of 2 split(s)")) << m;
  bad = good;
  put_f32_at(bad, 28 + 9, std::nanf(""));  // line a of record 0
  m = problem_with(bad);
  EXPECT_TRUE(has(m, "record 0") && has(m, "non-finite")) << m;
  bad = good;
  put_f32_at(bad, 28 + 17, 2.5f);  // line c: the line no longer crosses pixel (3, 1)
  m = problem_with(bad);
  EXPECT_TRUE(has(m, "record 0 (pixel 11) line 0") && has(m, "does not cross the pixel")) << m;
  bad = good;
  bad[28 + 27] = 2;  // record 1's pixel below record 0's
  bad[28 + 28] = bad[28 + 29] = bad[28 + 30] = 0;
  m = problem_with(bad);
  EXPECT_TRUE(has(m, "record 1 pixel") && has(m, "strictly ascending")) << m;
  m = problem_with(good.substr(0, good.size() - 2));
  EXPECT_TRUE(has(m, "record 1") && has(m, "truncated")) << m;
  m = problem_with(good + "xy");
  EXPECT_TRUE(has(m, "2 trailing byte(s)")) << m;
  bad = good;
  bad[24] = static_cast<char>(0xff);  // count: far more records than the file holds
  m = problem_with(bad);
  EXPECT_TRUE(has(m, "count")) << m;
  const auto dir = test::scratch_dir("bsp_missing");
  m = "";
  try {
    read_bsp_border_file(dir / "none.bsp", 5, {8, 6});
  } catch (const Error& e) {
    m = e.what();
  }
  EXPECT_TRUE(has(m, "none.bsp") && has(m, "frame 5") && has(m, "missing")) << m;
  std::filesystem::remove_all(dir);
}

// ---- the render job ----

RenderJobOptions tiny_job(int bsp_depth) {
  const auto doc = config::Document::load_file(std::string(CGSR_SOURCE_DIR) + "/configs/scenes/tiny.yaml");
  RenderJobOptions o;
  o.frames = 3;
  o.resolutions = {"64x48", "128x96"};
  o.shadow_map_size = 128;
  o.scene = config::Block{doc.root()["scene"], std::make_shared<config::Document>(doc), "scene"};
  o.bsp_border.depth = bsp_depth;
  return o;
}

struct TinyConfig : RenderJobOptions {
  int64_t seed = 0;
};

// The fingerprint `cgsr render --config configs/scenes/tiny.yaml --set frames=3` recorded before
// the option existed (the fuzz seed manifest, written by fuzz/make_seeds.sh) is the one it records now.
TEST(BspBorderRender, RenderWithoutTheOptionKeepsItsEarlierFingerprint) {
  config::Schema<TinyConfig> schema;
  add_render_job_fields(schema);
  schema.field("seed", &TinyConfig::seed, "seed");
  config::Document doc = config::Document::load_file(std::string(CGSR_SOURCE_DIR) + "/configs/scenes/tiny.yaml");
  doc.apply_override("frames=3", "test");
  const TinyConfig o = config::parse_document(doc, schema);
  const auto dir = test::scratch_dir("bsp_seed_manifest");
  std::filesystem::copy_file(std::string(CGSR_SOURCE_DIR) + "/fuzz/corpus/manifest/tiny_manifest.yaml", dir / "manifest.yaml");
  const DatasetManifest seed_manifest = read_manifest(dir);
  EXPECT_EQ(render_fingerprint(o, 0), seed_manifest.fingerprint);
  EXPECT_EQ(seed_manifest.bsp_border_depth, 0);
  std::filesystem::remove_all(dir);
}

TEST(BspBorderRender, OffByDefaultKeepsFingerprintAndFiles) {
  RenderJobOptions off = tiny_job(0);
  RenderJobOptions on = tiny_job(2);
  EXPECT_FALSE(RenderJobOptions{}.bsp_border.enabled());
  // Off: the fingerprint is the one computed without the option (samples do not enter it).
  off.bsp_border.samples = 9;
  EXPECT_EQ(render_fingerprint(off, 1), render_fingerprint(tiny_job(0), 1));
  EXPECT_NE(render_fingerprint(on, 1), render_fingerprint(off, 1));

  const auto dir = test::scratch_dir("bsp_render");
  const RenderJobResult plain = run_render_job(off, 1, dir / "plain");
  EXPECT_FALSE(std::filesystem::exists(dir / "plain" / "64x48" / "bsp_border"));
  EXPECT_EQ(read_file(dir / "plain" / "manifest.yaml").find("bsp_border"), std::string::npos);
  const RenderJobResult with = run_render_job(on, 1, dir / "with");
  finish_render(dir / "with", with.manifest);
  // The images are the same with and without BSP files.
  for (const FileKind kind : all_file_kinds())
    for (const Resolution& r : {Resolution{64, 48}, Resolution{128, 96}})
      EXPECT_EQ(read_file(frame_file(dir / "plain", r, kind, 1)), read_file(frame_file(dir / "with", r, kind, 1)))
          << file_kind_name(kind) << " at " << r.name();
  EXPECT_GT(with.bsp_border_bytes, 28);
  EXPECT_GT(with.bsp_border_fraction, 0.01);
  EXPECT_LT(with.bsp_border_fraction, 0.5);
  EXPECT_GE(with.bsp_border_lines, 1.0);
  const DatasetManifest m = read_manifest(dir / "with");
  EXPECT_EQ(m.bsp_border_depth, 2);
  EXPECT_EQ(m.bsp_border_samples, 4);
  // The data set hands every LR frame its BSP image, HR frames none.
  const Dataset data = Dataset::open(dir / "with");
  EXPECT_TRUE(data.info().bsp_border);
  ASSERT_TRUE(data.frame(1, 0)->bsp_border);
  EXPECT_EQ(data.frame(1, 0)->bsp_border->width(), 64);
  EXPECT_FALSE(data.frame(1, 1)->bsp_border);
  EXPECT_EQ(check_dataset(dir / "with").problem_count(), 0);
  // A corrupt file is an error naming it when the frame is read, and a problem for data check.
  const auto file = bsp_border_file(dir / "with", {64, 48}, 2);
  write_file_atomic(file, read_file(file).substr(0, 30));
  const DataCheckReport report = check_dataset(dir / "with");
  EXPECT_EQ(report.problems.count("bsp_border"), 1u);
  ASSERT_FALSE(report.messages.empty());
  EXPECT_NE(report.messages.front().find("000002.bsp"), std::string::npos) << report.messages.front();
  try {
    Dataset::open(dir / "with").frame(2, 0);
    ADD_FAILURE() << "a truncated BSP border file was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("000002.bsp"), std::string::npos) << e.what();
  }
  std::filesystem::remove_all(dir);
}

}  // namespace bsp_test
}  // namespace cgsr
