#include "distributed/work_queue.h"

#include <spdlog/spdlog.h>

#include <atomic>
#include <map>
#include <optional>
#include <thread>

#include "core/error.h"

namespace cgsr::distributed {

namespace {
const std::chrono::milliseconds kPoll(100);
std::string batch_prefix(int64_t batch) { return "queue/" + std::to_string(batch) + "/"; }
std::string indexed(const std::string& batch, const char* what, size_t i) { return batch + what + std::to_string(i); }

// Rank 0's watch over the other ranks while a batch runs, on a thread and a store connection of
// its own (so a dead rank's tasks go back to the queue even while rank 0 trains a candidate).
class Watchdog {
 public:
  Watchdog(World& world, std::string batch, size_t size)
      : world_(world), batch_(std::move(batch)), size_(size), thread_([this] { watch(); }) {}
  ~Watchdog() {
    stop_ = true;
    thread_.join();
  }

 private:
  using Clock = std::chrono::steady_clock;
  void watch() {
    try {
      auto store = world_.connect();
      const auto timeout = std::chrono::duration<double>(world_.options().heartbeat_timeout);
      std::map<int, std::pair<int64_t, Clock::time_point>> last;  // heartbeat value, when it last moved
      std::map<size_t, Clock::time_point> ownerless;              // claimed, owner not yet written
      while (!stop_) {
        const auto now = Clock::now();
        std::map<int, bool> dead;
        for (int r = 1; r < world_.size(); ++r) {
          const int64_t beat = world_.heartbeat(*store, r);
          auto it = last.find(r);
          if (it == last.end() || it->second.first != beat) last[r] = {beat, now};
          dead[r] = now - last[r].second > timeout;
        }
        for (size_t i = 0; i < size_ && !stop_; ++i) {
          if (store->check(indexed(batch_, "result/", i))) continue;
          const int64_t epoch = store->add(indexed(batch_, "epoch/", i), 0);
          const std::string owner_key = indexed(batch_, "owner/", i) + "/" + std::to_string(epoch);
          bool requeue = false;
          std::string who;
          if (store->check(owner_key)) {
            const int owner = std::stoi(store->get(owner_key));
            requeue = owner != 0 && dead[owner];
            who = "rank " + std::to_string(owner) + " stopped beating";
          } else if (store->add(indexed(batch_, "claim/", i) + "/" + std::to_string(epoch), 0) > 0) {
            const auto since = ownerless.emplace(i, now).first->second;
            requeue = now - since > timeout;
            who = "its claimant never recorded itself";
          }
          if (!requeue) continue;
          ownerless.erase(i);
          store->add(indexed(batch_, "epoch/", i), 1);
          store->add(batch_ + "requeued", 1);
          spdlog::warn("distributed: {} for {:.0f} s: task {} of {} goes back to the queue", who, timeout.count(),
                       i, batch_);
        }
        for (int k = 0; k < 5 && !stop_; ++k) std::this_thread::sleep_for(kPoll);
      }
    } catch (const std::exception& e) {
      spdlog::error("distributed: the watch over the ranks stopped: {}", e.what());
    }
  }

