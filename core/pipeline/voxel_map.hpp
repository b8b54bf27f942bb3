#pragma once
// A sparse voxel map of world points (KISS-ICP's voxel hash map): at most `max_points_per_voxel` points per
// voxel, so density stays bounded however long the rig dwells. Used as the local map (registration target)
// and as the global map (the dense output). Voxel of p: floor(p / voxel_size_m) per axis (double division).
// With one point per voxel the full-voxel bits below are the whole index (a voxel exists iff it is full), so the
// voxel table stays empty; with more, the table finds a voxel's points. Thread-safety: none.
#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include <Eigen/Core>

#include "core/util/chunked_vector.hpp"

namespace rotolidar {

class VoxelMap {
 public:
  /// voxel_size_m > 0; max_points_per_voxel >= 1.
  VoxelMap(double voxel_size_m, int max_points_per_voxel);

  /// Adds world points; a point is kept when its voxel has room and it is at least voxel/sqrt(n) from the
  /// voxel's points already there (uniform spread inside the voxel).
  void Add(const std::vector<Eigen::Vector3d>& p_world);
  /// The same for n points at p_world (not kept; the caller may reuse the buffer, e.g. in chunks: adding a
  /// sequence in pieces gives the same map as adding it at once). With `kept`, appends the index (for Point /
  /// Remove) of each point the map took, in p_world's order.
  void Add(const Eigen::Vector3d* p_world, size_t n, std::vector<size_t>* kept = nullptr);
  /// The point at `index` (from Add's `kept`); NaN once removed. Valid until RemoveFar.
  const Eigen::Vector3d& Point(size_t index) const { return points_[index]; }
  /// Takes the point at `index` out of the map (a moving object found later); false when it was removed
  /// already. With one point per voxel the voxel may take a new point again; with more, the removed point's
  /// place in its voxel stays used (the voxel takes no replacement). Indices of other points stay valid.
  bool Remove(size_t index);
  /// True when p_world's voxel holds max_points_per_voxel points already (Add would turn p away).
  bool Full(const Eigen::Vector3d& p_world) const;
  /// Removes voxels whose centre is farther than max_distance_m from `center_world`.
  void RemoveFar(const Eigen::Vector3d& center_world, double max_distance_m);
  /// All points, removed ones left out (order unspecified but deterministic for the same insertion sequence).
  std::vector<Eigen::Vector3d> Points() const;
  size_t NumPoints() const;
  bool Empty() const { return num_points_ == 0; }  ///< removed points do not count
  double voxel_size_m() const { return voxel_size_m_; }

 private:
  struct Key {
    int32_t x, y, z;
    bool operator==(const Key& o) const { return x == o.x && y == o.y && z == o.z; }
  };
  /// One slot of the open-addressing table: a voxel's key and number (kEmpty: unused).
  struct Slot {
    Key key;
    uint32_t voxel;
  };
  static constexpr uint32_t kEmpty = UINT32_MAX;
  Key KeyOf(const Eigen::Vector3d& p) const;
  size_t HomeSlot(const Key& key) const;  ///< where the key's probe starts (its hash)
  size_t SlotOf(const Key& key) const;    ///< the key's slot, or the empty slot where it would go
  void Rehash(size_t num_slots);         ///< rebuilds the table from keys_ (num_slots: a power of two)
  void AddOnePerVoxel(const Eigen::Vector3d* p_world, size_t n, std::vector<size_t>* kept);  ///< one per voxel

  // Full-voxel filter: one bit per voxel, set once the voxel holds max_points_per_voxel points, in blocks of
  // kBlock^3 voxels found through a small table of block keys. A scan mostly revisits full voxels of surfaces seen
  // before; their points are turned away by one bit test in a block that stays in cache along a ring, instead of
  // a probe into the large voxel table (a cache miss per point). Exact: the bit is only a shortcut to the
  // `count >= max_points_per_voxel` test.
  static constexpr int kBlockBits = 5;  ///< 32 voxels per block edge
  static constexpr int kBlock = 1 << kBlockBits;
  using BlockBits = std::array<uint64_t, kBlock * kBlock * kBlock / 64>;
  struct BlockSlot {
    Key key;
    uint32_t block;
  };
  static Key BlockKeyOf(const Key& voxel);
  static size_t BitOf(const Key& voxel);
  BlockBits* FindBlock(const Key& block_key, bool create);
  /// The block key's slot in block_table_ (non-empty), or the empty slot where it would go.
  size_t BlockSlotOf(const Key& block_key) const;
  void MarkFull(const Key& voxel);
  void ClearFull(const Key& voxel);
  void RebuildFullBits();

  std::vector<BlockSlot> block_table_;              ///< linear probing, power-of-two size, at most half full
  std::vector<std::unique_ptr<BlockBits>> blocks_;  ///< per block its bits (stable addresses)
  struct BlockCacheEntry {
    Key key{0, 0, 0};
    BlockBits* bits = nullptr;  ///< nullptr: unused
  };
  static constexpr size_t kBlockCache = 64;
  static size_t CacheSlotOf(const Key& block_key);
  std::array<BlockCacheEntry, kBlockCache> block_cache_{};  ///< FindBlock's direct-mapped cache (the ring's blocks)

  double voxel_size_m_;
  int max_points_per_voxel_;
  double min_spacing_m_;
  Key KeyOfVoxel(size_t v) const;  ///< voxel v's key (one point per voxel: derived from its point)
  uint32_t CountOf(size_t v) const { return max_points_per_voxel_ == 1 ? 1u : counts_[v]; }

  // Flat storage instead of a node-based hash map of vectors: a dense map of ~1e6 voxels gets ~3e4 lookups per
  // scan, and one probe into a flat table (plus one into the voxel's points) is what they cost. Chunked, not one
  // vector: the dense map of an hour-long run grows to 1e7+ points, and a doubling copy would stall a scan.
  // One point per voxel keeps only points_ (a voxel's key is its point's, its count is 1).
  std::vector<Slot> table_;                ///< linear probing, power-of-two size, at most half full
  ChunkedVector<Key> keys_;                ///< per voxel, in insertion order (keeps Points() deterministic)
  ChunkedVector<uint32_t> counts_;         ///< per voxel: points kept
  ChunkedVector<Eigen::Vector3d> points_;  ///< voxel v's points at [v * max_points_per_voxel, + count)
  size_t num_voxels_ = 0;
  size_t num_points_ = 0;
};

}  // namespace rotolidar
