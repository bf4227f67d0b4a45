#include "core/tensor_checks.h"

#include "core/error.h"

namespace cgsr {

std::string shape_string(const torch::Tensor& t) {
  std::string s = "[";
  for (int64_t i = 0; i < t.dim(); ++i) s += (i ? ", " : "") + std::to_string(t.size(i));
  return s + "]";
}

NonFiniteCount count_non_finite(const torch::Tensor& t) {
  if (!t.is_floating_point()) return {};
  return {torch::isnan(t).sum().item<int64_t>(), torch::isinf(t).sum().item<int64_t>()};
}

void require_finite(const torch::Tensor& t, const std::string& context) {
  if (!t.is_floating_point() || torch::isfinite(t).all().item<bool>()) return;
  const auto count = count_non_finite(t);
  throw Error(context, "contains " + std::to_string(count.nan) + " NaN and " + std::to_string(count.inf) +
                           " infinite value(s)");
}

}  // namespace cgsr
