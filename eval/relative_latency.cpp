#include "eval/relative_latency.h"

#include "core/error.h"
#include "core/timing.h"

namespace cgsr {

LatencyReference::LatencyReference(std::unique_ptr<Upscaler> reference, Dataset data, std::vector<int> frames, int runs)
    : reference_(std::move(reference)), data_(std::move(data)), frames_(std::move(frames)), runs_(runs) {
  if (runs_ < 1) throw Error("latency", "a latency comparison needs at least one timed run");
  if (frames_.empty()) throw Error(data_.info().root.string(), "no frame to time latency on");
  sequence_ = timing_sequence(data_, frames_, reference_->scale(), *reference_, runs_);
}

RelativeLatency LatencyReference::time(Upscaler& candidate) const {
  const TimingSequence mine = timing_sequence(data_, frames_, candidate.scale(), candidate, runs_);
  size_t next_reference = 0, next_candidate = 0;
  const auto stats = measure_latency_interleaved(
      {[&] { sequence_.run(*reference_, next_reference++ % sequence_.size()); },
       [&] { mine.run(candidate, next_candidate++ % mine.size()); }},
      /*warmup=*/2, runs_);
  return {stats[1].median_ms, stats[0].median_ms};
}

}  // namespace cgsr
