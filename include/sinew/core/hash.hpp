// Deterministic pseudo-random numbers from integers (splitmix64 finalizer): the same value on every
// rank and thread for the same global id, so randomized inputs (scramble, jitter) do not depend on the
// partition.
#pragma once

#include <Kokkos_Macros.hpp>

#include <cstdint>

namespace sinew {

// Uniform in [0, 1) from (id, component, seed).
KOKKOS_INLINE_FUNCTION double unit_hash(std::int64_t id, int component, int seed) {
  std::uint64_t x = static_cast<std::uint64_t>(id) * 3 + static_cast<std::uint64_t>(component) +
                    0x9E3779B97F4A7C15ull * static_cast<std::uint64_t>(seed);
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  x ^= x >> 31;
  return static_cast<double>(x >> 11) * (1.0 / 9007199254740992.0);
}

}  // namespace sinew
