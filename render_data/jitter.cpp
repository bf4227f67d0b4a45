#include "render_data/jitter.h"

#include "core/error.h"

namespace cgsr {

config::Schema<JitterSettings> jitter_settings_schema() {
  config::Schema<JitterSettings> s;
  s.field("sequence", &JitterSettings::sequence, "sub-pixel offset sequence of the smallest resolution's frames")
      .one_of({"none", "halton"});
  s.field("phases", &JitterSettings::phases, "offsets before the sequence repeats (8 or 16 are usual)").range(1, 1024);
  return s;
}

double halton(int index, int base) {
  CGSR_CHECK(index >= 1 && base >= 2, "halton needs index >= 1 and base >= 2");
  double result = 0, f = 1;
  for (int i = index; i > 0; i /= base) {
    f /= base;
    result += f * (i % base);
  }
  return result;
}

Vec2 jitter_offset(const JitterSettings& settings, int frame) {
  if (!settings.enabled()) return {0, 0};
  CGSR_CHECK(frame >= 0 && settings.phases >= 1, "jitter needs a frame >= 0 and phases >= 1");
  const int index = frame % settings.phases + 1;
  return {static_cast<float>(halton(index, 2) - 0.5), static_cast<float>(halton(index, 3) - 0.5)};
}

}  // namespace cgsr
