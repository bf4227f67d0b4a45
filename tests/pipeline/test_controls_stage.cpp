// The controls stage cuts each kind to each latency factor of the final network: one control per
// pair, named and filed by its factor, narrower for a smaller factor, never the same cut twice,
// its cut kept for a resumed run.
#include <gtest/gtest.h>

#include <set>

#include "core/config.h"
#include "core/error.h"
#include "models/model_file.h"
#include "pipeline/controls_stage.h"
#include "tests/pruning/pruning_cases.h"
#include "tests/support/scratch_dir.h"
#include "tests/support/tiny_data.h"

using namespace cgsr;

namespace {
ControlsOptions parse_controls(const std::string& yaml) {
  return config::parse_document(config::Document::parse(yaml, "controls.yaml"), controls_schema());
}
}  // namespace

TEST(ControlsStage, LatencyFactorsAreCheckedByKey) {
  EXPECT_EQ(parse_controls("kinds: [uniform]\n").latency_factors, std::vector<double>{1.0});
  EXPECT_EQ(parse_controls("latency_factors: [0.75, 1, 1.5]\n").latency_factors.size(), 3u);
  for (const std::string bad : {"[]", "[1, 1]", "[0]", "[5]"}) {
    try {
      parse_controls("latency_factors: " + bad + "\n");
      ADD_FAILURE() << bad << " was accepted";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("latency_factors"), std::string::npos) << e.what();
    }
  }
}

TEST(ControlsStage, CutsEachKindToEachLatencyFactor) {
  torch::manual_seed(41);
  const auto dir = test::scratch_dir("controls-stage");
  SRNetwork enhanced(test::small_spec("pan", 2, 2, 8, 8, /*rit=*/true));
  test::randomize(*enhanced);
  Provenance named;
  named.extra = {{"name", "tiny CG"}};
  save_model(dir / "enhanced.cgsr", *enhanced, named);
  const auto half = control_at_rate(*enhanced, ControlKind::Uniform, 0.5, [](const SRNetwork&) { return 0.0; });
  save_model(dir / "final.cgsr", *half.network);

  ControlsJob job;
  // 0.25 and 0.5 may both reach the narrowest cut on this tiny network; it is trained once.
  job.options = parse_controls("kinds: [uniform]\nlatency_factors: [0.5, 0.25, 1]\n");
  job.enhanced = (dir / "enhanced.cgsr").string();
  job.final_model = (dir / "final.cgsr").string();
  job.data = test::tiny_data().string();
  job.schedule.steps = 2;
  job.schedule.batch_size = 2;
  job.schedule.patch_size = 16;
  job.schedule.validate_every = 0;
  job.distill = 0;
  const auto run = [&](bool resume) {
    RunDir run_dir(dir / "run", /*own_log=*/false);
    return run_controls(job, run_dir, resume);
  };
  const auto first = run(false);
  const auto& controls = first["controls"];
  ASSERT_GE(controls.size(), 2u);
  ASSERT_LE(controls.size(), 3u);
  const auto& at_one = controls[0];  // equal latency first
  const auto& at_half = controls[1];
  EXPECT_EQ(at_half["name"], "tiny CG uniform width at 0.5x");
  EXPECT_EQ(at_one["name"], "tiny CG uniform width");
  EXPECT_DOUBLE_EQ(at_half["latency_factor"].get<double>(), 0.5);
  for (const std::string file : {"uniform_x0.5.cgsr", "uniform.cgsr", "cut_uniform_x0.5.json", "cut_uniform.json"})
    EXPECT_TRUE(std::filesystem::exists(dir / "run" / file)) << file;
  // A smaller latency keeps no more of the network (timings are noisy; the order is not).
  EXPECT_LE(at_half["keep_rate"].get<double>(), at_one["keep_rate"].get<double>());
  EXPECT_EQ(read_model_file(at_half["file"].get<std::string>()).provenance.extra["latency_factor"], 0.5);
  std::set<double> rates;
  for (const auto& c : controls) EXPECT_TRUE(rates.insert(c["keep_rate"].get<double>()).second) << c.dump();

  // Resumed, each control is cut where its kept cut says, not timed again.
  const auto resumed = run(true);
  ASSERT_EQ(resumed["controls"].size(), controls.size());
  for (size_t i = 0; i < controls.size(); ++i)
    EXPECT_EQ(resumed["controls"][i]["keep_rate"], controls[i]["keep_rate"]) << i;
}
