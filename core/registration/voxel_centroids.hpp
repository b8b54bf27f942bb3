#pragma once
// An incremental voxel-centroid table: the same output as a PCL VoxelGrid over the union of every point set added
// and not yet removed (per voxel: the centroid of its points, intensity averaged), maintained by adding and
// subtracting running sums instead of re-merging the union.
//
// Voxels: PCL's indexing, floor(coord * (1 / leaf)) in float, on a grid anchored at the origin of the points'
// frame (metres). Sums are doubles of the float inputs, so Remove subtracts exactly what Add added (a voxel whose
// count returns to 0 is dropped and its sums reset). Non-finite points are ignored (as VoxelGrid does).
// Order: Centroids() lists the live voxels in the order they were first created (compaction keeps that order),
// so the output depends only on the sequence of Add/Remove calls, never on hash or pointer values.
// Views: Add/Remove may name the sensor position the points were seen from (same frame); each point then adds
// its unit view vector (point -> sensor) to its voxel, and MeanViews() gives each centroid the mean of those
// vectors (which side of a surface the map saw it from; ~0 where both sides merged in one voxel).
// Slots: every voxel has a slot (its position in creation order, dead ones included) that stays fixed until the
// table compacts or clears (layout_version() then changes). A voxel that dies keeps its dead slot; one re-created
// later gets a new slot. TakeTouched lists the slots whose sums changed since the previous call, so an index over
// the centroids (CentroidIndex) can follow the table without re-reading it.
// Contract: Remove must be given a point set previously Added (with the same sensor position) and not yet
// removed (checked: a voxel's count never goes negative). Thread-safety: none.
#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

namespace rotolidar {

class VoxelCentroidTable {
 public:
  struct Mean {
    pcl::PointXYZI point;  ///< centroid, intensity averaged
    Eigen::Vector3f view;  ///< mean unit view vector
  };

  explicit VoxelCentroidTable(double voxel_m);  ///< voxel_m > 0 (checked)

  void Add(const pcl::PointCloud<pcl::PointXYZI>& points, const Eigen::Vector3f& sensor = Eigen::Vector3f::Zero());
  void Remove(const pcl::PointCloud<pcl::PointXYZI>& points,
              const Eigen::Vector3f& sensor = Eigen::Vector3f::Zero());
  void Clear();

  /// The live voxels' centroids (x, y, z, intensity as float), creation order, into *out (replaced).
  void Centroids(pcl::PointCloud<pcl::PointXYZI>* out) const;
  /// Per centroid (same order as Centroids), the mean unit view vector of its points, into *out (replaced).
  void MeanViews(std::vector<Eigen::Vector3f>* out) const;
  size_t num_voxels() const { return live_; }

  /// The voxel key of a point under PCL VoxelGrid's indexing (21 bits per axis, two's complement).
  uint64_t KeyOf(const pcl::PointXYZI& p) const;

  // Slot access (see the top comment).
  size_t num_slots() const { return voxels_.size(); }
  bool live(size_t slot) const { return voxels_[slot].count != 0; }  ///< slot < num_slots()
  Mean MeanAt(size_t slot) const { return MeanOf(voxels_[slot]); }    ///< a live slot
  /// The slots touched (sums changed, or died) since the previous call, each once, into *out (replaced).
  void TakeTouched(std::vector<uint32_t>* out);
  /// Changes whenever slots are renumbered (Compact, Clear); the touched list is then emptied.
  uint64_t layout_version() const { return layout_version_; }

 private:
  struct Voxel {
    uint64_t key = 0;
    int64_t count = 0;  ///< 0: dead (awaiting compaction)
    double x = 0, y = 0, z = 0, intensity = 0;
    double vx = 0, vy = 0, vz = 0;  ///< sum of unit view vectors
  };
  static constexpr uint32_t kEmpty = 0xFFFFFFFFu;
  static Mean MeanOf(const Voxel& v);  ///< v.count > 0
  void Accumulate(const pcl::PointXYZI& p, const Eigen::Vector3f& sensor, int sign);
  size_t Home(uint64_t key) const;
  size_t Find(uint64_t key) const;  ///< the index_ slot holding key, or the empty slot where it would go
  void Erase(size_t slot);          ///< backward-shift deletion (no tombstones)
  void Grow();
  void Compact();

  float inverse_leaf_;
  std::vector<Voxel> voxels_;    ///< creation order; dead entries until Compact
  std::vector<uint8_t> touched_flag_;  ///< per slot: listed in touched_
  std::vector<uint32_t> touched_;      ///< slots touched since TakeTouched
  uint64_t layout_version_ = 0;
  std::vector<uint32_t> index_;  ///< open addressing, linear probing: voxels_ position or kEmpty; power of 2
  size_t live_ = 0;
  size_t dead_ = 0;
};

}  // namespace rotolidar
