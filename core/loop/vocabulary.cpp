#include "core/loop/vocabulary.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <utility>

#include "core/util/log.hpp"
#include "core/util/rng.hpp"
#include "core/util/validation.hpp"

namespace rotolidar::loop {
namespace {

constexpr int kBytes = kOrbDescriptorBytes;
constexpr char kMagic[8] = {'R', 'L', 'B', 'O', 'W', 'V', 'O', 'C'};
constexpr uint32_t kVersion = 1;
constexpr size_t kHeaderBytes = 40;                    // magic, version, bytes, k, L, nodes, words, images
constexpr size_t kNodeBytes = 4 + kBytes + 8;          // parent, descriptor, weight
constexpr size_t kChecksumBytes = 8;
constexpr uint32_t kMaxNodes = 1u << 26;               // sanity bound for a header read from disk

// Bit count without the popcnt instruction (the build does not assume one): twice as fast as libgcc's fallback.
int PopCount(uint64_t x) {
  x = x - ((x >> 1) & 0x5555555555555555ULL);
  x = (x & 0x3333333333333333ULL) + ((x >> 2) & 0x3333333333333333ULL);
  x = (x + (x >> 4)) & 0x0f0f0f0f0f0f0f0fULL;
  return int((x * 0x0101010101010101ULL) >> 56);
}

int Hamming(const uint8_t* a, const uint8_t* b) {
  uint64_t x[4], y[4];
  std::memcpy(x, a, kBytes);
  std::memcpy(y, b, kBytes);
  return PopCount(x[0] ^ y[0]) + PopCount(x[1] ^ y[1]) + PopCount(x[2] ^ y[2]) + PopCount(x[3] ^ y[3]);
}

uint64_t Fnv1a64(const uint8_t* data, size_t size) {
  uint64_t h = 0xcbf29ce484222325ULL;
  for (size_t i = 0; i < size; ++i) h = (h ^ data[i]) * 0x100000001b3ULL;
  return h;
}

// Little-endian encoding, independent of the host; doubles travel as their IEEE-754 bits.
void PutLe(std::vector<uint8_t>* out, uint64_t v, int bytes) {
  for (int i = 0; i < bytes; ++i) out->push_back(uint8_t(v >> (8 * i)));
}
uint64_t GetLe(const uint8_t* p, int bytes) {
  uint64_t v = 0;
  for (int i = 0; i < bytes; ++i) v |= uint64_t(p[i]) << (8 * i);
  return v;
}

Status CheckDescriptors(const cv::Mat& m, const std::string& what) {
  if (m.empty()) return Status::Ok();
  if (m.type() != CV_8UC1 || m.cols != kBytes)
    return Status::Error(what + ": descriptors must be CV_8U with " + std::to_string(kBytes) + " columns (got type " +
                         std::to_string(m.type()) + ", " + std::to_string(m.cols) + " columns)");
  return Status::Ok();
}

}  // namespace

bool VocabularyConfig::Validate(std::string* error) const {
  if (branching < 2) return FailValidation(error, "vocabulary.branching: must be >= 2");
  if (depth < 1) return FailValidation(error, "vocabulary.depth: must be >= 1");
  if (depth * std::log2(double(branching)) > 24.0)
    return FailValidation(error, "vocabulary: branching^depth must not exceed 2^24 words");
  if (max_iterations < 1) return FailValidation(error, "vocabulary.max_iterations: must be >= 1");
  return true;
}

// Hierarchical k-majority clustering (DBoW2's HKmeansStep for binary descriptors), depth first so that the
// children of a node get consecutive ids and one random stream is consumed in a fixed order.
struct Vocabulary::Builder {
  const VocabularyConfig& config;
  std::vector<const uint8_t*> rows;
  Vocabulary* vocabulary;
  const std::function<void(double)>& progress;
  RandomStream rng;
  size_t finished = 0;
  int last_percent = -1;

  void Split(NodeId node, const std::vector<uint32_t>& members) {
    const int level = vocabulary->nodes_[node].level;
    if (level == config.depth || AllEqual(members)) return Finish(members.size());
    std::vector<uint8_t> centres;
    std::vector<std::vector<uint32_t>> groups = Cluster(members, &centres);
    const NodeId first = NodeId(vocabulary->nodes_.size());
    vocabulary->nodes_[node].first_child = first;
    vocabulary->nodes_[node].num_children = uint32_t(groups.size());
    for (size_t c = 0; c < groups.size(); ++c) {
      Node child;
      child.parent = node;
      child.level = level + 1;
      vocabulary->nodes_.push_back(child);
    }
    vocabulary->descriptors_.insert(vocabulary->descriptors_.end(), centres.begin(), centres.end());
    for (size_t c = 0; c < groups.size(); ++c) Split(first + NodeId(c), groups[c]);
  }

