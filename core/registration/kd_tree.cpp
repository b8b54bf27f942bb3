#include "core/registration/kd_tree.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/util/log.hpp"

namespace rotolidar {
namespace {

constexpr int kLeafSize = 8;  ///< points per leaf at most (measured: 6..12 are within noise)

}  // namespace

/// The k best so far, sorted ascending by distance.
struct KdTree3f::Result {
  int k = 0, count = 0;
  float worst = std::numeric_limits<float>::infinity();  ///< only distances below this count (the bound, then
                                                          ///< the k-th best once k are held)
  int index[kMaxK];
  float dist[kMaxK];
  void Offer(int i, float d) {
    if (d >= worst) return;
    int j = count < k ? count++ : k - 1;  // the slot freed at the end
    for (; j > 0 && dist[j - 1] > d; --j) {
      dist[j] = dist[j - 1];
      index[j] = index[j - 1];
    }
    dist[j] = d;
    index[j] = i;
    if (count == k) worst = dist[k - 1];
  }
};

void KdTree3f::Build(const std::vector<float>& xyz) {
  ROTOLIDAR_CHECK(xyz.size() % 3 == 0, "xyz size " << xyz.size() << " is not a multiple of 3");
  const int n = int(xyz.size() / 3);
  std::vector<Item>& items = scratch_;
  items.resize(size_t(n));
  for (int i = 0; i < n; ++i) items[size_t(i)] = {{xyz[size_t(3 * i)], xyz[size_t(3 * i + 1)], xyz[size_t(3 * i + 2)]}, i};
  nodes_.clear();
  nodes_.reserve(size_t(2 * (n / kLeafSize + 1)));
  if (n > 0) BuildRoot(n);
  // Padded by one leaf: Search reads whole kLeafSize blocks (the padding's distances are never offered).
  for (auto& axis : coords_) axis.assign(size_t(n + kLeafSize), 0.0f);
  original_.resize(size_t(n));
  position_.resize(size_t(n));
  for (int i = 0; i < n; ++i) {
    for (int d = 0; d < 3; ++d) coords_[d][size_t(i)] = items[size_t(i)].p[d];
    original_[size_t(i)] = items[size_t(i)].index;
    position_[size_t(items[size_t(i)].index)] = i;
  }
  leaf_of_.resize(size_t(n));
  for (size_t node = 0; node < nodes_.size(); ++node)
    if (nodes_[node].axis < 0)
      for (int i = nodes_[node].a; i < nodes_[node].b; ++i) leaf_of_[size_t(i)] = int(node);
  boxes_.assign(6 * nodes_.size(), 0.0f);
  dirty_.assign(nodes_.size(), 1);
  dirty_leaves_.clear();
  for (size_t node = 0; node < nodes_.size(); ++node)
    if (nodes_[node].axis < 0) dirty_leaves_.push_back(int(node));
  size_ = size_t(n);
  Refit();  // the same split bounds as the build's (every box is the exact box of its points)
}

void KdTree3f::Move(int index, const float p[3]) {
  ROTOLIDAR_CHECK(index >= 0 && size_t(index) < size_, "index " << index << " of " << size_);
  ROTOLIDAR_CHECK(std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]), "non-finite point");
  const int at = position_[size_t(index)];
  for (int d = 0; d < 3; ++d) coords_[d][size_t(at)] = p[d];
  MarkDirty(leaf_of_[size_t(at)]);
}

void KdTree3f::Hide(int index) {
  ROTOLIDAR_CHECK(index >= 0 && size_t(index) < size_, "index " << index << " of " << size_);
  // An infinite coordinate gives an infinite distance, which is never below the search bound.
  const int at = position_[size_t(index)];
  for (auto& axis : coords_) axis[size_t(at)] = std::numeric_limits<float>::infinity();
  MarkDirty(leaf_of_[size_t(at)]);
}

void KdTree3f::MarkDirty(int leaf) {
  if (dirty_[size_t(leaf)]) return;
  dirty_[size_t(leaf)] = 1;
  dirty_leaves_.push_back(leaf);
}

