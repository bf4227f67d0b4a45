#pragma once
// What a checkpoint must share with the run that resumes from it: the seed, the schedule (but
// its length and how often it validates and checkpoints, which a resumed run may change), the
// data set (a fingerprint of its layout, name, frames, resolutions, channels and split) and the
// model spec. A resume that differs would train on as another run, silently; the trainer refuses
// it, listing the differences, unless forced.

#include <map>
#include <string>
#include <vector>

#include "render_data/dataset.h"

namespace cgsr {

struct TrainSchedule;
struct ArchSpec;

// Named entries, e.g. {"seed": "3", "schedule.batch_size": "2", "data": "...", "model": "..."}.
using RunIdentity = std::map<std::string, std::string>;

RunIdentity run_identity(uint64_t seed, const TrainSchedule& schedule, const DatasetInfo& data, const ArchSpec& spec);

// One line per entry that differs: "schedule.batch_size: 2 in the checkpoint, 4 now". Entries
// that only one side has (a checkpoint of an older cgsr) are not compared.
std::vector<std::string> identity_differences(const RunIdentity& checkpoint, const RunIdentity& now);

}  // namespace cgsr
