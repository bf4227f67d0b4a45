#include "distributed/world.h"

// The torch CMake package defines USE_C10D_GLOO (LibTorch was built with Gloo); without it the
// header below is empty.
#ifndef USE_C10D_GLOO
#define USE_C10D_GLOO 1
#endif
#include <torch/csrc/distributed/c10d/PrefixStore.hpp>
#include <torch/csrc/distributed/c10d/ProcessGroupGloo.hpp>
#include <torch/csrc/distributed/c10d/TCPStore.hpp>
#include <torch/torch.h>

#include <spdlog/spdlog.h>
#include <unistd.h>

#include <condition_variable>
#include <mutex>

#include "core/error.h"

namespace cgsr::distributed {

config::Schema<DistributedOptions> distributed_schema() {
  config::Schema<DistributedOptions> s;
  s.field("world_size", &DistributedOptions::world_size, "processes in the run (1 = not distributed)").range(1, 4096);
  s.field("rank", &DistributedOptions::rank, "this process: 0..world_size-1 (rank 0 coordinates)").range(0, 4095);
  s.field("store", &DistributedOptions::store, "HOST:PORT of the store rank 0 hosts (every rank the same)");
  s.field("interface", &DistributedOptions::interface, "network interface for Gloo (default: this host's address)");
  s.field("timeout", &DistributedOptions::timeout, "seconds to wait for the ranks to join, and for a collective")
      .range(1, 86400);
  s.field("heartbeat_timeout", &DistributedOptions::heartbeat_timeout,
          "seconds without a heartbeat before rank 0 counts a rank as dead")
      .range(2, 86400);
  return s;
}

// ---- Store ------------------------------------------------------------------------------------

struct Store::Impl {
  c10::intrusive_ptr<c10d::Store> store;
};

namespace {
std::vector<uint8_t> bytes_of(const std::string& s) { return {s.begin(), s.end()}; }
std::string string_of(const std::vector<uint8_t>& v) { return {v.begin(), v.end()}; }
std::chrono::milliseconds millis(double seconds) {
  return std::chrono::milliseconds(static_cast<int64_t>(seconds * 1000));
}

// A connection to the store at `address`; rank 0's first connection also hosts it.
std::unique_ptr<Store> open_store(const StoreAddress& address, bool host, double timeout) {
  c10d::TCPStoreOptions o;
  o.port = address.port;
  o.isServer = host;
  o.waitWorkers = false;  // join() waits itself, and can then name the missing ranks
  o.timeout = millis(timeout);
  try {
    auto impl = std::make_unique<Store::Impl>();
    impl->store = c10::make_intrusive<c10d::TCPStore>(address.host, o);
    return std::make_unique<Store>(std::move(impl));
  } catch (const std::exception& e) {
    if (host)
      throw Error("distributed.store " + address.text(),
                  "rank 0 cannot host the store on port " + std::to_string(address.port) +
                      " (in use by another run or program? pick another port): " + e.what());
    throw Error("distributed.store " + address.text(),
                "cannot reach the store within " + std::to_string(static_cast<int>(timeout)) +
                    " s (is rank 0 running, with the same --store, and the port open?): " + e.what());
  }
}
}  // namespace

Store::Store(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Store::~Store() = default;
void Store::set(const std::string& key, const std::string& value) { impl_->store->set(key, bytes_of(value)); }
std::string Store::get(const std::string& key) { return string_of(impl_->store->get(key)); }
int64_t Store::add(const std::string& key, int64_t delta) { return impl_->store->add(key, delta); }
bool Store::check(const std::string& key) { return impl_->store->check({key}); }

// ---- World ------------------------------------------------------------------------------------

struct World::Collectives {
  c10::intrusive_ptr<c10d::ProcessGroupGloo> group;
};

World::World(DistributedOptions options) : options_(std::move(options)) {}

std::unique_ptr<World> World::join(const DistributedOptions& options) {
  if (options.rank >= options.world_size)
    throw Error("distributed.rank", "rank " + std::to_string(options.rank) + " is outside a world of " +
                                        std::to_string(options.world_size) + " (ranks 0.." +
                                        std::to_string(options.world_size - 1) + ")");
  if (options.store.empty())
    throw Error("distributed.store", "a run of " + std::to_string(options.world_size) +
                                         " processes needs the store address HOST:PORT (--store)");
  std::unique_ptr<World> world(new World(options));
  world->address_ = parse_store_address(options.store, "distributed.store");
  world->store_ = open_store(world->address_, world->coordinator(), options.timeout);
  Store& store = *world->store_;

  // Announce this rank; a second process with the same rank is a mistake in the commands.
  const std::string me = std::to_string(options.rank);
  if (store.add("join/count/" + me, 1) != 1)
    throw Error("distributed.rank", "rank " + me + " joined the store at " + world->address_.text() +
                                        " twice: give every process its own --rank");
  store.set("join/host/" + me, [] {
    char name[256] = {};
    ::gethostname(name, sizeof name - 1);
    return std::string(name) + " pid " + std::to_string(::getpid());
  }());
  if (world->coordinator()) store.set("world_size", std::to_string(options.world_size));
  const std::string size_seen = store.get("world_size");
  if (size_seen != std::to_string(options.world_size))
    throw Error("distributed.world_size", "this rank was started with world size " +
                                              std::to_string(options.world_size) + ", rank 0 with " + size_seen);
  world->heartbeat_ = std::thread([w = world.get()] { w->beat(); });
  for (int r = 0; r < options.world_size; ++r) world->wait_for("join/host/" + std::to_string(r), r, "join");
  world->joined_ = true;
  spdlog::info("distributed: {} joined ({} ranks)", world->describe(), options.world_size);
  return world;
}

World::~World() {
  stopping_ = true;
  if (heartbeat_.joinable()) heartbeat_.join();
  if (!joined_) return;  // the join failed: nobody relies on this process
  try {
    collectives_.reset();
    if (coordinator()) {
      // The store lives in this process: give the other ranks a moment to finish their last
      // operations before it goes (a dead rank never leaves: wait no longer than its silence
      // takes to count as death).
      const auto deadline = std::chrono::steady_clock::now() + millis(std::min(5.0, options_.heartbeat_timeout));
      for (int r = 1; r < size(); ++r)
        while (!store_->check("left/" + std::to_string(r)) && std::chrono::steady_clock::now() < deadline)
          std::this_thread::sleep_for(std::chrono::milliseconds(20));
    } else {
      store_->set("left/" + std::to_string(rank()), "1");
    }
  } catch (const std::exception&) {
    // Leaving a store whose host is gone: nothing left to tell anyone.
  }
}

std::string World::describe() const {
  return "rank " + std::to_string(rank()) + " of " + std::to_string(size()) + " (store " + address_.text() + ")";
}

std::unique_ptr<Store> World::connect() const { return open_store(address_, false, options_.timeout); }

int64_t World::heartbeat(Store& store, int rank) const { return store.add("heartbeat/" + std::to_string(rank), 0); }

void World::beat() {
  std::unique_ptr<Store> own;
  try {
    own = connect();
    while (!stopping_) {
      own->add("heartbeat/" + std::to_string(rank()), 1);
      for (int i = 0; i < 10 && !stopping_; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
  } catch (const std::exception& e) {
    // The store is gone (rank 0 ended): the main thread finds out at its next operation.
    if (!stopping_) spdlog::debug("distributed: heartbeat stopped: {}", e.what());
  }
}

std::string World::next_key(const std::string& tag) { return "collective/" + std::to_string(calls_++) + "/" + tag; }

void World::wait_for(const std::string& key, int who, const std::string& what) {
  const auto deadline = std::chrono::steady_clock::now() + millis(options_.timeout);
  while (!store_->check(key)) {
    if (std::chrono::steady_clock::now() > deadline)
      throw Error("distributed " + address_.text(),
                  "rank " + std::to_string(who) + " did not reach '" + what + "' within " +
                      std::to_string(static_cast<int>(options_.timeout)) + " s (" + describe() +
                      "; is every rank started, with the same --world-size and --store?)");
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
}

void World::barrier(const std::string& tag) {
  const std::string key = next_key(tag);
  store_->set(key + "/" + std::to_string(rank()), "");
  for (int r = 0; r < size(); ++r) wait_for(key + "/" + std::to_string(r), r, tag);
}

std::vector<std::string> World::gather(const std::string& tag, const std::string& bytes) {
  const std::string key = next_key(tag);
  store_->set(key + "/" + std::to_string(rank()), bytes);
  std::vector<std::string> all;
  if (!coordinator()) return all;
  for (int r = 0; r < size(); ++r) {
    wait_for(key + "/" + std::to_string(r), r, tag);
    all.push_back(store_->get(key + "/" + std::to_string(r)));
  }
  return all;
}

std::string World::broadcast(const std::string& tag, const std::string& bytes) {
  const std::string key = next_key(tag);
  if (coordinator()) store_->set(key, bytes);
  wait_for(key, 0, tag);
  return store_->get(key);
}

namespace {
c10::intrusive_ptr<c10d::ProcessGroupGloo> make_group(Store& store, const World& world) {
  auto options = c10d::ProcessGroupGloo::Options::create(millis(world.options().timeout));
  try {
    if (!world.options().interface.empty())
      options->devices.push_back(c10d::ProcessGroupGloo::createDeviceForInterface(world.options().interface));
    else if (world.address().is_loopback())
      options->devices.push_back(c10d::ProcessGroupGloo::createDeviceForHostname(world.address().host));
    else
      options->devices.push_back(c10d::ProcessGroupGloo::createDefaultDevice());
    // Gloo's own rendezvous keys stay apart from ours.
    auto prefixed = c10::make_intrusive<c10d::PrefixStore>("gloo/", store.impl().store);
    return c10::make_intrusive<c10d::ProcessGroupGloo>(prefixed, world.rank(), world.size(), options);
  } catch (const Error&) {
    throw;
  } catch (const std::exception& e) {
    throw Error("distributed " + world.describe(), std::string("cannot form the Gloo process group (set "
                                                               "distributed.interface to a network interface the "
                                                               "other machines reach): ") + e.what());
  }
}
}  // namespace

void World::allreduce_mean(const std::vector<torch::Tensor>& tensors) {
  if (tensors.empty()) return;
  if (!collectives_) collectives_ = std::make_unique<Collectives>(Collectives{make_group(*store_, *this)});
  // One flat buffer: one collective per call instead of one per tensor.
  std::vector<torch::Tensor> flat{torch::cat([&] {
    std::vector<torch::Tensor> parts;
    for (const auto& t : tensors) parts.push_back(t.detach().reshape({-1}).to(torch::kFloat64));
    return parts;
  }())};
  collectives_->group->allreduce(flat)->wait();
  flat[0].div_(size());
  int64_t offset = 0;
  for (const auto& t : tensors) {
    const int64_t n = t.numel();
    torch::NoGradGuard no_grad;
    t.copy_(flat[0].slice(0, offset, offset + n).view(t.sizes()));
    offset += n;
  }
}

void World::broadcast_tensors(const std::vector<torch::Tensor>& tensors) {
  if (!collectives_) collectives_ = std::make_unique<Collectives>(Collectives{make_group(*store_, *this)});
  for (const auto& t : tensors) {
    std::vector<torch::Tensor> one{t.detach().contiguous()};
    collectives_->group->broadcast(one)->wait();
    torch::NoGradGuard no_grad;
    if (!one[0].is_same(t)) t.copy_(one[0]);
  }
}

}  // namespace cgsr::distributed
