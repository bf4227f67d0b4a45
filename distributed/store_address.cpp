#include "distributed/store_address.h"

#include <cctype>

#include "core/error.h"

namespace cgsr::distributed {

bool StoreAddress::is_loopback() const {
  return host == "localhost" || host == "::1" || host.rfind("127.", 0) == 0;
}

StoreAddress parse_store_address(const std::string& text, const std::string& context) {
  const auto bad = [&](const std::string& why) {
    return Error(context, "'" + text + "' is not a store address HOST:PORT (" + why + "), e.g. 10.0.0.1:29500");
  };
  const size_t colon = text.rfind(':');
  if (colon == std::string::npos) throw bad("no ':PORT'");
  std::string host = text.substr(0, colon);
  const std::string port_text = text.substr(colon + 1);
  if (host.size() >= 2 && host.front() == '[' && host.back() == ']') host = host.substr(1, host.size() - 2);
  else if (host.find(':') != std::string::npos) throw bad("an IPv6 host goes in brackets, [::1]:29500");
  if (host.empty()) throw bad("no host");
  if (port_text.empty() || port_text.size() > 5) throw bad("the port is not a number from 1 to 65535");
  for (char c : port_text)
    if (!std::isdigit(static_cast<unsigned char>(c))) throw bad("the port is not a number from 1 to 65535");
  const int port = std::stoi(port_text);
  if (port < 1 || port > 65535) throw bad("the port is not a number from 1 to 65535");
  return {host, static_cast<uint16_t>(port)};
}

}  // namespace cgsr::distributed
