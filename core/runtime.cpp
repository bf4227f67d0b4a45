#include "core/runtime.h"

#include <ATen/Parallel.h>
#include <omp.h>
#include <oneapi/tbb/global_control.h>
#include <oneapi/tbb/task_scheduler_observer.h>

#include <memory>
#include <thread>

#include "core/hash.h"

namespace cgsr {
namespace {
std::unique_ptr<tbb::global_control>& tbb_limit() {
  static std::unique_ptr<tbb::global_control> limit;
  return limit;
}
uint64_t& seed_storage() {
  static uint64_t seed = 0;
  return seed;
}
int& threads_storage() {
  static int threads = 0;
  return threads;
}
// LibTorch ops run on a TBB worker (frame decoding, batch building) would otherwise start an
// OpenMP team of the process-wide size on that thread. libgomp, then managing more threads than
// there are cores, lets every OpenMP worker (the training step's too) sleep at once between
// parallel regions: the train stage ran its compute 2.3x slower than the same step alone. TBB
// workers are already parallel across tasks, so their torch ops run on their own thread.
class OneOpenMpThreadPerTbbWorker : public tbb::task_scheduler_observer {
 public:
  OneOpenMpThreadPerTbbWorker() { observe(true); }
  void on_scheduler_entry(bool is_worker) override {
    if (!is_worker) return;
    // LibTorch sets a thread's team size on its first parallel op; that happens here first so
    // that the size set after it (per thread, in OpenMP) stays.
    at::internal::lazy_init_num_threads();
    omp_set_num_threads(1);
  }
};

// SplitMix64: decorrelates seeds derived from nearby integers.
uint64_t mix(uint64_t x) {
  x += 0x9E3779B97F4A7C15ULL;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ULL;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBULL;
  return x ^ (x >> 31);
}
}  // namespace

// LeakSanitizer: oneTBB leaks the 40-byte proxy it allocates for an observer (the one above) at
// exit, a library-internal report. observe(true) notifies the calling thread, which then holds a
// reference to the proxy until it leaves its arena; the main thread never does before exit, so
// the observer's destructor (observe(false)) cannot free the proxy, and TBB's shutdown skips
// proxies whose observer is gone (observer_list::clear). A dozen lines of TBB alone, a static
// observer and nothing else, show the same report. tbb::finalize at exit would free it, at the
// cost of joining the workers in every exit path; suppressed instead, in every binary of an
// ASan build (the cgsr executable, tests, fuzz targets) however it is run.
// Fontconfig, which Cairo asks for the plots' font (core/canvas.cpp), keeps its configuration and
// font patterns for the life of the process: about 1 KB reported at exit by every binary that
// drew text. A Cairo program of ten lines that destroys all it creates shows the same report;
// only cairo_debug_reset_static_data() and FcFini() free it, debugging calls that must come
// after every other use of Cairo in the process. Suppressed too, as is Cairo 1.16's own leak of
// a recording surface painted into an SVG surface: every such canvas but the last keeps a
// reference and leaks its drawing (a few KB per SVG plot; thirty lines of Cairo, recording a
// line and painting it into two SVG streams, show it). A Canvas cgsr fails to free is still
// reported: its own memory is not Cairo's.
// AddressSanitizer ends the process when an allocation fails; cgsr turns a failed allocation of
// the sizes a user asked for into exit 2 (cli/failure.h), which the sanitizer build tests too,
// so its allocator returns null as the system's does.
#if defined(__has_feature)
#if __has_feature(address_sanitizer)
#define CGSR_ASAN 1
#endif
#endif
#if defined(__SANITIZE_ADDRESS__) || defined(CGSR_ASAN)
extern "C" const char* __lsan_default_suppressions() {
  return "leak:tbb::detail::r1::observe\nleak:libfontconfig.so\nleak:libcairo.so\n";
}
extern "C" const char* __lsan_default_options() { return "print_suppressions=0"; }
extern "C" const char* __asan_default_options() { return "allocator_may_return_null=1"; }
#endif

int set_threads(int threads) {
  if (threads <= 0) threads = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  torch::set_num_threads(threads);
  tbb_limit() = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                      static_cast<size_t>(threads));
  threads_storage() = threads;
  static OneOpenMpThreadPerTbbWorker observer;
  return threads;
}

int thread_count() { return threads_storage() > 0 ? threads_storage() : torch::get_num_threads(); }

void seed_everything(uint64_t seed) {
  seed_storage() = seed;
  torch::manual_seed(seed);
}

uint64_t global_seed() { return seed_storage(); }

std::mt19937_64 make_rng(const char* purpose, uint64_t extra) {
  const uint64_t h = fnv1a64(purpose, kLegacyFnv1a64Basis);  // legacy basis: every seeded stream stays the same
  return std::mt19937_64(mix(seed_storage() ^ mix(h) ^ mix(extra + 1)));
}

}  // namespace cgsr
