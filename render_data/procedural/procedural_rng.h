#pragma once
// The random source of the procedural scene sources (procedural levels, random shapes): one
// 64-bit Mersenne twister per scene, with the few draws the generators need. Same seed, same
// draws, on every platform (no std:: distributions, whose output is implementation-defined).
// Also what the sources share around it: the seed of a `variant`, and their [lo, hi] options.

#include <algorithm>
#include <cstdint>
#include <random>
#include <vector>

namespace cgsr {

class ProceduralRng {
 public:
  explicit ProceduralRng(uint64_t seed) : engine_(seed ^ 0x5DEECE66DULL) {}
  double uniform() { return static_cast<double>(engine_() >> 11) * (1.0 / 9007199254740992.0); }
  float range(float lo, float hi) { return lo + static_cast<float>(uniform()) * (hi - lo); }
  int below(int n) { return std::min(n - 1, static_cast<int>(uniform() * n)); }
  // An integer in [lo, hi], both included.
  int between(int lo, int hi) { return lo + below(hi - lo + 1); }
  bool chance(double p) { return uniform() < p; }
  uint64_t bits() { return engine_(); }
  template <class T>
  const T& pick(const std::vector<T>& v) { return v[below(static_cast<int>(v.size()))]; }

 private:
  std::mt19937_64 engine_;
};

// The seed of scene `variant` of a render seed: the seed itself for variant 0 (the scene every
// config made before variants existed), else the two mixed (splitmix64 finalizer).
inline uint64_t variant_seed(uint64_t seed, int variant) {
  if (variant == 0) return seed;
  uint64_t x = seed ^ (0x9E3779B97F4A7C15ULL * static_cast<uint64_t>(variant));
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ULL;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBULL;
  return x ^ (x >> 31);
}

// [lo, hi] options a generator draws from: two values, lo <= hi (a config::Schema check).
template <class V>
bool is_range(const std::vector<V>& v) {
  return v.size() == 2 && v[0] <= v[1];
}
inline const char* const kRangeMessage = "must be [lo, hi] with lo <= hi";

}  // namespace cgsr
