// The trainer on a tiny rendered scene: the memory layout of its steps changes results only
// within float tolerance, the network comes back in NCHW, and the choice is made once per
// machine, recorded and kept by a resumed run or a rerun of the run directory; steps with
// a non-finite loss or gradient are skipped and counted, and a run that blows up stops with an error.
#include <gtest/gtest.h>
#include <torch/torch.h>

#include <cstdlib>
#include <filesystem>
#include <unistd.h>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/runtime.h"
#include "models/arch_spec.h"
#include "models/model_file.h"
#include "tests/support/tiny_data.h"
#include "train/run_identity.h"
#include "train/trainer.h"

using namespace cgsr;
using namespace cgsr::test;

namespace {

ArchSpec small_pan() { return spec_from_yaml("backbone: pan\nscale: 2\nblocks: 2\n", "test"); }

TrainSchedule short_schedule(MemoryLayout layout) {
  TrainSchedule s;
  s.steps = 6;
  s.batch_size = 2;
  s.patch_size = 16;
  s.validate_every = 0;
  s.val_frames = 1;
  s.layout = layout;
  return s;
}

// Trains a fresh small PAN (same seed each time) and returns it with the outcome.
std::pair<SRNetwork, TrainOutcome> train(MemoryLayout layout) {
  seed_everything(3);
  SRNetwork net(small_pan());
  const Dataset data = Dataset::open(tiny_data());
  Trainer trainer(net, data, short_schedule(layout), LossOptions{});
  TrainOutcome outcome = trainer.run();
  return {net, outcome};
}

}  // namespace

TEST(Trainer, LayoutsTrainToTheSameWeightsWithinTolerance) {
  set_threads(1);
  const auto [nchw, nchw_outcome] = train(MemoryLayout::Nchw);
  const auto [nhwc, nhwc_outcome] = train(MemoryLayout::Nhwc);
  EXPECT_EQ(nchw_outcome.layout, MemoryLayout::Nchw);
  EXPECT_EQ(nhwc_outcome.layout, MemoryLayout::Nhwc);
  const auto a = nchw->parameters(), b = nhwc->parameters();
  ASSERT_EQ(a.size(), b.size());
  double worst = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    // Handed back in NCHW whatever the steps ran in.
    EXPECT_TRUE(b[i].is_contiguous()) << i;
    worst = std::max(worst, (a[i] - b[i]).abs().max().item<double>());
  }
  // Six Adam steps of lr 1e-3 move weights by up to ~6e-3; the layouts agree far below that.
  EXPECT_LT(worst, 1e-4);
  EXPECT_NEAR(nchw_outcome.best.psnr, nhwc_outcome.best.psnr, 1e-3);
}

TEST(Trainer, SameLayoutAndSeedIsBitIdentical) {
  set_threads(1);
  const auto [first, first_outcome] = train(MemoryLayout::Nhwc);
  const auto [second, second_outcome] = train(MemoryLayout::Nhwc);
  const auto a = first->parameters(), b = second->parameters();
  for (size_t i = 0; i < a.size(); ++i) EXPECT_TRUE(torch::equal(a[i], b[i])) << i;
}

TEST(Trainer, AutoLayoutRecordsItsChoice) {
  set_threads(1);
  const auto [net, outcome] = train(MemoryLayout::Auto);
  EXPECT_TRUE(outcome.layout == MemoryLayout::Nchw || outcome.layout == MemoryLayout::Nhwc) << enum_name(outcome.layout);
  for (const auto& p : net->parameters()) EXPECT_TRUE(p.is_contiguous());
}

