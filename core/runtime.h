#pragma once
// Process-wide execution settings: thread counts and random seeds.

#include <cstdint>
#include <random>

namespace cgsr {

// Sets LibTorch intra-op threads and the TBB arena width together; 0 = all hardware threads.
// Torch ops on TBB worker threads run single-threaded from then on (the tasks are the
// parallelism; nested OpenMP teams would oversubscribe the cores). Returns the number in effect.
int set_threads(int threads);
int thread_count();

// Seeds every RNG the project uses: torch's default generator and the project's own streams.
void seed_everything(uint64_t seed);
uint64_t global_seed();

// An independent, reproducible random stream for one purpose (e.g. "patch-sampler"), derived
// from the global seed so that adding a consumer elsewhere does not shift this one.
std::mt19937_64 make_rng(const char* purpose, uint64_t extra = 0);

}  // namespace cgsr
