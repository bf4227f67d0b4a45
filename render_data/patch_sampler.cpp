#include "render_data/patch_sampler.h"

#include <oneapi/tbb/parallel_for.h>
#include <oneapi/tbb/task_group.h>
#include <torch/torch.h>

#include <algorithm>
#include <deque>

#include "core/config.h"
#include "core/error.h"
#include "core/runtime.h"
#include "render_data/augment.h"
#include "render_data/history_channel.h"

namespace cgsr {

std::pair<size_t, size_t> resolution_pair(const Dataset& data, int scale, int lr_width) {
  const auto& rs = data.resolutions();
  std::vector<std::string> names;
  for (const auto& r : rs) names.push_back(r.name());
  if (scale < 1) throw Error("sampler", "scale " + config::out_of_range(scale, 1, config::kUnbounded));
  for (size_t lo = 0; lo < rs.size(); ++lo) {
    if (lr_width > 0 && rs[lo].width != lr_width) continue;
    for (size_t hi = 0; hi < rs.size(); ++hi)
      if (rs[hi].width == scale * rs[lo].width && rs[hi].height == scale * rs[lo].height) return {lo, hi};
  }
  throw Error(data.info().root.string(), "has no resolution pair with scale " + std::to_string(scale) +
                                             (lr_width > 0 ? " and LR width " + std::to_string(lr_width) : "") +
                                             " (resolutions: " + join(names) + ")");
}

namespace {

template <class Rng>
double uniform01(Rng& rng) {
  return static_cast<double>(rng() >> 11) * 0x1.0p-53;  // [0, 1): the top 53 bits
}

// Both resolutions must carry every channel a batch needs.
void require_channels(const Dataset& data, const std::vector<RenderChannel>& channels, size_t lo, size_t hi) {
  for (size_t r : {lo, hi}) {
    const auto& here = channels_at(data.info(), r);
    for (auto c : channels)
      if (std::find(here.begin(), here.end(), c) == here.end())
        throw Error(data.info().root.string(), "batches need channel '" + channel_name(c) + "' at " +
                                                   data.resolutions()[r].name() + ", which the dataset does not provide there" +
                                                   (here.empty() ? std::string() : " (it has: " + join(channel_names(here)) + ")") +
                                                   (c == RenderChannel::History || c == RenderChannel::HistoryOut
                                                        ? ": " + history_missing_at(data.info(), r)
                                                        : ""));
  }
}

// One (LR, HR) pair of windows, augmented, as float tensors.
struct Item {
  torch::Tensor lr_color, lr_info, hr_color, hr_info;
};

Item make_item(const Frame& lr, const Frame& hr, int x, int y, int w, int h, int s,
               const std::vector<RenderChannel>& channels, DepthEncoding depth, double near_plane, double far_plane,
               const Augmentation* aug, const ColorAugmentation* color = nullptr) {
  const Frame l = crop(lr, x, y, w, h), H = crop(hr, s * x, s * y, s * w, s * h);
  Item it;
  it.lr_color = l.color_float();
  it.hr_color = H.color_float();
  it.lr_info = l.info(channels, depth, near_plane, far_plane);
  it.hr_info = H.info(channels, depth, near_plane, far_plane);
  if (aug) {
    it.lr_color = augment_image(it.lr_color, *aug);
    it.hr_color = augment_image(it.hr_color, *aug);
    it.lr_info = augment_info(it.lr_info, channels, *aug);
    it.hr_info = augment_info(it.hr_info, channels, *aug);
  }
  if (color) {
    it.lr_color = augment_color(it.lr_color, *color);
    it.hr_color = augment_color(it.hr_color, *color);
    it.lr_info = augment_info_color(it.lr_info, channels, *color);
    it.hr_info = augment_info_color(it.hr_info, channels, *color);
  }
  // A window's previous output ends at its border, so history_out is valid only where the motion
  // stays inside the window (in a whole frame that is the data set's validity already).
  if (std::find(channels.begin(), channels.end(), RenderChannel::HistoryOut) != channels.end()) {
    restrict_history_out_to_window(it.lr_info, channels);
    restrict_history_out_to_window(it.hr_info, channels);
  }
  return it;
}

Batch stack(std::vector<Item>& items, const std::vector<RenderChannel>& channels, DepthEncoding depth,
            std::vector<int> frames, int scale) {
  Batch b;
  b.depth_encoding = depth;
  std::vector<torch::Tensor> lc, li, hc, hi;
  for (auto& it : items) {
    lc.push_back(it.lr_color);
    li.push_back(it.lr_info);
    hc.push_back(it.hr_color);
    hi.push_back(it.hr_info);
  }
  b.lr_color = torch::stack(lc);
  b.hr_color = torch::stack(hc);
  b.lr_info = torch::stack(li);
  b.hr_info = torch::stack(hi);
  b.channels = channels;
  b.frames = std::move(frames);
  b.scale = scale;
  return b;
}

}  // namespace

struct PatchSampler::Prefetch {
  struct Slot {
    int64_t index = 0;
    std::unique_ptr<tbb::task_group> group;
    Batch batch;
  };
  std::deque<std::unique_ptr<Slot>> slots;
  ~Prefetch() {
    for (auto& s : slots) {
      s->group->cancel();
      try {
        s->group->wait();
      } catch (...) {
        // A cancelled batch's error no longer matters.
      }
    }
  }
};

PatchSampler::PatchSampler(Dataset data, PatchSamplerOptions options)
    : data_(std::move(data)), options_(std::move(options)), prefetch_(std::make_unique<Prefetch>()) {
  const auto& o = options_;
  if (o.patch_size < 1) throw Error("sampler", "patch_size " + config::out_of_range(o.patch_size, 1, config::kUnbounded));
  if (o.batch_size < 1) throw Error("sampler", "batch_size " + config::out_of_range(o.batch_size, 1, config::kUnbounded));
  if (o.prefetch < 0) throw Error("sampler", "prefetch " + config::out_of_range(o.prefetch, 0, config::kUnbounded));
  std::tie(lr_, hr_) = resolution_pair(data_, o.scale, o.lr_width);
  const Resolution& lr = data_.resolutions()[lr_];
  if (o.patch_size > lr.width || o.patch_size > lr.height)
    throw Error("sampler", "LR patch " + std::to_string(o.patch_size) + " is larger than the LR frames " + lr.name());
  require_channels(data_, o.channels, lr_, hr_);
  if (o.sequence_length < 1)
    throw Error("sampler", "sequence_length " + config::out_of_range(o.sequence_length, 1, config::kUnbounded));
  frames_ = data_.frames(o.split);
  if (frames_.empty()) throw Error(data_.info().root.string(), "the " + split_name(o.split) + " split has no frames");
  for (const auto& s : data_.scenes())
    if (s.frames < o.sequence_length &&
        std::any_of(frames_.begin(), frames_.end(), [&](int f) { return s.contains(f); }))
      throw Error(data_.info().root.string(), "scene '" + s.name + "' has " + std::to_string(s.frames) +
                                                  " frames, fewer than a training sequence's " +
                                                  std::to_string(o.sequence_length));
  // Weighted scenes: the split's frames per scene, and each scene's share of the draws. Without
  // weights a frame is drawn uniformly from the split, which is each scene in proportion to its
  // frames there (and the draw sequence of a single-scene data set).
  const auto& scenes = data_.scenes();
  if (std::any_of(scenes.begin(), scenes.end(), [](const SceneInfo& s) { return s.weight > 0; })) {
    double total = 0;
    for (const auto& s : scenes) {
      std::vector<int> mine;
      for (int f : frames_)
        if (s.contains(f)) mine.push_back(f);
      if (mine.empty()) continue;  // a scene with no frame in this split (too short to have one)
      total += s.weight;
      scene_frames_.push_back(std::move(mine));
      scene_cumulative_.push_back(total);
    }
    for (double& c : scene_cumulative_) c /= total;
    scene_cumulative_.back() = 1.0;
  }
}

PatchSampler::~PatchSampler() = default;

Batch PatchSampler::build(int64_t k) const { return make(k, /*parallel=*/true); }

Batch PatchSampler::make(int64_t k, bool parallel) const {
  const auto& o = options_;
  const Resolution lr = data_.resolutions()[lr_];
  // Draw every item's choices first from one stream: the batch depends only on (seed, k).
  struct Choice {
    int frame, x, y, aug;
    ColorAugmentation color;
  };
  std::vector<Choice> choices(o.batch_size);
  auto rng = make_rng("patch-sampler", o.seed * 0x9E3779B97F4A7C15ULL + static_cast<uint64_t>(k));
  for (auto& c : choices) {
    if (scene_frames_.empty()) {
      c.frame = frames_[rng() % frames_.size()];
    } else {
      const double u = uniform01(rng);
      const size_t s = std::upper_bound(scene_cumulative_.begin(), scene_cumulative_.end(), u) - scene_cumulative_.begin();
      const auto& mine = scene_frames_[std::min(s, scene_frames_.size() - 1)];
      c.frame = mine[rng() % mine.size()];
    }
    c.x = static_cast<int>(rng() % static_cast<uint64_t>(lr.width - o.patch_size + 1));
    c.y = static_cast<int>(rng() % static_cast<uint64_t>(lr.height - o.patch_size + 1));
    c.aug = o.augment ? static_cast<int>(rng() % 8) : 0;
  }
  // Colours from a stream of their own: with or without them, a batch has the same windows, so
  // colour augmentation is compared with its control on the same patches.
  if (o.color_augment) {
    auto colour_rng = make_rng("patch-colour", o.seed * 0x9E3779B97F4A7C15ULL + static_cast<uint64_t>(k));
    for (auto& c : choices) {
      const double u_permutation = uniform01(colour_rng);  // drawn first: argument order is unspecified
      c.color = ColorAugmentation::from_uniform(u_permutation, uniform01(colour_rng));
    }
  }
  // Sequences: the T consecutive frames of the drawn frame's scene that hold it, as near to ending
  // at it as the scene allows.
  const int steps = o.sequence_length;
  std::vector<int> frames(static_cast<size_t>(steps) * o.batch_size);
  for (int i = 0; i < o.batch_size; ++i) {
    const SceneInfo& scene = data_.scene_of(choices[i].frame);
    const int first = std::clamp(choices[i].frame - (steps - 1), scene.first_frame, scene.first_frame + scene.frames - steps);
    for (int t = 0; t < steps; ++t) frames[static_cast<size_t>(t) * o.batch_size + i] = first + t;
  }
  std::vector<Item> items(frames.size());
  const auto make_one = [&](int j) {
    const Choice& c = choices[j % o.batch_size];
    const int frame = frames[j];
    const auto l = data_.frame(frame, lr_), h = data_.frame(frame, hr_);
    const Augmentation aug = Augmentation::from_index(c.aug);
    const SceneInfo& scene = data_.scene_of(frame);  // depth is encoded with its scene's planes
    items[j] = make_item(*l, *h, c.x, c.y, o.patch_size, o.patch_size, o.scale, o.channels, o.depth_encoding,
                         scene.near_plane, scene.far_plane, o.augment ? &aug : nullptr,
                         o.color_augment ? &c.color : nullptr);
  };
  const int n = static_cast<int>(items.size());
  if (parallel) {
    tbb::parallel_for(0, n, make_one);
  } else {
    for (int j = 0; j < n; ++j) make_one(j);
  }
  return stack(items, o.channels, o.depth_encoding, frames, o.scale);
}

Batch PatchSampler::next() { return batch(next_); }

Batch PatchSampler::batch(int64_t k) {
  if (options_.prefetch == 0) {
    next_ = k + 1;
    return make(k, /*parallel=*/false);
  }
  auto& slots = prefetch_->slots;
  // A jump (e.g. a resumed run) drops what was prefetched for other batch numbers.
  while (!slots.empty() && slots.front()->index != k) {
    auto dropped = std::move(slots.front());
    slots.pop_front();
    dropped->group->cancel();
    try {
      dropped->group->wait();
    } catch (...) {
      // A dropped batch's error no longer matters.
    }
  }
  // Keep batches k .. k + prefetch in flight.
  while (static_cast<int>(slots.size()) <= options_.prefetch) {
    auto slot = std::make_unique<Prefetch::Slot>();
    slot->index = k + static_cast<int64_t>(slots.size());
    slot->group = std::make_unique<tbb::task_group>();
    Prefetch::Slot* raw = slot.get();
    raw->group->run([this, raw] { raw->batch = build(raw->index); });
    slots.push_back(std::move(slot));
  }
  std::unique_ptr<Prefetch::Slot> slot = std::move(slots.front());
  slots.pop_front();
  slot->group->wait();  // rethrows a loading error
  next_ = k + 1;
  return std::move(slot->batch);
}

Batch frame_batch(const Dataset& data, int frame, int scale, const std::vector<RenderChannel>& channels,
                  DepthEncoding depth, int lr_width) {
  const auto [lo, hi] = resolution_pair(data, scale, lr_width);
  require_channels(data, channels, lo, hi);
  const auto l = data.frame(frame, lo), h = data.frame(frame, hi);
  const SceneInfo& scene = data.scene_of(frame);
  std::vector<Item> items{make_item(*l, *h, 0, 0, l->width, l->height, scale, channels, depth, scene.near_plane,
                                    scene.far_plane, nullptr)};
  Batch b = stack(items, channels, depth, {frame}, scale);
  if (l->bsp_border) b.lr_bsp_border.push_back(l->bsp_border);
  b.lr_jitter.push_back(l->jitter);
  return b;
}

FrameIterator::FrameIterator(Dataset data, FrameIteratorOptions options) : data_(std::move(data)), options_(std::move(options)) {
  std::tie(lr_, hr_) = resolution_pair(data_, options_.scale, options_.lr_width);
  require_channels(data_, options_.channels, lr_, hr_);
  frames_ = data_.frames(options_.split);
}

Batch FrameIterator::get(int k) const {
  return frame_batch(data_, frames_.at(k), options_.scale, options_.channels, options_.depth_encoding,
                     data_.resolutions()[lr_].width);
}

}  // namespace cgsr
