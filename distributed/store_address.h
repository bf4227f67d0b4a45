#pragma once
// The rendezvous address of a distributed run, "HOST:PORT": rank 0 hosts the key-value store
// there and every other rank connects to it.

#include <cstdint>
#include <string>

namespace cgsr::distributed {

struct StoreAddress {
  std::string host;
  uint16_t port = 0;
  std::string text() const { return host + ":" + std::to_string(port); }
  // 127.x.x.x, localhost or ::1: every rank runs on this machine.
  bool is_loopback() const;
};

// Parses "HOST:PORT" (an IPv6 host in brackets: "[::1]:29500"); a bad text is an Error naming
// `context` (the option or config key it came from).
StoreAddress parse_store_address(const std::string& text, const std::string& context);

}  // namespace cgsr::distributed
