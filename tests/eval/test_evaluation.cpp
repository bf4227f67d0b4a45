// Evaluation on the tiny scene: frame selection by range, a consecutive range scoring like the
// same frames evaluated one by one, PSNR on geometry edges and on the rest (against a direct
// computation with torch ops), and the JSON and CSV records.
#include <gtest/gtest.h>
#include <torch/torch.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>

#include "core/error.h"
#include "eval/evaluation.h"
#include "eval/frame_plot.h"
#include "eval/report.h"
#include "render_data/patch_sampler.h"
#include "tests/support/svg_paths.h"
#include "tests/support/eval_frames.h"
#include "tests/support/tiny_data.h"

using namespace cgsr;
using namespace cgsr::test;


TEST(Evaluation, FrameRangeSelectsWithinTheSplit) {
  const Dataset data = Dataset::open(tiny_data());
  EXPECT_EQ(evaluation_frames(data, all_frames("1:4")), (std::vector<int>{1, 2, 3}));
  EXPECT_EQ(evaluation_frames(data, all_frames("")).size(), 6u);
  EXPECT_THROW(evaluation_frames(data, all_frames("4:2")), Error);
  EXPECT_THROW(evaluation_frames(data, all_frames("10:20")), Error);  // no frame there
  EXPECT_THROW(evaluation_frames(data, all_frames("x:2")), Error);
}

TEST(Evaluation, ConsecutiveFramesGiveTheSameScoresAsSingleFrames) {
  const Dataset data = Dataset::open(tiny_data());
  auto upscaler = classic_upscalers().get("bicubic")(2);
  const EvalResult range = evaluate(*upscaler, data, all_frames("1:4"));
  ASSERT_EQ(range.frames.size(), 3u);
  for (const auto& f : range.frames) {
    SCOPED_TRACE(f.frame);
    const EvalResult one = evaluate(*upscaler, data, all_frames(std::to_string(f.frame) + ":" + std::to_string(f.frame + 1)));
    ASSERT_EQ(one.frames.size(), 1u);
    EXPECT_DOUBLE_EQ(one.frames[0].psnr, f.psnr);
    ASSERT_TRUE(one.frames[0].temporal_error && f.temporal_error);
    EXPECT_DOUBLE_EQ(*one.frames[0].temporal_error, *f.temporal_error);
  }
}

// A caller sees the quality (to write it out) before the latency is measured: at 1080p the
// timing runs for minutes.
TEST(Evaluation, QualityIsReportedBeforeTheLatency) {
  const Dataset data = Dataset::open(tiny_data());
  auto upscaler = classic_upscalers().get("bilinear")(2);
  EvalOptions options = all_frames("0:2");
  options.latency_runs = 3;
  int calls = 0;
  const EvalResult r = evaluate(*upscaler, data, options, [&](const EvalResult& early) {
    ++calls;
    EXPECT_EQ(early.frames.size(), 2u);
    EXPECT_GT(early.psnr, 10);
    EXPECT_FALSE(early.latency.has_value());
  });
  EXPECT_EQ(calls, 1);
  ASSERT_TRUE(r.latency.has_value());
  EXPECT_EQ(r.latency->runs, 3);
}

// Game captures store motion vectors at the render (LR) size only; the temporal error then uses
// them repeated over each 2x2 block and doubled, which lands close to the HR vectors' figure.
TEST(Evaluation, TemporalErrorFromMotionStoredAtLowResolutionOnly) {
  const auto dir = scratch_dir("lr-motion");
  const std::string root = tiny_data().string();
  std::ofstream(dir / "capture.yaml") << "layout: glob\nresolutions:\n"
                                         "  - {size: 64x48, color: '" << root << "/64x48/color/*.png', motion: '"
                                      << root << "/64x48/motion/*.exr'}\n"
                                         "  - {size: 128x96, color: '" << root << "/128x96/color/*.png'}\n";
  const Dataset capture = Dataset::open(dir / "capture.yaml");
  const Dataset native = Dataset::open(tiny_data());
  auto upscaler = classic_upscalers().get("bicubic")(2);
  const EvalResult from_lr = evaluate(*upscaler, capture, all_frames("1:6"));
  const EvalResult from_hr = evaluate(*upscaler, native, all_frames("1:6"));
  ASSERT_TRUE(from_lr.temporal_error && from_hr.temporal_error);
  EXPECT_DOUBLE_EQ(from_lr.psnr, from_hr.psnr);
  EXPECT_NE(*from_lr.temporal_error, *from_hr.temporal_error);
  EXPECT_NEAR(*from_lr.temporal_error, *from_hr.temporal_error, 0.25 * *from_hr.temporal_error);
}

