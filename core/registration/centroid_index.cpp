#include "core/registration/centroid_index.hpp"

#include <algorithm>
#include <cmath>

#include "core/util/log.hpp"

namespace rotolidar {
namespace {

/// The main tree is rebuilt when the overflow holds more than this fraction of its live centroids (or the hidden
/// entries more than twice that). Parking loop (37-55 k planar centroids, one keyframe per scan), median map /
/// register stage [ms]: 1/4: 2.05 / 4.60, 1/8: 2.06 / 4.62, 1/16: 1.96 / 4.52, 1/32: 2.29 / 4.56 (within the
/// machine's noise up to 1/16); a rebuild every scan: 6.77 / 4.19.
constexpr size_t kOverflowDivisor = 8;
constexpr size_t kMinOverflow = 512;  ///< small maps: rebuild at most every few hundred new voxels

}  // namespace

void CentroidIndex::Sync(VoxelCentroidTable* table) {
  if (table->layout_version() != layout_version_) {
    pending_.reset();  // waits for a background build: its snapshot's slot numbers are gone
    BuildMain(table);
    return;
  }
  table->TakeTouched(&touched_);
  std::sort(touched_.begin(), touched_.end());  // slot order: the table's and the index's arrays in sequence
  ApplyTouched(*table);
  if (pending_) {
    pending_->touched.insert(pending_->touched.end(), touched_.begin(), touched_.end());
    if (--pending_->syncs_left <= 0) InstallPending(*table);
  } else {
    const size_t limit = std::max(kMinOverflow, main_live_ / kOverflowDivisor);
    const size_t created = table->num_slots() - main_slots_;  // the overflow's size, counting voxels dead since
    if (created > limit || main_dead_ > 2 * limit) StartPending(*table);
  }
  BuildOverflow(*table);
}

void CentroidIndex::StartPending(const VoxelCentroidTable& table) {
  auto pending = std::make_unique<Pending>();
  pending->slots = table.num_slots();
  pending->syncs_left = kSwapAfterSyncs;
  std::vector<float> xyz;
  LiveSlots(table, pending->slots, &pending->main_slot, &xyz);
  pending->tree = std::async(std::launch::async, [xyz = std::move(xyz)] {
    KdTree3f tree;
    tree.Build(xyz);
    return tree;
  });
  pending_ = std::move(pending);
}

void CentroidIndex::InstallPending(const VoxelCentroidTable& table) {
  main_ = pending_->tree.get();
  ++background_builds_;
  AdoptMain(pending_->slots, std::move(pending_->main_slot));
  std::vector<uint32_t>& touched = pending_->touched;
  std::sort(touched.begin(), touched.end());
  touched.erase(std::unique(touched.begin(), touched.end()), touched.end());
  ApplyToMain(table, touched);
  pending_.reset();
}

void CentroidIndex::BuildMain(VoxelCentroidTable* table) {
  table->TakeTouched(&touched_);  // everything is read afresh
  layout_version_ = table->layout_version();
  const size_t slots = table->num_slots();
  slot_xyz_.resize(3 * slots);
  views_.resize(slots);
  for (size_t slot = 0; slot < slots; ++slot)
    if (table->live(slot)) Remember(slot, table->MeanAt(slot));
  std::vector<int> main_slot;
  LiveSlots(*table, slots, &main_slot, &xyz_);
  main_.Build(xyz_);
  AdoptMain(slots, std::move(main_slot));
  BuildOverflow(*table);
}

void CentroidIndex::LiveSlots(const VoxelCentroidTable& table, size_t slots, std::vector<int>* main_slot,
                              std::vector<float>* xyz) const {
  main_slot->clear();
  xyz->clear();
  for (size_t slot = 0; slot < slots; ++slot) {
    if (!table.live(slot)) continue;
    main_slot->push_back(int(slot));
    xyz->insert(xyz->end(), slot_xyz_.begin() + long(3 * slot), slot_xyz_.begin() + long(3 * slot + 3));
  }
}

void CentroidIndex::AdoptMain(size_t slots, std::vector<int> main_slot) {
  ++main_builds_;
  main_slots_ = slots;
  main_slot_ = std::move(main_slot);
  main_index_.assign(main_slots_, -1);
  for (size_t i = 0; i < main_slot_.size(); ++i) main_index_[size_t(main_slot_[i])] = int(i);
  main_live_ = main_slot_.size();
  main_dead_ = 0;
  hidden_.assign(main_live_, 0);
}

void CentroidIndex::Remember(size_t slot, const VoxelCentroidTable::Mean& m) {
  float* c = &slot_xyz_[3 * slot];
  c[0] = m.point.x;
  c[1] = m.point.y;
  c[2] = m.point.z;
  views_[slot] = m.view;
}

void CentroidIndex::ApplyTouched(const VoxelCentroidTable& table) {
  slot_xyz_.resize(3 * table.num_slots());
  views_.resize(table.num_slots());
  for (const uint32_t slot : touched_)
    if (table.live(slot)) Remember(slot, table.MeanAt(slot));
  ApplyToMain(table, touched_);
}

void CentroidIndex::ApplyToMain(const VoxelCentroidTable& table, const std::vector<uint32_t>& slots) {
  for (const uint32_t slot : slots) {
    if (slot >= main_slots_) continue;  // created since the main build: in the overflow
    const int i = main_index_[slot];
    if (i < 0 || hidden_[size_t(i)]) continue;  // (a voxel never comes back to a dead slot)
    if (!table.live(slot)) {
      main_.Hide(i);
      hidden_[size_t(i)] = 1;
      --main_live_;
      ++main_dead_;
      continue;
    }
    main_.Move(i, &slot_xyz_[3 * size_t(slot)]);
  }
  main_.Refit();
}

void CentroidIndex::BuildOverflow(const VoxelCentroidTable& table) {
  overflow_slots_.clear();
  xyz_.clear();
  for (size_t slot = main_slots_; slot < table.num_slots(); ++slot) {
    if (!table.live(slot)) continue;
    overflow_slots_.push_back(int(slot));
    xyz_.insert(xyz_.end(), slot_xyz_.begin() + long(3 * slot), slot_xyz_.begin() + long(3 * slot + 3));
  }
  overflow_.Build(xyz_);
}

int CentroidIndex::Nearest(const float q[3], int k, int* slots, float* sq_dist, float max_sq_dist,
                           float* xyz) const {
  ROTOLIDAR_CHECK(k >= 1 && k <= kMaxK, "k = " << k);
  int main_i[kMaxK], over_i[kMaxK];
  float main_sq[kMaxK], over_sq[kMaxK], main_xyz[3 * kMaxK], over_xyz[3 * kMaxK];
  // The overflow first: it holds the newest voxels, where a scan's points usually find their neighbours, and its
  // k-th distance then bounds the main tree's search.
  const int no = overflow_slots_.empty() ? 0 : overflow_.Nearest(q, k, over_i, over_sq, max_sq_dist, over_xyz);
  const float bound = no == k ? std::min(max_sq_dist, std::nextafter(over_sq[k - 1], max_sq_dist)) : max_sq_dist;
  const int nm = main_.Nearest(q, k, main_i, main_sq, bound, main_xyz);
  int a = 0, b = 0, n = 0;
  for (; n < k && (a < nm || b < no); ++n) {
    const bool from_main = b == no || (a < nm && main_sq[a] <= over_sq[b]);
    const int src = from_main ? a++ : b++;
    slots[n] = from_main ? main_slot_[size_t(main_i[src])] : overflow_slots_[size_t(over_i[src])];
    sq_dist[n] = from_main ? main_sq[src] : over_sq[src];
    if (xyz != nullptr)
      for (int d = 0; d < 3; ++d) xyz[3 * n + d] = from_main ? main_xyz[3 * src + d] : over_xyz[3 * src + d];
  }
  return n;
}

}  // namespace rotolidar
