#pragma once

#include <cstdint>

namespace imumatch {

// SplitMix64's finaliser (Steele, Lea and Flood 2014): spreads a seed's bits so that neighbouring
// seeds (a scene's seed times a surface index, a vertex index) start unrelated random streams.
// The scene's textures and the renderer's sensor noise derive their generators' seeds with it.
inline uint64_t SplitMix64(uint64_t x) {
  x += 0x9E3779B97F4A7C15ULL;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ULL;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBULL;
  return x ^ (x >> 31);
}

}  // namespace imumatch