  World& world_;
  std::string batch_;
  size_t size_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};
}  // namespace

bool WorkQueue::claim(Store& store, const std::string& batch, size_t size, size_t& cursor, size_t& claimed) {
  for (; cursor < size; ++cursor) {
    const size_t i = cursor;
    if (store.check(indexed(batch, "result/", i))) continue;
    const std::string epoch = std::to_string(store.add(indexed(batch, "epoch/", i), 0));
    if (store.add(indexed(batch, "claim/", i) + "/" + epoch, 1) != 1) continue;
    store.set(indexed(batch, "owner/", i) + "/" + epoch, std::to_string(world_.rank()));
    claimed = i;
    ++cursor;
    return true;
  }
  return false;
}

std::string WorkQueue::run_claimed(const std::string& batch, size_t index, const Runner& run) {
  Store& store = world_.store();
  const std::string task = store.get(indexed(batch, "task/", index));
  std::string result;
  try {
    result = run(index, task);
  } catch (const std::exception& e) {
    store.set(indexed(batch, "error/", index), "rank " + std::to_string(world_.rank()) + ": " + e.what());
    throw;
  }
  store.set(indexed(batch, "result/", index), result);
  return result;
}

void WorkQueue::run_batch(const std::vector<std::string>& tasks, const Runner& run, const Done& done) {
  CGSR_CHECK(world_.coordinator(), "only rank 0 publishes batches");
  const std::string batch = batch_prefix(batches_++);
  Store& store = world_.store();
  try {
    for (size_t i = 0; i < tasks.size(); ++i) store.set(indexed(batch, "task/", i), tasks[i]);
    store.set(batch + "size", std::to_string(tasks.size()));  // last: the batch is whole when it appears
    Watchdog watchdog(world_, batch, tasks.size());
    std::vector<std::optional<std::string>> results(tasks.size());
    size_t next_done = 0, cursor = 0;
    int64_t requeues_seen = 0;
    while (next_done < tasks.size()) {
      for (size_t i = next_done; i < tasks.size(); ++i) {
        if (results[i]) continue;
        if (store.check(indexed(batch, "error/", i)))
          throw Error("distributed task " + std::to_string(i), store.get(indexed(batch, "error/", i)));
        if (store.check(indexed(batch, "result/", i))) results[i] = store.get(indexed(batch, "result/", i));
      }
      for (; next_done < tasks.size() && results[next_done]; ++next_done) done(next_done, *results[next_done]);
      if (next_done == tasks.size()) break;
      if (const int64_t requeues = store.add(batch + "requeued", 0); requeues != requeues_seen) {
        requeues_seen = requeues;
        cursor = 0;
      }
      size_t index = 0;
      if (claim(store, batch, tasks.size(), cursor, index)) {
        results[index] = run_claimed(batch, index, run);
        continue;
      }
      std::this_thread::sleep_for(kPoll);
    }
    store.set(batch + "closed", "1");
  } catch (const std::exception& e) {
    abort(e.what());
    throw;
  }
}

void WorkQueue::finish() { world_.store().set("queue/finished", "1"); }

void WorkQueue::abort(const std::string& reason) {
  try {
    world_.store().set("queue/abort", reason);
  } catch (const std::exception&) {
  }
}

int WorkQueue::serve(const Runner& run) {
  CGSR_CHECK(!world_.coordinator(), "rank 0 publishes batches, it does not serve them");
  Store& store = world_.store();
  int ran = 0;
  const auto stop_if_aborted = [&] {
    if (store.check("queue/abort")) throw Error(world_.describe(), "rank 0 stopped: " + store.get("queue/abort"));
  };
  try {
    for (int64_t k = 0;; ++k) {
      const std::string batch = batch_prefix(k);
      while (!store.check(batch + "size")) {
        stop_if_aborted();
        if (store.check("queue/finished") && !store.check(batch + "size")) return ran;
        std::this_thread::sleep_for(kPoll);
      }
      const size_t size = std::stoul(store.get(batch + "size"));
      size_t cursor = 0, index = 0;
      int64_t requeues_seen = 0;
      while (!store.check(batch + "closed")) {
        stop_if_aborted();
        if (const int64_t requeues = store.add(batch + "requeued", 0); requeues != requeues_seen) {
          requeues_seen = requeues;
          cursor = 0;
        }
        if (claim(store, batch, size, cursor, index)) {
          run_claimed(batch, index, run);
          ++ran;
          continue;
        }
        std::this_thread::sleep_for(kPoll);
      }
    }
  } catch (const Error&) {
    throw;
  } catch (const std::exception& e) {
    throw Error(world_.describe(), std::string("lost the store (did rank 0 end?): ") + e.what());
  }
}

}  // namespace cgsr::distributed
