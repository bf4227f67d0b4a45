#include "core/error.h"

namespace cgsr {
namespace {
std::string format(const std::string& context, const std::string& what) {
  return context.empty() ? what : context + ": " + what;
}
}  // namespace

Error::Error(std::string context, const std::string& what, ErrorKind kind)
    : std::runtime_error(format(context, what)),
      context_(std::move(context)),
      message_(what),
      kind_(kind) {}

Error Error::within(const std::string& outer) const {
  return Error(context_.empty() ? outer : outer + ": " + context_, message_, kind_);
}

}  // namespace cgsr