namespace {
MemoryLayout other(MemoryLayout layout) { return layout == MemoryLayout::Nhwc ? MemoryLayout::Nchw : MemoryLayout::Nhwc; }

// An empty machine cache of layouts of its own (CGSR_CACHE_DIR), which every cgsr process the
// test starts uses too.
std::filesystem::path fresh_layout_cache(const std::string& name) {
  const auto dir = scratch_dir("layouts-" + name);
  ::setenv("CGSR_CACHE_DIR", dir.c_str(), 1);
  forget_measured_layouts();
  return dir;
}

// Rewrites every decision of a layouts.json to the other layout: what a timing on a busy machine
// might have decided instead.
void flip_layouts(const std::filesystem::path& file) {
  nlohmann::json j = read_json(file);
  ASSERT_FALSE(j.empty());
  for (auto& [key, value] : j.items())
    value = enum_name(other(enum_from_name<MemoryLayout>(value.get<std::string>())));
  write_file_atomic(file, j.dump());
}
}  // namespace

// `auto` trains in the layout this machine decided once, whatever a timing would say now, so two
// runs of one config agree bit for bit.
TEST(Trainer, AutoLayoutIsTheMachinesCachedDecisionSoRunsAgreeBitForBit) {
  set_threads(1);
  const auto cache = fresh_layout_cache("trainer");
  const auto [measured, measured_outcome] = train(MemoryLayout::Auto);
  flip_layouts(cache / "layouts.json");
  forget_measured_layouts();  // as a new process
  const auto [first, first_outcome] = train(MemoryLayout::Auto);
  EXPECT_EQ(first_outcome.layout, other(measured_outcome.layout));
  forget_measured_layouts();
  const auto [second, second_outcome] = train(MemoryLayout::Auto);
  EXPECT_EQ(second_outcome.layout, first_outcome.layout);
  const auto a = first->parameters(), b = second->parameters();
  for (size_t i = 0; i < a.size(); ++i) EXPECT_TRUE(torch::equal(a[i], b[i])) << i;
  std::filesystem::remove_all(cache);
}

// A resumed run goes on in the layout its checkpoint was written in, whatever the machine's
// cache says by then.
TEST(Trainer, AResumedRunKeepsItsLayout) {
  set_threads(1);
  const auto cache = fresh_layout_cache("resume");
  const auto checkpoint = cache / "checkpoint.pt";
  const Dataset data = Dataset::open(tiny_data());
  TrainSchedule schedule = short_schedule(MemoryLayout::Auto);
  schedule.checkpoint_every = 1;
  seed_everything(3);
  schedule.steps = 3;
  const TrainOutcome begun = Trainer(SRNetwork(small_pan()), data, schedule, LossOptions{}).run(checkpoint);
  flip_layouts(cache / "layouts.json");
  forget_measured_layouts();
  seed_everything(3);
  schedule.steps = 6;
  const TrainOutcome resumed = Trainer(SRNetwork(small_pan()), data, schedule, LossOptions{}).run(checkpoint, true);
  EXPECT_TRUE(resumed.resumed);
  EXPECT_EQ(resumed.layout, begun.layout);
  std::filesystem::remove_all(cache);
}

// `cgsr train` records the layouts it chose in its run directory (layouts.json); a rerun of the
// directory uses them before the machine's cache (which another machine, or a cleared cache,
// would decide anew).
TEST(TrainCommand, ARerunOfItsRunDirectoryTrainsInTheLayoutItRecorded) {
  const auto cache = fresh_layout_cache("command");
  const auto out = cache / "run";
  const std::string train = "train --data " + tiny_data().string() +
                            " --model pan --steps 2 --threads 1 --set schedule.batch_size=2"
                            " --set schedule.patch_size=16 --set schedule.val_frames=1 --out " + out.string();
  auto r = run_cgsr(train);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string used = read_json(out / "results.json")["training"]["layout"];
  const auto recorded = read_json(out / "layouts.json");
  ASSERT_EQ(recorded.size(), 1u) << recorded.dump();
  EXPECT_EQ(recorded.begin().value(), used);
  EXPECT_EQ(recorded.begin().key().rfind("training of pan x2 on 2x16x16 patches", 0), 0u) << recorded.dump();

  flip_layouts(cache / "layouts.json");
  r = run_cgsr(train);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(read_json(out / "results.json")["training"]["layout"], used);
  EXPECT_NE(r.err.find("as recorded in " + (out / "layouts.json").string()), std::string::npos) << r.err;
  std::filesystem::remove_all(cache);
}

