#pragma once
// Batches of independent tasks spread over the ranks of a World through its store, with no
// collective a dead rank could block:
//
//   rank 0:  queue.run_batch(tasks, run, done);  // publishes, works on tasks too, gathers
//            ...more batches...; queue.finish();
//   others:  queue.serve(run);                    // claims and runs tasks until finish()
//
// A rank claims a task with an atomic counter in the store, runs it and posts the result. Rank 0
// watches the heartbeats (world.h): a rank silent for heartbeat_timeout seconds is counted dead,
// and the tasks it claimed but never finished go back to the queue for whoever is free (rank 0
// included). A task is a pure function of its text, so running it twice is harmless: the first
// result in is taken. `done` sees the results in task order, whatever order they came in, so
// what rank 0 records does not depend on how the tasks were spread.
//
// Store keys, under "queue/<batch>/": size, task/<i>, epoch/<i> (times requeued), claim/<i>/<e>
// (counter; the rank that makes it 1 owns epoch e), owner/<i>/<e>, result/<i>, error/<i>,
// requeued, closed; and "queue/finished", "queue/abort".

#include <functional>
#include <string>
#include <vector>

#include "distributed/world.h"

namespace cgsr::distributed {

class WorkQueue {
 public:
  explicit WorkQueue(World& world) : world_(world) {}

  // Runs one task: its index in the batch and its text; returns the result text. An exception is
  // reported to rank 0, which fails the batch naming the rank and the task.
  using Runner = std::function<std::string(size_t index, const std::string& task)>;
  using Done = std::function<void(size_t index, const std::string& result)>;

  // Rank 0: one batch, finished when every task has a result.
  void run_batch(const std::vector<std::string>& tasks, const Runner& run, const Done& done);
  // Rank 0: no more batches; the serving ranks return.
  void finish();
  // Rank 0, on an error: the serving ranks stop with `reason`.
  void abort(const std::string& reason);

  // Ranks > 0: serve every batch until rank 0 finishes. Returns the number of tasks this rank ran.
  int serve(const Runner& run);

 private:
  // Claims an open task of `batch` (fresh or requeued) for this rank, scanning from `cursor`.
  bool claim(Store& store, const std::string& batch, size_t size, size_t& cursor, size_t& claimed);
  std::string run_claimed(const std::string& batch, size_t index, const Runner& run);

  World& world_;
  int64_t batches_ = 0;  // rank 0: batches published so far
};

}  // namespace cgsr::distributed
