#include "render_data/dataset.h"

#include <malloc.h>
#include <unistd.h>

#include <algorithm>
#include <fstream>
#include <limits>
#include <list>
#include <mutex>
#include <unordered_map>

#include "core/config.h"
#include "core/error.h"
#include "core/text.h"
#include "render_data/bsp_channel.h"
#include "render_data/derive_channels.h"
#include "render_data/frame_files.h"
#include "render_data/history_channel.h"
#include "render_data/render_job.h"

namespace cgsr {
namespace fs = std::filesystem;

config::Schema<DatasetOpenOptions> dataset_open_schema() {
  config::Schema<DatasetOpenOptions> s;
  s.field("layout", &DatasetOpenOptions::layout, "dataset layout (auto, cgsr, cgsr-release, glob)");
  auto names_ok = [](const std::vector<std::string>& v) {
    const auto valid = channel_names(all_render_channels());
    for (const auto& n : v)
      if (std::find(valid.begin(), valid.end(), n) == valid.end()) return false;
    return true;
  };
  s.field("channels", &DatasetOpenOptions::channels, "rendering channels to load (empty: all)")
      .check(names_ok, "unknown channel; valid: " + join(channel_names(all_render_channels())));
  s.field("derive", &DatasetOpenOptions::derive, "channels to derive from depth when missing (edge, normal, normal_angle)")
      .check(names_ok, "unknown channel; valid: " + join(channel_names(all_render_channels())));
  s.field("clean_grid_lines", &DatasetOpenOptions::clean_grid_lines, "remove tile-grid lines from CGSR-release edges");
  s.field("near", &DatasetOpenOptions::near_plane, "near plane for layouts without one (0: default)").at_least(0);
  s.field("far", &DatasetOpenOptions::far_plane, "far plane for layouts without one (0: default)").at_least(0);
  s.field("vfov", &DatasetOpenOptions::vfov, "vertical field of view for derived normals (0: default)").range(0, 179);
  s.field("cache_gb", &DatasetOpenOptions::cache_gb, "frame cache budget, GiB").range(0, 1024);
  s.field("cache_reserve_gb", &DatasetOpenOptions::cache_reserve_gb,
          "machine memory the frame cache leaves available, GiB")
      .range(0, 1024);
  s.section("edges", &DatasetOpenOptions::edges, edge_settings_schema(), "thresholds for derived edges");
  return s;
}

namespace {

constexpr double kGiB = 1024.0 * 1024.0 * 1024.0;

double physical_memory_gb() {
  const long pages = ::sysconf(_SC_PHYS_PAGES), page = ::sysconf(_SC_PAGESIZE);
  return pages > 0 && page > 0 ? static_cast<double>(pages) * static_cast<double>(page) / kGiB : 0;
}

// MemAvailable of /proc/meminfo in bytes; the largest size_t when the machine does not say.
size_t available_memory_bytes() {
  std::ifstream meminfo("/proc/meminfo");
  std::string key;
  size_t kib = 0;
  while (meminfo >> key >> kib) {
    if (key == "MemAvailable:") return kib * 1024;
    meminfo.ignore(std::numeric_limits<std::streamsize>::max(), '\n');
  }
  return std::numeric_limits<size_t>::max();
}

}  // namespace

double default_frame_cache_gb() {
  const double gb = physical_memory_gb();
  return gb > 0 ? 0.5 * gb : 3.0;  // unknown: what fits on a small machine
}

double default_frame_cache_reserve_gb() {
  const double gb = physical_memory_gb();
  return gb > 0 ? gb / 8 : 1.0;
}

int lr_multiple(const DatasetInfo& info, size_t resolution) {
  if (info.resolutions.empty()) return 0;
  const Resolution& lo = info.resolutions.front(), &r = info.resolutions.at(resolution);
  const bool whole = r.width % lo.width == 0 && r.height % lo.height == 0 && r.width / lo.width == r.height / lo.height;
  return whole ? r.width / lo.width : 0;
}

bool bsp_available_at(const DatasetInfo& info, size_t resolution) {
  return info.bsp_border && lr_multiple(info, resolution) > 0;
}

std::string history_missing_at(const DatasetInfo& info, size_t resolution) {
  const Resolution& r = info.resolutions.at(resolution);
  if (lr_multiple(info, resolution) == 0)
    return r.name() + " is not an integer multiple of the jittered resolution " + info.resolutions.front().name();
  const auto& at = info.stored_at.empty() ? info.stored : info.stored_at[resolution];
  const auto& lr = info.stored_at.empty() ? info.stored : info.stored_at.front();
  auto has = [](const std::vector<RenderChannel>& v, RenderChannel c) { return std::find(v.begin(), v.end(), c) != v.end(); };
  // Motion and depth at r, or at LR to upsample (resolve_history); and LR depth for the samples.
  std::vector<std::string> missing;
  const std::string or_lr = resolution == 0 ? "" : " or " + info.resolutions.front().name();
  if (!has(at, RenderChannel::Motion) && !has(lr, RenderChannel::Motion)) missing.push_back("motion at " + r.name() + or_lr);
  if (!has(lr, RenderChannel::Depth)) missing.push_back("depth at " + info.resolutions.front().name());
  return missing.empty() ? std::string() : "the data set has no " + join(missing, " and no ");
}

bool history_available_at(const DatasetInfo& info, size_t resolution) {
  return !info.resolutions.empty() && history_missing_at(info, resolution).empty();
}

bool has_previous_frame(const DatasetInfo& info, int frame) {
  for (const auto& s : info.scenes)
    if (s.contains(frame)) return frame > s.first_frame;
  throw Error(info.root.string(), "frame " + config::out_of_range(frame, 0, info.frames - 1));
}

void resolve_channels(DatasetInfo& info, const DatasetOpenOptions& options) {
  const auto derive = parse_channels(options.derive);
  auto stored = [&](RenderChannel c) { return std::find(info.stored.begin(), info.stored.end(), c) != info.stored.end(); };
  std::vector<RenderChannel> requested;
  if (options.channels.empty()) {
    requested = info.stored;
    for (auto c : derive)
      if (!stored(c)) requested.push_back(c);
    // Every channel the data can give: bsp too when it has the BSP files.
    if (info.bsp_border && std::find(requested.begin(), requested.end(), RenderChannel::Bsp) == requested.end())
      requested.push_back(RenderChannel::Bsp);
    std::sort(requested.begin(), requested.end());
  } else {
    requested = parse_channels(options.channels);
  }
  info.derived.clear();
  for (auto c : requested) {
    if (stored(c)) continue;
    if (c == RenderChannel::Bsp) {
      if (!info.bsp_border)
        throw Error(info.root.string(),
                    "the dataset has no sub-pixel BSP border files, which the 'bsp' channel is made from: render it with "
                    "bsp_border: {depth: 2} in each scene's config (cgsr render; docs/bsp_border.md)");
      info.derived.push_back(c);
      continue;
    }
    if (c == RenderChannel::History || c == RenderChannel::HistoryOut) {
      // Made from motion and depth (history_channel.h): an error when no resolution can have it.
      std::vector<std::string> why;
      bool anywhere = false;
      for (size_t r = 0; r < info.resolutions.size(); ++r) {
        const std::string missing = history_missing_at(info, r);
        anywhere = anywhere || missing.empty();
        if (!missing.empty()) why.push_back(info.resolutions[r].name() + ": " + missing);
      }
      if (!anywhere)
        throw Error(info.root.string(), "cannot derive the '" + channel_name(c) + "' channel at any resolution (" + join(why, "; ") +
                                            "): it is made from the motion and depth of the previous frames");
      info.derived.push_back(c);
      continue;
    }
    if (c == RenderChannel::Jitter) {  // from each LR frame's jitter (0 when not jittered): always possible
      info.derived.push_back(c);
      continue;
    }
    const bool asked = std::find(derive.begin(), derive.end(), c) != derive.end();
    if (!asked || !derivable(c))
      throw Error(info.root.string(), "the dataset has no '" + channel_name(c) + "' channel (stored: " +
                                          (info.stored.empty() ? std::string("none") : join(channel_names(info.stored))) + ")" +
                                          (derivable(c) ? "; list it under derive to compute it from depth" : ""));
    info.derived.push_back(c);
  }
  if (!depth_derived(info).empty() && !stored(RenderChannel::Depth))
    throw Error(info.root.string(), "cannot derive " + join(channel_names(depth_derived(info))) + ": the dataset has no depth");
  info.channels = requested;
  if (info.stored_at.empty()) info.stored_at.assign(info.resolutions.size(), info.stored);
  info.channels_at.clear();
  for (size_t r = 0; r < info.stored_at.size(); ++r) {
    const auto& here = info.stored_at[r];
    auto has = [&](RenderChannel c) { return std::find(here.begin(), here.end(), c) != here.end(); };
    std::vector<RenderChannel> out;
    for (auto c : requested) {
      const bool derived = std::find(info.derived.begin(), info.derived.end(), c) != info.derived.end();
      const bool available = c == RenderChannel::Bsp       ? bsp_available_at(info, r)
                             : c == RenderChannel::History || c == RenderChannel::HistoryOut ? history_available_at(info, r)
                             : c == RenderChannel::Jitter  ? true
                                                           : has(c) || (derived && has(RenderChannel::Depth));
      if (available) out.push_back(c);
    }
    info.channels_at.push_back(out);
  }
}

std::vector<RenderChannel> depth_derived(const DatasetInfo& info) {
  std::vector<RenderChannel> out;
  for (auto c : info.derived)
    if (c != RenderChannel::Bsp && c != RenderChannel::History && c != RenderChannel::Jitter &&
        c != RenderChannel::HistoryOut)
      out.push_back(c);
  return out;
}

const std::vector<RenderChannel>& channels_at(const DatasetInfo& info, size_t resolution) {
  return info.channels_at.at(resolution);
}

// ---- our own format -----------------------------------------------------------------------------

namespace {
// A single-scene data set, or a multi-scene one whose frames are read from its scenes' data sets.
class CgsrDataset : public FrameSource {
 public:
  CgsrDataset(const fs::path& root, const DatasetOpenOptions&) : manifest_(read_manifest(root)) {
    if (!manifest_.complete)
      throw Error((root / "manifest.yaml").string(),
                  "the render is incomplete (complete: false); rerun the same `cgsr render` command to finish it");
    parts_ = scene_parts(root, manifest_);
    const DatasetManifest& first = parts_.front().manifest;
    info_.name = manifest_.name;
    info_.layout = "cgsr";
    info_.root = root;
    info_.frames = manifest_.frames;
    info_.resolutions = manifest_.resolutions;
    info_.near_plane = first.near_plane;
    info_.far_plane = first.far_plane;
    info_.vfov = first.vfov;
    info_.stored = {RenderChannel::Depth, RenderChannel::Normal, RenderChannel::NormalAngle, RenderChannel::Edge,
                    RenderChannel::Motion};  // every file channel; bsp is derived (bsp_channel.h)
    info_.split = manifest_.split;
    for (const auto& p : parts_)
      info_.scenes.push_back({p.name, p.first_frame, p.manifest.frames, p.manifest.near_plane, p.manifest.far_plane,
                              p.manifest.vfov, p.weight, p.manifest.hr_samples,
                              hr_target_description(p.manifest.hr_samples, p.manifest.hr_filter)});
    info_.bsp_border = std::all_of(parts_.begin(), parts_.end(),
                                   [](const ScenePart& p) { return p.manifest.bsp_border_depth > 0; });
    // One target for the set, or each scene's named (a merge of aliased and supersampled scenes).
    const bool one_target = std::all_of(info_.scenes.begin(), info_.scenes.end(),
                                        [&](const SceneInfo& s) { return s.target == info_.scenes.front().target; });
    info_.hr_samples = one_target ? info_.scenes.front().hr_samples : 0;
    info_.target = one_target ? info_.scenes.front().target : "mixed:";
    if (!one_target)
      for (const auto& s : info_.scenes) info_.target += (&s == &info_.scenes.front() ? " " : ", ") + s.name + " " + s.target;
  }
  const DatasetInfo& info() const override { return info_; }
  Frame load(int frame, size_t res, const std::vector<RenderChannel>& channels) const override {
    for (const auto& p : parts_)
      if (frame >= p.first_frame && frame < p.first_frame + p.manifest.frames)
        return read_dataset_frame(p.root, p.manifest, frame - p.first_frame, res, channels);
    throw Error(info_.root.string(), "frame " + std::to_string(frame) + " out of range", ErrorKind::Internal);
  }

