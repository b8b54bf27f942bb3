#pragma once
// Exact k-nearest-neighbour search over the live centroids of a VoxelCentroidTable that follows the table's
// changes instead of rebuilding a kd-tree over every centroid after each change (the local map changes by one
// keyframe per scan, while its tens of thousands of centroids would otherwise be re-indexed every scan).
//
// How: a main kd-tree over the centroids of the voxels live at its build; a voxel's later centroids are moved in
// place (KdTree3f::Move), voxels that died are hidden, and voxels created since go to a small overflow tree,
// rebuilt at each Sync. The main tree is rebuilt when the overflow or the dead outgrow a fraction of it, or when
// the table renumbers its slots. Queries search both trees and merge.
//
// Rebuilds in the background: a rebuild for growth (tens of thousands of centroids, ~6 ms, the slowest step of a
// scan) runs on its own thread from a snapshot of the live centroids, while the old main tree and the growing
// overflow go on serving queries. kSwapAfterSyncs Syncs later the new tree takes over (waiting for it if it is not
// done: the swap point never depends on timing, so results stay deterministic), after the changes made since the
// snapshot are replayed onto it (moved centroids, dead voxels; voxels created since stay in the overflow). A
// renumbering of the table (compaction) rebuilds at once, dropping a background build.
//
// Contract: Nearest returns the same squared distances as an exact search over the table's Centroids() (float
// arithmetic as KdTree3f: dx*dx + dy*dy + dz*dz), nearest first; the order among equal distances is unspecified.
// Frames and units: the table's (map frame, metres).
// Ownership: owns its trees; reads the table only inside Sync (one index per table: Sync consumes the table's
// touched list). The background build owns its snapshot; the destructor waits for it. Thread-safety: Sync is
// not; const queries are re-entrant.
#include <cstdint>
#include <future>
#include <limits>
#include <memory>
#include <vector>

#include "core/registration/kd_tree.hpp"
#include "core/registration/voxel_centroids.hpp"

namespace rotolidar {

class CentroidIndex {
 public:
  static constexpr int kMaxK = KdTree3f::kMaxK;

  /// Brings the index up to date with `table` (the table's touched list is consumed).
  void Sync(VoxelCentroidTable* table);

  /// The min(k, live) nearest centroids to q with squared distance < max_sq_dist: their table slots in *slots,
  /// squared distances [m^2] in *sq_dist and, with xyz (3 k floats), the centroids; arrays of at least k entries,
  /// nearest first. 1 <= k <= kMaxK. Returns how many were written.
  int Nearest(const float q[3], int k, int* slots, float* sq_dist,
              float max_sq_dist = std::numeric_limits<float>::infinity(), float* xyz = nullptr) const;

  /// The mean unit view vector of a live slot's voxel (VoxelCentroidTable::MeanViews), as of the last Sync.
  const Eigen::Vector3f& view(int slot) const { return views_[size_t(slot)]; }
  size_t size() const { return main_live_ + overflow_slots_.size(); }  ///< live centroids indexed
  int main_builds() const { return main_builds_; }  ///< how often the main tree was rebuilt (tests, tuning)
  int background_builds() const { return background_builds_; }  ///< of those, built in the background
  /// Syncs from the start of a background rebuild to its swap (see the top comment).
  static constexpr int kSwapAfterSyncs = 2;

 private:
  /// A main tree being built on another thread, with its slot maps and what changed since its snapshot.
  struct Pending {
    std::future<KdTree3f> tree;
    size_t slots = 0;                   ///< main_slots_ at the snapshot
    std::vector<int> main_slot;         ///< tree index -> table slot
    std::vector<uint32_t> touched;      ///< slots touched since the snapshot (may repeat)
    int syncs_left = 0;
  };
  /// Starts a background rebuild from the live slots' remembered centroids.
  void StartPending(const VoxelCentroidTable& table);
  /// Makes the pending tree the main one and replays the changes since its snapshot.
  void InstallPending(const VoxelCentroidTable& table);
  /// The live slots among [0, slots) and their remembered centroids (x, y, z), in slot order.
  void LiveSlots(const VoxelCentroidTable& table, size_t slots, std::vector<int>* main_slot,
                 std::vector<float>* xyz) const;
  /// The main tree (just built over main_slot's centroids, in that order) now covers slots [0, slots).
  void AdoptMain(size_t slots, std::vector<int> main_slot);
  void BuildMain(VoxelCentroidTable* table);
  /// Remembers the touched slots' centroids, then ApplyToMain.
  void ApplyTouched(const VoxelCentroidTable& table);
  /// Moves the main tree's entries of `slots` (sorted, each once) to their remembered centroids, hides those whose
  /// voxels died, and refits.
  void ApplyToMain(const VoxelCentroidTable& table, const std::vector<uint32_t>& slots);
  void BuildOverflow(const VoxelCentroidTable& table);
  void Remember(size_t slot, const VoxelCentroidTable::Mean& m);  ///< into slot_xyz_ / views_

  KdTree3f main_, overflow_;
  std::vector<int> main_slot_;        ///< main tree index -> table slot
  std::vector<int> main_index_;       ///< table slot (< main_slots_) -> main tree index, or -1
  std::vector<uint8_t> hidden_;       ///< per main tree index: its voxel died
  size_t main_slots_ = 0;             ///< slots [0, main_slots_) existed at the main build
  size_t main_live_ = 0;              ///< live centroids held by the main tree
  size_t main_dead_ = 0;              ///< main tree entries hidden (their voxels died)
  std::vector<int> overflow_slots_;   ///< overflow tree index -> table slot
  uint64_t layout_version_ = std::numeric_limits<uint64_t>::max();
  int main_builds_ = 0;
  int background_builds_ = 0;
  std::vector<float> slot_xyz_;       ///< per table slot: its centroid (x, y, z) as of the last Sync
  std::vector<Eigen::Vector3f> views_;  ///< per table slot: its mean view vector, likewise
  std::vector<uint32_t> touched_;     ///< scratch
  std::vector<float> xyz_;            ///< scratch
  std::unique_ptr<Pending> pending_;  ///< null when no background rebuild runs
};

}  // namespace rotolidar
