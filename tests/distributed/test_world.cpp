// The distributed module in one process: ranks are threads, each with its own World (its own
// store connections and Gloo pair), on a port the kernel just handed out.
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <torch/torch.h>
#include <unistd.h>

#include <future>
#include <set>

#include "core/error.h"
#include "distributed/world.h"
#include "tests/support/free_port.h"

namespace cgsr::distributed {
namespace {

DistributedOptions options_for(int rank, int size, int port, double timeout = 20) {
  DistributedOptions o;
  o.world_size = size;
  o.rank = rank;
  o.store = "127.0.0.1:" + std::to_string(port);
  o.timeout = timeout;
  return o;
}

// Runs `body(world)` on `size` ranks (threads) and returns their results in rank order.
template <class F>
auto on_ranks(int size, F body) {
  const int port = test::free_port();
  std::vector<std::future<decltype(body(std::declval<World&>()))>> ranks;
  for (int r = 0; r < size; ++r)
    ranks.push_back(std::async(std::launch::async, [=] {
      auto world = World::join(options_for(r, size, port));
      return body(*world);
    }));
  std::vector<decltype(body(std::declval<World&>()))> results;
  for (auto& f : ranks) results.push_back(f.get());
  return results;
}

std::string message_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(StoreAddress, ParsesHostAndPortAndNamesTheKeyOfABadOne) {
  EXPECT_EQ(parse_store_address("10.0.0.1:29500", "k").host, "10.0.0.1");
  EXPECT_EQ(parse_store_address("10.0.0.1:29500", "k").port, 29500);
  EXPECT_EQ(parse_store_address("[::1]:80", "k").host, "::1");
  EXPECT_TRUE(parse_store_address("localhost:1", "k").is_loopback());
  EXPECT_FALSE(parse_store_address("node7:1", "k").is_loopback());
  for (const std::string bad : {"node7", "node7:", ":29500", "node7:http", "node7:70000", "::1:80"}) {
    const std::string m = message_of([&] { parse_store_address(bad, "--store"); });
    EXPECT_NE(m.find("--store"), std::string::npos) << bad << ": " << m;
    EXPECT_NE(m.find("HOST:PORT"), std::string::npos) << bad << ": " << m;
  }
}

TEST(World, RanksMeetAverageGatherAndBroadcast) {
  const auto results = on_ranks(3, [](World& world) {
    // Each rank holds rank + 1 (and its square): the mean is the same on every rank.
    std::vector<torch::Tensor> t{torch::full({2, 3}, float(world.rank() + 1)),
                                 torch::full({4}, float((world.rank() + 1) * (world.rank() + 1)))};
    world.allreduce_mean(t);
    const auto gathered = world.gather("names", std::string(world.rank() + 1, 'x'));  // different sizes
    const std::string shared = world.broadcast("word", world.coordinator() ? "from rank 0" : "ignored");
    world.barrier("end");
    return std::make_tuple(t[0].mean().item<float>(), t[1].mean().item<float>(), gathered, shared);
  });
  for (int r = 0; r < 3; ++r) {
    EXPECT_FLOAT_EQ(std::get<0>(results[r]), 2.0f);             // (1 + 2 + 3) / 3
    EXPECT_FLOAT_EQ(std::get<1>(results[r]), 14.0f / 3.0f);     // (1 + 4 + 9) / 3
    EXPECT_EQ(std::get<3>(results[r]), "from rank 0");
  }
  EXPECT_EQ(std::get<2>(results[0]), (std::vector<std::string>{"x", "xx", "xxx"}));
  EXPECT_TRUE(std::get<2>(results[1]).empty());
}

TEST(World, ClearErrorsForBadRanksBusyPortsAndMissingPeers) {
  EXPECT_NE(message_of([] { World::join(options_for(2, 2, test::free_port())); }).find("outside a world of 2"),
            std::string::npos);
  DistributedOptions no_store = options_for(0, 2, 1);
  no_store.store.clear();
  EXPECT_NE(message_of([&] { World::join(no_store); }).find("--store"), std::string::npos);

  // A port another program listens on.
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_ANY);
  socklen_t size = sizeof address;
  ASSERT_EQ(::bind(fd, reinterpret_cast<sockaddr*>(&address), sizeof address), 0);
  ASSERT_EQ(::listen(fd, 1), 0);
  ASSERT_EQ(::getsockname(fd, reinterpret_cast<sockaddr*>(&address), &size), 0);
  const std::string busy = message_of([&] { World::join(options_for(0, 2, ntohs(address.sin_port), 2)); });
  ::close(fd);
  EXPECT_NE(busy.find("cannot host the store on port " + std::to_string(ntohs(address.sin_port))), std::string::npos)
      << busy;

  // Rank 0 alone: rank 1 never comes.
  const std::string alone = message_of([] { World::join(options_for(0, 2, test::free_port(), 1)); });
  EXPECT_NE(alone.find("rank 1 did not reach 'join'"), std::string::npos) << alone;
  // Rank 1 alone: nobody hosts the store.
  const std::string lost = message_of([] { World::join(options_for(1, 2, test::free_port(), 1)); });
  EXPECT_NE(lost.find("cannot reach the store"), std::string::npos) << lost;
}

}  // namespace
}  // namespace cgsr::distributed
