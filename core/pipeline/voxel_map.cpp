#include "core/pipeline/voxel_map.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/util/log.hpp"
#include "core/util/voxel_hash.hpp"

namespace rotolidar {

VoxelMap::VoxelMap(double voxel_size_m, int max_points_per_voxel)
    : voxel_size_m_(voxel_size_m),
      max_points_per_voxel_(max_points_per_voxel),
      min_spacing_m_(voxel_size_m / std::sqrt(double(max_points_per_voxel))),
      points_(size_t(std::max(1, max_points_per_voxel)) << 13) {  // chunks of whole voxels
  ROTOLIDAR_CHECK(voxel_size_m > 0 && max_points_per_voxel >= 1, "bad VoxelMap parameters");
}

namespace {

/// int32_t(std::floor(d)) without the libm call (no SSE4.1 round instruction in the baseline ISA): exact for every
/// d whose floor fits int32_t (the only case where the cast is defined).
inline int32_t FloorToInt(double d) {
  const int64_t i = int64_t(d);  // truncation toward zero
  return int32_t(double(i) > d ? i - 1 : i);
}

}  // namespace

inline VoxelMap::Key VoxelMap::KeyOf(const Eigen::Vector3d& p) const {
  return {FloorToInt(p.x() / voxel_size_m_), FloorToInt(p.y() / voxel_size_m_), FloorToInt(p.z() / voxel_size_m_)};
}

size_t VoxelMap::HomeSlot(const Key& key) const {
  return size_t(VoxelHash(key.x, key.y, key.z)) & (table_.size() - 1);
}

size_t VoxelMap::SlotOf(const Key& key) const {
  const size_t mask = table_.size() - 1;
  size_t slot = HomeSlot(key);
  while (table_[slot].voxel != kEmpty && !(table_[slot].key == key)) slot = (slot + 1) & mask;
  return slot;
}

void VoxelMap::Rehash(size_t num_slots) {
  table_.assign(num_slots, Slot{{0, 0, 0}, kEmpty});
  for (size_t v = 0; v < keys_.size(); ++v) table_[SlotOf(keys_[v])] = Slot{keys_[v], uint32_t(v)};
}

VoxelMap::Key VoxelMap::KeyOfVoxel(size_t v) const {
  return max_points_per_voxel_ == 1 ? KeyOf(points_[v]) : keys_[v];
}

inline VoxelMap::Key VoxelMap::BlockKeyOf(const Key& v) {
  return {v.x >> kBlockBits, v.y >> kBlockBits, v.z >> kBlockBits};  // arithmetic shift: floor division
}

// Brick layout: bits 0-5 a 4^3 brick (one word), bits 6-8 a 2^3 group of bricks (one 64-byte line: 8^3 voxels),
// bits 9-14 the line within the block. Any surface through a line's 40 cm cube shares it (a row-major layout
// gave a vertical wall a new line per 5 cm of height: a cache miss per point).
inline size_t VoxelMap::CacheSlotOf(const Key& b) {
  return size_t(uint32_t(b.x) * 73856093u ^ uint32_t(b.y) * 19349663u ^ uint32_t(b.z) * 83492791u) % kBlockCache;
}

inline size_t VoxelMap::BitOf(const Key& v) {
  const uint32_t x = uint32_t(v.x), y = uint32_t(v.y), z = uint32_t(v.z);
  const auto field = [&](int shift, uint32_t mask, int width) {
    return size_t((x >> shift) & mask) | size_t((y >> shift) & mask) << width |
           size_t((z >> shift) & mask) << (2 * width);
  };
  return field(0, 3, 2) | field(2, 1, 1) << 6 | field(3, 3, 2) << 9;
}

VoxelMap::BlockBits* VoxelMap::FindBlock(const Key& block_key, bool create) {
  BlockCacheEntry& cached = block_cache_[CacheSlotOf(block_key)];
  if (cached.bits != nullptr && cached.key == block_key) return cached.bits;
  if (block_table_.empty() || (create && 2 * (blocks_.size() + 1) > block_table_.size())) {
    std::vector<BlockSlot> old = std::move(block_table_);
    block_table_.assign(std::max<size_t>(256, 2 * old.size()), BlockSlot{{0, 0, 0}, kEmpty});
    for (const BlockSlot& b : old)
      if (b.block != kEmpty) block_table_[BlockSlotOf(b.key)] = b;
  }
  const size_t slot = BlockSlotOf(block_key);
  if (block_table_[slot].block == kEmpty) {
    if (!create) return nullptr;
    block_table_[slot] = BlockSlot{block_key, uint32_t(blocks_.size())};
    blocks_.push_back(std::make_unique<BlockBits>());
    blocks_.back()->fill(0);
  }
  cached = BlockCacheEntry{block_key, blocks_[block_table_[slot].block].get()};
  return cached.bits;
}

size_t VoxelMap::BlockSlotOf(const Key& block_key) const {
  const size_t mask = block_table_.size() - 1;
  size_t slot = size_t(VoxelHash(block_key.x, block_key.y, block_key.z)) & mask;
  while (block_table_[slot].block != kEmpty && !(block_table_[slot].key == block_key)) slot = (slot + 1) & mask;
  return slot;
}

bool VoxelMap::Full(const Eigen::Vector3d& p_world) const {
  const Key key = KeyOf(p_world);
  const Key block_key = BlockKeyOf(key);
  const BlockBits* bits = nullptr;
  const BlockCacheEntry& cached = block_cache_[CacheSlotOf(block_key)];
  if (cached.bits != nullptr && cached.key == block_key) {
    bits = cached.bits;
  } else if (!block_table_.empty()) {
    const size_t slot = BlockSlotOf(block_key);
    if (block_table_[slot].block != kEmpty) bits = blocks_[block_table_[slot].block].get();
  }
  if (bits == nullptr) return false;
  const size_t bit = BitOf(key);
  return ((*bits)[bit >> 6] >> (bit & 63)) & 1;
}

void VoxelMap::MarkFull(const Key& voxel) {
  const size_t bit = BitOf(voxel);
  (*FindBlock(BlockKeyOf(voxel), true))[bit >> 6] |= uint64_t(1) << (bit & 63);
}

void VoxelMap::ClearFull(const Key& voxel) {
  const size_t bit = BitOf(voxel);
  if (BlockBits* bits = FindBlock(BlockKeyOf(voxel), false)) (*bits)[bit >> 6] &= ~(uint64_t(1) << (bit & 63));
}

void VoxelMap::RebuildFullBits() {
  block_table_.clear();
  blocks_.clear();
  block_cache_.fill(BlockCacheEntry{});
  const size_t per_voxel = size_t(max_points_per_voxel_);
  for (size_t v = 0; v < num_voxels_; ++v)
    if (CountOf(v) >= per_voxel && !std::isnan(points_[v * per_voxel].x())) MarkFull(KeyOfVoxel(v));
}

// A removed point becomes NaN (a tombstone): indices of the others stay valid, and nothing is moved.
bool VoxelMap::Remove(size_t index) {
  Eigen::Vector3d& p = points_[index];
  if (std::isnan(p.x())) return false;
  const Key key = max_points_per_voxel_ == 1 ? KeyOf(p) : keys_[index / size_t(max_points_per_voxel_)];
  p.setConstant(std::numeric_limits<double>::quiet_NaN());
  --num_points_;
  if (max_points_per_voxel_ == 1) ClearFull(key);
  return true;
}

// One point per voxel: a voxel exists iff it is full, so its bit is the whole index and the large voxel table is
// never probed (a new voxel costs appends and one bit, no cache miss into table_).
void VoxelMap::AddOnePerVoxel(const Eigen::Vector3d* p_world, size_t n, std::vector<size_t>* kept) {
  constexpr size_t kBatch = 64;  // pass 1 finds (and prefetches) the words, pass 2 tests them in order
  uint64_t* words[kBatch];
  uint64_t masks[kBatch];
  Key keys[kBatch];
  for (size_t begin = 0; begin < n; begin += kBatch) {
    const size_t count = std::min(kBatch, n - begin);
    for (size_t i = 0; i < count; ++i) {
      const Key key = KeyOf(p_world[begin + i]);
      const size_t bit = BitOf(key);
      const Key block_key = BlockKeyOf(key);
      BlockBits* bits = FindBlock(block_key, true);
      keys[i] = key;
      words[i] = &(*bits)[bit >> 6];
      masks[i] = uint64_t(1) << (bit & 63);
      __builtin_prefetch(words[i], 1);
    }
    for (size_t i = 0; i < count; ++i) {
      if (*words[i] & masks[i]) continue;  // the voxel is full
      *words[i] |= masks[i];
      if (kept) kept->push_back(points_.size());
      points_.push_back(p_world[begin + i]);
      ++num_voxels_;
      ++num_points_;
    }
  }
}

void VoxelMap::Add(const std::vector<Eigen::Vector3d>& p_world) { Add(p_world.data(), p_world.size()); }

void VoxelMap::Add(const Eigen::Vector3d* p_world, size_t n, std::vector<size_t>* kept) {
  if (max_points_per_voxel_ == 1) return AddOnePerVoxel(p_world, n, kept);
  // Room for every point to open a voxel, so the table stays put during the loop.
  size_t num_slots = std::max<size_t>(table_.size(), 1024);
  while (2 * (keys_.size() + n) > num_slots) num_slots *= 2;
  if (num_slots != table_.size()) Rehash(num_slots);
  const double min_sq = min_spacing_m_ * min_spacing_m_;
  const size_t per_voxel = size_t(max_points_per_voxel_);
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d& p = p_world[i];
    const Key key = KeyOf(p);
    if (const BlockBits* bits = FindBlock(BlockKeyOf(key), false)) {
      const size_t bit = BitOf(key);
      if (((*bits)[bit >> 6] >> (bit & 63)) & 1) continue;  // the voxel is full
    }
    const size_t slot = SlotOf(key);
    if (table_[slot].voxel == kEmpty) {  // a new voxel: its first point always fits
      table_[slot] = Slot{key, uint32_t(keys_.size())};
      keys_.push_back(key);
      counts_.push_back(0);
      points_.resize(points_.size() + per_voxel);
      ++num_voxels_;
    }
    const size_t v = table_[slot].voxel;
    uint32_t& count = counts_[v];
    if (count >= per_voxel) continue;
    Eigen::Vector3d* pts = &points_[v * per_voxel];  // a chunk holds whole voxels: contiguous
    bool far_enough = true;
    for (uint32_t j = 0; j < count; ++j) far_enough = far_enough && !((pts[j] - p).squaredNorm() < min_sq);
    if (!far_enough) continue;  // (a removed point, NaN, is far from everything)
    if (kept) kept->push_back(v * per_voxel + count);
    pts[count++] = p;
    ++num_points_;
    if (count >= per_voxel) MarkFull(key);
  }
}