// Adam's first step moves every weight with a gradient by the learning rate, so after one step
// the largest change per part is that part's rate: the RIT's is rit_lr_scale times the backbone's.
TEST(Trainer, RenderingInformationPartsLearnAtTheirOwnRate) {
  set_threads(1);
  seed_everything(3);
  SRNetwork net(spec_from_yaml(
      "backbone: pan\nscale: 2\nblocks: 2\nrit: {enabled: true, channels: [depth, edge], source: hr_fuse}\n", "test"));
  std::vector<std::pair<std::string, torch::Tensor>> before;
  for (const auto& item : net->named_parameters()) before.emplace_back(item.key(), item.value().detach().clone());
  TrainSchedule schedule = short_schedule(MemoryLayout::Nchw);
  schedule.steps = 1;
  schedule.lr_max = schedule.lr_min = 1e-3;
  schedule.rit_lr_scale = 10;
  const Dataset data = Dataset::open(tiny_data());
  Trainer(net, data, schedule, LossOptions{}).run();

  double backbone = 0, rit = 0;
  const auto after = net->named_parameters();
  for (const auto& [key, value] : before) {
    const double moved = (after[key] - value).abs().max().item<double>();
    double& part = key.rfind("rit.", 0) == 0 ? rit : backbone;
    part = std::max(part, moved);
  }
  EXPECT_NEAR(backbone, 1e-3, 1e-5);
  EXPECT_NEAR(rit, 1e-2, 1e-4);
}

namespace {

std::vector<torch::Tensor> weights_of(const SRNetwork& net) {
  std::vector<torch::Tensor> out;
  for (const auto& p : net->parameters()) out.push_back(p.detach().clone());
  return out;
}

double largest_change(const std::vector<torch::Tensor>& a, const std::vector<torch::Tensor>& b) {
  double worst = 0;
  for (size_t i = 0; i < a.size(); ++i) worst = std::max(worst, (a[i] - b[i]).abs().max().item<double>());
  return worst;
}

bool all_finite(const std::vector<torch::Tensor>& weights) {
  for (const auto& w : weights)
    if (!torch::isfinite(w).all().item<bool>()) return false;
  return true;
}

// A constant learning rate (no cosine decay), NCHW, `steps` steps.
TrainSchedule constant_rate(double lr, int steps) {
  TrainSchedule s = short_schedule(MemoryLayout::Nchw);
  s.steps = steps;
  s.lr_max = s.lr_min = lr;
  return s;
}

// Trains a fresh small PAN with an extra loss term `extra(step, network)` and returns the
// weights each step started from (index = step) with the outcome.
std::pair<std::vector<std::vector<torch::Tensor>>, TrainOutcome> train_with_extra_loss(
    const TrainSchedule& schedule, const std::function<torch::Tensor(int, SRNetworkImpl&)>& extra) {
  seed_everything(3);
  SRNetwork net(small_pan());
  std::vector<std::vector<torch::Tensor>> started_from;
  TrainHooks hooks;
  hooks.extra_loss = [&](const Batch&, const TrainOutput&, int step) {
    EXPECT_EQ(static_cast<size_t>(step), started_from.size());
    started_from.push_back(weights_of(net));
    return extra(step, *net);
  };
  const Dataset data = Dataset::open(tiny_data());
  TrainOutcome outcome = Trainer(net, data, schedule, LossOptions{}, {}, hooks).run();
  return {started_from, outcome};
}

// The message of the cgsr::Error that `f` throws ("" and a test failure when it throws none).
std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  ADD_FAILURE() << "no cgsr::Error";
  return "";
}

}  // namespace