  bool AllEqual(const std::vector<uint32_t>& members) const {
    for (uint32_t m : members)
      if (std::memcmp(rows[m], rows[members[0]], kBytes) != 0) return false;
    return true;
  }

  void Finish(size_t count) {
    finished += count;
    const int percent = int(100 * finished / rows.size());
    if (progress && percent != last_percent) progress(double(finished) / double(rows.size()));
    last_percent = percent;
  }

  // k-means++ seeding with D^2 sampling; stops early when every member coincides with a centre.
  void Seed(const std::vector<uint32_t>& members, std::vector<uint8_t>* centres) {
    const size_t n = members.size();
    const auto squared = [&](size_t i, const uint8_t* centre) {
      const double d = Hamming(rows[members[i]], centre);
      return d * d;  // exact: integer sums stay below 2^53, so the sampling is the same on every platform
    };
    const uint8_t* first = rows[members[rng.NextU64() % n]];
    centres->assign(first, first + kBytes);
    std::vector<double> d2(n);
    for (size_t i = 0; i < n; ++i) d2[i] = squared(i, first);
    while (centres->size() < size_t(config.branching) * kBytes) {
      double sum = 0.0;
      for (double d : d2) sum += d;
      if (sum <= 0.0) break;
      const double cut = rng.Uniform() * sum;
      size_t pick = 0;
      for (double acc = d2[0]; acc <= cut && pick + 1 < n;) acc += d2[++pick];
      while (d2[pick] <= 0.0) --pick;  // rounding at the end of the walk: step back to a real candidate
      const uint8_t* centre = rows[members[pick]];
      centres->insert(centres->end(), centre, centre + kBytes);
      for (size_t i = 0; i < n; ++i) d2[i] = std::min(d2[i], squared(i, centre));
    }
  }

  // Alternates nearest-centre assignment and bitwise-majority centres; the returned groups are those of the
  // final centres (the last step is always an assignment), empty clusters dropped.
  std::vector<std::vector<uint32_t>> Cluster(const std::vector<uint32_t>& members, std::vector<uint8_t>* centres) {
    Seed(members, centres);
    const size_t n = members.size(), k = centres->size() / kBytes;
    std::vector<uint32_t> assign(n, uint32_t(k));
    for (int iteration = 0; iteration < config.max_iterations; ++iteration) {
      bool changed = false;
      for (size_t i = 0; i < n; ++i) {
        uint32_t best = 0;
        int best_d = Hamming(rows[members[i]], centres->data());
        for (size_t c = 1; c < k; ++c) {
          const int d = Hamming(rows[members[i]], centres->data() + c * kBytes);
          if (d < best_d) best_d = d, best = uint32_t(c);
        }
        changed |= assign[i] != best;
        assign[i] = best;
      }
      if (!changed || iteration + 1 == config.max_iterations) break;
      UpdateCentres(members, assign, centres);
    }
    std::vector<std::vector<uint32_t>> groups(k);
    for (size_t i = 0; i < n; ++i) groups[assign[i]].push_back(members[i]);
    for (size_t c = k; c-- > 0;) {  // backwards, so erasing keeps the lower indices valid
      if (!groups[c].empty()) continue;
      groups.erase(groups.begin() + long(c));
      centres->erase(centres->begin() + long(c * kBytes), centres->begin() + long((c + 1) * kBytes));
    }
    return groups;
  }

