#pragma once
// A 3-D kd-tree over float points (fixed structure, movable points) for the local map's exact k-nearest-neighbour
// queries (replaces PCL's KdTreeFLANN there: no per-query heap allocation, no OpenMP region per query, no index
// remapping).
//
// Contract: Build copies the points (any frame, metres); Nearest returns the exact k nearest points to the query
// in squared float distance (dx*dx + dy*dy + dz*dz, as FLANN's L2_Simple computes it), nearest first. Among
// equal distances the order is unspecified. Non-finite points must not be passed to Build (the caller filters).
// Moving points: Move puts a point anywhere (finite) and Hide takes one out of the results, both O(1); Refit then
// recomputes the split bounds (the boxes of the changed leaves, then every inner node, O(n / leaf size)), so the
// search is exact again without a rebuild. The structure stays the build's: a tree whose points drift a little,
// such as voxel centroids, prunes as well as a fresh one. Search only after Refit (checked).
// Thread-safety: Build, Move, Hide and Refit are not; const queries are re-entrant.
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

namespace rotolidar {

class KdTree3f {
 public:
  static constexpr int kMaxK = 32;  ///< the largest k Nearest accepts

  /// (Re)builds over `xyz` (3 floats per point, n = xyz.size() / 3). O(n log n).
  void Build(const std::vector<float>& xyz);
  /// Moves point `index` (its Build input index) to p (finite, checked). A hidden point comes back.
  void Move(int index, const float p[3]);
  /// Takes point `index` out of every search result until it is moved again.
  void Hide(int index);
  /// Makes the tree searchable after Move / Hide (a no-op when nothing changed).
  void Refit();
  size_t size() const { return size_; }

  /// The min(k, size()) nearest points to q: their indices (into the Build input) in *indices and squared
  /// distances [unit^2] in *sq_dist, both arrays of at least k entries, nearest first. 1 <= k <= kMaxK.
  /// Returns how many were written. Only points with squared distance < max_sq_dist count (default: all), so
  /// fewer than k come back when fewer lie that close. With xyz (3 k floats), also the points themselves (the
  /// Build input's values).
  int Nearest(const float q[3], int k, int* indices, float* sq_dist,
              float max_sq_dist = std::numeric_limits<float>::infinity(), float* xyz = nullptr) const;

 private:
  struct Node {
    float left_max = 0.0f;   ///< inner: the largest `axis` coordinate in the left child
    float right_min = 0.0f;  ///< inner: the smallest in the right child (>= left_max)
    int32_t axis = -1;    ///< inner: 0..2; leaf: -1
    int32_t a = 0, b = 0; ///< inner: children; leaf: [a, b) range in coords_
  };
  struct Item {
    float p[3];
    int index;
  };
  struct Result;
  void BuildRoot(int n);  ///< over scratch_[0, n), n > 0
  /// Over scratch_[begin, end) whose exact bounding box is [lo, hi]; returns the node.
  int BuildRange(int begin, int end, const float lo[3], const float hi[3]);
  void Search(int node, const float q[3], float min_sq, float* axis_sq, Result* r) const;

  std::vector<float> coords_[3];  ///< x, y, z, reordered so that every leaf's points are contiguous (+ padding)
  size_t size_ = 0;
  std::vector<int> original_;    ///< original index of point i of coords_
  std::vector<int> position_;    ///< position in coords_ of original index i (inverse of original_)
  std::vector<int> leaf_of_;     ///< per position in coords_: its leaf node
  std::vector<float> boxes_;     ///< per node: lo x y z, hi x y z of its shown points (as of the last Refit)
  std::vector<uint8_t> dirty_;   ///< per node: a leaf changed since Refit
  std::vector<int> dirty_leaves_;
  void MarkDirty(int leaf);
  std::vector<Node> nodes_;
  std::vector<Item> scratch_;    ///< Build's working copy, capacity kept across builds
};

}  // namespace rotolidar
