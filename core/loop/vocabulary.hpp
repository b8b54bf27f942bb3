#pragma once
// A bag-of-binary-words vocabulary in the manner of DBoW2 (Galvez-Lopez & Tardos, "Bags of Binary Words for Fast
// Place Recognition in Image Sequences", IEEE T-RO 28(5), 2012): a hierarchical k-medians tree over 256-bit ORB
// descriptors whose leaves are the visual words, with TF-IDF word weights and the L1 score. It is stage 1 of the
// two-stage loop closure of LV-SLAM (Sensors 2025, Sec. 3.4): images are turned into sparse word vectors and
// compared through the inverted index of core/loop/bow_database.hpp.
//
// Training (Nister & Stewenius, "Scalable recognition with a vocabulary tree", CVPR 2006; DBoW2's k-majority for
// binary data): the descriptors are split into `branching` clusters seeded by k-means++ (Arthur & Vassilvitskii
// 2007) under the Hamming distance, each centre being the bitwise majority of its members, and every cluster is split
// again down to `depth` levels, so the vocabulary has at most branching^depth words. A cluster whose descriptors are
// all equal, or that reaches the depth, is a leaf. The IDF weight of word i is log(N / n_i): N training images, n_i
// of them with at least one descriptor falling into word i (descended through the tree, as Transform does); a word
// no training image reaches is weighted as if one did (log N).
//
// Thread-safety: Train and Load modify the vocabulary; every const method may run concurrently with other const
// methods. Failures come back as Status; a failed Train or Load leaves the vocabulary as it was. Only a programmer
// error throws (ROTOLIDAR_CHECK: FindWord on an empty vocabulary).
#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "core/loop/orb_features.hpp"
#include "core/util/status.hpp"

namespace rotolidar::loop {

using WordId = uint32_t;  ///< a leaf of the tree, numbered 0 .. num_words() - 1 in node order
using NodeId = uint32_t;  ///< a tree node; 0 is the root

/// Sparse word histogram: word -> TF-IDF weight, sorted by word. Transform's output sums to 1 (L1-normalised).
using BowVector = std::map<WordId, double>;
/// Direct index for feature matching: node of the tree -> indices (rows of the descriptor matrix) of the features
/// that passed through it, ascending.
using FeatureVector = std::map<NodeId, std::vector<uint32_t>>;

/// Training parameters. Default k = 10, L = 5: at most 10^5 words. The depth sets how well unrelated images are
/// told apart: with ~1000 ORB features per image, two unrelated images score about features / (effectively used
/// words) by chance, measured 0.14 with 10^4 words (L = 4) and 0.05 with ~5 10^4 words on synthetic textures,
/// while views of one place after a small viewpoint change score ~0.15-0.3; the seed's eta >= 0.35 (bow_database.hpp)
/// needs the chance score well below that. DBoW2's ORB vocabulary (ORB-SLAM) uses k = 10, L = 6 on ~10^7
/// descriptors; L = 5 wants a few hundred thousand training descriptors and saves up to 4.9 MB (44 bytes a node).
struct VocabularyConfig {
  int branching = 10;       ///< k: children per node, >= 2
  int depth = 5;            ///< L: levels below the root, >= 1; branching^depth <= 2^24
  int max_iterations = 20;  ///< k-majority rounds per node; a node stops earlier once no assignment changes
  uint64_t seed = 1;        ///< RandomStream(seed, "vocabulary.kmeans++"): same seed and data -> same tree

  bool Validate(std::string* error) const;
};

/// What Train built.
struct VocabularyTrainStats {
  size_t num_images = 0;       ///< training images with at least one descriptor (N of the IDF)
  size_t num_descriptors = 0;
  size_t num_nodes = 0;        ///< including the root
  size_t num_words = 0;
  size_t unreached_words = 0;  ///< words no training descriptor descends to (weighted log N)
};

class Vocabulary {
 public:
  /// Builds the tree from per-image descriptor matrices (CV_8U, 32 columns, one row per feature; an empty matrix
  /// is an image without features). Fails on another type or shape (naming the image index), an invalid config
  /// or fewer than 2 images with descriptors (the IDF of a single image is 0 for every word). `progress`, when
  /// given, is called with the trained fraction in [0, 1] (at most ~100 times). Deterministic: the same
  /// descriptors (in the same order) and config give the same tree, byte for byte.
  Status Train(const std::vector<cv::Mat>& descriptors_per_image, const VocabularyConfig& config,
               VocabularyTrainStats* stats = nullptr, const std::function<void(double)>& progress = {});

