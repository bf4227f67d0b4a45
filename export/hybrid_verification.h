#pragma once
// Verification of an exported hybrid model (hybrid_export.h): every pattern file in the runtimes
// of its format (verification.h) against cgsr's own run of that pattern (PatternNetworks::run),
// and the selector in ONNX Runtime against DynamicSamplers on sampler inputs of several frames:
// a first frame (the current information passed twice), frames with a previous one, and one
// with motion beyond a frame width (the clamp). A selector check passes when the scores are
// within the tolerance and the chosen pattern is the same.
//
//   VerifyReport r = verify_hybrid_export(model, exported, VerifyOptions(), /*seed=*/1);

#include <cstdint>

#include "export/hybrid_export.h"
#include "export/verification.h"

namespace cgsr {

VerifyReport verify_hybrid_export(const HybridModel& model, const HybridExport& exported, const VerifyOptions& options,
                                  uint64_t seed);

}  // namespace cgsr