 private:
  DatasetManifest manifest_;
  std::vector<ScenePart> parts_;
  DatasetInfo info_;
};

const SceneInfo& find_scene(const DatasetInfo& info, int frame) {
  for (const auto& s : info.scenes)
    if (s.contains(frame)) return s;
  throw Error(info.root.string(), "frame " + config::out_of_range(frame, 0, info.frames - 1));
}
}  // namespace

std::unique_ptr<FrameSource> open_cgsr_dataset(const fs::path& root, const DatasetOpenOptions& options) {
  return std::make_unique<CgsrDataset>(root, options);
}

// ---- registry -------------------------------------------------------------------------------------

Registry<DatasetLoader>& dataset_loaders() {
  static Registry<DatasetLoader> registry = [] {
    Registry<DatasetLoader> r("dataset layout");
    r.add("cgsr", {[](const fs::path& p) { return fs::is_directory(p) && has_manifest(p); }, open_cgsr_dataset},
          "cgsr's own format (manifest.yaml), written by `cgsr render`");
    r.add("cgsr-release", {looks_like_cgsr_release, open_cgsr_release},
          "the CGSR data release: <trace>/<width>/frame###.sim.ppm + feature###.bmp");
    r.add("glob", {looks_like_glob_layout, open_glob_layout},
          "per-channel glob patterns in a YAML file (layout: glob)");
    return r;
  }();
  return registry;
}

// ---- Dataset ------------------------------------------------------------------------------------

struct Dataset::Impl {
  std::unique_ptr<FrameSource> source;
  DatasetInfo info;
  DatasetOpenOptions options;
  std::vector<RenderChannel> load_channels;  // what the source reads (adds depth for derivation)
  size_t budget = 0;

