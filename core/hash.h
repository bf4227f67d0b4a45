#pragma once
// FNV-1a, 64 bit: the project's one non-cryptographic hash (model file checksums, cache keys,
// seeds derived from names).

#include <cstdint>
#include <string_view>

namespace cgsr {

// The published FNV-1a 64 offset basis and prime.
inline constexpr uint64_t kFnv1a64OffsetBasis = 14695981039346656037ull;
inline constexpr uint64_t kFnv1a64Prime = 1099511628211ull;

// The basis cgsr used before it had this header: the real one with its last digit dropped. Seeds,
// render fingerprints and stage cache keys keep it so that every reproduced result stays the same,
// and version 1 model files were checksummed with it.
inline constexpr uint64_t kLegacyFnv1a64Basis = 1469598103934665603ull;

// FNV-1a 64 of `bytes`, starting from `basis`.
uint64_t fnv1a64(std::string_view bytes, uint64_t basis = kFnv1a64OffsetBasis);

}  // namespace cgsr
