#include "render_data/glob_layout.h"

#include <torch/torch.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <fstream>
#include <iterator>
#include <sstream>

#include "core/error.h"
#include "core/image_io.h"
#include "core/text.h"
#include "render_data/dataset.h"
#include "render_data/frame_files.h"

namespace cgsr {
namespace fs = std::filesystem;

config::Schema<GlobLayoutOptions> glob_layout_schema() {
  config::Schema<GlobResolution> r;
  r.field("size", &GlobResolution::size, "WxH of this resolution").required();
  r.field("color", &GlobResolution::color, "colour frames (required)").required();
  r.field("depth", &GlobResolution::depth, "depth frames");
  r.field("normal", &GlobResolution::normal, "normal frames, (n + 1) / 2");
  r.field("normal_angle", &GlobResolution::normal_angle, "normal angle frames, grey");
  r.field("edge", &GlobResolution::edge, "edge masks, grey 0/1");
  r.field("motion", &GlobResolution::motion, "motion vectors (dx, dy) in pixels");
  config::Schema<GlobLayoutOptions> s;
  s.field("layout", &GlobLayoutOptions::layout, "must be glob").one_of({"glob"}).required();
  s.field("name", &GlobLayoutOptions::name, "dataset name");
  s.field("near", &GlobLayoutOptions::near_plane, "near plane of the depth").range(1e-9, 1e12);
  s.field("far", &GlobLayoutOptions::far_plane, "far plane of the depth").range(1e-9, 1e30);
  s.field("vfov", &GlobLayoutOptions::vfov, "vertical field of view, degrees").range(1, 179);
  s.field("color_alpha", &GlobLayoutOptions::color_alpha, "what the alpha of RGBA colour means");
  s.field("depth_encoding", &GlobLayoutOptions::depth_encoding, "how depth is stored");
  s.field("depth_scale", &GlobLayoutOptions::depth_scale, "linear depth: metres per stored unit").range(1e-12, 1e12);
  s.section("motion_format", &GlobLayoutOptions::motion_format, motion_format_schema(), "how motion images map to pixels");
  s.field("jitter", &GlobLayoutOptions::jitter, "text file of the LR frames' jitter offsets, one 'x y' line per frame");
  s.list("resolutions", &GlobLayoutOptions::resolutions, r, "one entry per resolution");
  s.validate([](const GlobLayoutOptions& o, const config::Cursor& at, const YAML::Node& node) {
    if (o.resolutions.empty()) at.child("resolutions").fail(node, "needs at least one resolution");
    if (!(o.far_plane > o.near_plane)) at.child("far").fail(node, "far must be larger than near");
    if (o.depth_scale != 1 && o.depth_encoding != CaptureDepth::Linear)
      at.child("depth_scale").fail(node["depth_scale"], "applies to depth_encoding: linear only");
  });
  return s;
}

bool natural_less(const std::string& a, const std::string& b) {
  size_t i = 0, j = 0;
  while (i < a.size() && j < b.size()) {
    if (std::isdigit(static_cast<unsigned char>(a[i])) && std::isdigit(static_cast<unsigned char>(b[j]))) {
      size_t ie = i, je = j;
      while (ie < a.size() && std::isdigit(static_cast<unsigned char>(a[ie]))) ++ie;
      while (je < b.size() && std::isdigit(static_cast<unsigned char>(b[je]))) ++je;
      // Compare by value: strip leading zeros, then length, then digits.
      size_t is = i, js = j;
      while (is + 1 < ie && a[is] == '0') ++is;
      while (js + 1 < je && b[js] == '0') ++js;
      if (ie - is != je - js) return ie - is < je - js;
      const int c = a.compare(is, ie - is, b, js, je - js);
      if (c != 0) return c < 0;
      i = ie;
      j = je;
    } else {
      if (a[i] != b[j]) return a[i] < b[j];
      ++i;
      ++j;
    }
  }
  return a.size() - i < b.size() - j;
}

namespace {
// The jitter file's offsets, one per frame; throws cgsr::Error naming the file and line.
std::vector<std::array<double, 2>> read_jitter_file(const fs::path& path, int frames) {
  std::ifstream in(path);
  if (!in) throw Error(path.string(), "cannot open the jitter file");
  std::vector<std::array<double, 2>> offsets;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    const auto first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    const std::string at = "line " + std::to_string(number) + ": ";
    if (static_cast<int>(offsets.size()) == frames)
      throw Error(path.string(), at + "more offsets than the capture's " + std::to_string(frames) + " frames");
    std::istringstream fields(line);
    std::array<double, 2> o{};
    std::string extra;
    if (!(fields >> o[0] >> o[1]) || (fields >> extra))
      throw Error(path.string(), at + "expected two numbers 'x y', got '" + line + "'");
    for (double v : o)
      if (!(v >= -0.5 && v < 0.5))
        throw Error(path.string(), at + "offset " + fixed(v, 4) + " is outside [-0.5, 0.5) pixels");
    offsets.push_back(o);
  }
  if (static_cast<int>(offsets.size()) != frames)
    throw Error(path.string(), "has " + std::to_string(offsets.size()) + " offsets for the capture's " +
                                   std::to_string(frames) + " frames (one 'x y' line per frame)");
  return offsets;
}

bool wildcard_match(const char* p, const char* s) {
  // Iterative matcher with backtracking on the last '*'.
  const char *star = nullptr, *resume = nullptr;
  while (*s) {
    if (*p == '?' || *p == *s) {
      ++p, ++s;
    } else if (*p == '*') {
      star = p++;
      resume = s;
    } else if (star) {
      p = star + 1;
      s = ++resume;
    } else {
      return false;
    }
  }
  while (*p == '*') ++p;
  return *p == 0;
}
}  // namespace

