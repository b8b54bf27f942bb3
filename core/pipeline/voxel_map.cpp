#include "core/pipeline/voxel_map.hpp"

#include <algorithm>
#include <cmath>

#include "core/util/log.hpp"
#include "core/util/voxel_hash.hpp"

namespace rotolidar {

VoxelMap::VoxelMap(double voxel_size_m, int max_points_per_voxel)
    : voxel_size_m_(voxel_size_m),
      max_points_per_voxel_(max_points_per_voxel),
      min_spacing_m_(voxel_size_m / std::sqrt(double(max_points_per_voxel))) {
  ROTOLIDAR_CHECK(voxel_size_m > 0 && max_points_per_voxel >= 1, "bad VoxelMap parameters");
}

VoxelMap::Key VoxelMap::KeyOf(const Eigen::Vector3d& p) const {
  return {int32_t(std::floor(p.x() / voxel_size_m_)), int32_t(std::floor(p.y() / voxel_size_m_)),
          int32_t(std::floor(p.z() / voxel_size_m_))};
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

VoxelMap::Key VoxelMap::BlockKeyOf(const Key& v) {
  return {v.x >> kBlockBits, v.y >> kBlockBits, v.z >> kBlockBits};  // arithmetic shift: floor division
}

size_t VoxelMap::BitOf(const Key& v) {
  const uint32_t m = kBlock - 1;
  return size_t(uint32_t(v.x) & m) | size_t(uint32_t(v.y) & m) << kBlockBits |
         size_t(uint32_t(v.z) & m) << (2 * kBlockBits);
}

VoxelMap::BlockBits* VoxelMap::FindBlock(const Key& block_key, bool create) {
  if (last_block_ != nullptr && last_block_key_ == block_key) return last_block_;
  if (block_table_.empty() || (create && 2 * (blocks_.size() + 1) > block_table_.size())) {
    std::vector<BlockSlot> old = std::move(block_table_);
    block_table_.assign(std::max<size_t>(256, 2 * old.size()), BlockSlot{{0, 0, 0}, kEmpty});
    for (const BlockSlot& b : old)
      if (b.block != kEmpty) {
        size_t slot = size_t(VoxelHash(b.key.x, b.key.y, b.key.z)) & (block_table_.size() - 1);
        while (block_table_[slot].block != kEmpty) slot = (slot + 1) & (block_table_.size() - 1);
        block_table_[slot] = b;
      }
  }
  const size_t mask = block_table_.size() - 1;
  size_t slot = size_t(VoxelHash(block_key.x, block_key.y, block_key.z)) & mask;
  while (block_table_[slot].block != kEmpty && !(block_table_[slot].key == block_key)) slot = (slot + 1) & mask;
  if (block_table_[slot].block == kEmpty) {
    if (!create) return nullptr;
    block_table_[slot] = BlockSlot{block_key, uint32_t(blocks_.size())};
    blocks_.push_back(std::make_unique<BlockBits>());
    blocks_.back()->fill(0);
  }
  last_block_key_ = block_key;
  last_block_ = blocks_[block_table_[slot].block].get();
  return last_block_;
}

void VoxelMap::MarkFull(const Key& voxel) {
  const size_t bit = BitOf(voxel);
  (*FindBlock(BlockKeyOf(voxel), true))[bit >> 6] |= uint64_t(1) << (bit & 63);
}

void VoxelMap::RebuildFullBits() {
  block_table_.clear();
  blocks_.clear();
  last_block_ = nullptr;
  for (size_t v = 0; v < keys_.size(); ++v)
    if (counts_[v] >= uint32_t(max_points_per_voxel_)) MarkFull(keys_[v]);
}

void VoxelMap::Add(const std::vector<Eigen::Vector3d>& p_world) {
  // Room for every point to open a voxel, so the table stays put during the loop.
  size_t num_slots = std::max<size_t>(table_.size(), 1024);
  while (2 * (keys_.size() + p_world.size()) > num_slots) num_slots *= 2;
  if (num_slots != table_.size()) Rehash(num_slots);
  const double min_sq = min_spacing_m_ * min_spacing_m_;
  const size_t per_voxel = size_t(max_points_per_voxel_);
  for (size_t i = 0; i < p_world.size(); ++i) {
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
    }
    const size_t v = table_[slot].voxel;
    uint32_t& count = counts_[v];
    if (count >= per_voxel) continue;
    Eigen::Vector3d* pts = points_.data() + v * per_voxel;
    bool far_enough = true;
    for (uint32_t j = 0; j < count; ++j) far_enough = far_enough && (pts[j] - p).squaredNorm() >= min_sq;
    if (!far_enough) continue;
    pts[count++] = p;
    ++num_points_;
    if (count >= per_voxel) MarkFull(key);
  }
}

void VoxelMap::RemoveFar(const Eigen::Vector3d& center_world, double max_distance_m) {
  const double max_sq = max_distance_m * max_distance_m;
  const size_t per_voxel = size_t(max_points_per_voxel_);
  size_t kept = 0;
  num_points_ = 0;
  for (size_t v = 0; v < keys_.size(); ++v) {  // compact in place, insertion order kept
    if (counts_[v] == 0 || (points_[v * per_voxel] - center_world).squaredNorm() > max_sq) continue;
    keys_[kept] = keys_[v];
    counts_[kept] = counts_[v];
    std::copy_n(points_.begin() + long(v * per_voxel), per_voxel, points_.begin() + long(kept * per_voxel));
    num_points_ += counts_[kept];
    ++kept;
  }
  keys_.resize(kept);
  counts_.resize(kept);
  points_.resize(kept * per_voxel);
  if (!table_.empty()) Rehash(table_.size());
  RebuildFullBits();
}

std::vector<Eigen::Vector3d> VoxelMap::Points() const {
  std::vector<Eigen::Vector3d> out;
  out.reserve(num_points_);
  const size_t per_voxel = size_t(max_points_per_voxel_);
  for (size_t v = 0; v < keys_.size(); ++v)
    out.insert(out.end(), points_.begin() + long(v * per_voxel), points_.begin() + long(v * per_voxel + counts_[v]));
  return out;
}

size_t VoxelMap::NumPoints() const { return num_points_; }

}  // namespace rotolidar