  /// Writes the vocabulary in this module's own format (not DBoW2's or ORB-SLAM's text files; little-endian:
  /// magic "RLBOWVOC", version, k, L, counts, per node its parent, centre and weight, FNV-1a checksum) to `path`
  /// through a temporary file renamed into place, so a failure leaves no partial file. Fails, naming the file,
  /// when the vocabulary is empty or the file cannot be written.
  Status Save(const std::string& path) const;
  /// Reads a file written by Save. A missing, truncated, oversized or corrupt file (bad magic, version, counts,
  /// tree structure or checksum) fails with a message naming the file and the byte offset.
  Status Load(const std::string& path);

  bool empty() const { return words_.empty(); }
  int branching() const { return branching_; }
  int depth() const { return depth_; }
  size_t num_words() const { return words_.size(); }
  size_t num_nodes() const { return nodes_.size(); }
  uint64_t num_training_images() const { return num_training_images_; }
  /// IDF weight of a word (>= 0); 0 for an id out of range.
  double WordWeight(WordId word) const { return word < words_.size() ? weights_[word] : 0.0; }
  /// The node a word is (its leaf).
  NodeId WordNode(WordId word) const { return word < words_.size() ? words_[word] : 0; }
  /// Level of a node: 0 for the root, 1..depth() below it.
  int NodeLevel(NodeId node) const { return node < nodes_.size() ? nodes_[node].level : -1; }

  /// The word of one descriptor (kOrbDescriptorBytes bytes), found by descending to the nearest child (Hamming
  /// distance; ties go to the lower node id) at each level. The vocabulary must not be empty (ROTOLIDAR_CHECK).
  WordId FindWord(const uint8_t* descriptor) const;

  /// The BoW vector of an image: each descriptor adds its word's IDF weight, then the vector is L1-normalised, so
  /// weights are TF-IDF (DBoW2's TF_IDF weighting). Words of weight 0 (in every training image) are left out.
  /// With `features`, also the direct index at `levels_up` levels above the leaves: each feature is listed under
  /// its ancestor at level depth() - levels_up (under its leaf when the leaf is shallower). Fails (outputs empty) on
  /// an empty vocabulary or descriptors that are not CV_8U with 32 columns; no descriptors give empty outputs.
  Status Transform(const cv::Mat& descriptors, BowVector* bow, FeatureVector* features = nullptr,
                   int levels_up = 0) const;

  /// DBoW2's L1 score s(a, b) = 1 - 0.5 * || a/|a|_1 - b/|b|_1 ||_1, in [0, 1]: 1 for vectors proportional to
  /// each other, 0 for vectors without a common word (or an empty one). Symmetric. Weights must be >= 0.
  static double Score(const BowVector& a, const BowVector& b);

 private:
  struct Node {
    NodeId parent = 0;
    uint32_t first_child = 0;   ///< children are the consecutive ids [first_child, first_child + num_children)
    uint32_t num_children = 0;  ///< 0 for a leaf
    WordId word = 0;            ///< valid for leaves
    int level = 0;
  };
  struct Builder;
  struct Reader;
  const uint8_t* NodeDescriptor(NodeId node) const { return &descriptors_[size_t(node) * kOrbDescriptorBytes]; }
  NodeId DescendToLeaf(const uint8_t* descriptor, int ancestor_level, NodeId* ancestor) const;
  void NumberWords();
  std::vector<uint8_t> Serialise() const;

  int branching_ = 0;
  int depth_ = 0;
  uint64_t num_training_images_ = 0;
  std::vector<Node> nodes_;             ///< nodes_[0] is the root
  std::vector<uint8_t> descriptors_;    ///< kOrbDescriptorBytes per node (the root's are zero)
  std::vector<NodeId> words_;           ///< word -> leaf node
  std::vector<double> weights_;         ///< word -> IDF weight
};

}  // namespace rotolidar::loop
