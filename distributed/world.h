#pragma once
// One process's place in a distributed run on torch.distributed's C++ engine: N processes
// (ranks 0..N-1, on one machine or several) meet at a TCP key-value store that rank 0 hosts
// (c10d::TCPStore), and average tensors over a Gloo process group (c10d::ProcessGroupGloo).
//
//   auto world = World::join(options);       // every rank; returns when all N have joined
//   world->store().set("key", "value");      // small messages (the training's layout, resume state)
//   world->allreduce_mean(gradients);        // collectives (data-parallel training)
//
// Every rank beats a heartbeat counter in the store once a second from a thread of its own, so
// rank 0 can tell a rank that died (SIGKILL, a lost machine) from one that is busy. The store
// lives in rank 0: when rank 0 dies every other rank fails at its next store operation.

#include <torch/types.h>

#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "core/config.h"
#include "distributed/store_address.h"

namespace cgsr::distributed {

struct DistributedOptions {
  int world_size = 1;          // processes in the run; 1 = not distributed
  int rank = 0;                // this process, 0..world_size-1; rank 0 coordinates and hosts the store
  std::string store;           // HOST:PORT of rank 0's store (required when world_size > 1)
  std::string interface;       // network interface Gloo binds to ("" = the store's loopback, or this host's name)
  double timeout = 300;        // seconds to wait for every rank to join, and for a collective
  double heartbeat_timeout = 30;  // seconds without a heartbeat before rank 0 counts a rank as dead

  bool enabled() const { return world_size > 1; }
};
config::Schema<DistributedOptions> distributed_schema();

// A string view of one connection to the store. Keys and values are arbitrary bytes.
class Store {
 public:
  struct Impl;
  explicit Store(std::unique_ptr<Impl> impl);
  ~Store();
  void set(const std::string& key, const std::string& value);
  std::string get(const std::string& key);  // waits for the key (up to the store timeout)
  int64_t add(const std::string& key, int64_t delta);  // atomic; add(key, 0) reads a counter
  bool check(const std::string& key);       // whether the key exists, without waiting
  Impl& impl() { return *impl_; }

 private:
  std::unique_ptr<Impl> impl_;
};

class World {
 public:
  // Rendezvous: rank 0 hosts the store at options.store, every rank connects, announces itself
  // and waits until all world_size ranks have. Errors name the address and the missing ranks.
  static std::unique_ptr<World> join(const DistributedOptions& options);
  ~World();
  World(const World&) = delete;
  World& operator=(const World&) = delete;

  int rank() const { return options_.rank; }
  int size() const { return options_.world_size; }
  bool coordinator() const { return options_.rank == 0; }
  const DistributedOptions& options() const { return options_; }
  const StoreAddress& address() const { return address_; }
  std::string describe() const;  // "rank 1 of 2 (store 127.0.0.1:29500)"

  Store& store() { return *store_; }
  // A second connection, for a thread of its own (a connection serves one operation at a time).
  std::unique_ptr<Store> connect() const;
  // The heartbeat counter of `rank`: it grows once a second while that rank lives.
  int64_t heartbeat(Store& store, int rank) const;

  // Store-based collectives (they survive no dead rank, but need no process group). Every rank
  // calls them in the same order; `tag` names the call in errors.
  void barrier(const std::string& tag);
  // Rank 0 gets every rank's bytes, in rank order; the others get an empty vector.
  std::vector<std::string> gather(const std::string& tag, const std::string& bytes);
  // Every rank gets rank 0's bytes (the others' argument is ignored).
  std::string broadcast(const std::string& tag, const std::string& bytes);

  // Gloo collectives (the group is created by the first call, collectively): the element-wise
  // mean over the ranks of each tensor, in place; rank 0's values into every rank's tensors.
  void allreduce_mean(const std::vector<torch::Tensor>& tensors);
  void broadcast_tensors(const std::vector<torch::Tensor>& tensors);

 private:
  explicit World(DistributedOptions options);
  void beat();
  std::string next_key(const std::string& tag);
  // Waits for `key`, failing after the timeout with a message naming `who` and `what`.
  void wait_for(const std::string& key, int who, const std::string& what);
  struct Collectives;

  DistributedOptions options_;
  StoreAddress address_;
  std::unique_ptr<Store> store_;
  std::unique_ptr<Collectives> collectives_;
  int64_t calls_ = 0;  // numbers the store-based collectives, so their keys never repeat
  bool joined_ = false;  // every rank arrived
  std::atomic<bool> stopping_{false};
  std::thread heartbeat_;
};

}  // namespace cgsr::distributed