std::vector<fs::path> glob_files(const fs::path& base, const std::string& pattern) {
  const fs::path full = base / pattern;
  const fs::path dir = full.parent_path();
  const std::string name = full.filename().string();
  // Only the pattern's own folders are read as wildcards: the capture's folder may be named
  // anything, '*' included.
  if (fs::path(pattern).parent_path().string().find_first_of("*?") != std::string::npos)
    throw Error(pattern, "wildcards are only supported in the file name, not in folders");
  if (!fs::is_directory(dir)) throw Error(pattern, "no such folder " + dir.string());
  std::vector<fs::path> out;
  for (const auto& e : fs::directory_iterator(dir))
    if (e.is_regular_file() && wildcard_match(name.c_str(), e.path().filename().string().c_str())) out.push_back(e.path());
  std::sort(out.begin(), out.end(),
            [](const fs::path& a, const fs::path& b) { return natural_less(a.filename().string(), b.filename().string()); });
  return out;
}

namespace {

struct ResolutionFiles {
  Resolution size;
  std::vector<std::vector<fs::path>> files;  // per RenderChannel (empty: absent)
  std::vector<fs::path> color;
};

class GlobDataset : public FrameSource {
 public:
  GlobDataset(const fs::path& yaml, const DatasetOpenOptions& options) {
    const auto doc = config::Document::load_file(yaml);
    const auto o = config::parse_document(doc, glob_layout_schema());
    color_alpha_ = o.color_alpha;
    motion_format_ = o.motion_format;
    motion_format_.declared = static_cast<bool>(doc.root()["motion_format"]);
    const fs::path base = yaml.parent_path();
    info_.name = o.name.empty() ? yaml.stem().string() : o.name;
    info_.layout = "glob";
    info_.root = yaml;
    info_.near_plane = options.near_plane > 0 ? options.near_plane : o.near_plane;
    info_.far_plane = options.far_plane > 0 ? options.far_plane : o.far_plane;
    info_.vfov = options.vfov > 0 ? options.vfov : o.vfov;
    depth_format_.encoding = o.depth_encoding;
    depth_format_.near_plane = info_.near_plane;
    depth_format_.far_plane = info_.far_plane;
    depth_format_.scale = o.depth_scale;
    size_t count = 0;
    std::string count_from;
    std::vector<bool> present(all_render_channels().size(), false);
    std::vector<std::vector<RenderChannel>> stored_at;
    for (const auto& r : o.resolutions) {
      ResolutionFiles rf;
      rf.size = parse_resolution(r.size, yaml.string() + ": size");
      rf.files.resize(all_render_channels().size());
      auto collect = [&](const std::string& pattern, std::vector<fs::path>& out, const std::string& what) {
        if (pattern.empty()) return false;
        out = glob_files(base, pattern);
        if (out.empty()) throw Error(yaml.string(), r.size + " " + what + ": pattern '" + pattern + "' matches no file");
        if (count == 0) count = out.size(), count_from = r.size + " " + what;
        if (out.size() != count)
          throw Error(yaml.string(), r.size + " " + what + ": pattern '" + pattern + "' matches " + std::to_string(out.size()) +
                                         " files but " + count_from + " matches " + std::to_string(count));
        return true;
      };
      collect(r.color, rf.color, "color");
      // The stored channels, in the fixed order (bsp is made from a cgsr data set's BSP files only).
      const std::string* patterns[] = {&r.depth, &r.normal, &r.normal_angle, &r.edge, &r.motion};
      std::vector<RenderChannel> here;
      for (size_t c = 0; c < std::size(patterns); ++c)
        if (collect(*patterns[c], rf.files[c], channel_name(all_render_channels()[c]))) {
          present[c] = true;
          here.push_back(all_render_channels()[c]);
        }
      stored_at.push_back(here);
      info_.resolutions.push_back(rf.size);
      res_.push_back(std::move(rf));
    }
    std::vector<size_t> order(res_.size());
    for (size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return res_[a].size.width < res_[b].size.width; });
    std::vector<ResolutionFiles> sorted;
    info_.resolutions.clear();
    for (size_t i : order) {
      info_.resolutions.push_back(res_[i].size);
      info_.stored_at.push_back(stored_at[i]);
      sorted.push_back(std::move(res_[i]));
    }
    res_ = std::move(sorted);
    const Resolution& lo = info_.resolutions.front();
    for (const auto& r : info_.resolutions)
      if (r.width % lo.width != 0 || r.height % lo.height != 0 || r.width / lo.width != r.height / lo.height)
        throw Error(yaml.string(), "resolution " + r.name() + " is not an integer scale of " + lo.name());
    for (size_t c = 0; c < present.size(); ++c)
      if (present[c]) info_.stored.push_back(all_render_channels()[c]);
    info_.frames = static_cast<int>(count);
    info_.split = make_split(info_.frames);
    if (!o.jitter.empty()) jitter_ = read_jitter_file(base / o.jitter, info_.frames);
  }