namespace {
// PSNR from a mean squared error.
double psnr_of(double mse) { return -10 * std::log10(mse); }
}  // namespace

TEST(Evaluation, EdgeAndRestPsnrMatchADirectComputation) {
  const Dataset data = Dataset::open(tiny_data());
  auto upscaler = classic_upscalers().get("bicubic")(2);
  const EvalResult r = evaluate(*upscaler, data, all_frames(""));
  ASSERT_EQ(r.frames.size(), 6u);
  double edge_sum = 0;
  int with_edges = 0;
  for (const auto& f : r.frames) {
    SCOPED_TRACE(f.frame);
    // The same figures from the dataset's HR edge map, grown by a 3x3 max pool.
    const Batch b = frame_batch(data, f.frame, 2, {}, DepthEncoding::Log);
    const auto sr = upscaler->upscale(b).clamp(0.0, 1.0).to(torch::kFloat64);
    const auto hr = b.hr_color.to(torch::kFloat64);
    const auto edge = data.frame(f.frame, data.resolution_index({128, 96}))->edge.to(torch::kFloat32);
    const auto mask = (torch::max_pool2d(edge.unsqueeze(0), 3, 1, 1) > 0).to(torch::kFloat64);  // [1,1,H,W]
    const auto squared = (sr - hr).pow(2);
    const double selected = mask.sum().item<double>(), total = static_cast<double>(mask.numel());
    ASSERT_TRUE(f.edge_fraction && f.psnr_rest);
    EXPECT_NEAR(*f.edge_fraction, selected / total, 1e-12);
    if (selected == 0) {  // the camera sees no silhouette in this frame: all of it is "rest"
      EXPECT_FALSE(f.psnr_edge.has_value());
      EXPECT_NEAR(*f.psnr_rest, f.psnr, 1e-9);
      continue;
    }
    ++with_edges;
    ASSERT_TRUE(f.psnr_edge.has_value());
    EXPECT_LT(*f.edge_fraction, 1.0);
    EXPECT_GT(std::abs(*f.psnr_edge - *f.psnr_rest), 0.1);  // a real difference, not rounding
    edge_sum += *f.psnr_edge;
    EXPECT_NEAR(*f.psnr_edge, psnr_of((squared * mask).sum().item<double>() / (3 * selected)), 1e-6);
    EXPECT_NEAR(*f.psnr_rest, psnr_of((squared * (1 - mask)).sum().item<double>() / (3 * (total - selected))), 1e-6);
    // Edges and rest together are the whole frame.
    const double mse = *f.edge_fraction * std::pow(10, -*f.psnr_edge / 10) +
                       (1 - *f.edge_fraction) * std::pow(10, -*f.psnr_rest / 10);
    EXPECT_NEAR(psnr_of(mse), f.psnr, 1e-6);
  }
  ASSERT_GE(with_edges, 3);
  ASSERT_TRUE(r.psnr_edge && r.psnr_rest && r.edge_fraction);
  EXPECT_NEAR(*r.psnr_edge, edge_sum / with_edges, 1e-9);
  EXPECT_GT(std::abs(*r.psnr_edge - *r.psnr_rest), 0.1);
  EXPECT_GT(*r.edge_fraction, 0.0);
  EXPECT_LT(*r.edge_fraction, 1.0);
}

