#pragma once
// The random source of the procedural scenes: one 64-bit Mersenne twister per level, with the
// few draws the generator needs. Same seed, same draws, on every platform (no std::
// distributions, whose output is implementation-defined).

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

}  // namespace cgsr
