#include "render_data/hr_samples.h"

namespace cgsr {

int hr_samples_per_side(int hr_samples) {
  for (int n = 1; n <= kMaxHrSamplesPerSide; ++n)
    if (n * n == hr_samples) return n;
  return 0;
}

std::string hr_samples_expected() {
  std::string list;
  for (int n = 1; n <= kMaxHrSamplesPerSide; ++n)
    list += (n > 1 ? (n == kMaxHrSamplesPerSide ? " or " : ", ") : "") + std::to_string(n * n);
  return "a square n x n with n in 1.." + std::to_string(kMaxHrSamplesPerSide) + " (" + list + ")";
}

std::string hr_target_description(int hr_samples, const std::string& filter) {
  if (hr_samples <= 1) return "aliased (1 sample per pixel)";
  return "supersampled (" + std::to_string(hr_samples) + " samples per pixel, " + filter + " filter)";
}

}  // namespace cgsr
