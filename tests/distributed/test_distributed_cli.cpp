// `cgsr search` and `cgsr train` as two local processes (--world-size 2) against one process with
// the same seed and threads: the search records the same history and makes the same pick, also
// when rank 1 is SIGKILLed mid-candidate (the survivor trains its candidate) or rank 0 is (all
// resume); data-parallel training follows the 1-process loss curve, also killed and resumed. Every process runs one thread, so the two ranks share this 2-core machine fairly.
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <sstream>

#include "tests/support/child_process.h"
#include "tests/support/free_port.h"
#include "tests/support/tiny_data.h"

using namespace cgsr::test;
namespace fs = std::filesystem;
using namespace std::chrono_literals;

namespace {

std::vector<std::string> with_run_flags(std::vector<std::string> args, const fs::path& out) {
  args.insert(args.end(), {"--out", out.string(), "--seed", "7", "--threads", "1"});
  return args;
}

std::vector<std::string> as_rank(std::vector<std::string> args, int rank, int port) {
  args.insert(args.end(), {"--world-size", "2", "--rank", std::to_string(rank), "--store",
                           "127.0.0.1:" + std::to_string(port)});
  return args;
}

std::vector<nlohmann::json> history_of(const fs::path& run) {
  std::vector<nlohmann::json> lines;
  std::ifstream in(run / "history.jsonl");
  for (std::string line; std::getline(in, line);) lines.push_back(nlohmann::json::parse(line));
  return lines;
}

// The same candidates in the same order with the same scores (train_seconds is a timing).
void expect_same_search(const fs::path& reference, const fs::path& run) {
  const auto expected = history_of(reference), got = history_of(run);
  ASSERT_EQ(got.size(), expected.size());
  for (size_t i = 0; i < got.size(); ++i) {
    auto a = expected[i], b = got[i];
    a["score"].erase("train_seconds");
    b["score"].erase("train_seconds");
    EXPECT_EQ(b, a) << "history line " << i;
  }
  const auto r0 = read_json(reference / "results.json"), r1 = read_json(run / "results.json");
  EXPECT_EQ(r1["pick"]["spec_yaml"], r0["pick"]["spec_yaml"]);
  EXPECT_EQ(r1["pick"]["score"]["val_psnr"], r0["pick"]["score"]["val_psnr"]);
  EXPECT_EQ(r1["candidates"], r0["candidates"]);
  EXPECT_EQ(r1["world_size"], 2);
}

class DistributedSearch : public ::testing::Test {
 protected:
  // A briefly trained CG-enhanced PAN x2 with 2 blocks, the search config, and the 1-process
  // reference search, made once for the tests below.
  static void SetUpTestSuite() {
    dir_ = scratch_dir("distributed-search");
    std::ofstream(dir_ / "pan.yaml") << "backbone: pan\nscale: 2\nblocks: 2\n";
    auto r = run_cgsr_args(
        with_run_flags({"train", "--data", tiny_data().string(), "--model", (dir_ / "pan.yaml").string(), "--set",
                        "enhance.enabled=true", "--set", "enhance.rit.width=8", "--steps", "4", "--set",
                        "schedule.batch_size=2", "--set", "schedule.patch_size=16", "--set", "schedule.val_frames=1"},
                       dir_ / "parent"),
        dir_ / "parent");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    // 1 parent + 2 generations of 4 candidates; a candidate trains long enough to be killed in.
    std::ofstream(dir_ / "search.yaml") << R"(search:
  population: 4
  selection_ratio: 0.5
  generations: 2
  min_candidates: 1
  tolerance_db: 0.5
  space: {min_blocks: 1}
candidate:
  fade_steps: 2
  schedule: {steps: 12, batch_size: 2, patch_size: 16, validate_every: 0, val_frames: 1, layout: nhwc}
final: {steps: 2, batch_size: 2, patch_size: 16, validate_every: 0, val_frames: 1, layout: nhwc}
)";
    r = run_cgsr_args(with_run_flags(search_args(), dir_ / "reference"), dir_ / "reference");
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
  static void TearDownTestSuite() { fs::remove_all(dir_); }

  static std::vector<std::string> search_args() {
    return {"search", "--config", (dir_ / "search.yaml").string(), "--parent",
            (dir_ / "parent" / "model.cgsr").string(), "--data", tiny_data().string()};
  }

