#pragma once
// Guards at data boundaries: shapes and finiteness, with errors that say where.

#include <torch/types.h>

#include <string>

namespace cgsr {

std::string shape_string(const torch::Tensor& t);  // "[1, 3, 64, 64]"

// Throws cgsr::Error(context, "contains N NaN and M infinite values") when not all finite.
void require_finite(const torch::Tensor& t, const std::string& context);

// Counts of NaN and +-Inf entries, for reports that count instead of failing.
struct NonFiniteCount {
  int64_t nan = 0;
  int64_t inf = 0;
  bool any() const { return nan + inf > 0; }
};
NonFiniteCount count_non_finite(const torch::Tensor& t);

}  // namespace cgsr