  // Each bit of a centre is the majority of its members' bits (a tie sets it, as in DBoW2); an empty cluster
  // keeps its centre.
  void UpdateCentres(const std::vector<uint32_t>& members, const std::vector<uint32_t>& assign,
                     std::vector<uint8_t>* centres) const {
    const size_t k = centres->size() / kBytes;
    std::vector<uint32_t> ones(k * kBytes * 8, 0), count(k, 0);
    for (size_t i = 0; i < members.size(); ++i) {
      uint32_t* c = &ones[assign[i] * kBytes * 8];
      ++count[assign[i]];
      for (int b = 0; b < kBytes * 8; ++b) c[b] += (rows[members[i]][b >> 3] >> (7 - (b & 7))) & 1u;
    }
    for (size_t c = 0; c < k; ++c) {
      if (count[c] == 0) continue;
      uint8_t* centre = centres->data() + c * kBytes;
      std::fill(centre, centre + kBytes, 0);
      for (int b = 0; b < kBytes * 8; ++b)
        if (2 * ones[c * kBytes * 8 + b] >= count[c]) centre[b >> 3] |= uint8_t(1u << (7 - (b & 7)));
    }
  }
};

Status Vocabulary::Train(const std::vector<cv::Mat>& descriptors_per_image, const VocabularyConfig& config,
                         VocabularyTrainStats* stats, const std::function<void(double)>& progress) {
  std::string why;
  if (!config.Validate(&why)) return Status::Error(why);
  Vocabulary v;
  v.branching_ = config.branching;
  v.depth_ = config.depth;
  v.nodes_.assign(1, Node());
  v.descriptors_.assign(kBytes, 0);
  Builder builder{config, {}, &v, progress, RandomStream(config.seed, "vocabulary.kmeans++")};
  for (size_t i = 0; i < descriptors_per_image.size(); ++i) {
    const cv::Mat& m = descriptors_per_image[i];
    if (Status s = CheckDescriptors(m, "vocabulary training image " + std::to_string(i)); !s) return s;
    for (int r = 0; r < m.rows; ++r) builder.rows.push_back(m.ptr<uint8_t>(r));
    v.num_training_images_ += m.rows > 0;
  }
  if (v.num_training_images_ < 2)
    return Status::Error("vocabulary training: needs descriptors from at least 2 images (IDF weights), got " +
                         std::to_string(v.num_training_images_));
  if (builder.rows.size() >= kMaxNodes) return Status::Error("vocabulary training: more than 2^26 descriptors");
  std::vector<uint32_t> all(builder.rows.size());
  for (size_t i = 0; i < all.size(); ++i) all[i] = uint32_t(i);
  builder.Split(0, all);
  v.NumberWords();

  // IDF: the number of images each word appears in, found by descending as Transform does.
  std::vector<uint64_t> images_with(v.words_.size(), 0), last_image(v.words_.size(), 0);
  uint64_t image_number = 0;
  for (const cv::Mat& m : descriptors_per_image) {
    if (m.rows > 0) ++image_number;
    for (int r = 0; r < m.rows; ++r) {
      const WordId w = v.FindWord(m.ptr<uint8_t>(r));
      if (last_image[w] != image_number) ++images_with[w], last_image[w] = image_number;
    }
  }
  v.weights_.resize(v.words_.size());
  size_t unreached = 0;
  for (size_t w = 0; w < v.words_.size(); ++w) {
    unreached += images_with[w] == 0;
    v.weights_[w] = std::log(double(v.num_training_images_) / double(std::max<uint64_t>(images_with[w], 1)));
  }
  if (stats)
    *stats = {size_t(v.num_training_images_), builder.rows.size(), v.nodes_.size(), v.words_.size(), unreached};
  *this = std::move(v);
  return Status::Ok();
}

void Vocabulary::NumberWords() {
  words_.clear();
  for (NodeId n = 1; n < nodes_.size(); ++n) {
    if (nodes_[n].num_children != 0) continue;
    nodes_[n].word = WordId(words_.size());
    words_.push_back(n);
  }
}

NodeId Vocabulary::DescendToLeaf(const uint8_t* descriptor, int ancestor_level, NodeId* ancestor) const {
  NodeId node = 0;
  if (ancestor) *ancestor = 0;
  while (nodes_[node].num_children > 0) {
    const Node& parent = nodes_[node];
    NodeId best = parent.first_child;
    int best_d = Hamming(descriptor, NodeDescriptor(best));
    for (NodeId c = best + 1; c < parent.first_child + parent.num_children; ++c) {
      const int d = Hamming(descriptor, NodeDescriptor(c));
      if (d < best_d) best_d = d, best = c;
    }
    node = best;
    if (ancestor && nodes_[node].level <= ancestor_level) *ancestor = node;
  }
  return node;
}

WordId Vocabulary::FindWord(const uint8_t* descriptor) const {
  ROTOLIDAR_CHECK(!empty(), "FindWord on an empty vocabulary");
  return nodes_[DescendToLeaf(descriptor, 0, nullptr)].word;
}

Status Vocabulary::Transform(const cv::Mat& descriptors, BowVector* bow, FeatureVector* features,
                             int levels_up) const {
  bow->clear();
  if (features) features->clear();
  if (empty()) return Status::Error("vocabulary: Transform on an empty vocabulary");
  if (Status s = CheckDescriptors(descriptors, "vocabulary: Transform"); !s) return s;
  const int ancestor_level = depth_ - std::clamp(levels_up, 0, depth_);
  for (int r = 0; r < descriptors.rows; ++r) {
    NodeId ancestor = 0;
    const WordId word = nodes_[DescendToLeaf(descriptors.ptr<uint8_t>(r), ancestor_level, &ancestor)].word;
    const double weight = weights_[word];
    if (weight <= 0.0) continue;
    (*bow)[word] += weight;
    if (features) (*features)[ancestor].push_back(uint32_t(r));
  }
  double sum = 0.0;
  for (const auto& [word, weight] : *bow) sum += weight;
  for (auto& [word, weight] : *bow) weight /= sum;
  return Status::Ok();
}

double Vocabulary::Score(const BowVector& a, const BowVector& b) {
  double norm_a = 0.0, norm_b = 0.0;
  for (const auto& [word, weight] : a) norm_a += std::abs(weight);
  for (const auto& [word, weight] : b) norm_b += std::abs(weight);
  if (!(norm_a > 0.0) || !(norm_b > 0.0)) return 0.0;
  // Over the common words only: |x - y| - |x| - |y| is the change of ||a - b||_1 from its disjoint value 2.
  double delta = 0.0;
  auto ia = a.begin(), ib = b.begin();
  while (ia != a.end() && ib != b.end()) {
    if (ia->first != ib->first) {
      ia->first < ib->first ? ++ia : ++ib;
      continue;
    }
    const double x = ia->second / norm_a, y = ib->second / norm_b;
    delta += std::abs(x - y) - std::abs(x) - std::abs(y);
    ++ia, ++ib;
  }
  const double score = -0.5 * delta;
  return score > 0.0 ? std::min(score, 1.0) : 0.0;  // also maps -0.0 (no common word) to 0.0
}

std::vector<uint8_t> Vocabulary::Serialise() const {
  std::vector<uint8_t> out(kMagic, kMagic + 8);
  out.reserve(kHeaderBytes + (nodes_.size() - 1) * kNodeBytes + kChecksumBytes);
  for (uint32_t v : {kVersion, uint32_t(kBytes), uint32_t(branching_), uint32_t(depth_), uint32_t(nodes_.size()),
                     uint32_t(words_.size())})
    PutLe(&out, v, 4);
  PutLe(&out, num_training_images_, 8);
  for (NodeId n = 1; n < nodes_.size(); ++n) {
    PutLe(&out, nodes_[n].parent, 4);
    out.insert(out.end(), NodeDescriptor(n), NodeDescriptor(n) + kBytes);
    const double weight = nodes_[n].num_children == 0 ? weights_[nodes_[n].word] : 0.0;
    uint64_t bits;
    std::memcpy(&bits, &weight, sizeof bits);
    PutLe(&out, bits, 8);
  }
  PutLe(&out, Fnv1a64(out.data(), out.size()), 8);
  return out;
}

Status Vocabulary::Save(const std::string& path) const {
  if (empty()) return Status::Error(path + ": cannot save an empty vocabulary");
  const std::vector<uint8_t> bytes = Serialise();
  const std::string temporary = path + ".partial";
  std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
  out.close();
  std::error_code ec;
  if (out) std::filesystem::rename(temporary, path, ec);
  if (out && !ec) return Status::Ok();
  std::filesystem::remove(temporary, ec);
  return Status::Error(path + ": cannot write the vocabulary (via " + temporary + ")");
}

// Parses a Serialise()d buffer; every error names the file and the byte offset.
struct Vocabulary::Reader {
  const std::string& path;
  const std::vector<uint8_t>& bytes;