  static fs::path dir_;
};
fs::path DistributedSearch::dir_;

TEST_F(DistributedSearch, TwoProcessesRecordTheOneProcessHistoryAndPick) {
  const int port = free_port();
  const auto out = dir_ / "two";
  CgsrProcess rank1(as_rank(with_run_flags(search_args(), out), 1, port), dir_ / "two-rank1");
  const auto r = run_cgsr_args(as_rank(with_run_flags(search_args(), out), 0, port), dir_ / "two-rank0");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  ASSERT_EQ(rank1.wait(), 0) << rank1.err();
  expect_same_search(dir_ / "reference", out);
  // Rank 1 trained some of the candidates, into its own run directory.
  const auto worker = read_json(out / "rank1" / "results.json");
  EXPECT_GT(worker["candidates_trained"].get<int>(), 0);
  EXPECT_LT(worker["candidates_trained"].get<int>(), 8);
}

TEST_F(DistributedSearch, ARankKilledMidCandidateLosesNothing) {
  const int port = free_port();
  const auto out = dir_ / "killed";
  auto args = [&](int rank) {
    auto a = as_rank(with_run_flags(search_args(), out), rank, port);
    a.insert(a.end(), {"--set", "distributed.heartbeat_timeout=2"});
    return a;
  };
  CgsrProcess rank0(args(0), dir_ / "killed-rank0");
  {
    CgsrProcess rank1(args(1), dir_ / "killed-rank1");
    ASSERT_TRUE(rank1.wait_for([&] { return rank1.err().find("training candidate") != std::string::npos; }, 60s))
        << rank1.err();
    ASSERT_TRUE(rank1.kill()) << "rank 1 ended before it could be killed";
  }
  ASSERT_EQ(rank0.wait(), 0) << rank0.err();
  EXPECT_NE(rank0.err().find("goes back to the queue"), std::string::npos) << rank0.err();
  expect_same_search(dir_ / "reference", out);
}

// Rank 0 holds the store: when it dies the others stop, and all are restarted with --resume.
TEST_F(DistributedSearch, RankZeroKilledMidSearchResumesToTheSamePick) {
  const auto out = dir_ / "resumed";
  auto args = [&](int rank, int port, bool resume) {
    auto a = as_rank(with_run_flags(search_args(), out), rank, port);
    a.insert(a.end(), {"--set", "distributed.timeout=20"});
    if (resume) a.push_back("--resume");
    return a;
  };
  const auto recorded = [&] {  // whole lines only: the last may be half written
    const std::string text = slurp(out / "history.jsonl");
    return std::count(text.begin(), text.end(), '\n');
  };
  {
    const int port = free_port();
    CgsrProcess rank1(args(1, port, false), dir_ / "resumed-rank1-first");
    CgsrProcess rank0(args(0, port, false), dir_ / "resumed-rank0-first");
    // Killed once the parent and a first candidate are recorded.
    ASSERT_TRUE(rank0.wait_for([&] { return recorded() >= 2; }, 60s)) << rank0.err();
    ASSERT_TRUE(rank0.kill()) << "rank 0 finished before it could be killed";
    EXPECT_NE(rank1.wait(), 0);
    EXPECT_NE(rank1.err().find("lost the store"), std::string::npos) << rank1.err();
  }
  EXPECT_LT(recorded(), 9);
  const int port = free_port();
  CgsrProcess rank1(args(1, port, true), dir_ / "resumed-rank1");
  const auto r = run_cgsr_args(args(0, port, true), dir_ / "resumed-rank0");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  ASSERT_EQ(rank1.wait(), 0) << rank1.err();
  expect_same_search(dir_ / "reference", out);
}

std::vector<double> loss_curve(const fs::path& run) {
  std::vector<double> losses;
  std::ifstream in(run / "loss_curve.csv");
  std::string line;
  std::getline(in, line);  // header
  while (std::getline(in, line)) losses.push_back(std::stod(line.substr(line.find(',') + 1)));
  return losses;
}

TEST(DistributedTrain, TwoProcessesFollowTheOneProcessLossCurveAndResume) {
  const auto dir = scratch_dir("distributed-train");
  std::ofstream(dir / "pan.yaml") << "backbone: pan\nscale: 2\nblocks: 2\n";
  // A global batch of 4: 2 patches per rank.
  const std::vector<std::string> train = {"train", "--data", tiny_data().string(), "--model",
                                          (dir / "pan.yaml").string(), "--steps", "12", "--set",
                                          "schedule.batch_size=4", "--set", "schedule.patch_size=16", "--set",
                                          "schedule.val_frames=1", "--set", "schedule.validate_every=4", "--set",
                                          "schedule.checkpoint_every=3", "--set", "schedule.layout=nhwc"};
  auto r = run_cgsr_args(with_run_flags(train, dir / "one"), dir / "one");
  ASSERT_EQ(r.exit_code, 0) << r.err;

  // Two ranks, rank 0 killed once its checkpoint is written, then both resumed.
  const auto out = dir / "two";
  auto start = [&](int rank, int port, bool resume) {
    auto a = as_rank(with_run_flags(train, out), rank, port);
    a.insert(a.end(), {"--set", "distributed.timeout=20"});
    if (resume) a.push_back("--resume");
    return a;
  };
  {
    const int port = free_port();
    CgsrProcess rank1(start(1, port, false), dir / "two-rank1");
    CgsrProcess rank0(start(0, port, false), dir / "two-rank0");
    ASSERT_TRUE(rank0.wait_for([&] { return fs::exists(out / "checkpoint.pt"); }, 60s)) << rank0.err();
    ASSERT_TRUE(rank0.kill()) << "rank 0 finished before it could be killed";
    EXPECT_NE(rank1.wait(), 0);  // its partner (and the store) is gone: an error, not a hang
  }
  const int port = free_port();
  CgsrProcess rank1(start(1, port, true), dir / "resumed-rank1");
  r = run_cgsr_args(start(0, port, true), dir / "resumed-rank0");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  ASSERT_EQ(rank1.wait(), 0) << rank1.err();
  EXPECT_NE(r.err.find("resuming from"), std::string::npos) << r.err;

  const auto expected = loss_curve(dir / "one"), got = loss_curve(out);
  ASSERT_EQ(got.size(), 12u);
  ASSERT_EQ(got.size(), expected.size());
  for (size_t i = 0; i < got.size(); ++i) EXPECT_NEAR(got[i], expected[i], 1e-4 * expected[i]) << "step " << i + 1;
  const auto a = read_json(dir / "one" / "results.json"), b = read_json(out / "results.json");
  EXPECT_NEAR(b["training"]["best"]["psnr"].get<double>(), a["training"]["best"]["psnr"].get<double>(), 1e-3);
  EXPECT_FALSE(fs::exists(out / "rank1" / "model.cgsr"));  // rank 0 alone writes the outputs
  fs::remove_all(dir);
}

}  // namespace
