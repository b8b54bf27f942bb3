#pragma once
// Internal to core/preprocess/filters.cpp: the ring-order neighbourhood statistic behind
// RingNeighbourMeanDistances (filters.hpp has the contract; docs/features.md the design). Templates on the
// K-smallest slot width, hence a header. Not a public interface: include filters.hpp instead.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "core/preprocess/filters.hpp"
#include "core/util/log.hpp"

namespace rotolidar {
namespace ring_sor {

/// One ring in firing order (ties: input order), positions as contiguous arrays for the distance loops.
struct RingCloud {
  std::vector<uint32_t> index;  ///< input indices
  std::vector<float> x, y, z;
  std::vector<double> t_s;
};

/// The scan's rings. Decoded scans arrive in firing order, so the sort is usually skipped.
inline std::vector<RingCloud> SplitRings(const std::vector<ScanPoint>& points) {
  std::vector<uint32_t> count;
  for (const ScanPoint& p : points) {
    if (p.ring >= count.size()) count.resize(p.ring + 1u, 0);
    ++count[p.ring];
  }
  std::vector<RingCloud> rings(count.size());
  for (std::size_t r = 0; r < rings.size(); ++r) rings[r].index.reserve(count[r]);
  for (std::size_t i = 0; i < points.size(); ++i) rings[points[i].ring].index.push_back(static_cast<uint32_t>(i));
  const auto earlier = [&](uint32_t a, uint32_t b) { return points[a].t_s < points[b].t_s; };
  for (RingCloud& ring : rings) {
    if (!std::is_sorted(ring.index.begin(), ring.index.end(), earlier))
      std::stable_sort(ring.index.begin(), ring.index.end(), earlier);
    const std::size_t n = ring.index.size();
    ring.x.resize(n), ring.y.resize(n), ring.z.resize(n), ring.t_s.resize(n);
    for (std::size_t j = 0; j < n; ++j) {
      const ScanPoint& p = points[ring.index[j]];
      ring.x[j] = p.p_base.x(), ring.y[j] = p.p_base.y(), ring.z[j] = p.p_base.z(), ring.t_s[j] = p.t_s;
    }
  }
  return rings;
}

/// First of 2 * half + 1 positions centred on `centre` where possible, shifted inside [0, n).
inline int WindowStart(int centre, int half, int n) { return std::max(0, std::min(centre - half, n - 1 - 2 * half)); }

/// For each position of `from`, the position of `to` fired closest in time (both in time order: one merge pass).
inline std::vector<int> ClosestInTime(const RingCloud& from, const RingCloud& to) {
  std::vector<int> closest(from.t_s.size());
  std::size_t c = 0;
  for (std::size_t j = 0; j < from.t_s.size(); ++j) {
    while (c + 1 < to.t_s.size() && std::abs(to.t_s[c + 1] - from.t_s[j]) <= std::abs(to.t_s[c] - from.t_s[j])) ++c;
    closest[j] = static_cast<int>(c);
  }
  return closest;
}

/// The K smallest of a stream of values, kept sorted: on each new value v, slot i (slot 0 = -inf, unused slots
/// +inf) becomes min(slot i, max(slot i - 1, v)), a branch-free update over a fixed width (near-range neighbour
/// distances are dominated by range noise, so their order is random and a branching insertion mispredicts; this
/// costs half of nth_element per point). Holds K <= kSlots.
template <int kSlots>
class KSmallest {
 public:
  explicit KSmallest(int k) : k_(k) { ROTOLIDAR_CHECK(k >= 1 && k <= kSlots, "k = " << k); }
  void Clear() {
    buf_.fill(std::numeric_limits<float>::infinity());
    buf_[0] = -std::numeric_limits<float>::infinity();
    n_ = 0;
  }
  void Add(float v) {
    ++n_;
    if (!(v < buf_[k_])) return;  // not among the K smallest so far (most far candidates)
    std::array<float, kSlots> next;
    const float* prev = buf_.data();  // prev[i] = slot i, cur[i] = slot i + 1
    const float* cur = buf_.data() + 1;
    for (int i = 0; i < kSlots; ++i) next[i] = std::min(cur[i], std::max(prev[i], v));
    std::copy(next.begin(), next.end(), buf_.begin() + 1);
  }
  /// Mean of the square roots of the K smallest (of all values when fewer came; NaN when none).
  float MeanSqrt() const {
    const int use = std::min(n_, k_);
    float sum = 0.f;
    for (int i = 1; i <= use; ++i) sum += std::sqrt(buf_[i]);
    return use ? sum / static_cast<float>(use) : std::numeric_limits<float>::quiet_NaN();
  }

