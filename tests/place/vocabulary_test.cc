#include "semslam/place/vocabulary.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <set>

#include "semslam/core/binary_io.h"
#include "semslam/core/error.h"
#include "support/test_support.h"
#include "vocab_test_util.h"

namespace semslam {
namespace {

constexpr std::uint64_t kOnes = ~std::uint64_t{0};

// root 0 -> {1: zeros, 2: ones}; 1 -> {3: zeros, 4: zeros + low byte}; 2 -> {5: ones, 6: ones - low byte}.
Vocabulary TinyVocabulary(BowWeighting weighting = BowWeighting::kTfIdf) {
  const Descriptor zeros{}, ones{kOnes, kOnes, kOnes, kOnes};
  const Descriptor low_byte{0xFF, 0, 0, 0}, ones_but_low{kOnes << 8, kOnes, kOnes, kOnes};
  return Vocabulary::FromTree(2, 2, weighting, OrbDescriptorPattern::kSemslam, {0, 0, 0, 1, 1, 2, 2},
                              {zeros, zeros, ones, zeros, low_byte, ones, ones_but_low},
                              {0.5, 1.0, 2.0, 0.0});
}

TEST(Vocabulary, HandMadeTinyVocabularyGivesKnownTfIdfVectors) {
  const Vocabulary v = TinyVocabulary();
  EXPECT_EQ(v.size(), 4u);
  EXPECT_EQ(v.num_nodes(), 7u);
  EXPECT_EQ(v.branching(), 2);
  EXPECT_EQ(v.depth(), 2);
  const Descriptor a{}, b{0xFF, 0, 0, 0}, c{kOnes, kOnes, kOnes, kOnes}, d{kOnes << 8, kOnes, kOnes, kOnes};
  EXPECT_EQ(v.Word(a), 0u);
  EXPECT_EQ(v.Word(b), 1u);
  EXPECT_EQ(v.Word(c), 2u);
  EXPECT_EQ(v.Word(d), 3u);
  EXPECT_EQ(v.Word(Descriptor{0x3, 0, 0, 0}), 0u);  // 2 bits from zeros, 6 from the low byte
  // TF-IDF: word 0 twice (2 x 0.5), word 1 once (1), word 2 once (2), word 3 has IDF 0 -> dropped; L1 -> /4.
  BowVector bow;
  FeatureVector fv;
  v.Transform({a, a, b, c, d}, &bow, &fv, 1);
  EXPECT_EQ(bow, BowVector({{0, 0.25}, {1, 0.25}, {2, 0.5}}));
  EXPECT_EQ(fv, (FeatureVector{{1, {0, 1, 2}}, {2, {3, 4}}}));
  v.Transform({a, a, b, c, d}, nullptr, &fv, 2);
  EXPECT_EQ(fv, (FeatureVector{{3, {0, 1}}, {4, {2}}, {5, {3}}, {6, {4}}}));
  EXPECT_EQ(v.DefaultDirectIndexLevel(), 2);
  // Score with an image of only word 2: min(0.5, 1).
  EXPECT_DOUBLE_EQ(v.Score(bow, v.Transform({c})), 0.5);
  EXPECT_DOUBLE_EQ(v.Score(bow, bow), 1.0);
  // Other weightings.
  EXPECT_EQ(TinyVocabulary(BowWeighting::kTf).Transform({a, a, b, c, d}),
            BowVector({{0, 0.4}, {1, 0.2}, {2, 0.2}, {3, 0.2}}));
  EXPECT_EQ(TinyVocabulary(BowWeighting::kBinary).Transform({a, a, b, c, d}),
            BowVector({{0, 0.25}, {1, 0.25}, {2, 0.25}, {3, 0.25}}));
  // An empty vocabulary gives empty vectors.
  EXPECT_TRUE(Vocabulary().Transform({a, b}).empty());
}

TEST(Vocabulary, RejectsTreesNotInBreadthFirstForm) {
  const Descriptor z{};
  // Children of the root not contiguous: 0 -> 1, 1 -> 2, 0 -> 3.
  EXPECT_THROW(Vocabulary::FromTree(2, 2, BowWeighting::kTfIdf, OrbDescriptorPattern::kSemslam, {0, 0, 1, 0},
                                    {z, z, z, z}, {1, 1}),
               InvalidArgument);
  // Three children with k = 2.
  EXPECT_THROW(Vocabulary::FromTree(2, 1, BowWeighting::kTfIdf, OrbDescriptorPattern::kSemslam, {0, 0, 0, 0},
                                    {z, z, z, z}, {1, 1, 1}),
               InvalidArgument);
  // Deeper than L.
  EXPECT_THROW(Vocabulary::FromTree(2, 1, BowWeighting::kTfIdf, OrbDescriptorPattern::kSemslam, {0, 0, 1},
                                    {z, z, z}, {1}),
               InvalidArgument);
  // Wrong number of weights, negative weight.
  EXPECT_THROW(Vocabulary::FromTree(2, 1, BowWeighting::kTfIdf, OrbDescriptorPattern::kSemslam, {0, 0, 0},
                                    {z, z, z}, {1}),
               InvalidArgument);
  EXPECT_THROW(Vocabulary::FromTree(2, 1, BowWeighting::kTfIdf, OrbDescriptorPattern::kSemslam, {0, 0, 0},
                                    {z, z, z}, {1, -1}),
               InvalidArgument);
}

TEST(Vocabulary, TrainingSeparatesClustersAndComputesIdf) {
  // 16 clusters; image i holds clusters i and i + 1 (mod 16), so every word is in 2 of 16 images.
  const auto data = testing::MakeClusteredData(16, 16, 200, 8);
  VocabularyTrainingOptions options;
  options.branching = 4;
  options.depth = 3;  // 64 leaves at most: room for every cluster (the top split need not be balanced)
  const Vocabulary v = Vocabulary::Train(data.images, options);
  EXPECT_GE(v.size(), 16u);
  // No word mixes clusters, and every cluster has words.
  std::map<WordId, std::set<int>> clusters_of_word;
  std::map<WordId, int> members;
  std::set<int> clusters_seen;
  for (size_t i = 0; i < data.images.size(); ++i) {
    for (size_t k = 0; k < data.images[i].size(); ++k) {
      clusters_of_word[v.Word(data.images[i][k])].insert(data.labels[i][k]);
      ++members[v.Word(data.images[i][k])];
      clusters_seen.insert(data.labels[i][k]);
    }
  }
  for (const auto& [word, clusters] : clusters_of_word) EXPECT_EQ(clusters.size(), 1u) << "word " << word;
  EXPECT_EQ(clusters_seen.size(), 16u);
  // A well-populated word is in the 2 images holding its cluster: IDF log(16 / 2). (k-means++ also seeds
  // on a few far-out noisy members, whose words may be in one image only: log(16).)
  for (const auto& [word, count] : members) {
    if (count >= 20) {
      EXPECT_NEAR(v.WordWeight(word), std::log(8.0), 1e-6);  // weights are kept as floats
    }
  }
  // Deterministic, and the same serial or parallel.
  EXPECT_EQ(Vocabulary::Train(data.images, options), v);
  options.parallel = false;
  EXPECT_EQ(Vocabulary::Train(data.images, options), v);
  // Bad options.
  options.branching = 1;
  EXPECT_THROW(Vocabulary::Train(data.images, options), InvalidArgument);
  EXPECT_THROW(Vocabulary::Train({}, VocabularyTrainingOptions{}), InvalidArgument);
}

TEST(Vocabulary, TrainingOnFewOrIdenticalDescriptors) {
  // Fewer descriptors than k: each becomes a word.
  const std::vector<std::vector<Descriptor>> few = {{Descriptor{1, 0, 0, 0}, Descriptor{2, 0, 0, 0}},
                                                    {Descriptor{4, 0, 0, 0}}};
  VocabularyTrainingOptions options;
  const Vocabulary v = Vocabulary::Train(few, options);
  EXPECT_EQ(v.size(), 3u);
  EXPECT_NE(v.Word(Descriptor{1, 0, 0, 0}), v.Word(Descriptor{4, 0, 0, 0}));
  // All identical: nothing to cluster.
  EXPECT_THROW(Vocabulary::Train({{Descriptor{}, Descriptor{}}}, options), InvalidArgument);
}

TEST(Vocabulary, SaveLoadRoundTripIsExact) {
  testing::TempDir dir;
  const auto data = testing::MakeClusteredData(30, 40, 100, 20, 7);
  VocabularyTrainingOptions options;
  options.branching = 5;
  options.depth = 3;
  const Vocabulary v = Vocabulary::Train(data.images, options);
  v.Save(dir / "v.voc");
  const Vocabulary loaded = Vocabulary::Load(dir / "v.voc");
  EXPECT_EQ(loaded, v);
  BowVector b1, b2;
  FeatureVector f1, f2;
  v.Transform(data.images[3], &b1, &f1);
  loaded.Transform(data.images[3], &b2, &f2);
  EXPECT_EQ(b1, b2);
  EXPECT_EQ(f1, f2);
  // Saving again gives the same bytes.
  loaded.Save(dir / "w.voc");
  std::ifstream a(dir / "v.voc", std::ios::binary), b(dir / "w.voc", std::ios::binary);
  EXPECT_EQ(std::string(std::istreambuf_iterator<char>(a), {}),
            std::string(std::istreambuf_iterator<char>(b), {}));
}

std::string ReadAll(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}
void WriteAll(const std::filesystem::path& p, const std::string& bytes) {
  std::ofstream(p, std::ios::binary) << bytes;
}

TEST(Vocabulary, MalformedFilesGiveInputErrors) {
  testing::TempDir dir;
  TinyVocabulary().Save(dir / "good.voc");
  const std::string good = ReadAll(dir / "good.voc");
  auto expect_input_error = [&](const std::string& bytes, const std::string& what) {
    WriteAll(dir / "bad.voc", bytes);
    try {
      Vocabulary::Load(dir / "bad.voc");
      ADD_FAILURE() << what << ": no error";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("bad.voc"), std::string::npos) << e.what();
    } catch (const std::exception& e) {
      ADD_FAILURE() << what << ": wrong exception " << e.what();
    }
  };
  expect_input_error(good.substr(0, good.size() - 5), "truncated");
  expect_input_error(good.substr(0, 12), "truncated header");
  std::string corrupt = good;
  corrupt[corrupt.size() - 20] ^= 0x10;
  expect_input_error(corrupt, "corrupt payload");
  std::string version = good;
  version[8] = 9;  // version field
  expect_input_error(version, "unknown version");
  expect_input_error("", "empty");
  expect_input_error("hello world\nthis is not a vocabulary\n", "text");
  expect_input_error(std::string("\0\1\2\3\4\5\6\7\10\11", 10), "binary garbage");
  // A checksummed payload whose tree is broken.
  BinaryWriter w;
  w.Put<std::uint32_t>(2);
  w.Put<std::uint32_t>(1);
  w.Put<std::uint32_t>(0);
  w.Put<std::uint32_t>(0);
  w.PutVector(std::vector<std::uint16_t>{1, 0, 0});  // node 2 has no parent
  w.PutVector(std::vector<Descriptor>(3));
  w.PutVector(std::vector<float>{1});
  WriteChecksummedFile(dir / "tree.voc", "SEMSLVOC", 1, w.bytes());
  expect_input_error(ReadAll(dir / "tree.voc"), "unreachable node");
  BinaryWriter n;
  n.Put<std::uint32_t>(2);
  n.Put<std::uint32_t>(1);
  n.Put<std::uint32_t>(0);
  n.Put<std::uint32_t>(0);
  n.PutVector(std::vector<std::uint16_t>{2, 0, 0});
  n.PutVector(std::vector<Descriptor>(3));
  n.PutVector(std::vector<float>{1, -2});  // negative weight
  WriteChecksummedFile(dir / "weight.voc", "SEMSLVOC", 1, n.bytes());
  expect_input_error(ReadAll(dir / "weight.voc"), "negative weight");
  EXPECT_THROW(Vocabulary::Load(dir / "missing.voc"), InputError);
}

TEST(DefaultVocabularyPath, EnvironmentOverridesAndDefaultNamesTheFile) {
  ::setenv("SEMSLAM_VOCABULARY", "/some/where/my.voc", 1);
  EXPECT_EQ(DefaultVocabularyPath(), std::filesystem::path("/some/where/my.voc"));
  ::unsetenv("SEMSLAM_VOCABULARY");
  const auto path = DefaultVocabularyPath();
  EXPECT_EQ(path.filename(), "semslam.voc");
  EXPECT_EQ(path.parent_path().filename(), "vocabulary");
}

}  // namespace
}  // namespace semslam