  Status Fail(size_t offset, const std::string& what) const {
    return Status::Error(path + ": offset " + std::to_string(offset) + ": " + what);
  }

  Status ReadHeader(Vocabulary* v, uint32_t* num_nodes, uint32_t* num_words) const {
    if (bytes.size() < kHeaderBytes + kChecksumBytes)
      return Fail(bytes.size(), "truncated: a vocabulary file has at least " +
                                    std::to_string(kHeaderBytes + kChecksumBytes) + " bytes");
    if (std::memcmp(bytes.data(), kMagic, 8) != 0) return Fail(0, "bad magic: not a rotolidar BoW vocabulary");
    if (uint32_t version = uint32_t(GetLe(&bytes[8], 4)); version != kVersion)
      return Fail(8, "unsupported version " + std::to_string(version) + " (expected " + std::to_string(kVersion) + ")");
    if (GetLe(&bytes[12], 4) != uint32_t(kBytes)) return Fail(12, "descriptor size is not " + std::to_string(kBytes));
    VocabularyConfig config;
    config.branching = int(std::min<uint32_t>(uint32_t(GetLe(&bytes[16], 4)), 1u << 20));
    config.depth = int(std::min<uint32_t>(uint32_t(GetLe(&bytes[20], 4)), 1u << 20));
    if (std::string why; !config.Validate(&why)) return Fail(16, why);
    *num_nodes = uint32_t(GetLe(&bytes[24], 4));
    *num_words = uint32_t(GetLe(&bytes[28], 4));
    if (*num_nodes < 2 || *num_nodes > kMaxNodes)
      return Fail(24, "node count " + std::to_string(*num_nodes) + " out of range");
    if (*num_words < 1 || *num_words >= *num_nodes)
      return Fail(28, "word count " + std::to_string(*num_words) + " out of range");
    v->branching_ = config.branching;
    v->depth_ = config.depth;
    v->num_training_images_ = GetLe(&bytes[32], 8);
    const size_t expected = kHeaderBytes + size_t(*num_nodes - 1) * kNodeBytes + kChecksumBytes;
    if (bytes.size() < expected)
      return Fail(bytes.size(), "truncated: the header's " + std::to_string(*num_nodes) + " nodes need " +
                                    std::to_string(expected) + " bytes");
    if (bytes.size() > expected)
      return Fail(expected, std::to_string(bytes.size() - expected) + " unexpected bytes after the checksum");
    if (GetLe(&bytes[expected - kChecksumBytes], 8) != Fnv1a64(bytes.data(), expected - kChecksumBytes))
      return Fail(expected - kChecksumBytes, "checksum mismatch: the file is corrupt");
    return Status::Ok();
  }

