#include "render_data/data_check.h"

#include <oneapi/tbb/parallel_for.h>
#include <torch/torch.h>

#include <algorithm>
#include <limits>
#include <mutex>

#include "core/error.h"
#include "core/tensor_checks.h"
#include "render_data/bsp_border_file.h"
#include "render_data/frame_files.h"

namespace cgsr {
namespace fs = std::filesystem;

int64_t DataCheckReport::problem_count() const {
  int64_t n = 0;
  for (const auto& [kind, count] : problems) n += count;
  return n;
}

namespace {

// Accumulates statistics and problems from parallel workers.
struct Collector {
  Collector(DataCheckReport& r, size_t max) : report(r), max_messages(max) {}
  DataCheckReport& report;
  size_t max_messages;
  std::mutex mutex;
  double depth_min = std::numeric_limits<double>::infinity(), depth_max = 0;
  double sky = 0, edges = 0, pixels = 0, edge_pixels = 0, motion_max = 0;

  void problem(const std::string& kind, const std::string& message) {
    std::lock_guard<std::mutex> lock(mutex);
    ++report.problems[kind];
    if (report.messages.size() < max_messages) report.messages.push_back(message);
  }
  void frame(const Frame& f) {
    double dmin = depth_min, dmax = depth_max, s = 0, e = 0, m = 0;
    const double n = static_cast<double>(f.width) * f.height;
    if (f.depth.defined()) {
      const auto finite = torch::isfinite(f.depth);
      s = n - finite.sum().item<double>();
      if (s < n) {
        const auto values = f.depth.masked_select(finite);
        dmin = values.min().item<double>();
        dmax = values.max().item<double>();
      }
    }
    if (f.edge.defined()) e = f.edge.to(torch::kFloat64).sum().item<double>();
    if (f.motion.defined()) m = f.motion.norm(2, 0).max().item<double>();
    std::lock_guard<std::mutex> lock(mutex);
    report.frames_checked++;
    if (f.depth.defined()) {
      depth_min = std::min(depth_min, dmin);
      depth_max = std::max(depth_max, dmax);
      sky += s;
      pixels += n;
    }
    if (f.edge.defined()) edges += e, edge_pixels += n;
    motion_max = std::max(motion_max, m);
  }
  void finish() {
    report.depth_min = std::isfinite(depth_min) ? depth_min : 0;
    report.depth_max = depth_max;
    report.sky_fraction = pixels > 0 ? sky / pixels : 0;
    report.edge_fraction = edge_pixels > 0 ? edges / edge_pixels : 0;
    report.motion_max = motion_max;
  }
};

// Checks the resolution list and the split; problems are counted, not thrown.
void check_structure(const DatasetInfo& info, Collector& c) {
  const Resolution& lo = info.resolutions.front();
  for (const auto& r : info.resolutions)
    if (r.width % lo.width != 0 || r.height % lo.height != 0 || r.width / lo.width != r.height / lo.height)
      c.problem("resolution scale", info.root.string() + ": resolution " + r.name() + " is not an integer scale of " + lo.name());
  std::vector<int> seen(info.frames, 0);
  for (const auto* list : {&info.split.train, &info.split.val, &info.split.test})
    for (int f : *list)
      if (f >= 0 && f < info.frames) ++seen[f];
  for (int f = 0; f < info.frames; ++f)
    if (seen[f] != 1)
      c.problem("split", info.root.string() + ": frame " + std::to_string(f) + " is listed " + std::to_string(seen[f]) +
                             " times in the split");
}

void check_cgsr_files(const fs::path& root, const DatasetManifest& m, Collector& c) {
  const auto& kinds = all_file_kinds();
  tbb::parallel_for(0, m.frames, [&](int frame) {
    for (size_t ri = 0; ri < m.resolutions.size(); ++ri) {
      const Resolution& r = m.resolutions[ri];
      Frame f;
      f.width = r.width;
      f.height = r.height;
      // Depth first: normals are checked against it.
      std::vector<FileKind> order = {FileKind::Depth};
      for (FileKind k : kinds)
        if (k != FileKind::Depth) order.push_back(k);
      for (FileKind k : order) {
        const fs::path path = frame_file(root, r, k, frame);
        DecodedFile d = decode_file(k, path, frame, r, f.depth);
        {
          std::lock_guard<std::mutex> lock(c.mutex);
          ++c.report.files_checked;
        }
        if (d.problem != FileProblem::None) {
          c.problem(file_problem_name(d.problem), path.string() + ": " + d.message);
          continue;
        }
        switch (k) {
          case FileKind::Color: f.color = d.value; break;
          case FileKind::Depth: f.depth = d.value; break;
          case FileKind::Normal: f.normal = d.value; break;
          case FileKind::NormalAngle: f.normal_angle = d.value; break;
          case FileKind::Edge: f.edge = d.value; break;
          case FileKind::Motion: f.motion = d.value; break;
          case FileKind::Id: break;
        }
      }
      c.frame(f);
    }
    if (m.bsp_border_depth > 0) {  // the BSP border file of the smallest resolution
      const fs::path path = bsp_border_file(root, m.resolutions.front(), frame);
      {
        std::lock_guard<std::mutex> lock(c.mutex);
        ++c.report.files_checked;
      }
      try {
        const BspBorderImage image = read_bsp_border_file(path, frame, m.resolutions.front());
        if (image.max_depth() != m.bsp_border_depth)
          c.problem("bsp_border", path.string() + ": frame " + std::to_string(frame) + ": max_depth " +
                                      std::to_string(image.max_depth()) + ", the manifest says depth " +
                                      std::to_string(m.bsp_border_depth));
      } catch (const Error& e) {
        c.problem(fs::exists(path) ? "bsp_border" : "missing", e.what());
      }
    }
  });
}

void check_through_loader(const Dataset& data, Collector& c) {
  const auto& info = data.info();
  tbb::parallel_for(0, info.frames, [&](int frame) {
    for (size_t ri = 0; ri < info.resolutions.size(); ++ri) {
      try {
        const Frame f = data.load(frame, ri);
        if (f.normal.defined() && f.depth.defined()) check_unit_normals(f.normal, f.depth, info.root.string(), frame);
        c.frame(f);
      } catch (const Error& e) {
        const std::string what = e.message();
        const char* kind = what.find("missing") != std::string::npos || what.find("no such") != std::string::npos ? "missing"
                           : what.find("NaN") != std::string::npos                                                 ? "NaN/Inf"
                           : what.find("does not match the resolution") != std::string::npos                      ? "wrong size"
                           : what.find("zero-length") != std::string::npos                                         ? "zero-length normals"
                                                                                                                  : "unreadable";
        c.problem(kind, e.what());
      }
    }
  });
}

}  // namespace

DataCheckReport check_dataset(const fs::path& path, const DatasetOpenOptions& options, size_t max_messages) {
  DataCheckReport report;
  Collector c(report, max_messages);
  const bool own = options.layout == "cgsr" || (options.layout == "auto" && fs::is_directory(path) && has_manifest(path));
  if (own) {
    // File by file, so one bad file does not hide the others; an incomplete render is a problem.
    const DatasetManifest m = read_manifest(path);
    report.name = m.name;
    report.layout = "cgsr";
    report.frames = m.frames;
    report.resolutions = m.resolutions;
    for (FileKind k : all_file_kinds()) report.channels.push_back(file_kind_name(k));
    if (m.bsp_border_depth > 0) report.channels.push_back("bsp_border");
    report.split_train = static_cast<int>(m.split.train.size());
    report.split_val = static_cast<int>(m.split.val.size());
    report.split_test = static_cast<int>(m.split.test.size());
    if (!m.complete) c.problem("incomplete render", (path / "manifest.yaml").string() + ": complete: false (the render was interrupted)");
    DatasetInfo info;
    info.root = path;
    info.frames = m.frames;
    info.resolutions = m.resolutions;
    info.split = m.split;
    check_structure(info, c);
    for (const auto& sc : m.scenes) report.scenes.push_back(sc.name + " (" + std::to_string(sc.frames) + " frames)");
    if (m.scenes.empty()) check_cgsr_files(path, m, c);
    for (const auto& sc : m.scenes) {
      // Scene by scene, so one missing or changed scene does not hide the others' files.
      DatasetManifest one = m;
      one.scenes = {sc};
      try {
        const ScenePart part = scene_parts(path, one).front();
        check_cgsr_files(part.root, part.manifest, c);
      } catch (const Error& e) {
        c.problem("scene", e.what());
      }
    }
  } else {
    const Dataset data = Dataset::open(path, options);
    const auto& info = data.info();
    report.name = info.name;
    report.layout = info.layout;
    report.frames = info.frames;
    report.resolutions = info.resolutions;
    report.channels = channel_names(info.channels);
    report.channels.insert(report.channels.begin(), "color");
    report.derived = channel_names(info.derived);
    report.split_train = static_cast<int>(info.split.train.size());
    report.split_val = static_cast<int>(info.split.val.size());
    report.split_test = static_cast<int>(info.split.test.size());
    check_structure(info, c);
    check_through_loader(data, c);
  }
  c.finish();
  std::sort(report.messages.begin(), report.messages.end());
  return report;
}

}  // namespace cgsr