void VoxelMap::RemoveFar(const Eigen::Vector3d& center_world, double max_distance_m) {
  const double max_sq = max_distance_m * max_distance_m;
  const size_t per_voxel = size_t(max_points_per_voxel_);
  const bool one = per_voxel == 1;
  size_t kept = 0;
  num_points_ = 0;
  for (size_t v = 0; v < num_voxels_; ++v) {  // compact in place, insertion order kept
    const Eigen::Vector3d* live = nullptr;  // the voxel's first point not removed decides
    for (uint32_t j = 0; j < CountOf(v) && !live; ++j)
      if (!std::isnan(points_[v * per_voxel + j].x())) live = &points_[v * per_voxel + j];
    if (!live || (*live - center_world).squaredNorm() > max_sq) continue;
    if (!one) {
      keys_[kept] = keys_[v];
      counts_[kept] = counts_[v];
    }
    for (size_t j = 0; j < per_voxel; ++j) points_[kept * per_voxel + j] = points_[v * per_voxel + j];
    for (uint32_t j = 0; j < CountOf(kept); ++j) num_points_ += !std::isnan(points_[kept * per_voxel + j].x());
    ++kept;
  }
  num_voxels_ = kept;
  if (!one) {
    keys_.resize(kept);
    counts_.resize(kept);
  }
  points_.resize(kept * per_voxel);
  if (!table_.empty()) Rehash(table_.size());
  RebuildFullBits();
}

std::vector<Eigen::Vector3d> VoxelMap::Points() const {
  std::vector<Eigen::Vector3d> out;
  out.reserve(num_points_);
  const size_t per_voxel = size_t(max_points_per_voxel_);
  for (size_t v = 0; v < num_voxels_; ++v)
    for (uint32_t j = 0; j < CountOf(v); ++j)
      if (!std::isnan(points_[v * per_voxel + j].x())) out.push_back(points_[v * per_voxel + j]);
  return out;
}

size_t VoxelMap::NumPoints() const { return num_points_; }

}  // namespace rotolidar
