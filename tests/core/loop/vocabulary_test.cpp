// The DBoW2-style vocabulary: clustering quality on synthetic binary descriptors with a known cluster structure,
// determinism, the file format (round trip, truncation, corruption) and the L1 score.
#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <set>

#include "core/loop/vocabulary.hpp"
#include "core/util/rng.hpp"

namespace rotolidar::loop {
namespace {

using Clock = std::chrono::steady_clock;
double SecondsSince(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

using Descriptor = std::array<uint8_t, kOrbDescriptorBytes>;

Descriptor RandomDescriptor(RandomStream* rng) {
  Descriptor d;
  for (int i = 0; i < kOrbDescriptorBytes; i += 8) {
    const uint64_t v = rng->NextU64();
    for (int b = 0; b < 8; ++b) d[i + b] = uint8_t(v >> (8 * b));
  }
  return d;
}

// Each of the 256 bits flips with probability p.
Descriptor NoisyCopy(const Descriptor& d, double p, RandomStream* rng) {
  Descriptor out = d;
  for (int bit = 0; bit < 8 * kOrbDescriptorBytes; ++bit)
    if (rng->Uniform() < p) out[bit / 8] ^= uint8_t(1u << (bit % 8));
  return out;
}

cv::Mat ToMat(const std::vector<Descriptor>& rows) {
  cv::Mat m(int(rows.size()), kOrbDescriptorBytes, CV_8U);
  for (size_t r = 0; r < rows.size(); ++r) std::copy(rows[r].begin(), rows[r].end(), m.ptr<uint8_t>(int(r)));
  return m;
}

// 300 random prototypes; 100 "images" of 60 noisy copies (5 % bit flips: ~13 bits from the prototype, while two
// random prototypes are ~128 +- 8 bits apart) of prototypes drawn at random.
struct SyntheticSet {
  static constexpr int kPrototypes = 300, kImages = 100, kPerImage = 60;
  static constexpr double kFlip = 0.05;
  std::vector<Descriptor> prototypes;
  std::vector<cv::Mat> images;
  explicit SyntheticSet(uint64_t seed) {
    RandomStream rng(seed, "test.prototypes");
    for (int p = 0; p < kPrototypes; ++p) prototypes.push_back(RandomDescriptor(&rng));
    for (int i = 0; i < kImages; ++i) {
      std::vector<Descriptor> rows;
      for (int f = 0; f < kPerImage; ++f)
        rows.push_back(NoisyCopy(prototypes[rng.NextU64() % kPrototypes], kFlip, &rng));
      images.push_back(ToMat(rows));
    }
  }
};

std::string TempPath(const std::string& name) { return ::testing::TempDir() + "rotolidar_vocab_" + name; }

std::vector<uint8_t> ReadBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::vector<uint8_t>(std::istreambuf_iterator<char>(in), {});
}

void WriteBytes(const std::string& path, const std::vector<uint8_t>& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
}

VocabularyConfig SmallConfig(uint64_t seed = 7) {
  VocabularyConfig c;
  c.branching = 10;
  c.depth = 2;  // <= 100 words for 300 prototypes: every word can hold whole prototype clusters
  c.seed = seed;
  return c;
}

TEST(Vocabulary, ConfigValidation) {
  std::string why;
  EXPECT_TRUE(VocabularyConfig().Validate(&why)) << why;
  VocabularyConfig c;
  c.branching = 1;
  EXPECT_FALSE(c.Validate(&why));
  EXPECT_NE(why.find("branching"), std::string::npos);
  c = VocabularyConfig();
  c.depth = 0;
  EXPECT_FALSE(c.Validate(&why));
  c = VocabularyConfig();
  c.depth = 8;  // 10^8 words
  EXPECT_FALSE(c.Validate(&why));
}

TEST(Vocabulary, NoisyCopiesOfAPrototypeShareItsWord) {
  const SyntheticSet set(1);
  Vocabulary vocabulary;
  VocabularyTrainStats stats;
  const auto t0 = Clock::now();
  ASSERT_TRUE(vocabulary.Train(set.images, SmallConfig(), &stats).ok);
  std::printf("train: %zu descriptors, %zu images -> %zu words, %zu nodes (%zu unreached) in %.3f s\n",
              stats.num_descriptors, stats.num_images, stats.num_words, stats.num_nodes, stats.unreached_words,
              SecondsSince(t0));
  EXPECT_EQ(stats.num_descriptors, size_t(SyntheticSet::kImages * SyntheticSet::kPerImage));
  EXPECT_EQ(vocabulary.num_words(), stats.num_words);
  EXPECT_LE(vocabulary.num_words(), 100u);

  // Fresh copies (not in the training set) of every prototype.
  RandomStream rng(2, "test.fresh-copies");
  int same = 0, total = 0;
  std::set<WordId> prototype_words;
  for (const Descriptor& p : set.prototypes) {
    const WordId word = vocabulary.FindWord(p.data());
    prototype_words.insert(word);
    for (int c = 0; c < 10; ++c, ++total)
      same += vocabulary.FindWord(NoisyCopy(p, SyntheticSet::kFlip, &rng).data()) == word;
  }
  const double share = double(same) / total;
  std::printf("copies in their prototype's word: %.4f (%d / %d); prototypes use %zu words\n", share, same, total,
              prototype_words.size());
  // A copy leaves its prototype's word only where the prototype lies within a few bits of the boundary between
  // two level-1 or level-2 centres: the ~13 flipped bits move the distance difference to two centres by ~+-5 bits
  // (half the flips fall on bits where the centres differ), against margins of ~8-20 bits. Measured 0.926; the
  // bound leaves room for another seed. A degenerate tree (everything in a few words) would pass this trivially,
  // hence the spread check: 300 prototypes must occupy most of the <= 100 words.
  EXPECT_GE(share, 0.85);
  EXPECT_GE(prototype_words.size(), size_t(0.6 * vocabulary.num_words()));
}

TEST(Vocabulary, TrainingIsDeterministic) {
  const SyntheticSet set(3);
  Vocabulary a, b, c;
  ASSERT_TRUE(a.Train(set.images, SmallConfig(11)).ok);
  ASSERT_TRUE(b.Train(set.images, SmallConfig(11)).ok);
  ASSERT_TRUE(c.Train(set.images, SmallConfig(12)).ok);
  const std::string pa = TempPath("det_a.bin"), pb = TempPath("det_b.bin"), pc = TempPath("det_c.bin");
  ASSERT_TRUE(a.Save(pa).ok);
  ASSERT_TRUE(b.Save(pb).ok);
  ASSERT_TRUE(c.Save(pc).ok);
  const std::vector<uint8_t> bytes_a = ReadBytes(pa);
  EXPECT_GT(bytes_a.size(), 48u);
  EXPECT_EQ(bytes_a, ReadBytes(pb)) << "same seed, same data: same bytes";
  EXPECT_NE(bytes_a, ReadBytes(pc)) << "the seed must matter (k-means++ seeding)";
  EXPECT_FALSE(std::filesystem::exists(pa + ".partial"));
}

TEST(Vocabulary, SaveLoadRoundTripGivesIdenticalTransform) {
  const SyntheticSet set(4);
  Vocabulary trained;
  ASSERT_TRUE(trained.Train(set.images, SmallConfig()).ok);
  const std::string path = TempPath("roundtrip.bin");
  ASSERT_TRUE(trained.Save(path).ok);
  Vocabulary loaded;
  const Status s = loaded.Load(path);
  ASSERT_TRUE(s.ok) << s.message;
  EXPECT_EQ(loaded.branching(), trained.branching());
  EXPECT_EQ(loaded.depth(), trained.depth());
  EXPECT_EQ(loaded.num_words(), trained.num_words());
  EXPECT_EQ(loaded.num_nodes(), trained.num_nodes());
  EXPECT_EQ(loaded.num_training_images(), trained.num_training_images());
  for (const cv::Mat& image : set.images) {
    BowVector bow_trained, bow_loaded;
    FeatureVector fv_trained, fv_loaded;
    ASSERT_TRUE(trained.Transform(image, &bow_trained, &fv_trained, 1).ok);
    ASSERT_TRUE(loaded.Transform(image, &bow_loaded, &fv_loaded, 1).ok);
    EXPECT_EQ(bow_trained, bow_loaded);  // exact: weights are stored as their IEEE-754 bits
    EXPECT_EQ(fv_trained, fv_loaded);
  }
  // Saving the loaded vocabulary reproduces the file.
  ASSERT_TRUE(loaded.Save(path + ".again").ok);
  EXPECT_EQ(ReadBytes(path), ReadBytes(path + ".again"));
}

TEST(Vocabulary, TruncatedOrCorruptFileFailsNamingFileAndOffset) {
  const SyntheticSet set(5);
  Vocabulary trained;
  ASSERT_TRUE(trained.Train(set.images, SmallConfig()).ok);
  const std::string good = TempPath("good.bin"), bad = TempPath("bad.bin");
  ASSERT_TRUE(trained.Save(good).ok);
  const std::vector<uint8_t> bytes = ReadBytes(good);

  auto expect_failure = [&](const std::vector<uint8_t>& content, const std::string& words, const char* what) {
    WriteBytes(bad, content);
    Vocabulary v;
    ASSERT_TRUE(v.Load(good).ok);
    const size_t words_before = v.num_words();
    const Status s = v.Load(bad);
    EXPECT_FALSE(s.ok) << what;
    EXPECT_NE(s.message.find(bad), std::string::npos) << what << ": " << s.message;
    EXPECT_NE(s.message.find("offset"), std::string::npos) << what << ": " << s.message;
    EXPECT_NE(s.message.find(words), std::string::npos) << what << ": " << s.message;
    EXPECT_EQ(v.num_words(), words_before) << what << ": a failed Load must leave the vocabulary as it was";
  };
  for (size_t keep : {size_t(0), size_t(10), size_t(47), bytes.size() / 2, bytes.size() - 1})
    expect_failure(std::vector<uint8_t>(bytes.begin(), bytes.begin() + long(keep)), "truncated", "truncated");
  std::vector<uint8_t> flipped = bytes;
  flipped[bytes.size() / 2] ^= 0x10;
  expect_failure(flipped, "checksum", "one flipped bit in a node");
  std::vector<uint8_t> magic = bytes;
  magic[0] = 'X';
  expect_failure(magic, "magic", "bad magic");
  std::vector<uint8_t> version = bytes;
  version[8] = 99;
  expect_failure(version, "version", "unknown version");
  std::vector<uint8_t> longer = bytes;
  longer.push_back(0);
  expect_failure(longer, "unexpected bytes", "trailing byte");

  Vocabulary v;
  const Status missing = v.Load(TempPath("does_not_exist.bin"));
  EXPECT_FALSE(missing.ok);
  EXPECT_NE(missing.message.find("does_not_exist.bin"), std::string::npos);
}

TEST(Vocabulary, ScoreProperties) {
  const BowVector a{{1, 0.5}, {2, 0.3}, {7, 0.2}}, b{{2, 0.6}, {3, 0.4}}, disjoint{{4, 0.5}, {5, 0.5}};
  EXPECT_NEAR(Vocabulary::Score(a, a), 1.0, 1e-12);
  EXPECT_DOUBLE_EQ(Vocabulary::Score(a, disjoint), 0.0);
  EXPECT_DOUBLE_EQ(Vocabulary::Score(a, b), Vocabulary::Score(b, a));
  // By hand: |a - b|_1 = 0.5 + 0.3 + 0.4 + 0.2 = 1.4 -> s = 1 - 0.7 = 0.3.
  EXPECT_NEAR(Vocabulary::Score(a, b), 0.3, 1e-12);
  // Scale invariance: the score normalises both vectors.
  BowVector a3 = a;
  for (auto& [w, v] : a3) v *= 3.0;
  EXPECT_NEAR(Vocabulary::Score(a3, b), 0.3, 1e-12);
  EXPECT_NEAR(Vocabulary::Score(a3, a), 1.0, 1e-12);
  EXPECT_DOUBLE_EQ(Vocabulary::Score(a, BowVector()), 0.0);
  EXPECT_DOUBLE_EQ(Vocabulary::Score(BowVector(), BowVector()), 0.0);
}

TEST(Vocabulary, TransformIsNormalisedAndTheFeatureVectorListsEachFeatureOnce) {
  const SyntheticSet set(6);
  VocabularyConfig config = SmallConfig();
  config.depth = 3;
  Vocabulary vocabulary;
  ASSERT_TRUE(vocabulary.Train(set.images, config).ok);
  for (int levels_up : {0, 1, 2, 3}) {
    BowVector bow;
    FeatureVector features;
    const auto t0 = Clock::now();
    ASSERT_TRUE(vocabulary.Transform(set.images[0], &bow, &features, levels_up).ok);
    if (levels_up == 0) std::printf("transform: %.1f us per descriptor\n", 1e6 * SecondsSince(t0) / 60);
    double sum = 0.0;
    for (const auto& [w, v] : bow) {
      EXPECT_GT(v, 0.0);
      sum += v;
    }
    EXPECT_NEAR(sum, 1.0, 1e-12);
    std::set<uint32_t> seen;
    for (const auto& [node, indices] : features) {
      // The node is at level depth - levels_up, or a shallower leaf.
      EXPECT_LE(vocabulary.NodeLevel(node), config.depth - levels_up);
      for (uint32_t i : indices) EXPECT_TRUE(seen.insert(i).second) << "feature " << i << " listed twice";
    }
    // Every feature whose word has a positive weight is listed.
    size_t weighted = 0;
    for (int r = 0; r < set.images[0].rows; ++r)
      weighted += vocabulary.WordWeight(vocabulary.FindWord(set.images[0].ptr<uint8_t>(r))) > 0.0;
    EXPECT_EQ(seen.size(), weighted);
  }
}

// The vocabulary shipped in scenes/vocabulary/ (its README: how it was trained) loads and has the stated shape.
TEST(Vocabulary, ShippedVocabularyLoads) {
  Vocabulary vocabulary;
  const Status s = vocabulary.Load(std::string(ROTOLIDAR_SOURCE_DIR) + "/scenes/vocabulary/twin_orb_k8_l5.bin");
  ASSERT_TRUE(s.ok) << s.message;
  EXPECT_EQ(vocabulary.branching(), 8);
  EXPECT_EQ(vocabulary.depth(), 5);
  EXPECT_EQ(vocabulary.num_words(), 31945u);
  EXPECT_EQ(vocabulary.num_training_images(), 957u);
  // Random descriptors spread over the tree: 500 of them land in nearly as many words (measured 492), each with a
  // positive IDF weight (log(957 / n_i) is 0 only for a word in every training image). A vocabulary whose words
  // had collapsed or whose weights were lost would give few or none.
  RandomStream rng(9, "test.shipped");
  std::vector<Descriptor> rows;
  for (int i = 0; i < 500; ++i) rows.push_back(RandomDescriptor(&rng));
  BowVector bow;
  ASSERT_TRUE(vocabulary.Transform(ToMat(rows), &bow).ok);
  std::printf("500 random descriptors -> %zu words\n", bow.size());
  EXPECT_GT(bow.size(), 400u);
}

TEST(Vocabulary, RejectsBadInput) {
  Vocabulary vocabulary;
  BowVector bow;
  EXPECT_FALSE(vocabulary.Transform(cv::Mat(3, 32, CV_8U, cv::Scalar(0)), &bow).ok) << "empty vocabulary";
  const SyntheticSet set(8);
  EXPECT_FALSE(vocabulary.Train({set.images[0]}, SmallConfig()).ok) << "one image: every IDF would be 0";
  const Status wrong = vocabulary.Train({set.images[0], cv::Mat(4, 16, CV_8U)}, SmallConfig());
  EXPECT_FALSE(wrong.ok);
  EXPECT_NE(wrong.message.find("image 1"), std::string::npos) << wrong.message;
  ASSERT_TRUE(vocabulary.Train(set.images, SmallConfig()).ok);
  EXPECT_FALSE(vocabulary.Transform(cv::Mat(3, 32, CV_32F), &bow).ok);
  EXPECT_TRUE(vocabulary.Transform(cv::Mat(), &bow).ok);
  EXPECT_TRUE(bow.empty());
}

}  // namespace
}  // namespace rotolidar::loop
