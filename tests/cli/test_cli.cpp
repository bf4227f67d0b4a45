// The real cgsr executable: help, version, info, run directories and config errors.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "core/atomic_file.h"
#include "tests/support/child_process.h"
#include "tests/support/cli_runner.h"

using cgsr::test::run_cgsr;
using cgsr::test::scratch_dir;
namespace fs = std::filesystem;

TEST(Cli, HelpListsSubcommands) {
  const auto r = run_cgsr("--help");
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_NE(r.out.find("info"), std::string::npos);
  EXPECT_NE(r.out.find("--threads"), std::string::npos);
}

TEST(Cli, Version) {
  const auto r = run_cgsr("--version");
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_EQ(r.out.rfind("cgsr ", 0), 0u) << r.out;
}

TEST(Cli, NoSubcommandIsAUsageError) { EXPECT_EQ(run_cgsr("").exit_code, 2); }

TEST(Cli, InfoPrintsVersionsAndThreads) {
  const auto r = run_cgsr("info --json --threads 1");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["system"]["libtorch"].get<std::string>().substr(0, 4), "1.13");
  EXPECT_EQ(j["system"]["threads"].get<int>(), 1);
  EXPECT_FALSE(j["system"]["opencv"].get<std::string>().empty());
  EXPECT_FALSE(j["system"]["cpu_simd"].get<std::string>().empty());
}

TEST(Cli, RunDirectoryHoldsConfigLogAndResults) {
  const auto dir = scratch_dir("cli-run");
  const auto r = run_cgsr("info --seed 5 --out " + (dir / "run").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto config = cgsr::read_file(dir / "run" / "config.yaml");
  EXPECT_NE(config.find("seed: 5"), std::string::npos) << config;
  EXPECT_NO_THROW(nlohmann::json::parse(cgsr::read_file(dir / "run" / "results.json")));
  EXPECT_TRUE(fs::exists(dir / "run" / "log.txt"));
  for (const auto& entry : fs::directory_iterator(dir / "run"))  // nothing half-written left
    EXPECT_EQ(entry.path().string().find(".tmp-"), std::string::npos) << entry.path();
}

TEST(Cli, ConfigFileErrorsNameFileLineKeyAndSuggestion) {
  const auto dir = scratch_dir("cli-config");
  const auto file = dir / "info.yaml";
  cgsr::write_file_atomic(file, "seed: 3\njsno: true\n");
  const auto r = run_cgsr("info --config " + file.string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("error: " + file.string() + ":2:1: jsno: unknown key 'jsno' (did you mean 'json'?)"),
            std::string::npos)
      << r.err;
}

TEST(Cli, WrongTypeAndOutOfRangeAreUserErrors) {
  auto r = run_cgsr("info --set seed=abc");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--set seed=abc: seed: expected an integer, got 'abc'"), std::string::npos) << r.err;
  r = run_cgsr("info --set threads=5000");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("threads: '5000' is out of range [0, 1024]"), std::string::npos) << r.err;
  r = run_cgsr("info --set threads=-1");
  EXPECT_EQ(r.exit_code, 2);
}

TEST(Cli, MissingConfigFileIsAUserError) {
  const auto r = run_cgsr("info --config /nonexistent/cgsr.yaml");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("/nonexistent/cgsr.yaml"), std::string::npos) << r.err;
}

TEST(Cli, PrintConfigShowsResolvedDefaults) {
  const auto r = run_cgsr("info --print-config --set json=true");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("json: true"), std::string::npos);
  EXPECT_NE(r.out.find("threads: 0"), std::string::npos);
}

TEST(Cli, AListAsAKeyInAStageSectionIsAUserErrorAtItsLine) {
  const auto dir = scratch_dir("cli-run-key");
  const auto file = dir / "run.yaml";
  cgsr::write_file_atomic(file, "name: x\ndata: " + dir.string() + "\ntrain:\n  ? [a, b]\n  : 1\n");
  const auto r = run_cgsr("run --config " + file.string() + " --out " + (dir / "run").string());
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find(file.string() + ":4:"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("a key must be a name"), std::string::npos) << r.err;
}

// One writer per run directory: while one command holds a directory, a second one exits 2
// naming the holder's PID (it used to write into it too, both exiting 0 with a mixed result).
TEST(Cli, ASecondCommandOnARunDirectoryInUseExitsTwoNamingTheHolder) {
  const auto dir = scratch_dir("cli-lock");
  const std::string tiny = std::string(CGSR_SOURCE_DIR) + "/configs/scenes/tiny.yaml";
  cgsr::test::CgsrProcess first(
      {"render", "--config", tiny, "--set", "frames=400", "--threads", "1", "--out", (dir / "data").string()},
      dir / "first");
  const std::string holder = std::to_string(first.pid()) + " render";
  ASSERT_TRUE(first.wait_for([&] { return cgsr::test::slurp(dir / "data" / ".cgsr.lock").rfind(holder, 0) == 0; },
                             std::chrono::seconds(60)))
      << cgsr::test::slurp(dir / "first.err");
  const auto second = run_cgsr("render --config " + tiny + " --set frames=400 --out " + (dir / "data").string());
  first.kill();
  EXPECT_EQ(second.exit_code, 2) << second.err;
  EXPECT_NE(second.err.find((dir / "data").string() + ": is in use by another command ('cgsr render', pid " +
                            std::to_string(first.pid()) + ")"),
            std::string::npos)
      << second.err;
}