TEST(Evaluation, WithoutAnEdgeChannelTheEdgeFiguresStayEmpty) {
  DatasetOpenOptions open;
  open.channels = {"motion"};
  const Dataset data = Dataset::open(tiny_data(), open);
  auto upscaler = classic_upscalers().get("bilinear")(2);
  const EvalResult r = evaluate(*upscaler, data, all_frames("0:2"));
  ASSERT_EQ(r.frames.size(), 2u);
  EXPECT_FALSE(r.psnr_edge || r.psnr_rest || r.edge_fraction);
  for (const auto& f : r.frames) EXPECT_FALSE(f.psnr_edge || f.psnr_rest || f.edge_fraction);
  const auto j = to_json(r);
  EXPECT_TRUE(j.at("psnr_edge").is_null());
  EXPECT_FALSE(eval_result_from_json(j, "test").psnr_edge.has_value());
}

namespace {
// Bicubic with one pixel replaced: an upscaler whose arithmetic overflowed (or went NaN).
class BrokenUpscaler : public Upscaler {
 public:
  explicit BrokenUpscaler(float value) : value_(value) {}
  std::string name() const override { return "broken"; }
  int scale() const override { return 2; }
  torch::Tensor upscale(const Batch& batch) override {
    auto out = bicubic_->upscale(batch).clone();
    out.index_put_({0, 1, 3, 4}, value_);
    return out;
  }

 private:
  float value_;
  std::unique_ptr<Upscaler> bicubic_ = classic_upscalers().get("bicubic")(2);
};
}  // namespace

// Infinite values are caught before clamping to [0,1] would hide them as 0 or 1.
TEST(Evaluation, NonFiniteUpscalerOutputIsAnErrorNamingTheFrame) {
  const Dataset data = Dataset::open(tiny_data());
  for (const float value : {INFINITY, -INFINITY, NAN}) {
    SCOPED_TRACE(value);
    BrokenUpscaler upscaler(value);
    try {
      evaluate(upscaler, data, all_frames("2:3"));
      ADD_FAILURE() << "no error";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("broken: frame 2"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("NaN or infinite values"), std::string::npos) << e.what();
    }
  }
}

TEST(Evaluation, JsonKeepsTheEdgeFigures) {
  const Dataset data = Dataset::open(tiny_data());
  auto upscaler = classic_upscalers().get("bicubic")(2);
  EvalResult r = evaluate(*upscaler, data, all_frames("4:6"));
  ASSERT_TRUE(r.psnr_edge && r.frames.at(0).psnr_edge);
  r.frames[1].psnr_rest = INFINITY;  // no error there: written as null + psnr_rest_infinite
  r.frames[1].psnr_edge.reset();     // no edge pixel in the frame
  const auto j = to_json(r);
  EXPECT_DOUBLE_EQ(j.at("psnr_edge").get<double>(), *r.psnr_edge);
  EXPECT_DOUBLE_EQ(j.at("edge_fraction").get<double>(), *r.edge_fraction);
  EXPECT_TRUE(j.at("frames")[1].at("psnr_rest_infinite").get<bool>());
  const EvalResult back = eval_result_from_json(nlohmann::ordered_json::parse(j.dump()), "test");
  EXPECT_EQ(back.psnr_edge, r.psnr_edge);
  EXPECT_EQ(back.psnr_rest, r.psnr_rest);
  EXPECT_EQ(back.edge_fraction, r.edge_fraction);
  ASSERT_EQ(back.frames.size(), 2u);
  for (size_t i = 0; i < 2; ++i) {
    SCOPED_TRACE(i);
    EXPECT_EQ(back.frames[i].psnr_edge, r.frames[i].psnr_edge);
    EXPECT_EQ(back.frames[i].psnr_rest, r.frames[i].psnr_rest);
    EXPECT_EQ(back.frames[i].edge_fraction, r.frames[i].edge_fraction);
  }
  EXPECT_TRUE(std::isinf(*back.frames[1].psnr_rest));
  EXPECT_FALSE(back.frames[1].psnr_edge.has_value());

  const auto csv = frames_csv(r);
  EXPECT_NE(csv.find("temporal_error_reference,psnr_edge,psnr_rest,edge_fraction\n"), std::string::npos) << csv;
  EXPECT_NE(csv.find("," + std::to_string(*r.frames[0].psnr_edge) + "," + std::to_string(*r.frames[0].psnr_rest) +
                     "," + std::to_string(*r.frames[0].edge_fraction) + "\n"),
            std::string::npos)
      << csv;
  EXPECT_NE(csv.find(",,inf,"), std::string::npos) << csv;  // frame 5: no edge PSNR, infinite rest
}