  mutable std::mutex mutex;
  using Key = int64_t;
  mutable std::list<Key> lru;  // most recent first
  struct Entry {
    std::shared_ptr<const Frame> frame;
    std::list<Key>::iterator position;
  };
  mutable std::unordered_map<Key, Entry> cache;
  mutable size_t bytes = 0;
  size_t reserve = 0;  // machine memory the cache leaves available

  // glibc keeps freed frames in its heap for reuse: without the trim a run's next stage (another
  // data set, other channels) would add its cache to this one's in the process's memory.
  ~Impl() {
    if (bytes == 0) return;
    cache.clear();
    lru.clear();
    ::malloc_trim(0);
  }

  Frame load(int index, size_t res) const {
    if (index < 0 || index >= info.frames)
      throw Error(info.root.string(), "frame " + config::out_of_range(index, 0, info.frames - 1));
    if (res >= info.resolutions.size()) throw Error(info.root.string(), "resolution index out of range");
    std::vector<RenderChannel> here;  // what this resolution's files can give
    for (auto c : load_channels)
      if (std::find(info.stored_at[res].begin(), info.stored_at[res].end(), c) != info.stored_at[res].end())
        here.push_back(c);
    Frame f = source->load(index, res, here);
    const auto from_depth = depth_derived(info);
    if (!from_depth.empty() && f.depth.defined()) {
      try {
        derive_channels(f, from_depth, find_scene(info, index).vfov, options.edges);
      } catch (const Error& e) {
        throw Error(info.root.string(), "frame " + std::to_string(index) + ": " + e.message(), e.kind());
      }
      if (std::find(info.channels.begin(), info.channels.end(), RenderChannel::Depth) == info.channels.end())
        f.depth = torch::Tensor();
    }
    if (std::find(info.channels.begin(), info.channels.end(), RenderChannel::Bsp) != info.channels.end() &&
        bsp_available_at(info, res))
      f.bsp = resolve_bsp(index, res, f);
    if (std::find(info.channels.begin(), info.channels.end(), RenderChannel::History) != info.channels.end() &&
        history_available_at(info, res))
      f.history = resolve_history(index, res, f);
    if (std::find(info.channels.begin(), info.channels.end(), RenderChannel::HistoryOut) != info.channels.end() &&
        history_available_at(info, res))
      f.history_out = resolve_history_out(index, res, f);
    if (std::find(info.channels.begin(), info.channels.end(), RenderChannel::Jitter) != info.channels.end()) {
      const auto jitter = res == 0 ? f.jitter : source->load(index, 0, {}).jitter;
      f.lr_jitter = torch::tensor({static_cast<float>(jitter[0]), static_cast<float>(jitter[1])}).view({2, 1, 1});
    }
    return f;
  }

