#pragma once
// Training and evaluation batches from a Dataset (dataset.h), as Batch (batch.h):
//
//   Dataset data = Dataset::open(dir);
//   PatchSamplerOptions o;          // scale 2, 48x48 LR patches, 16 per batch, train split
//   o.channels = parse_channels({"depth", "normal", "edge"});
//   PatchSampler sampler(data, o);
//   Batch b = sampler.next();       // lr_color [16,3,48,48], hr_color [16,3,96,96], lr_info, hr_info
//   Batch c = sampler.batch(step);  // batch number `step`: what the step-th next() returns
//
//   FrameIterator frames(data, {/*scale=*/2, Split::Test, channels});
//   for (int k = 0; k < frames.size(); ++k) { Batch b = frames.get(k); ... }   // N = 1, full frames
//   Batch f = frame_batch(data, /*frame=*/12, /*scale=*/2, channels, DepthEncoding::Log);  // any frame
//
// Patches: a random frame of the split (of a multi-scene data set with scene weights: a scene
// drawn by weight, then one of its frames; without: each scene in proportion to its frames in
// the split), a random LR window, the HR window exactly `scale` times
// it (LR pixel (i, j) <-> HR pixels (s i .. s i + s - 1, s j .. s j + s - 1), docs/design.md). With
// augment, each item gets one of the 8 flips/rotations, applied to every tensor; normals and
// motion vectors are rotated/flipped as vectors (augment.h); with color_augment, its LR and HR
// colour also get one colour permutation and gain. Batch k depends only on the seed
// and k (not on threads or timing), so a resumed training run sees the same data; batches are
// built in the background (TBB), `prefetch` ahead of the last one asked for (or, with prefetch
// 0, on the calling thread when asked for).

#include <cstdint>
#include <memory>
#include <vector>

#include "render_data/batch.h"
#include "render_data/dataset.h"

namespace cgsr {

struct PatchSamplerOptions {
  int scale = 2;
  int patch_size = 48;  // LR patch side; the HR patch side is scale x patch_size
  int batch_size = 16;
  Split split = Split::Train;
  std::vector<RenderChannel> channels;  // rendering information in the batch (may be empty)
  DepthEncoding depth_encoding = DepthEncoding::Log;  // of the depth channel (the reader's, e.g. the model's)
  bool augment = true;
  bool color_augment = false;  // colour channels permuted and scaled alike in LR and HR (augment.h)
  uint64_t seed = 0;
  // Batches built ahead on TBB threads; 0: each batch is built when asked for, on the calling
  // thread alone (no other thread runs while the caller's compute threads may own every core).
  int prefetch = 2;
  int lr_width = 0;  // LR resolution width; 0: the smallest with a scale-x partner
  // Recurrent training (history_out): T > 1 makes each batch T steps of batch_size sequences, step
  // t's items at t * batch_size .. (t + 1) * batch_size - 1. A sequence is T consecutive frames of
  // the drawn frame's scene that hold it (ending at it when the scene allows), in one window with
  // one augmentation; Batch::frames names each item's frame, which may lie in another split (its
  // inputs are context; the trainer scores only the split's frames).
  int sequence_length = 1;
};

// The (LR, HR) resolution indices of `data` for `scale` (and an optional LR width).
std::pair<size_t, size_t> resolution_pair(const Dataset& data, int scale, int lr_width = 0);

class PatchSampler {
 public:
  PatchSampler(Dataset data, PatchSamplerOptions options);
  ~PatchSampler();
  PatchSampler(const PatchSampler&) = delete;
  PatchSampler& operator=(const PatchSampler&) = delete;

  Batch next();  // batch(number of batches returned so far)
  // Batch number k; when k follows the previous request it is usually ready (prefetched).
  Batch batch(int64_t k);
  // Batch number k built now, on the calling thread's TBB arena, without touching the prefetch.
  Batch build(int64_t k) const;
  const PatchSamplerOptions& options() const { return options_; }

 private:
  struct Prefetch;
  Batch make(int64_t k, bool parallel) const;  // batch k, its items built in parallel or one by one
  Dataset data_;
  PatchSamplerOptions options_;
  size_t lr_, hr_;
  std::vector<int> frames_;
  // Data sets with scene weights: the split's frames of each scene that has some, and the
  // cumulative share of the draws up to each (the last is 1). Empty: uniform over frames_.
  std::vector<std::vector<int>> scene_frames_;
  std::vector<double> scene_cumulative_;
  int64_t next_ = 0;
  std::unique_ptr<Prefetch> prefetch_;
};

struct FrameIteratorOptions {
  int scale = 2;
  Split split = Split::Test;
  std::vector<RenderChannel> channels;
  DepthEncoding depth_encoding = DepthEncoding::Log;
  int lr_width = 0;
};

// One whole frame (N = 1) by frame index, LR/HR picked as in resolution_pair.
Batch frame_batch(const Dataset& data, int frame, int scale, const std::vector<RenderChannel>& channels,
                  DepthEncoding depth, int lr_width = 0);

// Whole frames of a split, one Batch (N = 1) per frame, in frame order.
class FrameIterator {
 public:
  FrameIterator(Dataset data, FrameIteratorOptions options);
  int size() const { return static_cast<int>(frames_.size()); }
  int frame_index(int k) const { return frames_.at(k); }
  Batch get(int k) const;

 private:
  Dataset data_;
  FrameIteratorOptions options_;
  size_t lr_, hr_;
  std::vector<int> frames_;
};

}  // namespace cgsr
