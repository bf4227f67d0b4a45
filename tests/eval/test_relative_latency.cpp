// A latency comparison times the candidate and the reference in turn, on the same frames, as the
// report times its rows; what it returns is what it timed. (No assertion on a duration: only the
// order of the runs and the arithmetic are checked.)
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <vector>

#include "core/error.h"
#include "eval/relative_latency.h"
#include "tests/support/tiny_data.h"

namespace cgsr {
namespace {

// Bicubic that logs each frame it upscales as tag * 100 + frame, in a log shared with another.
class TaggedUpscaler : public Upscaler {
 public:
  TaggedUpscaler(int tag, std::vector<int>& log) : tag_(tag), log_(log) {}
  std::string name() const override { return "tagged " + std::to_string(tag_); }
  int scale() const override { return 2; }
  torch::Tensor upscale(const Batch& batch) override {
    log_.push_back(tag_ * 100 + batch.frames.front());
    return bicubic_->upscale(batch);
  }

 private:
  int tag_;
  std::vector<int>& log_;
  std::unique_ptr<Upscaler> bicubic_ = classic_upscalers().get("bicubic")(2);
};

TEST(RelativeLatency, TimesTheCandidateAndTheReferenceInTurnOnTheSameFrames) {
  const Dataset data = Dataset::open(test::tiny_data());
  std::vector<int> log;
  const LatencyReference timer(std::make_unique<TaggedUpscaler>(1, log), data, {1, 3, 5}, 3);
  EXPECT_EQ(timer.reference().name(), "tagged 1");
  TaggedUpscaler candidate(2, log);
  const RelativeLatency r = timer.time(candidate);
  // Two warm-up runs of each, then 3 rounds: the reference, then the candidate, on the same frame.
  EXPECT_EQ(log, (std::vector<int>{101, 103, 201, 203, 105, 205, 101, 201, 103, 203}));
  EXPECT_GT(r.ms, 0);
  EXPECT_GT(r.reference_ms, 0);
  EXPECT_DOUBLE_EQ(r.fraction(), r.ms / r.reference_ms);

  // A second candidate starts from the reference's first frame again.
  log.clear();
  timer.time(candidate);
  EXPECT_EQ(std::vector<int>(log.begin(), log.begin() + 2), (std::vector<int>{101, 103}));
}

TEST(RelativeLatency, NeedsARunAndAFrame) {
  const Dataset data = Dataset::open(test::tiny_data());
  std::vector<int> log;
  EXPECT_THROW(LatencyReference(std::make_unique<TaggedUpscaler>(1, log), data, {1}, 0), Error);
  EXPECT_THROW(LatencyReference(std::make_unique<TaggedUpscaler>(1, log), data, {}, 3), Error);
}

}  // namespace
}  // namespace cgsr
