// The inference helper: eval mode, no autograd, identical results in both memory layouts; the
// choice of a layout, made once per machine and recorded in the run directory.
#include <gtest/gtest.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <thread>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/runtime.h"
#include "core/system_info.h"
#include "models/inference.h"
#include "tests/models/model_cases.h"
#include "tests/support/cli_runner.h"

using namespace cgsr;
using namespace cgsr::test;

TEST(Inference, MatchesForwardWithoutAutograd) {
  torch::manual_seed(12);
  for (const char* b : {"srcnn", "edsr", "pan"}) {
    SCOPED_TRACE(b);
    const ArchSpec spec = with_rit(default_spec(b, 2));
    SRNetwork net(spec);
    const auto [color, info] = random_inputs(spec, 6, 5);
    const auto out = infer(*net, color, info);
    EXPECT_FALSE(out.requires_grad());
    EXPECT_FALSE(net->is_training());
    EXPECT_TRUE(out.is_contiguous());
    torch::NoGradGuard no_grad;
    const auto ref = net->forward(color, info);
    EXPECT_TRUE(torch::allclose(out, ref, 1e-5, 1e-5));
    const auto nchw = infer(*net, color, info, MemoryLayout::Nchw);
    const auto nhwc = infer(*net, color, info, MemoryLayout::Nhwc);
    EXPECT_TRUE(torch::equal(nchw, ref));
    EXPECT_TRUE(nhwc.is_contiguous());
    EXPECT_TRUE(torch::allclose(nhwc, ref, 1e-4, 1e-5));
  }
}

TEST(Inference, LayoutNames) {
  EXPECT_EQ(enum_from_name<MemoryLayout>("nhwc"), MemoryLayout::Nhwc);
  EXPECT_EQ(enum_name(MemoryLayout::Auto), "auto");
  EXPECT_THROW(enum_from_name<MemoryLayout>("chw"), Error);
}

TEST(MemoryLayout, ParametersChangeLayoutInPlaceAndKeepValues) {
  torch::manual_seed(4);
  SRNetwork net(default_spec("pan", 2));
  const auto before = net->parameters();
  std::vector<torch::Tensor> values;
  for (const auto& p : before) values.push_back(p.detach().clone());
  set_parameter_layout(*net, MemoryLayout::Nhwc);
  const auto after = net->parameters();
  for (size_t i = 0; i < after.size(); ++i) {
    EXPECT_TRUE(after[i].is_same(before[i])) << i;  // the same tensors: optimizers stay valid
    EXPECT_TRUE(torch::equal(after[i], values[i])) << i;
    if (after[i].dim() == 4) {
      EXPECT_TRUE(after[i].is_contiguous(torch::MemoryFormat::ChannelsLast)) << i;
    }
  }
  set_parameter_layout(*net, MemoryLayout::Nchw);
  for (const auto& p : net->parameters()) EXPECT_TRUE(p.is_contiguous());
}

namespace {
// An empty machine cache of its own (CGSR_CACHE_DIR) and a process that remembers nothing yet.
std::filesystem::path fresh_layout_cache(const std::string& name) {
  const auto dir = test::scratch_dir("layouts-" + name);
  ::setenv("CGSR_CACHE_DIR", dir.c_str(), 1);
  forget_measured_layouts();
  return dir;
}

// A timing that makes `slow` slow on purpose, counting its calls.
std::function<void(MemoryLayout)> timing_where_slow(MemoryLayout slow, int& calls) {
  return [slow, &calls](MemoryLayout layout) {
    ++calls;
    if (layout == slow) std::this_thread::sleep_for(std::chrono::milliseconds(20));
  };
}
}  // namespace

TEST(MemoryLayout, MeasuredChoiceIsRememberedPerKey) {
  fresh_layout_cache("remembered");
  int calls = 0;
  const auto run = timing_where_slow(MemoryLayout::Nchw, calls);
  EXPECT_EQ(measured_layout("test key", run, 3), MemoryLayout::Nhwc);
  EXPECT_EQ(calls, 8);  // one warm-up and three rounds of each
  EXPECT_EQ(measured_layout("test key", run, 3), MemoryLayout::Nhwc);
  EXPECT_EQ(calls, 8);
}

// What a busy machine does to a timing: it may now prefer the other layout. The cached decision
// holds, so every run of a config on this machine trains in one layout.
TEST(MemoryLayout, ACachedChoiceIsReusedWhenATimingWouldNowPreferTheOtherLayout) {
  const auto dir = fresh_layout_cache("cached");
  int calls = 0;
  EXPECT_EQ(measured_layout("cached key", timing_where_slow(MemoryLayout::Nchw, calls)), MemoryLayout::Nhwc);
  EXPECT_EQ(calls, 8);
  // Keyed by the key, the thread count and the CPU model.
  const auto cache = read_json(dir / "layouts.json");
  EXPECT_EQ(layout_cache_file(), dir / "layouts.json");
  EXPECT_EQ(cache.at(machine_layout_key("cached key")), "nhwc") << cache.dump();
  EXPECT_NE(machine_layout_key("cached key").find(std::to_string(thread_count()) + " threads"), std::string::npos);
  EXPECT_NE(machine_layout_key("cached key").find(cpu_model()), std::string::npos);

  forget_measured_layouts();  // a new process
  EXPECT_EQ(measured_layout("cached key", timing_where_slow(MemoryLayout::Nhwc, calls)), MemoryLayout::Nhwc);
  EXPECT_EQ(calls, 8);  // not measured again
  // Another network or input shape is decided on its own.
  EXPECT_EQ(measured_layout("other key", timing_where_slow(MemoryLayout::Nhwc, calls)), MemoryLayout::Nchw);
  EXPECT_EQ(calls, 16);
  std::filesystem::remove_all(dir);
}

// A run directory's record comes before the machine's cache (a rerun on another machine, or after
// the cache was cleared, runs as the run did), and takes what the cache or a timing decided.
TEST(MemoryLayout, TheRunDirectorysRecordComesFirstAndRecordsEveryChoice) {
  const auto dir = fresh_layout_cache("record");
  const auto record = dir / "run" / "layouts.json";
  write_file_atomic(record, R"({"recorded key": "nchw"})");
  int calls = 0;
  {
    LayoutRecordScope scope(record);
    EXPECT_EQ(measured_layout("recorded key", timing_where_slow(MemoryLayout::Nchw, calls)), MemoryLayout::Nchw);
    EXPECT_EQ(calls, 0);
    EXPECT_EQ(measured_layout("new key", timing_where_slow(MemoryLayout::Nchw, calls)), MemoryLayout::Nhwc);
    EXPECT_EQ(calls, 8);
  }
  const auto recorded = read_json(record);
  EXPECT_EQ(recorded, (nlohmann::json{{"new key", "nhwc"}, {"recorded key", "nchw"}}));

  write_file_atomic(record, R"({"recorded key": "auto"})");
  forget_measured_layouts();
  LayoutRecordScope scope(record);
  EXPECT_THROW(measured_layout("recorded key", timing_where_slow(MemoryLayout::Nchw, calls)), Error);
  std::filesystem::remove_all(dir);
}

TEST(Inference, AutoLayoutGivesTheReferenceOutput) {
  torch::manual_seed(5);
  SRNetwork net(default_spec("pan", 2));
  const auto color = torch::rand({1, 3, 9, 11});
  const MemoryLayout chosen = inference_layout(*net, color, {});
  EXPECT_NE(chosen, MemoryLayout::Auto);
  torch::NoGradGuard no_grad;
  EXPECT_TRUE(torch::allclose(infer(*net, color), net->forward(color), 1e-4, 1e-5));
}
