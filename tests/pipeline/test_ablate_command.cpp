// cgsr ablate on the tiny rendered scene: every variant trains from the one plain network, the
// summary compares each with the control per seed, and a rerun resumes from the records. It trains
// 14 networks, so it sits with the slow pipeline tests (left out of the sanitizer run).
#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>

#include "core/atomic_file.h"
#include "models/model_file.h"
#include "tests/support/cli_runner.h"
#include "tests/support/tiny_data.h"

using namespace cgsr;
using namespace cgsr::test;
namespace fs = std::filesystem;

TEST(Ablation, TrainsEveryVariantAgainstTheControlAndResumes) {
  const auto dir = scratch_dir("ablation");
  save_model(dir / "plain.cgsr", *SRNetwork(default_spec("pan", 2)));
  const std::string command =
      "ablate --data " + tiny_data().string() + " --model " + (dir / "plain.cgsr").string() + " --out " +
      (dir / "run").string() +
      " --threads 1 --set ablation.sources=[lr,hr_fuse] --set ablation.seeds=[1,2] --set ablation.leave_out=true"
      " --set ablation.rit.channels=[depth,edge] --set ablation.small_width=0.5 --set ablation.schedule.steps=2"
      " --set ablation.schedule.batch_size=2 --set ablation.schedule.patch_size=16"
      " --set ablation.schedule.validate_every=0 --set ablation.schedule.val_frames=1"
      " --set ablation.schedule.layout=nchw --set ablation.eval.latency_runs=0";
  const auto r = run_cgsr(command);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto results = nlohmann::json::parse(read_file(dir / "run" / "results.json"));
  const auto& rows = results.at("rows");
  // control, 2 sources, the best source without depth / without edge, small plain, small + best
  ASSERT_EQ(rows.size(), 7u);
  EXPECT_EQ(rows[0].at("variant"), "plain (control)");
  const std::string best = results.at("best_source");
  EXPECT_TRUE(best == "lr" || best == "hr_fuse") << best;
  EXPECT_EQ(rows[3].at("variant"), best + " - depth");
  EXPECT_EQ(rows[6].at("variant"), "small + " + best);
  for (const auto& row : rows) {
    EXPECT_EQ(row.at("seeds"), nlohmann::json::array({1, 2})) << row;
    EXPECT_EQ(row.at("psnr").size(), 2u) << row;  // one per seed
    EXPECT_EQ(row.at("psnr_edge").size(), 2u) << row;
  }
  // The small network has about a quarter of the parameters.
  const double share = rows[5].at("params").get<double>() / rows[0].at("params").get<double>();
  EXPECT_GT(share, 0.15);
  EXPECT_LT(share, 0.4);
  // Seeds differ (the batches and a fresh RIT depend on them), so the range is real.
  const auto& control_psnr = rows[0].at("psnr");
  EXPECT_NE(control_psnr[0].get<double>(), control_psnr[1].get<double>());
  const std::string md = read_file(dir / "run" / "ablation.md");
  EXPECT_NE(md.find("| plain (control) |"), std::string::npos) << md;
  EXPECT_NE(md.find("closes"), std::string::npos) << md;
  EXPECT_TRUE(fs::exists(dir / "run" / "ablation.png"));
  // The CSV has one line per (variant, seed), naming the seed.
  const std::string csv = read_file(dir / "run" / "ablation.csv");
  EXPECT_NE(csv.find("\nplain (control),control,2,"), std::string::npos) << csv;

  // A rerun trains nothing: every (variant, seed) has its record.
  const auto again = run_cgsr(command);
  ASSERT_EQ(again.exit_code, 0) << again.err;
  const auto rerun = nlohmann::json::parse(read_file(dir / "run" / "results.json"));
  EXPECT_EQ(rerun.at("rows"), rows);
  EXPECT_EQ(rerun.at("best_source"), best);
  EXPECT_NE((again.out + again.err).find("already done"), std::string::npos);
  EXPECT_EQ((again.out + again.err).find("other settings"), std::string::npos);

  // Changed settings are not mixed with the records of the old ones: every run trains again.
  const auto changed = run_cgsr(command + " --set ablation.schedule.rit_lr_scale=10");
  ASSERT_EQ(changed.exit_code, 0) << changed.err;
  EXPECT_EQ((changed.out + changed.err).find("already done"), std::string::npos);
  EXPECT_NE((changed.out + changed.err).find("plain (control) seed 1 was trained under other settings"),
            std::string::npos);
  fs::remove_all(dir);
}

// channel_sets: each list of channels at the best source, named after it, here with the bsp
// channel of a data set rendered with BSP border files; a set naming no channel or an unknown one
// is refused before anything trains.
TEST(Ablation, ChannelSetsTrainTheBestSourceWithOtherChannels) {
  const auto dir = scratch_dir("ablation-channel-sets");
  const auto render = run_cgsr("render --config " + std::string(CGSR_SOURCE_DIR) +
                               "/configs/scenes/tiny.yaml --set frames=3 --set bsp_border.depth=2 --threads 1 --out " +
                               (dir / "data").string());
  ASSERT_EQ(render.exit_code, 0) << render.err;
  save_model(dir / "plain.cgsr", *SRNetwork(default_spec("pan", 2)));
  const std::string command =
      "ablate --data " + (dir / "data").string() + " --model " + (dir / "plain.cgsr").string() +
      " --threads 1 --set ablation.sources=[hr_fuse] --set ablation.seeds=[1] --set ablation.leave_out=false"
      " --set ablation.rit.channels=[depth,edge] --set ablation.small_width=0 --set ablation.schedule.steps=2"
      " --set ablation.schedule.batch_size=2 --set ablation.schedule.patch_size=16"
      " --set ablation.schedule.validate_every=0 --set ablation.schedule.val_frames=1"
      " --set ablation.schedule.layout=nchw --set ablation.eval.latency_runs=0 --set ablation.eval.split=all";
  const auto r = run_cgsr(command + " --set 'ablation.channel_sets=[[bsp], [edge, depth, bsp]]' --out " +
                          (dir / "run").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto rows = nlohmann::json::parse(read_file(dir / "run" / "results.json")).at("rows");
  ASSERT_EQ(rows.size(), 4u) << rows;
  EXPECT_EQ(rows[2].at("variant"), "hr_fuse [bsp]");
  EXPECT_EQ(rows[3].at("variant"), "hr_fuse [depth+edge+bsp]");  // the channels in their fixed order
  EXPECT_EQ(rows[2].at("kind"), "channels");
  EXPECT_NE(rows[3].at("spec").get<std::string>().find("rit[depth+edge+bsp"), std::string::npos) << rows[3];
  // The bsp channel's 4 inputs: more parameters than the same RIT without it would have.
  EXPECT_GT(rows[3].at("params").get<int64_t>(), rows[1].at("params").get<int64_t>());

  for (const char* bad : {"[[]]", "[[depht]]"}) {
    const auto refused = run_cgsr(command + " --set 'ablation.channel_sets=" + bad + "' --out " + (dir / "bad").string());
    EXPECT_EQ(refused.exit_code, 2) << bad << refused.all();
    EXPECT_NE(refused.all().find("channel_sets"), std::string::npos) << refused.all();
  }
  fs::remove_all(dir);
}
