#pragma once
// One hash for integer voxel coordinates, shared by the open-addressing voxel tables (core/preprocess voxel
// filter, core/pipeline VoxelMap). Multiplicative mixing per axis, then a shift-xor so that the low bits (the
// table slot under a power-of-two mask) depend on every axis.
#include <cstdint>

namespace rotolidar {

inline uint64_t VoxelHash(int64_t x, int64_t y, int64_t z) {
  const uint64_t h = static_cast<uint64_t>(x) * 0x9E3779B97F4A7C15ull ^ static_cast<uint64_t>(y) * 0xC2B2AE3D27D4EB4Full ^
                     static_cast<uint64_t>(z) * 0x165667B19E3779F9ull;
  return h ^ (h >> 29);
}

}  // namespace rotolidar