// A directory that belongs to another command is refused unless --force; the lock dies with its
// holder, so the directory is free again once that ends.
TEST(Cli, ARunDirectoryOfAnotherCommandIsRefusedUnlessForced) {
  const auto dir = scratch_dir("cli-kind") / "run";
  ASSERT_EQ(run_cgsr("info --out " + dir.string()).exit_code, 0);
  ASSERT_EQ(run_cgsr("info --out " + dir.string()).exit_code, 0);  // the same command may rerun
  const std::string render =
      "render --config " + std::string(CGSR_SOURCE_DIR) + "/configs/scenes/tiny.yaml --set frames=1 --out " + dir.string();
  auto r = run_cgsr(render);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find(dir.string() + ": belongs to 'cgsr info' (.cgsr.lock); choose another --out, or pass --force"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(cgsr::read_file(dir / "config.yaml").find("scene"), std::string::npos);  // info's config is untouched
  r = run_cgsr(render + " --force");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(cgsr::read_file(dir / ".cgsr.lock").find(" render"), std::string::npos);

  // A command of two words is one command: it may rerun in its directory, and is named whole.
  const auto two = scratch_dir("cli-kind-two");
  const std::string check = "data check " + (two / "no-data").string() + " --out " + (two / "run").string();
  ASSERT_EQ(run_cgsr(check).exit_code, 2);  // no data set there; the directory is data check's now
  r = run_cgsr(check);
  EXPECT_EQ(r.err.find("belongs to"), std::string::npos) << r.err;
  r = run_cgsr("info --out " + (two / "run").string());
  EXPECT_NE(r.err.find("belongs to 'cgsr data check' (.cgsr.lock)"), std::string::npos) << r.err;
}

// train --check builds the network the run would train: a spec file out of range, or a RIT
// reading an unknown channel, used to pass --check and fail the run. (run --check:
// RunCommand.CheckReadsEverySceneConfigAndWritesNothing.)
TEST(Cli, TrainCheckBuildsTheNetworkTheRunWould) {
  const auto dir = scratch_dir("cli-train-check");
  const fs::path spec = dir / "blocks0.yaml";
  cgsr::write_file_atomic(spec, "backbone: pan\nscale: 2\nblocks: 0\n");
  const std::string train = "train --data " + (dir / "no-data").string();
  auto r = run_cgsr(train + " --model " + spec.string() + " --check");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find(spec.string() + ":3:9: blocks: '0' is out of range [1, 64]"), std::string::npos) << r.err;
  r = run_cgsr(train + " --set enhance.enabled=true --set 'enhance.rit.channels=[bogus]' --check");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("unknown channel 'bogus'"), std::string::npos) << r.err;
  r = run_cgsr(train + " --set elastic.enabled=true --check");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("network  pan x2, elastic"), std::string::npos) << r.out;
}

// A non-UTF-8 --out used to pass every check and fail at the very end (exit 1, json type_error
// 316, no results.json); now it is refused before the directory is made.
TEST(Cli, ANonUtf8OutPathIsRefusedBeforeAnyWork) {
  const auto dir = scratch_dir("cli-utf8");
  const std::string bad = (dir / "caf\xE9").string();
  auto r = run_cgsr("info --out '" + bad + "'");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("error: --out: the path is not valid UTF-8 (byte 0xE9"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(bad));
  r = run_cgsr("info --set \"name=caf\xE9\" --out " + (dir / "ok").string());
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("not valid UTF-8 (byte 0xE9)"), std::string::npos) << r.err;
}

// A read-only --out was an internal error (exit 1, "Failed opening .../log.txt.partial"); it is
// the user's to fix: exit 2 naming the directory and what to do. Needs a read-only mount (root).
TEST(Cli, AReadOnlyOutExitsTwoNamingTheFix) {
  const auto dir = scratch_dir("cli-read-only");
  const std::string mount = "mount -t tmpfs -o ro,size=1M tmpfs " + dir.string() + " 2>/dev/null";
  if (::geteuid() != 0 || std::system(mount.c_str()) != 0) GTEST_SKIP() << "cannot mount a read-only tmpfs here";
  const auto r = run_cgsr("info --out " + (dir / "run").string());
  std::system(("umount " + dir.string()).c_str());
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("the file system is read-only; choose another --out"), std::string::npos) << r.err;
}

// Memory for the sizes asked for is the machine's limit, not a bug: exit 2 with the fix, and no
// LibTorch backtrace (it printed 40 frames).
TEST(Cli, OutOfMemoryForTheRequestedSizeExitsTwoWithoutABacktrace) {
  const auto r = run_cgsr("bench --model pan --input 16000x16000 --batch 64 --runs 1 --warmup 0 --threads 1");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("error: out of memory: the sizes asked for"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("frame #"), std::string::npos) << r.err;
}

// --check makes the checks the run makes: a render resolution beyond what cgsr reads back, and a
// scene option out of range (scene.size=[100000,100000] used to pass --check and fail the run).
TEST(Cli, RenderCheckAppliesTheRunsRangeChecks) {
  const std::string tiny = std::string(CGSR_SOURCE_DIR) + "/configs/scenes/tiny.yaml";
  auto r = run_cgsr("render --config " + tiny + " --check");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("triangles, 6 frames at 64x48, 128x96"), std::string::npos) << r.out;
  r = run_cgsr("render --config " + tiny + " --set scene.size=[100000,100000] --check");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("--set scene.size=[100000,100000]: scene.size[0]: '100000' is out of range [3, 200]"),
            std::string::npos)
      << r.err;
  r = run_cgsr("render --config " + tiny + " --set resolutions=[20000x15000,40000x30000] --check");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("resolution 20000x15000: width '20000' is out of range [1, 16384]"), std::string::npos)
      << r.err;
}