void KdTree3f::Refit() {
  if (dirty_leaves_.empty()) return;
  constexpr float kInf = std::numeric_limits<float>::infinity();
  for (const int leaf : dirty_leaves_) {  // the exact box of the leaf's shown points (empty: lo +inf, hi -inf)
    float* box = &boxes_[6 * size_t(leaf)];
    for (int d = 0; d < 3; ++d) box[d] = kInf, box[3 + d] = -kInf;
    for (int i = nodes_[size_t(leaf)].a; i < nodes_[size_t(leaf)].b; ++i) {
      if (coords_[0][size_t(i)] == kInf) continue;  // hidden
      for (int d = 0; d < 3; ++d) {
        box[d] = std::min(box[d], coords_[d][size_t(i)]);
        box[3 + d] = std::max(box[3 + d], coords_[d][size_t(i)]);
      }
    }
  }
  // Children follow their parent in nodes_ (BuildRange's preorder): one backward pass is bottom-up. Every inner
  // node is recomputed (a sequential pass over ~n/4 nodes, cheaper than walking each moved point's path).
  for (size_t node = nodes_.size(); node-- > 0;) {
    Node& nd = nodes_[node];
    dirty_[node] = 0;
    if (nd.axis < 0) continue;
    const float* l = &boxes_[6 * size_t(nd.a)];
    const float* r = &boxes_[6 * size_t(nd.b)];
    float* box = &boxes_[6 * node];
    for (int d = 0; d < 3; ++d) {
      box[d] = std::min(l[d], r[d]);
      box[3 + d] = std::max(l[3 + d], r[3 + d]);
    }
    nd.left_max = l[3 + nd.axis];  // -inf for an empty side: Search never enters it (cut = inf)
    nd.right_min = r[nd.axis];     // +inf likewise
  }
  dirty_leaves_.clear();
}

namespace {

struct Box {
  float lo[3], hi[3];
  void Reset() {
    for (int d = 0; d < 3; ++d) {
      lo[d] = std::numeric_limits<float>::infinity();
      hi[d] = -std::numeric_limits<float>::infinity();
    }
  }
  void Grow(const float p[3]) {
    for (int d = 0; d < 3; ++d) {
      lo[d] = std::min(lo[d], p[d]);
      hi[d] = std::max(hi[d], p[d]);
    }
  }
};

/// libstdc++'s std::partition (bidirectional form) step for step, so the arrangement and hence the tree are the
/// ones std::partition gives; on the way, the bounding boxes of both sides (each element is counted when it
/// settles on its side).
template <class Item, class Pred>
Item* PartitionWithBoxes(Item* first, Item* last, Pred pred, Box* left, Box* right) {
  left->Reset();
  right->Reset();
  while (true) {
    while (true) {
      if (first == last) return first;
      if (!pred(*first)) break;
      left->Grow(first->p);
      ++first;
    }
    --last;
    while (true) {
      if (first == last) {  // the item at first failed pred above: it is the right side's first
        right->Grow(first->p);
        return first;
      }
      if (pred(*last)) break;
      right->Grow(last->p);
      --last;
    }
    std::iter_swap(first, last);
    left->Grow(first->p);
    right->Grow(last->p);
    ++first;
  }
}

}  // namespace

void KdTree3f::BuildRoot(int n) {
  Box box;
  box.Reset();
  for (int i = 0; i < n; ++i) box.Grow(scratch_[size_t(i)].p);
  BuildRange(0, n, box.lo, box.hi);
}

