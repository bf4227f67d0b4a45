#pragma once
// A network's latency as a fraction of a reference's, timed the way the report times its rows:
// each upscaler through its whole upscale() (its rendering-information input assembled from the
// frame included) on the same frames, in interleaved rounds, so that load changing on a shared
// machine hits both alike. The search's latency budget and the controls' equal latency are
// checked this way, so that what they aim at is what the verdict measures.
//
//   LatencyReference pan(make_upscaler("runs/q/train/model.cgsr", "", 2), data, data.frames(Split::Val), 5);
//   RelativeLatency r = pan.time(candidate);  // r.fraction(): the candidate's median over PAN x2's

#include <memory>
#include <vector>

#include "eval/evaluation.h"
#include "eval/upscaler.h"
#include "render_data/dataset.h"

namespace cgsr {

struct RelativeLatency {
  double ms = 0;            // the candidate's median
  double reference_ms = 0;  // the reference's median over the same rounds
  double fraction() const { return ms / reference_ms; }
};

class LatencyReference {
 public:
  // Times on `runs` of `frames` (spread over them, as timing_sequence() picks), 2 warm-up runs each.
  LatencyReference(std::unique_ptr<Upscaler> reference, Dataset data, std::vector<int> frames, int runs);
  RelativeLatency time(Upscaler& candidate) const;
  const Upscaler& reference() const { return *reference_; }

 private:
  std::unique_ptr<Upscaler> reference_;
  Dataset data_;
  std::vector<int> frames_;
  int runs_;
  TimingSequence sequence_;
};

}  // namespace cgsr
