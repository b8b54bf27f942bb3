#include <gtest/gtest.h>

#include <vector>

#include "core/util/chunked_vector.hpp"

namespace rotolidar {
namespace {

// The same sequence of push_back / resize gives the same elements as a std::vector, across chunk borders.
TEST(ChunkedVector, MatchesStdVectorAcrossChunks) {
  ChunkedVector<int> chunked(7);
  std::vector<int> reference;
  for (int i = 0; i < 100; ++i) {
    chunked.push_back(i * 3);
    reference.push_back(i * 3);
  }
  chunked.resize(30);
  reference.resize(30);
  chunked.resize(45);
  reference.resize(45);
  for (size_t i = 30; i < 45; ++i) chunked[i] = reference[i] = int(i);  // grown elements are written first
  for (int i = 0; i < 10; ++i) {
    chunked.push_back(-i);
    reference.push_back(-i);
  }
  ASSERT_EQ(chunked.size(), reference.size());
  for (size_t i = 0; i < reference.size(); ++i) EXPECT_EQ(chunked[i], reference[i]) << i;
  chunked.clear();
  EXPECT_TRUE(chunked.empty());
}

// Growing never moves what is stored: a pointer into an early chunk stays valid (the point of chunking).
TEST(ChunkedVector, GrowthKeepsAddresses) {
  ChunkedVector<double> chunked(4);
  chunked.push_back(1.5);
  const double* first = &chunked[0];
  for (int i = 0; i < 1000; ++i) chunked.push_back(i);
  EXPECT_EQ(first, &chunked[0]);
  EXPECT_EQ(*first, 1.5);
}

}  // namespace
}  // namespace rotolidar