// Adam moves a weight by about the learning rate per step: at 10 the first step leaves weights
// near 10, the outputs near 1e30, and every later gradient overflows. Those steps are skipped;
// after max_nonfinite_steps of them in a row training stops, and a run that ends sooner stops
// too, because its best validation loss is not finite. Both errors name lr_max, and the weights
// stay finite (no non-finite step is applied).
TEST(Trainer, LearningRateOfTenStopsTrainingWithAnErrorNamingLrMax) {
  set_threads(1);
  const Dataset data = Dataset::open(tiny_data());
  for (const int max_nonfinite_steps : {3, 20}) {
    SCOPED_TRACE(max_nonfinite_steps);
    seed_everything(3);
    SRNetwork net(small_pan());
    TrainSchedule schedule = constant_rate(10, 8);
    schedule.max_nonfinite_steps = max_nonfinite_steps;
    const std::string what = error_of([&] { Trainer(net, data, schedule, LossOptions{}).run(); });
    EXPECT_NE(what.find("lr_max"), std::string::npos) << what;
    if (max_nonfinite_steps == 3)
      EXPECT_NE(what.find("3 consecutive steps with a non-finite loss or gradient"), std::string::npos) << what;
    else
      EXPECT_NE(what.find("the best validation (step 8) has a non-finite loss"), std::string::npos) << what;
    EXPECT_TRUE(all_finite(weights_of(net)));
  }
}

TEST(Trainer, LearningRateOfOneBillionthBarelyMovesTheWeights) {
  set_threads(1);
  seed_everything(3);
  SRNetwork net(small_pan());
  const auto before = weights_of(net);
  const Dataset data = Dataset::open(tiny_data());
  Trainer trainer(net, data, constant_rate(1e-9, 3), LossOptions{});
  const double untrained_psnr = trainer.validate(0).psnr;
  const TrainOutcome outcome = trainer.run();
  EXPECT_EQ(outcome.skipped_steps, 0);
  const auto after = weights_of(net);
  ASSERT_TRUE(all_finite(after));
  // Three steps of about 1e-9 each (a float32 weight near 1 cannot even show one of them).
  const double moved = largest_change(before, after);
  EXPECT_GT(moved, 0.0);
  EXPECT_LT(moved, 1e-7);
  EXPECT_TRUE(std::isfinite(outcome.best.psnr));
  EXPECT_NEAR(outcome.best.psnr, untrained_psnr, 1e-4);
}

// A NaN loss on step 2 (through the extra-loss hook): the step is skipped and counted, and the
// next step starts from the weights step 2 started from; the steps around it train normally.
TEST(Trainer, StepWithANonFiniteLossIsSkippedAndCounted) {
  set_threads(1);
  const auto [started_from, outcome] = train_with_extra_loss(constant_rate(1e-3, 5), [](int step, SRNetworkImpl&) {
    return torch::full({}, step == 2 ? std::numeric_limits<float>::quiet_NaN() : 0.f);
  });
  EXPECT_EQ(outcome.steps, 5);
  EXPECT_EQ(outcome.skipped_steps, 1);
  ASSERT_EQ(started_from.size(), 5u);
  EXPECT_EQ(largest_change(started_from[2], started_from[3]), 0.0);  // step 2 left every weight as it was
  EXPECT_GT(largest_change(started_from[1], started_from[2]), 0.0);  // steps 1 and 3 moved them
  EXPECT_GT(largest_change(started_from[3], started_from[4]), 0.0);
  EXPECT_TRUE(std::isfinite(outcome.best.psnr));
}

// A finite loss whose gradient is NaN (d sqrt(u)/du at u = 0 is infinite, times du/dw = 0) is
// caught by the gradient norm and skipped the same way.
TEST(Trainer, StepWithANonFiniteGradientIsSkippedAndCounted) {
  set_threads(1);
  const auto [started_from, outcome] =
      train_with_extra_loss(constant_rate(1e-3, 4), [](int step, SRNetworkImpl& net) {
        const auto w = net.parameters().front();
        return step == 1 ? torch::sqrt(w.sum() * 0) : torch::zeros({});
      });
  EXPECT_EQ(outcome.skipped_steps, 1);
  ASSERT_EQ(started_from.size(), 4u);
  EXPECT_EQ(largest_change(started_from[1], started_from[2]), 0.0);
  EXPECT_GT(largest_change(started_from[2], started_from[3]), 0.0);
  EXPECT_TRUE(all_finite(started_from[3]));
}

