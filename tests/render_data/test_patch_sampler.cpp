// Training batches: aligned LR/HR patches, consistent augmentation, determinism, splits,
// full-frame iteration, and the memory a 300-frame 640x480 set needs.
#include <gtest/gtest.h>

#include <torch/torch.h>

#include <fstream>
#include <set>

#include "core/error.h"
#include "core/runtime.h"
#include "render_data/patch_sampler.h"
#include "test_scenes.h"

namespace cgsr {
namespace {
namespace fs = std::filesystem;

// Frames whose HR images are the LR images with every pixel repeated s x s times, so aligned
// windows match exactly; HR motion is s x LR motion (pixels of its own resolution).
GBuffer synthetic(int frame, const Resolution& r, int lr_width) {
  const int s = r.width / lr_width, h = r.height / s, w = r.width / s;
  torch::manual_seed(1000 + frame);
  GBuffer g = test::flat_gbuffer(w, h);
  g.color = torch::rand({3, h, w});
  g.depth = torch::rand({1, h, w}) * 20 + 0.5f;
  g.normal = torch::randn({3, h, w});
  g.normal = g.normal / g.normal.norm(2, 0, true);
  g.normal_angle = torch::rand({1, h, w});
  g.edge = (torch::rand({1, h, w}) > 0.8f).to(torch::kFloat32);
  g.motion = torch::randn({2, h, w}) * 3;
  auto up = [s](const torch::Tensor& t) { return t.repeat_interleave(s, 1).repeat_interleave(s, 2).contiguous(); };
  g.width = r.width;
  g.height = r.height;
  g.color = up(g.color);
  g.depth = up(g.depth);
  g.normal = up(g.normal);
  g.normal_angle = up(g.normal_angle);
  g.edge = up(g.edge);
  g.motion = up(g.motion) * static_cast<float>(s);
  g.object_id = torch::zeros({1, r.height, r.width}, torch::kInt32);
  g.material_id = torch::zeros({1, r.height, r.width}, torch::kInt32);
  return g;
}

const fs::path& synthetic_dataset() {
  static const fs::path dir = [] {
    const fs::path d = test::scratch_dir("sampler_data");
    test::write_test_dataset(d, 10, {{40, 30}, {80, 60}}, [](int f, const Resolution& r) { return synthetic(f, r, 40); });
    return d;
  }();
  return dir;
}

const std::vector<RenderChannel> kAll = {RenderChannel::Depth, RenderChannel::Normal, RenderChannel::NormalAngle,
                                         RenderChannel::Edge, RenderChannel::Motion};

PatchSamplerOptions all_channels(int patch_size, int batch_size, uint64_t seed) {
  PatchSamplerOptions o;
  o.patch_size = patch_size;
  o.batch_size = batch_size;
  o.channels = kAll;
  o.seed = seed;
  return o;
}

TEST(PatchSampler, PatchesAreAlignedAndAugmentedConsistently) {
  const Dataset data = Dataset::open(synthetic_dataset());
  PatchSampler sampler(data, all_channels(12, 8, 3));
  for (int k = 0; k < 4; ++k) {
    const Batch b = sampler.next();
    ASSERT_EQ(b.lr_color.sizes(), (std::vector<int64_t>{8, 3, 12, 12}));
    ASSERT_EQ(b.hr_color.sizes(), (std::vector<int64_t>{8, 3, 24, 24}));
    ASSERT_EQ(b.lr_info.size(1), 8);
    EXPECT_EQ(b.scale, 2);
    EXPECT_EQ(b.channels, kAll);
    // HR pixel (2i, 2j) is LR pixel (i, j) for every tensor: augmentation kept them aligned.
    const auto hr_c = b.hr_color.slice(2, 0, 24, 2).slice(3, 0, 24, 2);
    EXPECT_TRUE(torch::equal(hr_c, b.lr_color));
    const auto hr_i = b.hr_info.slice(2, 0, 24, 2).slice(3, 0, 24, 2);
    EXPECT_TRUE(torch::allclose(hr_i.slice(1, 0, 6), b.lr_info.slice(1, 0, 6), 1e-6, 1e-6));
    EXPECT_TRUE(torch::allclose(hr_i.slice(1, 6, 8), 2 * b.lr_info.slice(1, 6, 8), 1e-5, 1e-5));
    // The normalized depth is the network's form, in [0,1].
    EXPECT_GE(b.lr_info.select(1, 0).min().item<float>(), 0.0f);
    EXPECT_LE(b.lr_info.select(1, 0).max().item<float>(), 1.0f);
    const auto train = data.frames(Split::Train);
    for (int f : b.frames) EXPECT_NE(std::find(train.begin(), train.end(), f), train.end());
  }
}

// Colour augmentation changes LR and HR colour alike (still aligned) and nothing else: the same
// windows, flips and rendering information as without it.
TEST(PatchSampler, ColourAugmentationChangesOnlyColourAndKeepsItAligned) {
  const Dataset data = Dataset::open(synthetic_dataset());
  PatchSamplerOptions o = all_channels(10, 6, 5);
  PatchSampler plain(data, o);
  o.color_augment = true;
  PatchSampler coloured(data, o);
  for (int k = 0; k < 3; ++k) {
    const Batch p = plain.next(), c = coloured.next();
    EXPECT_EQ(c.frames, p.frames);
    EXPECT_TRUE(torch::equal(c.lr_info, p.lr_info));
    EXPECT_TRUE(torch::equal(c.hr_info, p.hr_info));
    EXPECT_TRUE(torch::equal(c.hr_color.slice(2, 0, 20, 2).slice(3, 0, 20, 2), c.lr_color));
    EXPECT_FALSE(torch::equal(c.lr_color, p.lr_color));
    EXPECT_GE(c.lr_color.min().item<float>(), 0.0f);
    EXPECT_LE(c.lr_color.max().item<float>(), 1.0f);
  }
}

TEST(PatchSampler, DeterministicUnderTheSeedAndIndexable) {
  const Dataset data = Dataset::open(synthetic_dataset());
  PatchSamplerOptions o;
  o.patch_size = 8;
  o.batch_size = 4;
  o.channels = {RenderChannel::Normal, RenderChannel::Motion};
  o.seed = 11;
  PatchSampler a(data, o), b(data, o);
  std::vector<Batch> first;
  for (int k = 0; k < 5; ++k) first.push_back(a.next());
  for (int k = 0; k < 5; ++k) {
    const Batch x = b.next();
    EXPECT_TRUE(torch::equal(x.lr_color, first[k].lr_color));
    EXPECT_TRUE(torch::equal(x.hr_info, first[k].hr_info));
  }
  // Random access (a resumed run) gives the same batch as sequential access.
  PatchSampler c(data, o);
  EXPECT_TRUE(torch::equal(c.batch(3).lr_color, first[3].lr_color));
  EXPECT_TRUE(torch::equal(c.batch(1).hr_color, first[1].hr_color));
  EXPECT_TRUE(torch::equal(c.build(4).lr_info, first[4].lr_info));
  // Without prefetching (batches built on the calling thread) the batches are the same.
  o.prefetch = 0;
  PatchSampler serial(data, o);
  for (int k = 0; k < 5; ++k) {
    const Batch x = serial.next();
    EXPECT_TRUE(torch::equal(x.lr_color, first[k].lr_color));
    EXPECT_TRUE(torch::equal(x.hr_info, first[k].hr_info));
  }
  EXPECT_TRUE(torch::equal(serial.batch(2).hr_color, first[2].hr_color));
  o.prefetch = 2;
  o.seed = 12;
  PatchSampler d(data, o);
  EXPECT_FALSE(torch::equal(d.next().lr_color, first[0].lr_color));
}

TEST(PatchSampler, BadRequestsAreExplained) {
  const Dataset data = Dataset::open(synthetic_dataset());
  PatchSamplerOptions o;
  o.scale = 3;
  EXPECT_THROW(PatchSampler(data, o), Error);  // no x3 pair
  o.scale = 2;
  o.patch_size = 64;  // larger than 40x30
  EXPECT_THROW(PatchSampler(data, o), Error);
  DatasetOpenOptions only_depth;
  only_depth.channels = {"depth"};
  const Dataset narrow = Dataset::open(synthetic_dataset(), only_depth);
  PatchSamplerOptions wants_edges;
  wants_edges.patch_size = 8;
  wants_edges.channels = {RenderChannel::Edge};
  try {
    PatchSampler s(narrow, wants_edges);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("'edge'"), std::string::npos) << e.what();
  }
}

TEST(FrameIterator, IteratesWholeFramesOfASplit) {
  const Dataset data = Dataset::open(synthetic_dataset());
  FrameIterator it(data, {2, Split::Test, {RenderChannel::Depth, RenderChannel::Edge}});
  ASSERT_EQ(it.size(), 1);
  const Batch b = it.get(0);
  EXPECT_EQ(b.lr_color.sizes(), (std::vector<int64_t>{1, 3, 30, 40}));
  EXPECT_EQ(b.hr_info.sizes(), (std::vector<int64_t>{1, 2, 60, 80}));
  EXPECT_EQ(b.frames, std::vector<int>{it.frame_index(0)});
  const Batch same = frame_batch(data, it.frame_index(0), 2, {RenderChannel::Depth, RenderChannel::Edge}, DepthEncoding::Log);
  EXPECT_TRUE(torch::equal(same.hr_info, b.hr_info));
  FrameIterator all(data, {2, Split::All, {}});
  EXPECT_EQ(all.size(), 10);
  EXPECT_EQ(all.get(9).lr_info.size(1), 0);
}

TEST(Frame, ThreeHundredFramesAt640x480FitInFourGigabytes) {
  // The in-memory representation of one frame with every channel, at LR and HR.
  auto frame = [](int w, int h) { return frame_from_gbuffer(test::flat_gbuffer(w, h)); };
  const double per_frame = static_cast<double>(frame(640, 480).bytes() + frame(320, 240).bytes());
  EXPECT_LT(300 * per_frame, 4.0 * (1ull << 30));
  // Kept compact: well below float32 for every channel (13 floats per pixel).
  EXPECT_LT(frame(640, 480).bytes(), 640 * 480 * 13 * 4 / 2);
}

TEST(Dataset, CacheStaysWithinItsBudget) {
  DatasetOpenOptions o;
  o.cache_gb = 3.0 * (80 * 60 * 30) / (1ull << 30);  // room for about 3 HR frames
  const Dataset data = Dataset::open(synthetic_dataset(), o);
  const size_t budget = static_cast<size_t>(o.cache_gb * (1ull << 30));
  for (int f = 0; f < 10; ++f) {
    data.frame(f, 1);
    EXPECT_LE(data.cached_bytes(), budget);
  }
  EXPECT_GT(data.cached_bytes(), 0u);
  // A frame dropped from the cache loads again, identically.
  EXPECT_TRUE(torch::equal(data.frame(0, 1)->color, data.load(0, 1).color));
  // By default the cache may take half the machine's memory (/proc/meminfo says how much it has).
  std::ifstream meminfo("/proc/meminfo");
  std::string key;
  double total_kib = 0;
  meminfo >> key >> total_kib;
  ASSERT_EQ(key, "MemTotal:");
  EXPECT_NEAR(DatasetOpenOptions().cache_gb, 0.5 * total_kib / (1 << 20), 0.01 * total_kib / (1 << 20));
  EXPECT_NEAR(DatasetOpenOptions().cache_reserve_gb, total_kib / 8 / (1 << 20), 0.01 * total_kib / (1 << 20));
}

TEST(Dataset, CacheStopsGrowingWhenTheMachineIsShortOfMemory) {
  // A reserve larger than any machine's memory: the cache never grows, and frames still load.
  DatasetOpenOptions o;
  o.cache_reserve_gb = 1000;
  const Dataset short_of_memory = Dataset::open(synthetic_dataset(), o);
  for (int f = 0; f < 3; ++f) EXPECT_TRUE(torch::equal(short_of_memory.frame(f, 1)->color, short_of_memory.load(f, 1).color));
  EXPECT_EQ(short_of_memory.cached_bytes(), 0u);
  o.cache_reserve_gb = 0;
  const Dataset plenty = Dataset::open(synthetic_dataset(), o);
  plenty.frame(0, 1);
  EXPECT_EQ(plenty.cached_bytes(), plenty.frame(0, 1)->bytes());
}

TEST(Dataset, OpenForChannelsLoadsWhatIsNamedAndTheEdgeMap) {
  const Dataset narrow = open_for_channels(synthetic_dataset(), {RenderChannel::Depth, RenderChannel::Depth});
  const auto frame = narrow.frame(0, 1);
  EXPECT_EQ(frame->channels(), (std::vector<RenderChannel>{RenderChannel::Depth, RenderChannel::Edge}));
  const auto full = Dataset::open(synthetic_dataset()).frame(0, 1);
  EXPECT_GT(full->channels().size(), frame->channels().size());
  EXPECT_LT(frame->bytes(), full->bytes());
  EXPECT_TRUE(torch::equal(frame->depth, full->depth));
  EXPECT_TRUE(torch::equal(frame->color, full->color));
  // Colour only (a plain backbone) still brings the edge map: edge PSNR and the patch sampler's
  // edge weighting read it.
  EXPECT_EQ(open_for_channels(synthetic_dataset(), {}).frame(0, 1)->channels(),
            std::vector<RenderChannel>{RenderChannel::Edge});
}

}  // namespace
}  // namespace cgsr