 private:
  int k_;
  int n_ = 0;
  std::array<float, kSlots + 1> buf_{};  ///< slot 0 = -inf, then the kept values ascending, +inf where unused
};

/// An adjacent ring and, per position of the ring being scanned, the position fired closest in time on it.
struct AdjacentRing {
  const RingCloud* ring;
  std::vector<int> closest;
};

/// d_j of one position j (scalar path: any position, the ring ends included). kSlots >= k.
template <int kSlots>
float PointMeanDistance(const RingCloud& ring, int j, const std::vector<AdjacentRing>& others,
                        const SorNeighbourhood& hood, KSmallest<kSlots>* best) {
  const int n = static_cast<int>(ring.index.size());
  const float px = ring.x[j], py = ring.y[j], pz = ring.z[j];
  const auto sq = [&](const RingCloud& o, int q) {
    const float dx = o.x[q] - px, dy = o.y[q] - py, dz = o.z[q] - pz;
    return dx * dx + dy * dy + dz * dz;
  };
  best->Clear();
  const int first = WindowStart(j, hood.ring_window, n), last = std::min(n - 1, first + 2 * hood.ring_window);
  for (int q = first; q <= last; ++q)
    if (q != j) best->Add(sq(ring, q));
  for (const AdjacentRing& other : others) {
    const int m = static_cast<int>(other.ring->index.size());
    const int lo = WindowStart(other.closest[j], hood.adjacent_window, m);
    const int hi = std::min(m - 1, lo + 2 * hood.adjacent_window);
    for (int q = lo; q <= hi; ++q) best->Add(sq(*other.ring, q));
  }
  return best->MeanSqrt();
}

#if defined(__SSE2__)
/// PointMeanDistance for the 4 positions j..j+3 at once, one SSE lane each (the same float operations in the same
/// order, so bit-identical): needs ring_window <= j and j + 3 + ring_window < n (no window shifted at a ring end),
/// so that every lane has the same candidate count.
template <int kSlots>
void FourMeanDistances(const RingCloud& ring, int j, const std::vector<AdjacentRing>& others,
                       const SorNeighbourhood& hood, int k, float* out) {
  __m128 buf[kSlots + 1];  // as KSmallest, per lane
  buf[0] = _mm_set1_ps(-std::numeric_limits<float>::infinity());
  for (int i = 1; i <= kSlots; ++i) buf[i] = _mm_set1_ps(std::numeric_limits<float>::infinity());
  const __m128 px = _mm_loadu_ps(&ring.x[j]), py = _mm_loadu_ps(&ring.y[j]), pz = _mm_loadu_ps(&ring.z[j]);
  const auto add = [&](__m128 qx, __m128 qy, __m128 qz) {
    const __m128 dx = _mm_sub_ps(qx, px), dy = _mm_sub_ps(qy, py), dz = _mm_sub_ps(qz, pz);
    const __m128 v = _mm_add_ps(_mm_add_ps(_mm_mul_ps(dx, dx), _mm_mul_ps(dy, dy)), _mm_mul_ps(dz, dz));
    for (int i = kSlots; i >= 1; --i) buf[i] = _mm_min_ps(buf[i], _mm_max_ps(buf[i - 1], v));
  };
  int count = 0;
  for (int s = 1; s <= hood.ring_window; ++s, count += 2) {
    add(_mm_loadu_ps(&ring.x[j - s]), _mm_loadu_ps(&ring.y[j - s]), _mm_loadu_ps(&ring.z[j - s]));
    add(_mm_loadu_ps(&ring.x[j + s]), _mm_loadu_ps(&ring.y[j + s]), _mm_loadu_ps(&ring.z[j + s]));
  }
  for (const AdjacentRing& other : others) {
    const RingCloud& o = *other.ring;
    const int m = static_cast<int>(o.index.size());
    int lo[4];
    for (int l = 0; l < 4; ++l) lo[l] = WindowStart(other.closest[j + l], hood.adjacent_window, m);
    const int width = std::min(m, 2 * hood.adjacent_window + 1);  // the same in every lane
    for (int t = 0; t < width; ++t, ++count) {
      const int a = lo[0] + t, b = lo[1] + t, c = lo[2] + t, d = lo[3] + t;
      add(_mm_setr_ps(o.x[a], o.x[b], o.x[c], o.x[d]), _mm_setr_ps(o.y[a], o.y[b], o.y[c], o.y[d]),
          _mm_setr_ps(o.z[a], o.z[b], o.z[c], o.z[d]));
    }
  }
  const int use = std::min(count, k);
  __m128 sum = _mm_setzero_ps();
  for (int i = 1; i <= use; ++i) sum = _mm_add_ps(sum, _mm_sqrt_ps(buf[i]));
  const __m128 mean = use ? _mm_div_ps(sum, _mm_set1_ps(static_cast<float>(use)))
                          : _mm_set1_ps(std::numeric_limits<float>::quiet_NaN());
  _mm_storeu_ps(out, mean);
}
#endif

/// d_i of the ring neighbourhood (SorNeighbourhood) for every point: the mean distance to its K nearest
/// candidates, NaN when it has none. Indexed like `points`. kSlots >= k. vectorised: positions away from the ring
/// ends go 4 at a time (FourMeanDistances), with the same result.
template <int kSlots>
std::vector<float> RingNeighbourDistances(const std::vector<ScanPoint>& points, int k, const SorNeighbourhood& hood,
                                          bool vectorised) {
  const std::vector<RingCloud> rings = SplitRings(points);
  const int n_rings = static_cast<int>(rings.size());
  std::vector<float> mean_dist(points.size(), std::numeric_limits<float>::quiet_NaN());
  KSmallest<kSlots> best(k);
  std::vector<AdjacentRing> others;
  for (int r = 0; r < n_rings; ++r) {
    const RingCloud& ring = rings[r];
    const int n = static_cast<int>(ring.index.size()), w = hood.ring_window;
    others.clear();
    for (int rr = std::max(0, r - hood.adjacent_rings); rr <= std::min(n_rings - 1, r + hood.adjacent_rings); ++rr)
      if (rr != r && !rings[rr].index.empty()) others.push_back({&rings[rr], ClosestInTime(ring, rings[rr])});
    for (int j = 0; j < n;) {
#if defined(__SSE2__)
      if (vectorised && j >= w && j + 3 + w < n) {
        float four[4];
        FourMeanDistances<kSlots>(ring, j, others, hood, k, four);
        for (int l = 0; l < 4; ++l) mean_dist[ring.index[j + l]] = four[l];
        j += 4;
        continue;
      }
#endif
      mean_dist[ring.index[j]] = PointMeanDistance<kSlots>(ring, j, others, hood, &best);
      ++j;
    }
  }
  return mean_dist;
}

}  // namespace ring_sor
}  // namespace rotolidar