  // Frame `frame`'s depth and motion (or only the `wanted` of them) at resolution `res`: as stored
  // there, or, for a capture that stores them at the render size only, the LR ones upsampled as an
  // engine passes them. The LR frame read for that (with its depth) is left in `lr`, so the samples
  // need not read it again.
  Frame depth_and_motion(int frame, size_t res, Frame& lr,
                         const std::vector<RenderChannel>& wanted = {RenderChannel::Depth, RenderChannel::Motion}) const {
    const auto& here = info.stored_at[res];
    std::vector<RenderChannel> stored_here, from_lr;
    for (auto c : wanted) (std::find(here.begin(), here.end(), c) != here.end() ? stored_here : from_lr).push_back(c);
    Frame out = stored_here.empty() ? Frame() : source->load(frame, res, stored_here);
    if (from_lr.empty()) return out;
    lr = source->load(frame, 0, wanted);
    const int scale = lr_multiple(info, res);
    for (auto c : from_lr) {
      const bool depth = c == RenderChannel::Depth;
      (depth ? out.depth : out.motion) = upsample_channel(depth ? lr.depth : lr.motion, c, scale);
    }
    return out;
  }

  // The history channel of frame `index` at resolution `res`: the frame and up to kHistoryFrames
  // predecessors of its scene, their stored channels read from the source (never through the cache:
  // a cached frame would derive its own history, K frames deeper each time).
  torch::Tensor resolve_history(int index, size_t res, const Frame& f) const {
    const int scale = lr_multiple(info, res);
    std::vector<HistoryFrame> chain;
    for (int k = 0, frame = index; k <= kHistoryFrames; ++k, --frame) {
      if (k > 0 && !has_previous_frame(info, frame + 1)) break;  // a scene cut: the history starts here
      HistoryFrame h;
      // Motion and depth at r link the chain; the oldest frame only gives its LR samples.
      const bool link = k < kHistoryFrames;
      Frame at_r, lr;
      if (k == 0 && f.depth.defined() && f.motion.defined())
        at_r = f;
      else if (link)
        at_r = depth_and_motion(frame, res, lr);
      h.depth = at_r.depth;
      h.motion = at_r.motion;
      if (!lr.color.defined()) lr = res == 0 && at_r.color.defined() ? at_r : source->load(frame, 0, {RenderChannel::Depth});
      h.lr_color = lr.color;
      h.lr_depth = lr.depth;
      h.jitter = lr.jitter;
      chain.push_back(std::move(h));
    }
    return history_channel(chain, scale, info.root.string() + ": frame " + std::to_string(index) + " at " +
                                             info.resolutions[res].name());
  }

