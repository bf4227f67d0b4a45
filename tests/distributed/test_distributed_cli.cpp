// `cgsr train` as two local processes (--world-size 2) against one process with the same seed and
// threads: data-parallel training follows the 1-process loss curve, also killed and resumed.
// Every process runs one thread, so the two ranks share this 2-core machine fairly.
#include <gtest/gtest.h>

#include <fstream>

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
