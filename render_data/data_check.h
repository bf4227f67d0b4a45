#pragma once
// `cgsr data check DIR` as a library call: reads every frame at every resolution and counts what
// is wrong instead of stopping at the first problem. For the cgsr format each file is checked on
// its own (missing, unreadable, wrong size, NaN/Inf, out of range, zero-length normals); other
// layouts are checked frame by frame through their loader. Resolution pairs must be integer
// scales of the smallest; the manifest split must list every frame exactly once.

#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "render_data/dataset.h"

namespace cgsr {

struct DataCheckReport {
  std::string name, layout;
  int frames = 0;
  std::vector<Resolution> resolutions;
  std::vector<std::string> channels;   // channels checked
  std::vector<std::string> derived;    // of which derived (other layouts)
  std::vector<std::string> scenes;     // of a multi-scene data set: "name (N frames)"
  int64_t frames_checked = 0;          // (frame, resolution) pairs
  int64_t files_checked = 0;
  std::map<std::string, int64_t> problems;  // problem kind -> count ("missing", "NaN/Inf", ...)
  std::vector<std::string> messages;        // the first problems, naming file and frame
  // Value ranges over all valid frames.
  double depth_min = 0, depth_max = 0;      // finite linear depth, metres
  double sky_fraction = 0;                  // pixels without geometry
  double edge_fraction = 0;                 // pixels marked as edges
  double motion_max = 0;                    // largest |motion|, pixels
  int split_train = 0, split_val = 0, split_test = 0;

  int64_t problem_count() const;
};

// Throws only when `path` cannot be opened as a dataset at all.
DataCheckReport check_dataset(const std::filesystem::path& path, const DatasetOpenOptions& options = {},
                              size_t max_messages = 20);

}  // namespace cgsr