int KdTree3f::BuildRange(int begin, int end, const float lo[3], const float hi[3]) {
  const int self = int(nodes_.size());
  nodes_.emplace_back();
  int axis = 0;
  for (int d = 1; d < 3; ++d)
    if (hi[d] - lo[d] > hi[axis] - lo[axis]) axis = d;
  // A leaf when small enough, or when all points coincide (one oversized leaf).
  if (end - begin <= kLeafSize || !(hi[axis] > lo[axis])) {
    nodes_[size_t(self)].a = begin;
    nodes_[size_t(self)].b = end;
    return self;
  }
  // Midpoint split of the cell's widest side (lo/hi: the exact bounding box of the range), one partition pass
  // that also yields both children's boxes; both children are non-empty: lo and hi are attained on either side.
  Item* first = scratch_.data() + begin;
  Item* last = scratch_.data() + end;
  const float mid_value = 0.5f * (lo[axis] + hi[axis]);
  Box left, right;
  Item* split = PartitionWithBoxes(first, last, [&](const Item& it) { return it.p[axis] < mid_value; }, &left,
                                   &right);
  if (split == first) {  // float midpoint rounded onto lo: keep lo's points left (the first item moves over)
    ++split;
    left.Reset();
    right.Reset();
    left.Grow(first->p);
    for (const Item* it = split; it != last; ++it) right.Grow(it->p);
  }
  const int mid = int(split - scratch_.data());
  const int left_node = BuildRange(begin, mid, left.lo, left.hi);
  const int right_node = BuildRange(mid, end, right.lo, right.hi);
  Node& node = nodes_[size_t(self)];
  node.axis = axis;  // left_max / right_min: set by Refit, from the same exact boxes
  node.a = left_node;
  node.b = right_node;
  return self;
}

void KdTree3f::Search(int node_index, const float q[3], float min_sq, float* axis_sq, Result* r) const {
  const Node& node = nodes_[size_t(node_index)];
  if (node.axis < 0) {
    // Whole blocks of kLeafSize (SIMD-friendly, the same float operations as one point at a time); only the
    // leaf's own points are offered, in order.
    for (int base = node.a; base < node.b; base += kLeafSize) {
      const float* x = coords_[0].data() + base;
      const float* y = coords_[1].data() + base;
      const float* z = coords_[2].data() + base;
      float d[kLeafSize];
      for (int j = 0; j < kLeafSize; ++j) {
        const float dx = q[0] - x[j], dy = q[1] - y[j], dz = q[2] - z[j];
        d[j] = dx * dx + dy * dy + dz * dz;
      }
      const int n = std::min(kLeafSize, node.b - base);
      for (int j = 0; j < n; ++j)
        if (d[j] < r->worst) r->Offer(base + j, d[j]);
    }
    return;
  }
  // Incremental cell distance (Arya & Mount, as nanoflann): min_sq is the squared distance from q to the node's
  // cell, axis_sq[d] its per-axis terms; the far child's cell differs only along this node's axis.
  const float to_left = q[node.axis] - node.left_max;    // > 0: q is right of every left point
  const float to_right = q[node.axis] - node.right_min;  // < 0: q is left of every right point
  const bool go_left = to_left + to_right < 0.0f;
  const int near = go_left ? node.a : node.b;
  const int far = go_left ? node.b : node.a;
  // The far child's distance along the axis; 0 where moved points made the children's bounds overlap around q
  // (infinite for an empty side: it is never entered).
  const float cut = go_left ? (to_right < 0.0f ? to_right * to_right : 0.0f)
                            : (to_left > 0.0f ? to_left * to_left : 0.0f);
  Search(near, q, min_sq, axis_sq, r);
  const float saved = axis_sq[node.axis];
  const float far_sq = min_sq - saved + cut;
  if (far_sq < r->worst) {
    axis_sq[node.axis] = cut;
    Search(far, q, far_sq, axis_sq, r);
    axis_sq[node.axis] = saved;
  }
}

int KdTree3f::Nearest(const float q[3], int k, int* indices, float* sq_dist, float max_sq_dist, float* xyz) const {
  ROTOLIDAR_CHECK(k >= 1 && k <= kMaxK, "k = " << k);
  ROTOLIDAR_CHECK(dirty_leaves_.empty(), "KdTree3f::Nearest after Move / Hide without Refit");
  if (nodes_.empty()) return 0;
  Result r;
  r.k = k;
  r.worst = max_sq_dist;
  float axis_sq[3] = {0.0f, 0.0f, 0.0f};
  Search(0, q, 0.0f, axis_sq, &r);
  for (int i = 0; i < r.count; ++i) {
    indices[i] = original_[size_t(r.index[i])];
    sq_dist[i] = r.dist[i];
  }
  if (xyz != nullptr)  // from the tree's own copy: just searched, so in cache
    for (int i = 0; i < r.count; ++i)
      for (int d = 0; d < 3; ++d) xyz[3 * i + d] = coords_[d][size_t(r.index[i])];
  return r.count;
}

}  // namespace rotolidar
