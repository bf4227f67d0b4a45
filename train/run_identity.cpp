#include "train/run_identity.h"

#include "core/config.h"
#include "core/text.h"
#include "models/arch_spec.h"
#include "train/trainer.h"

namespace cgsr {

namespace {
// Schedule keys a resumed run may change: how long it trains, how often it validates and
// checkpoints, and how it computes (a checkpoint keeps its memory layout; prefetching changes no
// batch).
const std::vector<std::string> kResumableScheduleKeys = {"steps", "validate_every", "checkpoint_every", "layout",
                                                         "prefetch"};

std::string one_line(std::string text) {
  while (!text.empty() && text.back() == '\n') text.pop_back();
  for (auto& c : text)
    if (c == '\n') c = ' ';
  return text;
}

std::string data_fingerprint(const DatasetInfo& data) {
  std::vector<std::string> sizes;
  for (const auto& r : data.resolutions) sizes.push_back(r.name());
  std::string text = data.layout + " '" + data.name + "', " + std::to_string(data.frames) + " frames at " +
                     join(sizes) + ", channels " + join(channel_names(data.channels)) + ", split " +
                     std::to_string(data.split.train.size()) + "/" + std::to_string(data.split.val.size()) + "/" +
                     std::to_string(data.split.test.size());
  for (const auto& s : data.scenes) text += ", scene '" + s.name + "' " + std::to_string(s.frames);
  return text;
}
}  // namespace

RunIdentity run_identity(uint64_t seed, const TrainSchedule& schedule, const DatasetInfo& data, const ArchSpec& spec) {
  RunIdentity id;
  id["seed"] = std::to_string(seed);
  const YAML::Node emitted = schedule_schema().emit(schedule);
  for (const auto& kv : emitted) {
    const std::string key = kv.first.Scalar();
    if (std::find(kResumableScheduleKeys.begin(), kResumableScheduleKeys.end(), key) != kResumableScheduleKeys.end())
      continue;
    id["schedule." + key] = one_line(config::to_yaml(kv.second));
  }
  id["data"] = data_fingerprint(data);
  id["model"] = one_line(spec_to_yaml(spec));
  return id;
}

std::vector<std::string> identity_differences(const RunIdentity& checkpoint, const RunIdentity& now) {
  std::vector<std::string> out;
  for (const auto& [key, was] : checkpoint) {
    const auto it = now.find(key);
    if (it != now.end() && it->second != was) out.push_back(key + ": " + was + " in the checkpoint, " + it->second + " now");
  }
  return out;
}

}  // namespace cgsr