  const DatasetInfo& info() const override { return info_; }

  Frame load(int frame, size_t res, const std::vector<RenderChannel>& channels) const override {
    const ResolutionFiles& rf = res_.at(res);
    const Resolution& r = rf.size;
    // Reads one file, checked for size and NaN/Inf, and decodes it; errors name file and frame.
    auto decode = [&](const fs::path& p, const char* what, auto&& decoder) {
      try {
        const ImageFile image = read_image_file(p, {0, r.width, r.height});
        check_image_size(image.pixels, r, p.string(), frame);
        check_finite(image.pixels, p.string(), frame, what);
        return decoder(image);
      } catch (const Error& e) {
        const std::string at = "frame " + std::to_string(frame) + ": ";
        if (e.context() == p.string() && e.message().rfind(at, 0) == 0) throw;  // already says both
        throw Error(p.string(), at + e.message(), e.kind());
      }
    };
    auto file = [&](RenderChannel c) -> const fs::path& { return rf.files[static_cast<size_t>(c)].at(frame); };
    auto first = [](int ch) {
      return [ch](const ImageFile& image) {
        if (image.pixels.size(0) < ch)
          throw Error("image", "has " + std::to_string(image.pixels.size(0)) + " channel(s), expected at least " +
                                   std::to_string(ch));
        return image.pixels.slice(0, 0, ch).contiguous();
      };
    };
    Frame f;
    f.width = r.width;
    f.height = r.height;
    if (res == 0 && !jitter_.empty()) f.jitter = jitter_.at(static_cast<size_t>(frame));
    f.color = decode(rf.color.at(frame), "color", [&](const ImageFile& image) { return decode_capture_color(image, color_alpha_); });
    const bool has_depth = std::find(channels.begin(), channels.end(), RenderChannel::Depth) != channels.end();
    if (has_depth) {
      const auto map = decode(file(RenderChannel::Depth), "depth",
                              [&](const ImageFile& image) { return decode_capture_depth(image, depth_format_); });
      f.depth = map.depth;
      f.depth_precision = map.precision;
    }
    for (auto c : channels) {
      switch (c) {
        case RenderChannel::Depth: break;
        case RenderChannel::Normal: {
          const auto n = decode(file(c), "normal", first(3)) * 2 - 1;
          if (f.depth.defined()) check_unit_normals(n, f.depth, file(c).string(), frame);
          f.normal = n.to(torch::kFloat16);
          break;
        }
        case RenderChannel::NormalAngle: f.normal_angle = decode(file(c), "normal_angle", first(1)).to(torch::kFloat16); break;
        case RenderChannel::Edge: f.edge = (decode(file(c), "edge", first(1)) > 0.5f).to(torch::kUInt8); break;
        case RenderChannel::Motion:
          f.motion = decode(file(c), "motion", [&](const ImageFile& image) { return decode_capture_motion(image, motion_format_); });
          break;
        case RenderChannel::Bsp:  // never stored: resolve_channels only derives them
        case RenderChannel::History:
        case RenderChannel::Jitter:
        case RenderChannel::HistoryOut: break;
      }
    }
    return f;
  }

 private:
  DatasetInfo info_;
  std::vector<ResolutionFiles> res_;
  ColorAlpha color_alpha_ = ColorAlpha::Ignore;
  DepthFormat depth_format_;
  MotionFormat motion_format_;
  std::vector<std::array<double, 2>> jitter_;  // per frame, of resolution 0; empty: not jittered
};

fs::path glob_yaml(const fs::path& path) { return fs::is_directory(path) ? path / "dataset.yaml" : path; }

}  // namespace

bool looks_like_glob_layout(const fs::path& path) {
  const fs::path yaml = glob_yaml(path);
  if (!fs::is_regular_file(yaml)) return false;
  const auto ext = yaml.extension().string();
  if (ext != ".yaml" && ext != ".yml") return false;
  try {
    const YAML::Node n = config::Document::load_file(yaml).root();
    return n.IsMap() && n["layout"] && n["layout"].IsScalar() && n["layout"].Scalar() == "glob";
  } catch (const Error&) {
    // A YAML file that does not load (a syntax error, a duplicate key, too large) can only be
    // meant as a capture: opening it reports the error with its line and column, not "not a
    // dataset".
    return true;
  }
}

std::unique_ptr<FrameSource> open_glob_layout(const fs::path& path, const DatasetOpenOptions& options) {
  return std::make_unique<GlobDataset>(glob_yaml(path), options);
}

}  // namespace cgsr