  // The history_out channel's data part of frame `index` at resolution `res`: its reprojection into
  // the previous frame of its scene (none at the scene's first frame), read like resolve_history's.
  torch::Tensor resolve_history_out(int index, size_t res, const Frame& f) const {
    Frame lr;
    const Frame here = f.depth.defined() && f.motion.defined() ? f : depth_and_motion(index, res, lr);
    torch::Tensor previous_depth;
    Frame previous_lr;
    if (has_previous_frame(info, index))
      previous_depth = depth_and_motion(index - 1, res, previous_lr, {RenderChannel::Depth}).depth;
    return history_out_channel(here.depth, here.motion, previous_depth,
                               info.root.string() + ": frame " + std::to_string(index) + " at " + info.resolutions[res].name());
  }

  // The bsp channel of frame `index` at resolution `res`: the LR frame's BSP border image resolved
  // over its colour (`f` itself at the BSP resolution; else the LR colour and tree files are read).
  torch::Tensor resolve_bsp(int index, size_t res, const Frame& f) const {
    const Frame lr = res == 0 ? Frame() : source->load(index, 0, {});
    const Frame& base = res == 0 ? f : lr;
    const std::string what = info.root.string() + ": frame " + std::to_string(index);
    if (!base.bsp_border) throw Error(what, "has no sub-pixel BSP border image for the 'bsp' channel", ErrorKind::Internal);
    return bsp_channel(base.color_float(), *base.bsp_border, info.resolutions[res].width / info.resolutions[0].width, what);
  }
};

Dataset Dataset::open(const fs::path& path, const DatasetOpenOptions& options) {
  if (!fs::exists(path)) throw Error(path.string(), "no such dataset directory or file");
  auto& loaders = dataset_loaders();
  std::string layout = options.layout;
  if (layout == "auto") {
    layout.clear();
    for (const auto& name : loaders.names())
      if (loaders.get(name).detect(path)) {
        layout = name;
        break;
      }
    if (layout.empty())
      throw Error(path.string(), "not a dataset in any known layout (" + join(loaders.names()) +
                                     "): expected manifest.yaml, a YAML file with layout: glob, or "
                                     "<width>/frame###.sim.ppm folders");
  }
  Dataset d;
  d.impl_ = std::make_shared<Impl>();
  Impl& impl = *d.impl_;
  impl.source = loaders.get(layout).open(path, options);
  impl.info = impl.source->info();
  if (impl.info.scenes.empty())
    impl.info.scenes.push_back({impl.info.name, 0, impl.info.frames, impl.info.near_plane, impl.info.far_plane,
                                impl.info.vfov, 0, impl.info.hr_samples, impl.info.target});
  impl.options = options;
  resolve_channels(impl.info, options);
  for (auto c : impl.info.channels)
    if (std::find(impl.info.derived.begin(), impl.info.derived.end(), c) == impl.info.derived.end())
      impl.load_channels.push_back(c);
  if (!depth_derived(impl.info).empty() &&
      std::find(impl.load_channels.begin(), impl.load_channels.end(), RenderChannel::Depth) == impl.load_channels.end())
    impl.load_channels.push_back(RenderChannel::Depth);
  std::sort(impl.load_channels.begin(), impl.load_channels.end());
  impl.budget = static_cast<size_t>(options.cache_gb * kGiB);
  impl.reserve = static_cast<size_t>(options.cache_reserve_gb * kGiB);
  return d;
}

const DatasetInfo& Dataset::info() const { return view_ ? *view_ : impl_->info; }
int Dataset::frame_count() const { return impl_->info.frames; }
const std::vector<Resolution>& Dataset::resolutions() const { return impl_->info.resolutions; }

size_t Dataset::resolution_index(const Resolution& r) const {
  const auto& rs = impl_->info.resolutions;
  for (size_t i = 0; i < rs.size(); ++i)
    if (rs[i] == r) return i;
  std::vector<std::string> names;
  for (const auto& x : rs) names.push_back(x.name());
  throw Error(impl_->info.root.string(), "has no resolution " + r.name() + " (has: " + join(names) + ")");
}

std::vector<int> Dataset::frames(Split split) const {
  if (split != Split::All) return info().split.of(split);
  std::vector<int> all;
  for (const auto& s : info().scenes)
    for (int i = 0; i < s.frames; ++i) all.push_back(s.first_frame + i);
  return all;
}

const std::vector<SceneInfo>& Dataset::scenes() const { return info().scenes; }
const SceneInfo& Dataset::scene_of(int frame) const { return find_scene(impl_->info, frame); }
bool Dataset::has_previous(int frame) const { return has_previous_frame(impl_->info, frame); }

Dataset Dataset::scene(const std::string& name) const {
  std::vector<std::string> names;
  for (const auto& s : info().scenes) {
    if (s.name != name) {
      names.push_back(s.name);
      continue;
    }
    auto view = std::make_shared<DatasetInfo>(info());
    if (view->scenes.size() > 1) view->name += "/" + name;
    view->scenes = {s};
    view->hr_samples = s.hr_samples;  // a scene of a mixed set measures against its own target
    view->target = s.target;
    for (Split split : {Split::Train, Split::Val, Split::Test}) {
      auto& list = const_cast<std::vector<int>&>(view->split.of(split));
      list.erase(std::remove_if(list.begin(), list.end(), [&](int f) { return !s.contains(f); }), list.end());
    }
    Dataset d = *this;
    d.view_ = std::move(view);
    return d;
  }
  throw Error(info().root.string(), "has no scene '" + name + "'" + did_you_mean(name, names) + " (scenes: " + join(names) + ")");
}

Dataset open_for_channels(const fs::path& path, const std::vector<RenderChannel>& channels) {
  const Dataset all = Dataset::open(path);
  const auto& available = all.info().channels;
  std::vector<RenderChannel> needed;
  const auto need = [&](RenderChannel c) {
    if (std::find(needed.begin(), needed.end(), c) == needed.end() &&
        std::find(available.begin(), available.end(), c) != available.end())
      needed.push_back(c);
  };
  for (auto c : channels) need(c);
  // Derived only when asked for (history, jitter), or kept when the data cannot give it, so that
  // opening says what is missing and how to render it.
  for (auto c : {RenderChannel::Bsp, RenderChannel::History, RenderChannel::Jitter, RenderChannel::HistoryOut})
    if (std::find(channels.begin(), channels.end(), c) != channels.end() &&
        std::find(needed.begin(), needed.end(), c) == needed.end())
      needed.push_back(c);
  need(RenderChannel::Edge);
  std::sort(needed.begin(), needed.end());
  DatasetOpenOptions open;
  open.channels = channel_names(needed);
  if (open.channels.empty()) return all;  // no edge map either: every channel it has
  return Dataset::open(path, open);
}

Dataset open_with_asked_channels(const fs::path& path, const std::vector<RenderChannel>& channels) {
  const Dataset all = Dataset::open(path);
  auto wanted = all.info().channels;
  const auto has = [](const std::vector<RenderChannel>& v, RenderChannel c) { return std::find(v.begin(), v.end(), c) != v.end(); };
  bool added = false;
  for (auto c : {RenderChannel::History, RenderChannel::Jitter, RenderChannel::HistoryOut})
    if (has(channels, c) && !has(wanted, c)) {
      wanted.push_back(c);
      added = true;
    }
  if (!added) return all;
  std::sort(wanted.begin(), wanted.end());
  DatasetOpenOptions open;
  open.channels = channel_names(wanted);
  return Dataset::open(path, open);
}

std::vector<int> spread_frames(const std::vector<int>& frames, int count) {
  if (count <= 0 || static_cast<size_t>(count) >= frames.size()) return frames;
  std::vector<int> out;
  for (int i = 0; i < count; ++i) out.push_back(frames[i * frames.size() / count]);
  return out;
}

Frame Dataset::load(int index, size_t resolution) const { return impl_->load(index, resolution); }

std::shared_ptr<const Frame> Dataset::frame(int index, size_t resolution) const {
  Impl& impl = *impl_;
  const Impl::Key key = static_cast<int64_t>(index) * 64 + static_cast<int64_t>(resolution);
  {
    std::lock_guard<std::mutex> lock(impl.mutex);
    const auto it = impl.cache.find(key);
    if (it != impl.cache.end()) {
      impl.lru.splice(impl.lru.begin(), impl.lru, it->second.position);
      return it->second.frame;
    }
  }
  // Decode outside the lock; a concurrent load of the same frame keeps the first result.
  auto frame = std::make_shared<const Frame>(impl.load(index, resolution));
  std::lock_guard<std::mutex> lock(impl.mutex);
  const auto it = impl.cache.find(key);
  if (it != impl.cache.end()) return it->second.frame;
  const size_t size = frame->bytes();
  if (size > impl.budget) return frame;  // larger than the whole cache: not kept
  // Growing (not replacing frames) only while the machine keeps its reserve.
  if (impl.bytes + size <= impl.budget && available_memory_bytes() < impl.reserve + size) return frame;
  while (impl.bytes + size > impl.budget && !impl.lru.empty()) {
    const Impl::Key victim = impl.lru.back();
    impl.lru.pop_back();
    impl.bytes -= impl.cache.at(victim).frame->bytes();
    impl.cache.erase(victim);
  }
  impl.lru.push_front(key);
  impl.cache.emplace(key, Impl::Entry{frame, impl.lru.begin()});
  impl.bytes += size;
  return frame;
}

size_t Dataset::cached_bytes() const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  return impl_->bytes;
}

}  // namespace cgsr