  Status ReadNodes(Vocabulary* v, uint32_t num_nodes, uint32_t num_words) const {
    v->nodes_.assign(num_nodes, Node());
    v->descriptors_.assign(size_t(num_nodes) * kBytes, 0);
    std::vector<double> node_weight(num_nodes, 0.0);
    for (NodeId n = 1; n < num_nodes; ++n) {
      const size_t offset = kHeaderBytes + size_t(n - 1) * kNodeBytes;
      const std::string node = "node " + std::to_string(n) + ": ";
      const NodeId p = NodeId(GetLe(&bytes[offset], 4));
      if (p >= n) return Fail(offset, node + "parent " + std::to_string(p) + " does not precede it");
      Node& parent = v->nodes_[p];
      if (parent.num_children == 0) parent.first_child = n;
      if (parent.first_child + parent.num_children != n || parent.num_children >= uint32_t(v->branching_))
        return Fail(offset, node + "children of node " + std::to_string(p) + " are not consecutive or too many");
      ++parent.num_children;
      v->nodes_[n].parent = p;
      v->nodes_[n].level = parent.level + 1;
      if (v->nodes_[n].level > v->depth_) return Fail(offset, node + "deeper than the header's depth");
      std::memcpy(&v->descriptors_[size_t(n) * kBytes], &bytes[offset + 4], kBytes);
      const uint64_t bits = GetLe(&bytes[offset + 4 + kBytes], 8);
      std::memcpy(&node_weight[n], &bits, sizeof bits);
      if (!std::isfinite(node_weight[n]) || node_weight[n] < 0.0)
        return Fail(offset + 4 + kBytes, node + "weight is negative or not finite");
    }
    v->NumberWords();
    if (v->words_.size() != num_words)
      return Fail(28, "the header says " + std::to_string(num_words) + " words, the tree has " +
                          std::to_string(v->words_.size()) + " leaves");
    v->weights_.resize(num_words);
    for (WordId w = 0; w < num_words; ++w) v->weights_[w] = node_weight[v->words_[w]];
    return Status::Ok();
  }
};

Status Vocabulary::Load(const std::string& path) {
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in) return Status::Error(path + ": cannot open the vocabulary file");
  std::vector<uint8_t> bytes(size_t(std::max<std::streamoff>(in.tellg(), 0)));
  in.seekg(0);
  in.read(reinterpret_cast<char*>(bytes.data()), std::streamsize(bytes.size()));
  if (!in) return Status::Error(path + ": read error");
  Vocabulary v;
  Reader reader{path, bytes};
  uint32_t num_nodes = 0, num_words = 0;
  if (Status s = reader.ReadHeader(&v, &num_nodes, &num_words); !s) return s;
  if (Status s = reader.ReadNodes(&v, num_nodes, num_words); !s) return s;
  *this = std::move(v);
  return Status::Ok();
}

}  // namespace rotolidar::loop
