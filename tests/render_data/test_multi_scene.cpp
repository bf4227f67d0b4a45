// Multi-scene data sets: `cgsr render` with several scenes (scenes recorded, split per scene,
// resume), the sampler across scenes (proportional, weighted, deterministic, and a single scene
// drawn exactly as before scenes), old single-scene manifests, `cgsr data merge` (and its errors)
// and `cgsr eval --scene`. Real frames of the tiny scene, rendered once for the whole file.
#include <gtest/gtest.h>

#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "core/error.h"
#include "core/runtime.h"
#include "render_data/dataset_manifest.h"
#include "render_data/patch_sampler.h"
#include "test_scenes.h"
#include "tests/support/cli_runner.h"

namespace cgsr {
namespace multi_scene_test {  // named: the unity build joins this file with test_render_cli.cpp
namespace fs = std::filesystem;

using test::CliResult;
using test::run_cgsr;

std::string tiny_config() { return std::string(CGSR_SOURCE_DIR) + "/configs/scenes/tiny.yaml"; }

std::string read_text(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// The tiny scene with another layout, 10 frames and another far plane: a second scene that
// differs in frames, split sizes and depth planes.
fs::path second_scene_config(const fs::path& dir) {
  const fs::path p = dir / "tiny_b.yaml";
  std::string text = read_text(tiny_config());
  const auto replace = [&](const std::string& from, const std::string& to) {
    const auto at = text.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    text.replace(at, from.size(), to);
  };
  replace("name: tiny\nframes: 6", "name: tiny_b\nframes: 10");
  replace("camera: {steps: 4}", "camera: {steps: 4, far: 120}");
  std::ofstream(p) << text;
  return p;
}

// Rendered once: a two-scene set (tiny, 6 frames; tiny_b, 10 frames) and tiny alone.
struct Renders {
  fs::path root, set, solo, scene_b;
};
const Renders& renders() {
  static const Renders r = [] {
    Renders x;
    x.root = test::scratch_dir("multi_scene");
    x.scene_b = second_scene_config(x.root);
    x.set = x.root / "set";
    const CliResult set = run_cgsr("render --scene " + tiny_config() + " --scene " + x.scene_b.string() + " --out " + x.set.string());
    EXPECT_EQ(set.exit_code, 0) << set.all();
    x.solo = x.root / "solo";
    const CliResult solo = run_cgsr("render --config " + tiny_config() + " --out " + x.solo.string());
    EXPECT_EQ(solo.exit_code, 0) << solo.all();
    return x;
  }();
  return r;
}

std::vector<int> shifted(std::vector<int> v, int by) {
  for (int& f : v) f += by;
  return v;
}

TEST(MultiSceneRender, RecordsScenesAndSplitsEachScene) {
  const Renders& r = renders();
  const DatasetManifest m = read_manifest(r.set);
  EXPECT_NE(read_text(r.set / "manifest.yaml").find("version: 2"), std::string::npos);
  EXPECT_TRUE(m.complete);
  EXPECT_EQ(m.name, "tiny+tiny_b");
  EXPECT_EQ(m.frames, 16);
  ASSERT_EQ(m.scenes.size(), 2u);
  EXPECT_EQ(m.scenes[0].name, "tiny");
  EXPECT_EQ(m.scenes[0].path, "scenes/tiny");
  EXPECT_EQ(m.scenes[0].first_frame, 0);
  EXPECT_EQ(m.scenes[0].frames, 6);
  EXPECT_EQ(m.scenes[1].name, "tiny_b");
  EXPECT_EQ(m.scenes[1].first_frame, 6);
  EXPECT_EQ(m.scenes[1].frames, 10);
  // Each scene split by its own rule: every scene has frames in train, val and test.
  const FrameSplit a = make_split(6), b = make_split(10);
  for (Split s : {Split::Train, Split::Val, Split::Test}) {
    std::vector<int> want = a.of(s);
    for (int f : shifted(b.of(s), 6)) want.push_back(f);
    EXPECT_EQ(m.split.of(s), want) << split_name(s);
    EXPECT_FALSE(a.of(s).empty());
    EXPECT_FALSE(b.of(s).empty());
  }

  const Dataset data = Dataset::open(r.set);
  EXPECT_EQ(data.frame_count(), 16);
  ASSERT_EQ(data.scenes().size(), 2u);
  EXPECT_EQ(data.scene_of(5).name, "tiny");
  EXPECT_EQ(data.scene_of(6).name, "tiny_b");
  EXPECT_EQ(data.scene_of(15).name, "tiny_b");
  EXPECT_THROW(data.scene_of(16), Error);
  EXPECT_FALSE(data.has_previous(0));
  EXPECT_TRUE(data.has_previous(5));
  EXPECT_FALSE(data.has_previous(6));  // tiny_b's first frame follows no frame of its own scene
  EXPECT_TRUE(data.has_previous(7));
  // Planes per scene: tiny_b's depth is encoded with its own far plane.
  EXPECT_DOUBLE_EQ(data.scene_of(6).far_plane, 120);
  EXPECT_NE(data.scene_of(0).far_plane, 120);

  // Set frame 6 is tiny_b's frame 0; the set's tiny is tiny rendered alone (same seed).
  const Dataset b_alone = Dataset::open(r.set / "scenes" / "tiny_b");
  EXPECT_TRUE(torch::equal(data.frame(6, 1)->color, b_alone.frame(0, 1)->color));
  EXPECT_EQ(read_text(r.set / "scenes" / "tiny" / "64x48" / "color" / "000003.png"),
            read_text(r.solo / "64x48" / "color" / "000003.png"));
  const auto depth_b = frame_batch(data, 6, 2, {RenderChannel::Depth}, DepthEncoding::Log).lr_info;
  const auto depth_b_alone = frame_batch(b_alone, 0, 2, {RenderChannel::Depth}, DepthEncoding::Log).lr_info;
  EXPECT_TRUE(torch::equal(depth_b, depth_b_alone));

  // A one-scene view keeps the set's frame numbers.
  const Dataset only_b = data.scene("tiny_b");
  EXPECT_EQ(only_b.frames(Split::Test), shifted(b.test, 6));
  EXPECT_EQ(only_b.frames(Split::All).front(), 6);
  EXPECT_EQ(only_b.frames(Split::All).size(), 10u);
  try {
    data.scene("tiny_c");
    FAIL() << "no error for an unknown scene";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("did you mean 'tiny_b'"), std::string::npos) << e.what();
  }

  const CliResult check = run_cgsr("data check " + r.set.string());
  EXPECT_EQ(check.exit_code, 0) << check.all();
  EXPECT_NE(check.all().find("scenes       tiny (6 frames), tiny_b (10 frames)"), std::string::npos) << check.all();
  EXPECT_NE(check.all().find("32 frame/resolution pairs"), std::string::npos) << check.all();
}

TEST(MultiSceneRender, ResumesAndRefusesAnotherSet) {
  const Renders& r = renders();
  const fs::path copy = r.root / "resume";
  fs::copy(r.set, copy, fs::copy_options::recursive);
  // The set's manifest says complete: false while a scene is unfinished.
  fs::remove(copy / "scenes" / "tiny_b" / "128x96" / "edge" / "000004.png");
  const std::string args = "render --scene " + tiny_config() + " --scene " + r.scene_b.string() + " --out " + copy.string();
  const CliResult resume = run_cgsr(args);
  ASSERT_EQ(resume.exit_code, 0) << resume.all();
  EXPECT_NE(resume.all().find("rendered 1 frame(s) (15 resumed) of 2 scenes"), std::string::npos) << resume.all();
  EXPECT_TRUE(read_manifest(copy).complete);

  const CliResult other = run_cgsr("render --scene " + tiny_config() + " --out " + copy.string());
  EXPECT_EQ(other.exit_code, 2) << other.all();
  EXPECT_NE(other.all().find("different configuration"), std::string::npos) << other.all();
  // Two scenes under one name, and single-scene keys at the top of a set, are config errors.
  const CliResult twice = run_cgsr("render --scene " + tiny_config() + " --scene " + tiny_config() + " --out " +
                            (r.root / "twice").string());
  EXPECT_EQ(twice.exit_code, 2) << twice.all();
  EXPECT_NE(twice.all().find("scene name 'tiny' is also the name of the scene from"), std::string::npos) << twice.all();
  const CliResult frames = run_cgsr("render --scene " + tiny_config() + " --frames 3 --out " + (r.root / "frames").string());
  EXPECT_EQ(frames.exit_code, 2) << frames.all();
  EXPECT_NE(frames.all().find("'frames' is each scene's own"), std::string::npos) << frames.all();
}

TEST(MultiSceneRender, SceneSetConfigWithWeightsAndFrames) {
  const Renders& r = renders();
  const fs::path config = r.root / "set.yaml";
  std::ofstream(config) << "name: weighted\nscenes:\n  - {config: " << tiny_config()
                        << ", weight: 3, frames: 4}\n  - {config: " << r.scene_b.string() << ", name: b, weight: 1}\n";
  const fs::path out = r.root / "weighted";
  const CliResult run = run_cgsr("render --config " + config.string() + " --out " + out.string());
  ASSERT_EQ(run.exit_code, 0) << run.all();
  const DatasetManifest m = read_manifest(out);
  ASSERT_EQ(m.scenes.size(), 2u);
  EXPECT_EQ(m.name, "weighted");
  EXPECT_EQ(m.scenes[0].frames, 4);
  EXPECT_EQ(m.scenes[0].weight, 3);
  EXPECT_EQ(m.scenes[1].name, "b");
  EXPECT_EQ(m.scenes[1].weight, 1);
  // The resolved config lists the scenes only, and renders the same set again.
  const std::string resolved = read_text(out / "config.yaml");
  EXPECT_EQ(resolved.find("frames: 90"), std::string::npos) << resolved;
  const CliResult again = run_cgsr("render --config " + (out / "config.yaml").string() + " --out " + out.string());
  ASSERT_EQ(again.exit_code, 0) << again.all();
  EXPECT_NE(again.all().find("rendered 0 frame(s) (14 resumed)"), std::string::npos) << again.all();
}

TEST(MultiSceneRender, EntriesOverrideTheirConfig) {
  const Renders& r = renders();
  const fs::path config = r.root / "variants.yaml";
  std::ofstream(config) << "scenes:\n  - {config: " << tiny_config() << ", name: a, frames: 2, set: [scene.variant=1]}\n"
                        << "  - {config: " << tiny_config() << ", name: b, frames: 2, set: [scene.variant=2]}\n";
  const fs::path out = r.root / "variants";
  const CliResult run = run_cgsr("render --config " + config.string() + " --out " + out.string());
  ASSERT_EQ(run.exit_code, 0) << run.all();
  // One config, two levels: the scenes' first frames differ.
  EXPECT_NE(read_text(out / "scenes" / "a" / "128x96" / "color" / "000000.png"),
            read_text(out / "scenes" / "b" / "128x96" / "color" / "000000.png"));
  const fs::path bad = r.root / "bad_override.yaml";
  std::ofstream(bad) << "scenes:\n  - {config: " << tiny_config() << ", set: [scene.layuot=hall]}\n";
  const CliResult error = run_cgsr("render --config " + bad.string() + " --out " + (r.root / "bad").string());
  EXPECT_EQ(error.exit_code, 2) << error.all();
  EXPECT_NE(error.all().find("set scene.layuot=hall"), std::string::npos) << error.all();
  EXPECT_NE(error.all().find("did you mean 'layout'"), std::string::npos) << error.all();
}

// Frames drawn by batches 0 .. batches-1, counted per scene.
std::map<std::string, int> draws_per_scene(const Dataset& data, uint64_t seed, int batches) {
  PatchSamplerOptions o;
  o.patch_size = 8;
  o.batch_size = 16;
  o.augment = false;
  o.seed = seed;
  o.prefetch = 0;
  const PatchSampler sampler(data, o);
  std::map<std::string, int> count;
  for (int k = 0; k < batches; ++k)
    for (int f : sampler.build(k).frames) {
      EXPECT_TRUE(std::find(data.frames(Split::Train).begin(), data.frames(Split::Train).end(), f) !=
                  data.frames(Split::Train).end())
          << "frame " << f << " is not a training frame";
      ++count[data.scene_of(f).name];
    }
  return count;
}

TEST(MultiSceneSampler, DrawsEverySceneInProportionToItsTrainingFrames) {
  const Dataset data = Dataset::open(renders().set);
  const auto count = draws_per_scene(data, 7, 100);  // 1600 draws
  const double a = make_split(6).train.size(), b = make_split(10).train.size();
  ASSERT_EQ(count.size(), 2u);
  EXPECT_NEAR(count.at("tiny") / 1600.0, a / (a + b), 0.05);
  EXPECT_NEAR(count.at("tiny_b") / 1600.0, b / (a + b), 0.05);
}

TEST(MultiSceneSampler, HonoursSceneWeights) {
  const Renders& r = renders();
  // Weights by merging the set's two scene directories with weights 1 and 3.
  const fs::path out = r.root / "weights";
  fs::create_directories(out);
  write_manifest(out, merge_manifests(out, "", {r.set / "scenes" / "tiny", r.set / "scenes" / "tiny_b"}, {1, 3}));
  const Dataset data = Dataset::open(out);
  ASSERT_EQ(data.scenes().size(), 2u);
  EXPECT_EQ(data.scenes()[1].weight, 3);
  const auto count = draws_per_scene(data, 7, 100);
  EXPECT_NEAR(count.at("tiny") / 1600.0, 0.25, 0.05);
  EXPECT_NEAR(count.at("tiny_b") / 1600.0, 0.75, 0.05);
}

TEST(MultiSceneSampler, DeterministicPerSeed) {
  const Dataset data = Dataset::open(renders().set);
  PatchSamplerOptions o;
  o.patch_size = 8;
  o.batch_size = 8;
  o.channels = {RenderChannel::Depth, RenderChannel::Edge};
  o.seed = 3;
  PatchSampler one(data, o), two(data, o);
  for (int k = 0; k < 4; ++k) one.next();
  const Batch a = one.next(), b = two.batch(4);  // a resumed run jumps straight to batch 4
  EXPECT_EQ(a.frames, b.frames);
  EXPECT_TRUE(torch::equal(a.lr_color, b.lr_color));
  EXPECT_TRUE(torch::equal(a.hr_info, b.hr_info));
  o.seed = 4;
  const PatchSampler other(data, o);
  EXPECT_FALSE(torch::equal(other.build(4).lr_color, a.lr_color));
}

// A single-scene data set draws exactly what the sampler drew before scenes existed: frame
// frames[rng() % n] from the stream seeded by (seed, batch), then x, y and the augmentation.
TEST(MultiSceneSampler, SingleSceneDrawsAsBefore) {
  const Dataset data = Dataset::open(renders().solo);
  ASSERT_EQ(data.scenes().size(), 1u);
  PatchSamplerOptions o;
  o.patch_size = 8;
  o.batch_size = 16;
  o.seed = 11;
  o.prefetch = 0;
  const PatchSampler sampler(data, o);
  const auto frames = data.frames(Split::Train);
  for (int64_t k : {0, 1, 57}) {
    auto rng = make_rng("patch-sampler", o.seed * 0x9E3779B97F4A7C15ULL + static_cast<uint64_t>(k));
    std::vector<int> want;
    for (int i = 0; i < o.batch_size; ++i) {
      want.push_back(frames[rng() % frames.size()]);
      rng(), rng(), rng();  // x, y, augmentation
    }
    EXPECT_EQ(sampler.build(k).frames, want) << "batch " << k;
  }
}

TEST(MultiSceneData, SingleSceneManifestStaysVersion1AndLoadsAsOneScene) {
  const Renders& r = renders();
  const std::string text = read_text(r.solo / "manifest.yaml");
  EXPECT_NE(text.find("version: 1"), std::string::npos) << text;
  EXPECT_EQ(text.find("scenes"), std::string::npos) << text;
  // A manifest as builds before scenes wrote it (no scenes, version 1) loads as one scene.
  const Dataset data = Dataset::open(r.solo);
  ASSERT_EQ(data.scenes().size(), 1u);
  EXPECT_EQ(data.scenes()[0].name, "tiny");
  EXPECT_EQ(data.scenes()[0].first_frame, 0);
  EXPECT_EQ(data.scenes()[0].frames, 6);
  EXPECT_EQ(data.scenes()[0].far_plane, data.info().far_plane);
  EXPECT_EQ(data.frames(Split::Train), make_split(6).train);
  // A version this build does not know is refused with the file and key.
  const fs::path future = r.root / "future";
  fs::create_directories(future);
  std::string v3 = text;
  v3.replace(v3.find("version: 1"), 10, "version: 3");
  std::ofstream(future / "manifest.yaml") << v3;
  try {
    read_manifest(future);
    FAIL() << "no error for version 3";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("version: unsupported version 3"), std::string::npos) << e.what();
  }
}

TEST(MultiSceneData, MergeMixesDataSetsWithoutCopying) {
  const Renders& r = renders();
  const fs::path solo2 = r.root / "solo2";
  ASSERT_EQ(run_cgsr("render --config " + tiny_config() + " --set name=solo --set frames=3 --out " + solo2.string()).exit_code, 0);
  const fs::path out = r.root / "merged";
  const std::string args = "data merge " + r.set.string() + " " + solo2.string() + " --out " + out.string();
  // The manifest is written after results.json: a merge that fails at its results leaves no data set.
  ::setenv("CGSR_FAULT_NO_SPACE", "results.json", 1);
  const CliResult full = run_cgsr(args);
  ::unsetenv("CGSR_FAULT_NO_SPACE");
  EXPECT_EQ(full.exit_code, 2) << full.all();
  EXPECT_FALSE(has_manifest(out));
  const CliResult merge = run_cgsr(args);
  ASSERT_EQ(merge.exit_code, 0) << merge.all();
  const DatasetManifest m = read_manifest(out);
  ASSERT_EQ(m.scenes.size(), 3u);  // the set contributes its two scenes
  EXPECT_EQ(m.scenes[0].path, "../set/scenes/tiny");
  EXPECT_EQ(m.scenes[2].name, "solo");
  EXPECT_EQ(m.scenes[2].first_frame, 16);
  EXPECT_FALSE(fs::exists(out / "64x48"));
  const Dataset data = Dataset::open(out);
  EXPECT_EQ(data.frame_count(), 19);
  EXPECT_EQ(data.frames(Split::Test).back(), 16 + make_split(3).test.back());
  EXPECT_TRUE(torch::equal(data.frame(17, 0)->color, Dataset::open(solo2).frame(1, 0)->color));
  EXPECT_EQ(run_cgsr("data check " + out.string()).exit_code, 0);

  // A source that changed after the merge is named when the merged set is opened.
  DatasetManifest changed = read_manifest(solo2);
  const DatasetManifest original = changed;
  changed.fingerprint = "0000000000000000";
  write_manifest(solo2, changed);
  try {
    Dataset::open(out);
    FAIL() << "no error for a changed source";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("scene 'solo'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("changed since this set was written"), std::string::npos) << e.what();
  }
  write_manifest(solo2, original);

  // Two scenes of one name: both data sets are named.
  const CliResult twice = run_cgsr("data merge " + r.set.string() + " " + r.solo.string() + " --out " + (r.root / "m2").string());
  EXPECT_EQ(twice.exit_code, 2) << twice.all();
  EXPECT_NE(twice.all().find("two scenes are named 'tiny'"), std::string::npos) << twice.all();
  EXPECT_NE(twice.all().find("solo"), std::string::npos) << twice.all();
}

TEST(MultiSceneData, MergeRefusesOtherScales) {
  const Renders& r = renders();
  const fs::path x3 = r.root / "x3";
  ASSERT_EQ(run_cgsr("render --config " + tiny_config() + " --set frames=2 --set resolutions=[64x48,192x144] --out " +
                 x3.string())
                .exit_code,
            0);
  const CliResult merge = run_cgsr("data merge " + r.solo.string() + " " + x3.string() + " --out " + (r.root / "m3").string());
  EXPECT_EQ(merge.exit_code, 2) << merge.all();
  EXPECT_NE(merge.all().find(x3.string() + ": has resolutions 64x48, 192x144, but " + r.solo.string() +
                              " has 64x48, 128x96"),
            std::string::npos)
      << merge.all();
  EXPECT_FALSE(has_manifest(r.root / "m3"));
}

TEST(MultiSceneData, EvalBySceneAndPerScene) {
  const Renders& r = renders();
  const fs::path all = r.root / "eval_all", one = r.root / "eval_b";
  const CliResult a = run_cgsr("eval --data " + r.set.string() + " --model bicubic --latency-runs 0 --out " + all.string());
  ASSERT_EQ(a.exit_code, 0) << a.all();
  const auto ja = nlohmann::json::parse(read_text(all / "results.json"));
  const auto& scenes = ja["evaluations"][0]["scenes"];
  ASSERT_EQ(scenes.size(), 2u) << ja.dump(2);
  EXPECT_EQ(scenes[0]["scene"], "tiny");
  EXPECT_EQ(scenes[1]["scene"], "tiny_b");
  EXPECT_EQ(scenes[0]["frames"].get<int>() + scenes[1]["frames"].get<int>(), 2);  // a test frame per scene

  const CliResult b = run_cgsr("eval --data " + r.set.string() + " --scene tiny_b --split val --model bicubic --latency-runs 0 --out " +
                        one.string());
  ASSERT_EQ(b.exit_code, 0) << b.all();
  const auto jb = nlohmann::json::parse(read_text(one / "results.json"));
  EXPECT_EQ(jb["scene"], "tiny_b");
  const auto& frames = jb["evaluations"][0]["frames"];
  ASSERT_EQ(frames.size(), make_split(10).val.size()) << jb.dump(2);
  for (const auto& f : frames) EXPECT_GE(f["frame"].get<int>(), 6);
}

// `cgsr train` on a set: its training and validation frames come from every scene.
TEST(MultiSceneData, TrainsOnEveryScene) {
  const Renders& r = renders();
  const fs::path out = r.root / "train";
  const CliResult train = run_cgsr("train --config " + std::string(CGSR_SOURCE_DIR) + "/configs/train/pan_x2.yaml --set data=" +
                            r.set.string() + " --steps 4 --set schedule.batch_size=2 --set schedule.patch_size=16 " +
                            "--set schedule.validate_every=4 --set schedule.val_frames=3 --threads 1 --out " + out.string());
  ASSERT_EQ(train.exit_code, 0) << train.all();
  EXPECT_NE(read_text(out / "log.txt").find("(11 train / 3 val frames)"), std::string::npos) << read_text(out / "log.txt");
  EXPECT_TRUE(fs::exists(out / "model.cgsr"));
}

}  // namespace multi_scene_test
}  // namespace cgsr
