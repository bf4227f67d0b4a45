#include <gtest/gtest.h>
#include <omp.h>
#include <oneapi/tbb/parallel_for.h>
#include <oneapi/tbb/task_arena.h>
#include <torch/torch.h>

#include <mutex>
#include <vector>

#include "core/runtime.h"

using namespace cgsr;

// Torch ops inside TBB tasks run with a team of one on worker threads, while the calling thread
// keeps the process-wide team (core/runtime.h says why).
TEST(Runtime, TbbWorkersRunTorchOpsSingleThreaded) {
  ASSERT_EQ(set_threads(2), 2);
  std::mutex mutex;
  std::vector<int> worker_team_sizes;
  tbb::parallel_for(0, 64, [&](int i) {
    // Large enough for LibTorch to split it across its OpenMP team.
    const auto sum = (torch::ones({1 << 18}) * static_cast<float>(i)).sum().item<double>();
    EXPECT_DOUBLE_EQ(sum, static_cast<double>(i) * (1 << 18));
    if (tbb::this_task_arena::current_thread_index() == 0) return;
    std::lock_guard<std::mutex> lock(mutex);
    worker_team_sizes.push_back(omp_get_max_threads());
  });
  if (worker_team_sizes.empty()) GTEST_SKIP() << "no TBB worker thread ran a task";
  for (int size : worker_team_sizes) EXPECT_EQ(size, 1);
  EXPECT_EQ(omp_get_max_threads(), 2);
}
