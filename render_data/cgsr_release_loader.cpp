// The CGSR data release layout: <trace>/<width>/frame###.sim.ppm (colour) and feature###.bmp
// (R: object edge mask 0/255, G: depth normalized to [0,1], B: normal angle 0..90 deg -> 0..1).
// UI regions have depth 0 and normal angle 0. The release has no near/far planes and no
// normals: depth is made linear with the given (or default) planes, so normalize_depth with the
// same planes returns the stored values; normals can be derived from that depth.
#include <torch/torch.h>

#include <algorithm>
#include <map>
#include <regex>

#include "core/error.h"
#include "core/image_header.h"
#include "core/image_io.h"
#include "render_data/dataset.h"
#include "render_data/frame_files.h"
#include "render_data/grid_lines.h"

namespace cgsr {
namespace fs = std::filesystem;

namespace {

constexpr double kDefaultNear = 1.0, kDefaultFar = 1000.0;
// Doom 3 / Quake 4 render with a 90 degree horizontal field of view: 73.74 degrees vertically at 4:3.
constexpr double kDefaultVfov = 73.7398;

// Frame numbers of "frame<digits>.sim.ppm" files in `dir`, with the digits as written.
std::map<int, std::string> frame_numbers(const fs::path& dir) {
  static const std::regex pattern(R"(frame(\d+)\.sim\.ppm)");
  std::map<int, std::string> out;
  for (const auto& entry : fs::directory_iterator(dir)) {
    std::smatch m;
    const std::string name = entry.path().filename().string();
    if (std::regex_match(name, m, pattern)) out[std::stoi(m[1].str())] = m[1].str();
  }
  return out;
}

std::vector<std::pair<int, fs::path>> width_dirs(const fs::path& root) {
  std::vector<std::pair<int, fs::path>> out;
  if (!fs::is_directory(root)) return out;
  static const std::regex digits(R"(\d+)");
  for (const auto& entry : fs::directory_iterator(root))
    if (entry.is_directory() && std::regex_match(entry.path().filename().string(), digits))
      out.push_back({std::stoi(entry.path().filename().string()), entry.path()});
  std::sort(out.begin(), out.end());
  return out;
}

class CgsrRelease : public FrameSource {
 public:
  CgsrRelease(const fs::path& root, const DatasetOpenOptions& options) : root_(root), clean_(options.clean_grid_lines) {
    const auto dirs = width_dirs(root);
    if (dirs.empty()) throw Error(root.string(), "no <width> folders with frame###.sim.ppm files");
    const auto numbers = frame_numbers(dirs.front().second);
    if (numbers.empty()) throw Error(dirs.front().second.string(), "no frame###.sim.ppm files");
    for (const auto& [n, text] : numbers) frames_.push_back(text);
    for (const auto& [width, dir] : dirs) {
      // Every width holds every frame; the size comes from the first colour image.
      for (const auto& text : frames_)
        for (const auto& name : {"frame" + text + ".sim.ppm", "feature" + text + ".bmp"})
          if (!fs::exists(dir / name))
            throw Error((dir / name).string(), "missing (frame " + text + " exists at width " +
                                                   std::to_string(dirs.front().first) + ")");
      // The size is read from the header: the folder gives the width, the height is bounded.
      const fs::path first = dir / ("frame" + frames_.front() + ".sim.ppm");
      const ImageHeader header = read_image_header(first);
      if (header.width != width)
        throw Error(first.string(),
                    "is " + std::to_string(header.width) + " pixels wide, but its folder says " + std::to_string(width));
      check_image_limits(header, first.string());
      Resolution r{static_cast<int>(header.width), static_cast<int>(header.height)};
      dirs_.push_back(dir);
      info_.resolutions.push_back(r);
    }
    const Resolution& lo = info_.resolutions.front();
    for (const auto& r : info_.resolutions)
      if (r.width % lo.width != 0 || r.height % lo.height != 0 || r.width / lo.width != r.height / lo.height)
        throw Error(root.string(), "resolution " + r.name() + " is not an integer scale of " + lo.name());
    info_.name = root.filename().string();
    info_.layout = "cgsr-release";
    info_.root = root;
    info_.frames = static_cast<int>(frames_.size());
    info_.near_plane = options.near_plane > 0 ? options.near_plane : kDefaultNear;
    info_.far_plane = options.far_plane > 0 ? options.far_plane : kDefaultFar;
    if (!(info_.far_plane > info_.near_plane)) throw Error(root.string(), "need near < far");
    info_.vfov = options.vfov > 0 ? options.vfov : kDefaultVfov;
    info_.stored = {RenderChannel::Depth, RenderChannel::NormalAngle, RenderChannel::Edge};
    info_.split = make_split(info_.frames);
    if (clean_) info_.notes.push_back("periodic tile-grid lines removed from the edge masks");
  }

  const DatasetInfo& info() const override { return info_; }

  Frame load(int frame, size_t res, const std::vector<RenderChannel>& channels) const override {
    const Resolution& r = info_.resolutions.at(res);
    const fs::path color_path = dirs_[res] / ("frame" + frames_.at(frame) + ".sim.ppm");
    const fs::path feature_path = dirs_[res] / ("feature" + frames_.at(frame) + ".bmp");
    Frame f;
    f.width = r.width;
    f.height = r.height;
    f.color = read_color_file(color_path, frame, r);
    if (channels.empty()) return f;
    torch::Tensor features;
    try {
      features = read_image(feature_path, {3, r.width, r.height});
    } catch (const Error& e) {
      throw Error(feature_path.string(), "frame " + std::to_string(frame) + ": " + e.message(), e.kind());
    }
    check_image_size(features, r, feature_path.string(), frame);
    for (auto c : channels) {
      if (c == RenderChannel::Edge) {
        auto edge = (features[0] > 0.5f).to(torch::kUInt8).unsqueeze(0);
        if (clean_) edge = remove_grid_lines(edge, detect_grid_lines(edge));
        f.edge = edge;
      } else if (c == RenderChannel::Depth) {
        f.depth = linearize_depth(features[1].unsqueeze(0), info_.near_plane, info_.far_plane);
      } else if (c == RenderChannel::NormalAngle) {
        f.normal_angle = features[2].unsqueeze(0).to(torch::kFloat16);
      }
    }
    return f;
  }

 private:
  fs::path root_;
  bool clean_;
  std::vector<std::string> frames_;  // frame numbers as written in the file names
  std::vector<fs::path> dirs_;       // per resolution
  DatasetInfo info_;
};

}  // namespace

bool looks_like_cgsr_release(const fs::path& root) {
  for (const auto& [width, dir] : width_dirs(root))
    if (!frame_numbers(dir).empty()) return true;
  return false;
}

std::unique_ptr<FrameSource> open_cgsr_release(const fs::path& root, const DatasetOpenOptions& options) {
  return std::make_unique<CgsrRelease>(root, options);
}

}  // namespace cgsr
