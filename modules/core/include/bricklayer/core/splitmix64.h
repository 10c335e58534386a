#pragma once
// SplitMix64 (Steele, Lea and Flood, "Fast splittable pseudorandom number generators", 2014), the one
// generator behind the generated piles, simcam's noise and the benchmarks' seeds. It is written out here
// rather than taken from <random> because the standard fixes mt19937's sequence but not what its
// distributions make of it: these bit operations give the same numbers with every compiler and library,
// so a seed names the same pile and the same camera frame everywhere.
#include <cstdint>

namespace bricklayer::core {

// Advances the state by the golden-ratio increment and returns the mixed 64 bits.
inline uint64_t splitmix64(uint64_t& state) {
  uint64_t z = (state += 0x9E3779B97F4A7C15ULL);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

// The top 53 bits as a double in [0, 1): every value is exact and equally likely.
inline double unit_double(uint64_t bits) { return static_cast<double>(bits >> 11) * (1.0 / 9007199254740992.0); }

}  // namespace bricklayer::core