TEST(Trainer, ConsecutiveNonFiniteStepsStopTrainingWithAClearError) {
  set_threads(1);
  TrainSchedule schedule = constant_rate(1e-3, 6);
  schedule.max_nonfinite_steps = 2;
  try {
    train_with_extra_loss(schedule, [](int, SRNetworkImpl&) { return torch::full({}, INFINITY); });
    ADD_FAILURE() << "training did not stop";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("2 consecutive steps with a non-finite loss or gradient at step 1"), std::string::npos)
        << what;
    EXPECT_NE(what.find("lr_max"), std::string::npos) << what;
  }
}

// A train stage's results.json records where the step time went under phase_ms, in this order.
TEST(Trainer, PhaseTimesKeepTheirJsonFormat) {
  TrainOutcome o;
  o.phase_ms = {1.5, 2.5, 3.5, 0.25, 0, 0.125};
  EXPECT_EQ(to_json(o)["phase_ms"].dump(), R"({"batch":1.5,"forward_and_loss":2.5,"backward_and_clip":3.5,)"
                                           R"("optimizer":0.25,"validation":0.0,"checkpoint":0.125})");
  EXPECT_EQ(to_json(o)["layout"], "nchw");
}

namespace {
std::string train_command(const std::filesystem::path& out) {
  return "train --data " + tiny_data().string() +
         " --model pan --threads 1 --set schedule.steps=4 --set schedule.checkpoint_every=2"
         " --set schedule.batch_size=2 --set schedule.patch_size=16 --set schedule.val_frames=1 --out " +
         out.string();
}

size_t temporaries_in(const std::filesystem::path& dir) {
  size_t n = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir))
    if (e.path().filename().string().find(".tmp-") != std::string::npos) ++n;
  return n;
}
}  // namespace

// A full disk at a checkpoint used to end the process (SIGABRT from LibTorch's archive writer)
// and leave checkpoint.pt.tmp-PID behind. Now: exit 2 naming the file and the fix, no temporary
// left, the last good checkpoint kept, and --resume goes on from it.
TEST(TrainCommand, AFullDiskAtACheckpointExitsTwoAndResumeGoesOnFromTheLastGoodOne) {
  const auto out = scratch_dir("train-full-disk") / "run";
  ::setenv("CGSR_FAULT_NO_SPACE", "checkpoint.pt@1", 1);  // the step-2 checkpoint is written, step 4's is not
  auto r = run_cgsr(train_command(out));
  ::unsetenv("CGSR_FAULT_NO_SPACE");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find((out / "checkpoint.pt").string() + ": cannot write: no space left on the device"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(r.err.find("terminate called"), std::string::npos) << r.err;
  EXPECT_EQ(temporaries_in(out), 0u);
  ASSERT_TRUE(std::filesystem::exists(out / "checkpoint.pt"));
  EXPECT_FALSE(std::filesystem::exists(out / "results.json"));

  r = run_cgsr(train_command(out) + " --resume");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("at step 2/4"), std::string::npos) << r.err;
  EXPECT_TRUE(read_json(out / "results.json")["training"]["resumed"].get<bool>());
}

// The same on a real full file system, where the machine allows mounting one (root).
TEST(TrainCommand, ACheckpointOnASmallTmpfsExitsTwoAndLeavesNoTemporary) {
  const auto mount_point = scratch_dir("train-tmpfs");
  const std::string mount = "mount -t tmpfs -o size=3M tmpfs " + mount_point.string() + " 2>/dev/null";
  if (::geteuid() != 0 || std::system(mount.c_str()) != 0) GTEST_SKIP() << "cannot mount a tmpfs here";
  const auto r = run_cgsr(train_command(mount_point / "tr"));
  const size_t left = temporaries_in(mount_point / "tr");
  std::system(("umount " + mount_point.string()).c_str());
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("no space left on the device"), std::string::npos) << r.err;
  EXPECT_EQ(left, 0u);
}

