#pragma once
// A growable array in fixed-size chunks: push_back never moves the elements already stored, so a container that
// grows for hours (the dense map) costs the same per element at every size. A std::vector doubles and copies its
// whole content, which for a map of 1e7 points is a stall of seconds at each doubling and a transient 3x memory
// peak. Elements are not contiguous across chunks; within a chunk they are (ChunkOf(i) is the start of i's chunk).
//
// chunk_size: elements per chunk, fixed at construction (> 0). Indexing costs one division and two loads.
// Ownership: owns its elements. Thread safety: none.
#include <cstddef>
#include <memory>
#include <vector>

namespace rotolidar {

template <typename T>
class ChunkedVector {
 public:
  explicit ChunkedVector(size_t chunk_size = size_t(1) << 16) : chunk_size_(chunk_size) {}

  size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }
  size_t chunk_size() const { return chunk_size_; }

  T& operator[](size_t i) { return chunks_[i / chunk_size_][i % chunk_size_]; }
  const T& operator[](size_t i) const { return chunks_[i / chunk_size_][i % chunk_size_]; }

  void push_back(const T& value) {
    if (size_ == chunks_.size() * chunk_size_) chunks_.push_back(std::make_unique<T[]>(chunk_size_));
    (*this)[size_++] = value;
  }

  /// Grows or shrinks (freeing whole chunks no longer used). Grown elements hold unspecified values (for a
  /// trivial T, what an earlier shrink left there): write them before reading them.
  void resize(size_t n) {
    while (chunks_.size() * chunk_size_ < n) chunks_.push_back(std::make_unique<T[]>(chunk_size_));
    size_ = n;
    chunks_.resize((n + chunk_size_ - 1) / chunk_size_);
  }

  void clear() { resize(0); }

 private:
  size_t chunk_size_;
  size_t size_ = 0;
  std::vector<std::unique_ptr<T[]>> chunks_;
};

}  // namespace rotolidar
