#pragma once
// What the search knows about a subnet: its config in, scores out. The inference evaluator
// (subnet_evaluator.h) scores subnets of a trained elastic network without training them; tests
// inject their own.

#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>

#include "core/json_fields.h"
#include "models/subnet.h"

namespace cgsr {

struct SubnetScore {
  double psnr = 0;                   // on the validation crops (dB)
  std::optional<double> psnr_edge;   // on their geometry-edge pixels, when the data has edges
  double latency_ms = 0;             // predicted by the latency table
  int64_t params = 0, macs = 0;      // inference network, MACs at the table's LR size
};
CGSR_JSON_FIELDS(SubnetScore, psnr, psnr_edge, latency_ms, params, macs)

class Evaluator {
 public:
  virtual ~Evaluator() = default;
  // Deterministic for a given subnet, so that a resumed search reaches the same result. A
  // subnet that cannot be scored (its output is not finite) throws cgsr::Error.
  virtual SubnetScore evaluate(const SubnetConfig& subnet) = 0;
};

}  // namespace cgsr