// --resume with another seed, batch size or data set was accepted silently; now the differences
// are listed and the run exits 2, unless --force, which goes on and records them. A longer
// schedule is not a difference: that is what resuming is for.
TEST(TrainCommand, ResumingWithAnotherSeedOrScheduleExitsTwoListingTheDifferences) {
  const auto out = scratch_dir("train-resume-identity") / "run";
  auto r = run_cgsr(train_command(out) + " --seed 3");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = run_cgsr(train_command(out) + " --seed 4 --set schedule.batch_size=4 --set schedule.steps=6 --resume");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find((out / "checkpoint.pt").string() + ": was written by a different run"), std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("  seed: 3 in the checkpoint, 4 now"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("  schedule.batch_size: 2 in the checkpoint, 4 now"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("schedule.steps"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("pass --force"), std::string::npos) << r.err;

  r = run_cgsr(train_command(out) + " --seed 3 --set schedule.steps=6 --resume");  // only longer: fine
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_FALSE(read_json(out / "results.json")["training"].contains("resume_overrides"));

  r = run_cgsr(train_command(out) + " --seed 4 --set schedule.steps=8 --resume --force");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto overrides = read_json(out / "results.json")["training"]["resume_overrides"];
  ASSERT_EQ(overrides.size(), 1u) << overrides.dump();
  EXPECT_EQ(overrides[0], "seed: 3 in the checkpoint, 4 now");
}

// The data set's fingerprint: another data set (or the same one with other frames) differs.
TEST(RunIdentity, TheDataSetFingerprintTellsDataSetsApart) {
  const Dataset data = Dataset::open(tiny_data());
  const ArchSpec spec = small_pan();
  const TrainSchedule schedule = short_schedule(MemoryLayout::Nchw);
  const RunIdentity now = run_identity(3, schedule, data.info(), spec);
  EXPECT_TRUE(identity_differences(now, now).empty());
  DatasetInfo other = data.info();
  other.frames += 1;
  other.name = "other";
  const auto differences = identity_differences(run_identity(3, schedule, other, spec), now);
  ASSERT_EQ(differences.size(), 1u);
  EXPECT_EQ(differences[0].rfind("data: cgsr 'other', 7 frames", 0), 0u) << differences[0];
}

// `quantization_aware` fine-tunes through simulated INT8: the same schedule from the same start
// ends at other weights than the float32 fine-tuning, the calibration it used is in the model
// file, and an elastic network refuses it.
TEST(TrainCommand, QuantizationAwareFineTuningTrainsThroughSimulatedInt8) {
  const auto dir = test::scratch_dir("qat");
  const std::string common = " --data " + tiny_data().string() +
                             " --steps 2 --threads 1 --set seed=4 --set schedule.batch_size=2 --set schedule.patch_size=16"
                             " --set schedule.val_frames=1";
  auto r = run_cgsr("train --model pan" + common + " --out " + (dir / "start").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string start = (dir / "start" / "model.cgsr").string();
  r = run_cgsr("train --model " + start + common + " --out " + (dir / "fp32").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = run_cgsr("train --model " + start + common +
               " --set quantization_aware.enabled=true --set quantization_aware.calibration.frames=2 --out " +
               (dir / "qat").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("quantization-aware"), std::string::npos) << r.err;
  const Model fp32 = load_model(dir / "fp32" / "model.cgsr"), qat = load_model(dir / "qat" / "model.cgsr");
  const auto a = fp32.network->parameters(), b = qat.network->parameters();
  ASSERT_EQ(a.size(), b.size());
  bool differ = false;
  for (size_t i = 0; i < a.size(); ++i) differ = differ || !torch::equal(a[i], b[i]);
  EXPECT_TRUE(differ);  // the gradients came through the rounding
  ASSERT_TRUE(qat.provenance.extra.contains("quantization_aware"));
  EXPECT_EQ(qat.provenance.extra["quantization_aware"]["frames"], 2);
  EXPECT_FALSE(fp32.provenance.extra.contains("quantization_aware"));
  r = run_cgsr("train --model " + start + common +
               " --set elastic.enabled=true --set quantization_aware.enabled=true --out " + (dir / "both").string());
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("quantization_aware"), std::string::npos) << r.err;
  std::filesystem::remove_all(dir);
}
