#include "core/registration/voxel_centroids.hpp"

#include <algorithm>
#include <cmath>

#include "core/util/log.hpp"
#include "core/util/voxel_hash.hpp"

namespace rotolidar {
namespace {

constexpr int kAxisBits = 21;
constexpr uint64_t kAxisMask = (uint64_t(1) << kAxisBits) - 1;

int64_t Unpack(uint64_t key, int axis) {
  const uint64_t v = (key >> (kAxisBits * axis)) & kAxisMask;
  return int64_t(v << (64 - kAxisBits)) >> (64 - kAxisBits);  // sign-extend
}

}  // namespace

VoxelCentroidTable::VoxelCentroidTable(double voxel_m) {
  ROTOLIDAR_CHECK(voxel_m > 0, "voxel_m = " << voxel_m);
  inverse_leaf_ = 1.0f / float(voxel_m);  // as VoxelGrid: Array4f::Ones() / leaf_size_
}

uint64_t VoxelCentroidTable::KeyOf(const pcl::PointXYZI& p) const {
  const float c[3] = {p.x, p.y, p.z};
  uint64_t key = 0;
  for (int axis = 0; axis < 3; ++axis) {
    const int64_t i = int64_t(std::floor(c[axis] * inverse_leaf_));
    key |= (uint64_t(i) & kAxisMask) << (kAxisBits * axis);
  }
  return key;
}

size_t VoxelCentroidTable::Home(uint64_t key) const {
  return size_t(VoxelHash(Unpack(key, 0), Unpack(key, 1), Unpack(key, 2))) & (index_.size() - 1);
}

size_t VoxelCentroidTable::Find(uint64_t key) const {
  const size_t mask = index_.size() - 1;
  size_t slot = Home(key);
  while (index_[slot] != kEmpty && voxels_[index_[slot]].key != key) slot = (slot + 1) & mask;
  return slot;
}

void VoxelCentroidTable::Erase(size_t slot) {
  const size_t mask = index_.size() - 1;
  index_[slot] = kEmpty;
  for (size_t next = (slot + 1) & mask; index_[next] != kEmpty; next = (next + 1) & mask) {
    const size_t home = Home(voxels_[index_[next]].key);
    // `next` may move into the hole at `slot` unless its home lies cyclically in (slot, next].
    const bool stays = slot <= next ? (slot < home && home <= next) : (slot < home || home <= next);
    if (stays) continue;
    index_[slot] = index_[next];
    index_[next] = kEmpty;
    slot = next;
  }
}

void VoxelCentroidTable::Grow() {
  index_.assign(std::max<size_t>(1024, 2 * index_.size()), kEmpty);
  for (size_t i = 0; i < voxels_.size(); ++i)
    if (voxels_[i].count != 0) index_[Find(voxels_[i].key)] = uint32_t(i);
}

void VoxelCentroidTable::Accumulate(const pcl::PointXYZI& p, const Eigen::Vector3f& sensor, int sign) {
  if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) return;
  if (2 * (live_ + 1) > index_.size()) Grow();  // load factor <= 1/2
  const uint64_t key = KeyOf(p);
  const size_t slot = Find(key);
  if (index_[slot] == kEmpty) {
    ROTOLIDAR_CHECK(sign > 0, "VoxelCentroidTable::Remove of a point that was never added");
    index_[slot] = uint32_t(voxels_.size());
    voxels_.push_back(Voxel{key, 0, 0, 0, 0, 0, 0, 0, 0});
    touched_flag_.push_back(0);
    ++live_;
  }
  const uint32_t position = index_[slot];
  if (!touched_flag_[position]) {
    touched_flag_[position] = 1;
    touched_.push_back(position);
  }
  Voxel& v = voxels_[position];
  v.count += sign;
  if (v.count == 0) {  // exact reset: no rounding residue survives the voxel
    v = Voxel{key, 0, 0, 0, 0, 0, 0, 0, 0};
    Erase(slot);
    --live_;
    ++dead_;
    return;
  }
  v.x += sign * double(p.x);
  v.y += sign * double(p.y);
  v.z += sign * double(p.z);
  v.intensity += sign * double(p.intensity);
  const Eigen::Vector3f view = sensor - Eigen::Vector3f(p.x, p.y, p.z);
  const float norm = view.norm();
  if (norm > 0) {  // the same float operations for Add and Remove: the subtraction is exact
    v.vx += sign * double(view.x() / norm);
    v.vy += sign * double(view.y() / norm);
    v.vz += sign * double(view.z() / norm);
  }
}

void VoxelCentroidTable::Add(const pcl::PointCloud<pcl::PointXYZI>& points, const Eigen::Vector3f& sensor) {
  for (const auto& p : points) Accumulate(p, sensor, +1);
}

void VoxelCentroidTable::Remove(const pcl::PointCloud<pcl::PointXYZI>& points, const Eigen::Vector3f& sensor) {
  for (const auto& p : points) Accumulate(p, sensor, -1);
  if (dead_ > 1024 && dead_ > live_) Compact();
}

void VoxelCentroidTable::Clear() {
  voxels_.clear();
  index_.clear();
  touched_flag_.clear();
  touched_.clear();
  live_ = dead_ = 0;
  ++layout_version_;
}

void VoxelCentroidTable::TakeTouched(std::vector<uint32_t>* out) {
  out->swap(touched_);
  touched_.clear();
  for (uint32_t slot : *out) touched_flag_[slot] = 0;
}

void VoxelCentroidTable::Compact() {
  size_t out = 0;
  for (size_t i = 0; i < voxels_.size(); ++i)
    if (voxels_[i].count != 0) voxels_[out++] = voxels_[i];
  voxels_.resize(out);
  dead_ = 0;
  touched_flag_.assign(voxels_.size(), 0);
  touched_.clear();
  ++layout_version_;
  index_.assign(index_.size(), kEmpty);
  for (size_t i = 0; i < voxels_.size(); ++i) index_[Find(voxels_[i].key)] = uint32_t(i);
}

VoxelCentroidTable::Mean VoxelCentroidTable::MeanOf(const Voxel& v) {
  const double inv = 1.0 / double(v.count);
  Mean m;
  m.point.x = float(v.x * inv);
  m.point.y = float(v.y * inv);
  m.point.z = float(v.z * inv);
  m.point.intensity = float(v.intensity * inv);
  m.view = Eigen::Vector3f(float(v.vx * inv), float(v.vy * inv), float(v.vz * inv));
  return m;
}

void VoxelCentroidTable::Centroids(pcl::PointCloud<pcl::PointXYZI>* out) const {
  out->clear();
  out->reserve(live_);
  for (const Voxel& v : voxels_)
    if (v.count != 0) out->push_back(MeanOf(v).point);
  out->is_dense = true;
}

void VoxelCentroidTable::MeanViews(std::vector<Eigen::Vector3f>* out) const {
  out->clear();
  out->reserve(live_);
  for (const Voxel& v : voxels_)
    if (v.count != 0) out->push_back(MeanOf(v).view);
}

}  // namespace rotolidar