TEST(Evaluation, JsonWithoutEdgeKeysStillLoads) {
  const Dataset data = Dataset::open(tiny_data());
  auto upscaler = classic_upscalers().get("bilinear")(2);
  auto j = to_json(evaluate(*upscaler, data, all_frames("0:2")));
  // What evaluations wrote before edge PSNR existed.
  for (auto* record : {&j, &j["frames"][0], &j["frames"][1]})
    for (const char* key : {"psnr_edge", "psnr_rest", "edge_fraction"}) {
      ASSERT_TRUE(record->contains(key)) << key;
      record->erase(key);
    }
  const EvalResult old = eval_result_from_json(j, "old.json");
  EXPECT_EQ(old.frames.size(), 2u);
  EXPECT_FALSE(old.psnr_edge || old.psnr_rest || old.edge_fraction);
  for (const auto& f : old.frames) EXPECT_FALSE(f.psnr_edge || f.psnr_rest || f.edge_fraction);
}

TEST(Evaluation, EvalCommandLoadsEdgesForUpscalersThatDoNotReadThem) {
  // bicubic reads no rendering channel: `cgsr eval` must still load the HR edges.
  const auto dir = scratch_dir("eval-edges");
  const auto r = run_cgsr("eval --data '" + tiny_data().string() + "' --model bicubic --latency-runs 0 --out '" +
                          (dir / "run").string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = read_json(dir / "run" / "results.json");
  const auto& e = j.at("evaluations").at(0);
  ASSERT_TRUE(e.at("psnr_edge").is_number()) << e.dump();
  ASSERT_TRUE(e.at("psnr_rest").is_number()) << e.dump();
  EXPECT_LT(e.at("psnr_edge").get<double>(), e.at("psnr").get<double>());
  EXPECT_NE(r.out.find("| Edge PSNR (dB) | Rest PSNR (dB) |"), std::string::npos) << r.out;
  std::filesystem::remove_all(dir);
}

namespace {
// Bicubic that reads the previous frame and records what it was shown, in order.
class RecordingUpscaler : public Upscaler {
 public:
  std::string name() const override { return "recording"; }
  int scale() const override { return 2; }
  bool uses_previous_frame() const override { return true; }
  void previous_frame(const Batch& previous) override { seen.push_back(-previous.frames.front()); }
  void reset_history() override { seen.push_back(kReset); }
  torch::Tensor upscale(const Batch& batch) override {
    seen.push_back(batch.frames.front());
    return bicubic_->upscale(batch);
  }
  static constexpr int kReset = std::numeric_limits<int>::min();
  std::vector<int> seen;  // upscaled frames, the previous frames shown as negatives, and kReset

 private:
  std::unique_ptr<Upscaler> bicubic_ = classic_upscalers().get("bicubic")(2);
};
}  // namespace

// Latency is timed on what quality was measured with: an upscaler that reads the previous frame
// is shown each timed frame's predecessor first, as evaluate() shows it.
TEST(Evaluation, TimingShowsEachFrameItsPredecessor) {
  const Dataset data = Dataset::open(tiny_data());
  RecordingUpscaler recording;
  const TimingSequence sequence = timing_sequence(data, {1, 2, 4, 5}, 2, recording, 2);
  ASSERT_EQ(sequence.size(), 2u);  // `count` frames, spread over the frames given
  sequence.run(recording, 1);
  sequence.run(recording, 0);
  EXPECT_EQ(recording.seen, (std::vector<int>{-3, 4, 0, 1}));

  auto bicubic = classic_upscalers().get("bicubic")(2);
  EXPECT_TRUE(timing_sequence(data, {2, 4}, 2, *bicubic, 5).previous.empty());

  EvalOptions timed = all_frames("3:5");
  timed.latency_runs = 3;
  recording.seen.clear();
  const EvalResult r = evaluate(recording, data, timed);
  ASSERT_TRUE(r.latency.has_value());
  // Quality, then 2 warm-up and 3 timed runs over frames 3 and 4 in turn, each after its predecessor.
  const std::vector<int> timing(recording.seen.end() - 10, recording.seen.end());
  EXPECT_EQ(timing, (std::vector<int>{-2, 3, -3, 4, -2, 3, -3, 4, -2, 3}));
}

namespace {
// The tiny scene twice, as scenes "tiny" and "tiny_b" of one data set (6 frames each), rendered
// once per test process.
const std::filesystem::path& two_scene_set() {
  static const std::filesystem::path set = [] {
    const auto dir = scratch_dir("eval-two-scenes");
    std::string second = slurp(std::string(CGSR_SOURCE_DIR) + "/configs/scenes/tiny.yaml");
    second.replace(second.find("name: tiny\n"), 11, "name: tiny_b\n");
    std::ofstream(dir / "tiny_b.yaml") << second;
    const auto render = run_cgsr("render --scene " + std::string(CGSR_SOURCE_DIR) + "/configs/scenes/tiny.yaml --scene " +
                                 (dir / "tiny_b.yaml").string() + " --out " + (dir / "set").string() + " --threads 1");
    EXPECT_EQ(render.exit_code, 0) << render.err;
    return dir / "set";
  }();
  return set;
}
}  // namespace

// A multi-scene data set numbers its frames on across scenes: the first frame of the second
// scene must not see the last frame of the first as its predecessor. Evaluation and timing reset
// the upscaler's history there instead.
TEST(Evaluation, HistoryIsResetAtEverySceneCut) {
  const Dataset data = Dataset::open(two_scene_set());
  ASSERT_EQ(data.scenes().size(), 2u);
  const int cut = data.frames(Split::All).size() / 2;  // both scenes have 6 frames
  ASSERT_FALSE(data.has_previous(cut));

  RecordingUpscaler recording;
  EvalOptions options = all_frames(std::to_string(cut - 1) + ":" + std::to_string(cut + 2));
  options.temporal = false;
  evaluate(recording, data, options);
  const int reset = RecordingUpscaler::kReset;
  EXPECT_EQ(recording.seen, (std::vector<int>{-(cut - 2), cut - 1, reset, cut, -cut, cut + 1}));

  recording.seen.clear();
  const TimingSequence timing = timing_sequence(data, {cut}, 2, recording, 1);
  timing.run(recording, 0);
  EXPECT_EQ(recording.seen, (std::vector<int>{reset, cut}));
}

// `cgsr eval` on two scenes draws PSNR per frame beside results.json: one line per model and
// scene, a dashed line at the cut (and one in the legend), no model's line crossing it, and the
// page shows it.
TEST(Evaluation, EvalCommandPlotsPsnrPerFrameWithTheSceneCut) {
  const auto dir = scratch_dir("eval-frame-plot");
  const auto r = run_cgsr("eval --data '" + two_scene_set().string() +
                          "' --model bicubic --model nearest --split all --latency-runs 0 --out '" +
                          (dir / "run").string() + "' --threads 1");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = read_json(dir / "run" / "results.json");
  const auto& starts = j.at("evaluations").at(0).at("scene_starts");
  ASSERT_EQ(starts.size(), 2u) << starts.dump();
  EXPECT_EQ(starts[1].at("scene"), "tiny_b");
  const int cut = starts[1].at("first_frame");
  EXPECT_EQ(cut, 6);
  ASSERT_EQ(j.at("tables").size(), 1u);
  const std::string file = j["tables"][0].at("frame_plot_svg");
  ASSERT_FALSE(file.empty());
  EXPECT_NE(slurp(dir / "run" / "index.html").find("<img src=\"" + file + "\""), std::string::npos);

  const auto table = group_results(collect_evaluations({(dir / "run").string()})).at(0);
  const auto plot = psnr_per_frame_plot(table);
  ASSERT_TRUE(plot.has_value());
  ASSERT_EQ(plot->series.size(), 2u);
  const auto paths = svg_paths(slurp(dir / "run" / file));
  // The cut: a dashed vertical line across the plot, and the legend's sample of it.
  std::vector<double> cut_x;
  int dashed = 0;
  for (const auto& p : paths)
    if (p.stroked && p.dashed) {
      ++dashed;
      if (p.xs.size() == 2 && p.xs[0] == p.xs[1]) cut_x.push_back(p.xs[0]);
    }
  EXPECT_EQ(dashed, 2);
  ASSERT_EQ(cut_x.size(), 1u);
  // The frame round the plot area (its legend samples are right of it).
  double right = 0;
  for (const auto& p : paths)
    if (p.stroked && p.straight && p.stroke == Rgb{60, 60, 60}) right = *std::max_element(p.xs.begin(), p.xs.end());
  ASSERT_GT(right, cut_x[0]);
  for (const auto& s : plot->series) {
    int lines = 0;
    for (const auto& p : paths) {
      if (!p.stroked || !p.straight || p.dashed || p.stroke != s.colour) continue;
      if (*std::max_element(p.xs.begin(), p.xs.end()) >= right) continue;  // the legend's sample
      ++lines;
      const bool before = p.xs.front() < cut_x[0];
      for (double x : p.xs) EXPECT_EQ(x < cut_x[0], before) << s.name << ": a line crosses the cut";
    }
    EXPECT_EQ(lines, 2) << s.name << ": one line per scene of 6 frames";
  }
  std::filesystem::remove_all(dir);
}

// Every evaluation names the ground truth it measured against: the tiny scene rendered aliased
// and with 4 samples per pixel, a capture as captured; `cgsr eval` writes it into results.json
// and prints it over its table, and the report keeps the two targets of one scene apart.
TEST(Evaluation, ResultsNameTheTargetTheyMeasureAgainst) {
  const auto dir = scratch_dir("eval-target");
  const auto render = run_cgsr("render --config " + std::string(CGSR_SOURCE_DIR) +
                               "/configs/scenes/tiny.yaml --set frames=3 --set hr_samples=4 --out '" +
                               (dir / "aa").string() + "' --threads 1");
  ASSERT_EQ(render.exit_code, 0) << render.all();
  const std::string supersampled = "supersampled (4 samples per pixel, box filter)";
  const auto r = run_cgsr("eval --data '" + (dir / "aa").string() + "' --model bicubic --split all --latency-runs 0 --out '" +
                          (dir / "run").string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = read_json(dir / "run" / "results.json");
  EXPECT_EQ(j.at("target"), supersampled);
  EXPECT_EQ(j.at("evaluations").at(0).at("target"), supersampled);
  EXPECT_NE(r.out.find("Target: " + supersampled + "."), std::string::npos) << r.out;

  auto bicubic = classic_upscalers().get("bicubic")(2);
  const EvalResult aliased = evaluate(*bicubic, Dataset::open(tiny_data()), all_frames("0:3"));
  EXPECT_EQ(aliased.target, "aliased (1 sample per pixel)");
  const EvalResult smooth = evaluate(*bicubic, Dataset::open(dir / "aa"), all_frames("0:3"));
  EXPECT_EQ(smooth.target, supersampled);
  EXPECT_NE(smooth.psnr, aliased.psnr);  // the same LR input against another ground truth
  EXPECT_EQ(eval_result_from_json(to_json(smooth), "test").target, supersampled);
  auto old = to_json(smooth);
  old.erase("target");  // results written before the field load with none
  EXPECT_EQ(eval_result_from_json(old, "old.json").target, "");
  const auto tables = group_results({aliased, smooth});
  ASSERT_EQ(tables.size(), 2u);
  EXPECT_EQ(tables[1].target, supersampled);
  EXPECT_NE(report_markdown(tables[0]).find("Target: aliased (1 sample per pixel)."), std::string::npos);
  // Quoted: the description holds a comma.
  EXPECT_NE(report_csv(tables).find(",\"" + supersampled + "\"\n"), std::string::npos) << report_csv(tables);

  const std::string root = tiny_data().string();
  std::ofstream(dir / "capture.yaml") << "layout: glob\nresolutions:\n"
                                         "  - {size: 64x48, color: '" << root << "/64x48/color/*.png'}\n"
                                         "  - {size: 128x96, color: '" << root << "/128x96/color/*.png'}\n";
  EXPECT_EQ(evaluate(*bicubic, Dataset::open(dir / "capture.yaml"), all_frames("0:3")).target, "as captured");
  std::filesystem::remove_all(dir);
}
