#include "ddl/vocabulary/vocabulary_training.h"

#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <map>
#include <random>
#include <set>

#include "ddl/core/error.h"
#include "ddl/vocabulary/vocabulary.h"
#include "synthetic_descriptors.h"

namespace ddl::vocabulary {
namespace {

using test::flip_bits;
using test::random_descriptor;
using test::random_descriptors;
using test::random_image;

VocabularyConfig small_config(int k, int levels, std::uint64_t seed = 1) {
  VocabularyConfig c;
  c.branching = k;
  c.levels = levels;
  c.seed = seed;
  return c;
}

// Featureless training images are bad input (exit code 2), not a failure of the program.
TEST(VocabularyTraining, NoDescriptorsAtAllIsAnInputError) {
  const std::vector<cv::Mat> none(3, cv::Mat(0, 32, CV_8UC1));
  EXPECT_THROW(train_vocabulary(none, VocabularyConfig{}), InputError);
}

// With one image every word's idf is log(1 / 1) = 0: every bag of words would be empty, and
// relocalization and loop detection would find nothing (review, stop 26). tf and binary weighting
// need no second image.
TEST(VocabularyTraining, IdfWeightingNeedsTwoImagesWithFeatures) {
  std::mt19937_64 rng(3);
  const cv::Mat one = descriptors_to_mat(random_descriptors(40, rng));
  const cv::Mat blank(0, 32, CV_8UC1);
  for (const Weighting weighting : {Weighting::kTfIdf, Weighting::kIdf}) {
    VocabularyConfig config = small_config(3, 2);
    config.weighting = weighting;
    try {
      train_vocabulary({one, blank}, config);
      FAIL() << "expected an InputError";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("at least 2"), std::string::npos) << e.what();
    }
    const Vocabulary two = train_vocabulary({one, one}, config);
    EXPECT_FALSE(two.empty());
  }
  for (const Weighting weighting : {Weighting::kTf, Weighting::kBinary}) {
    VocabularyConfig config = small_config(3, 2);
    config.weighting = weighting;
    const Vocabulary voc = train_vocabulary({one}, config);
    EXPECT_GT(voc.word_weight(0), 0.0);
  }
}

// Four well separated prototypes (random 256-bit strings are ~128 bits apart), 60 observations
// each with 12 of 256 bits flipped. One level of 4-means must recover the four groups, and the
// majority vote must give back every prototype bit for bit (a bit is wrong only if > 30 of 60
// observations flipped it; each flips it with probability 12/256).
TEST(VocabularyTraining, KMeansRecoversSeparableClustersAndTheirCentres) {
  std::mt19937_64 rng(7);
  const std::vector<Descriptor> prototypes = random_descriptors(4, rng);
  std::vector<cv::Mat> images;
  std::vector<std::vector<Descriptor>> by_prototype(4);
  for (int img = 0; img < 12; ++img) {
    std::vector<Descriptor> image;
    for (int p = 0; p < 4; ++p) {
      for (int j = 0; j < 5; ++j) {
        image.push_back(flip_bits(prototypes[p], 12, rng));
        by_prototype[p].push_back(image.back());
      }
    }
    images.push_back(descriptors_to_mat(image));
  }
  const Vocabulary voc = train_vocabulary(images, small_config(4, 1));
  ASSERT_EQ(voc.word_count(), 4u);
  std::set<WordId> words_used;
  std::set<Descriptor> centres;
  for (int p = 0; p < 4; ++p) {
    const WordId w = voc.word(by_prototype[p][0]);
    for (const Descriptor& d : by_prototype[p]) EXPECT_EQ(voc.word(d), w) << "prototype " << p;
    EXPECT_EQ(voc.node_descriptor(voc.node_of_word(w)), prototypes[p]);
    words_used.insert(w);
  }
  EXPECT_EQ(words_used.size(), 4u);
}

// Two-level structure: 3 groups of 3 prototypes. Each group shares a base string; its prototypes
// differ from the base by 40 bits and from each other by ~80, groups by ~128. A k=3, L=2 tree must
// put each group under its own level-1 node and each prototype in its own word.
TEST(VocabularyTraining, HierarchyFollowsNestedClusters) {
  std::mt19937_64 rng(11);
  std::vector<std::vector<Descriptor>> prototypes(3);
  for (auto& group : prototypes) {
    const Descriptor base = random_descriptor(rng);
    for (int i = 0; i < 3; ++i) group.push_back(flip_bits(base, 40, rng));
  }
  std::vector<Descriptor> all;
  for (int n = 0; n < 40; ++n) {
    for (const auto& group : prototypes) {
      for (const Descriptor& p : group) all.push_back(flip_bits(p, 6, rng));
    }
  }
  VocabularyConfig config = small_config(3, 2);
  config.weighting = Weighting::kTf;  // one image: idf would weigh every word 0
  const Vocabulary voc = train_vocabulary({descriptors_to_mat(all)}, config);
  EXPECT_EQ(voc.word_count(), 9u);
  std::set<WordId> words;
  std::set<NodeId> groups;
  for (const auto& group : prototypes) {
    std::set<NodeId> group_nodes;
    for (const Descriptor& p : group) {
      const WordLookup hit = voc.lookup(p, 1);
      group_nodes.insert(hit.node_id);
      words.insert(hit.word_id);
      EXPECT_EQ(voc.depth(hit.node_id), 1);
      EXPECT_EQ(voc.parent(voc.node_of_word(hit.word_id)), hit.node_id);
    }
    EXPECT_EQ(group_nodes.size(), 1u);
    groups.insert(*group_nodes.begin());
  }
  EXPECT_EQ(words.size(), 9u);
  EXPECT_EQ(groups.size(), 3u);
}

std::vector<cv::Mat> clustered_training_images(std::size_t n_images, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  const std::vector<Descriptor> prototypes = random_descriptors(400, rng);
  std::vector<cv::Mat> images;
  for (std::size_t i = 0; i < n_images; ++i) {
    images.push_back(descriptors_to_mat(random_image(prototypes, 100, 8, rng)));
  }
  return images;
}

TEST(VocabularyTraining, SameSeedGivesIdenticalTreeForAnyThreadCount) {
  const std::vector<cv::Mat> images = clustered_training_images(40, 3);
  VocabularyConfig config = small_config(5, 3, 42);
  const Vocabulary a = train_vocabulary(images, config);
  const Vocabulary b = train_vocabulary(images, config);
  config.threads = 3;
  const Vocabulary c = train_vocabulary(images, config);
  EXPECT_TRUE(a == b);
  EXPECT_TRUE(a == c);
  EXPECT_EQ(a.nodes(), c.nodes());
  config.seed = 43;
  const Vocabulary d = train_vocabulary(images, config);
  EXPECT_FALSE(a == d) << "a different seed should give a different k-means++ seeding";
}

TEST(VocabularyTraining, TreeRespectsBranchingAndDepth) {
  TrainingStats stats;
  const Vocabulary voc =
      train_vocabulary(clustered_training_images(40, 5), small_config(6, 3), {}, &stats);
  EXPECT_EQ(stats.images, 40u);
  EXPECT_EQ(stats.descriptors, 4000u);
  EXPECT_EQ(stats.nodes, voc.node_count());
  EXPECT_EQ(stats.words, voc.word_count());
  std::size_t words = 0;
  for (NodeId n = 0; n < voc.node_count(); ++n) {
    EXPECT_LE(voc.child_count(n), 6);
    EXPECT_LE(voc.depth(n), 3);
    if (voc.is_word(n)) {
      EXPECT_EQ(voc.node_of_word(voc.word_of_node(n)), n);
      ++words;
    }
  }
  EXPECT_EQ(words, voc.word_count());
  EXPECT_EQ(voc.child_count(0), 6);
  EXPECT_GT(voc.word_count(), 150u);  // 400 prototypes, at most 6^3 = 216 words
}

// Nested clusters: 4 groups (random bases ~128 bits apart) x 4 subgroups (28 bits from their
// base) x 4 prototypes (12 bits from their subgroup), observed with 3 bits of noise.
std::vector<cv::Mat> nested_training_images(std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::vector<Descriptor> prototypes;
  for (int g = 0; g < 4; ++g) {
    const Descriptor base = random_descriptor(rng);
    for (int s = 0; s < 4; ++s) {
      const Descriptor sub = flip_bits(base, 28, rng);
      for (int p = 0; p < 4; ++p) prototypes.push_back(flip_bits(sub, 12, rng));
    }
  }
  std::vector<cv::Mat> images;
  for (int i = 0; i < 20; ++i) {
    images.push_back(descriptors_to_mat(random_image(prototypes, 64, 3, rng)));
  }
  return images;
}

// A descriptor equal to a word's centre descends to that word. Guaranteed where the clusters are
// nested as the tree is (each centre far nearer to its own ancestors than to their siblings).
TEST(VocabularyTraining, LookupOfAWordCentreReturnsThatWord) {
  const Vocabulary voc = train_vocabulary(nested_training_images(9), small_config(4, 3));
  EXPECT_EQ(voc.word_count(), 64u);
  for (WordId w = 0; w < voc.word_count(); ++w) {
    const NodeId leaf = voc.node_of_word(w);
    const WordLookup hit = voc.lookup(voc.node_descriptor(leaf), 0);
    EXPECT_EQ(hit.word_id, w);
    EXPECT_EQ(hit.node_id, leaf);
    EXPECT_EQ(hit.weight, voc.word_weight(w));
  }
}

// Without nested structure (400 unrelated prototypes in a 5^3 tree) hierarchical k-means does
// not guarantee it: a leaf centre is the majority of a subset of its parent's cluster and can lie
// nearer to an uncle. It holds for nearly all words all the same.
TEST(VocabularyTraining, LookupOfAWordCentreMostlyReturnsThatWordOnFlatData) {
  const Vocabulary voc = train_vocabulary(clustered_training_images(40, 9), small_config(5, 3));
  ASSERT_GT(voc.word_count(), 100u);
  std::size_t same = 0;
  for (WordId w = 0; w < voc.word_count(); ++w) {
    same += voc.word(voc.node_descriptor(voc.node_of_word(w))) == w ? 1 : 0;
  }
  std::printf("%zu of %zu word centres descend to their own word\n", same, voc.word_count());
  EXPECT_GE(static_cast<double>(same), 0.95 * static_cast<double>(voc.word_count()));
}

// levels_up picks the ancestor at depth levels - levels_up, or the word itself when shallower.
TEST(VocabularyTraining, LookupReportsTheAncestorLevelsUp) {
  const Vocabulary voc = train_vocabulary(clustered_training_images(40, 13), small_config(4, 3));
  std::mt19937_64 rng(99);
  for (int i = 0; i < 200; ++i) {
    const Descriptor d = random_descriptor(rng);
    const WordLookup w0 = voc.lookup(d, 0);
    EXPECT_EQ(w0.node_id, voc.node_of_word(w0.word_id));
    for (int up = 1; up <= 4; ++up) {
      const WordLookup hit = voc.lookup(d, up);
      EXPECT_EQ(hit.word_id, w0.word_id);
      const NodeId leaf = voc.node_of_word(w0.word_id);
      const int target = std::max(0, 3 - up);
      NodeId expected = leaf;
      while (voc.depth(expected) > target) expected = voc.parent(expected);
      EXPECT_EQ(hit.node_id, expected) << "levels_up " << up;
    }
  }
}

// IDF = log(N / n_w): a word in every image gets weight 0 (and is left out of BoW vectors, as in
// DBoW2), a word in 1 of 4 images log(4).
TEST(VocabularyTraining, IdfWeightsCountImagesContainingEachWord) {
  std::mt19937_64 rng(21);
  const std::vector<Descriptor> p = random_descriptors(3, rng);
  std::vector<cv::Mat> images;
  for (int i = 0; i < 4; ++i) {
    std::vector<Descriptor> image = {p[0], p[0], flip_bits(p[0], 2, rng)};
    if (i == 2) image.push_back(p[1]);
    if (i < 2) image.push_back(p[2]);
    images.push_back(descriptors_to_mat(image));
  }
  images.emplace_back();  // an empty image does not count in N
  const Vocabulary voc = train_vocabulary(images, small_config(3, 1));
  ASSERT_EQ(voc.word_count(), 3u);
  EXPECT_FLOAT_EQ(static_cast<float>(voc.word_weight(voc.word(p[0]))), 0.0f);
  EXPECT_FLOAT_EQ(static_cast<float>(voc.word_weight(voc.word(p[1]))), std::log(4.0f));
  EXPECT_FLOAT_EQ(static_cast<float>(voc.word_weight(voc.word(p[2]))), std::log(2.0f));

  // tf-idf BoW of {p0, p1, p1, p2}: p0 dropped (weight 0); p1 2*log4, p2 log2, normalised.
  const BowVector bow = voc.transform(std::vector<Descriptor>{p[0], p[1], p[1], p[2]});
  ASSERT_EQ(bow.size(), 2u);
  const double w1 = 2 * std::log(4.0);
  const double w2 = std::log(2.0);
  EXPECT_NEAR(bow.weight(voc.word(p[1])), w1 / (w1 + w2), 1e-6);
  EXPECT_NEAR(bow.weight(voc.word(p[2])), w2 / (w1 + w2), 1e-6);

  VocabularyConfig binary = small_config(3, 1);
  binary.weighting = Weighting::kBinary;
  const Vocabulary voc_binary = train_vocabulary(images, binary);
  const BowVector bow_binary = voc_binary.transform(std::vector<Descriptor>{p[0], p[1], p[1]});
  ASSERT_EQ(bow_binary.size(), 2u);
  EXPECT_DOUBLE_EQ(bow_binary.weight(voc_binary.word(p[1])), 0.5);
}

TEST(VocabularyTraining, BowOfAnImageScoresOneAgainstItselfAndLowAgainstAnother) {
  std::mt19937_64 rng(5);
  const std::vector<Descriptor> prototypes = random_descriptors(2000, rng);
  std::vector<cv::Mat> training;
  for (int i = 0; i < 60; ++i) {
    training.push_back(descriptors_to_mat(random_image(prototypes, 300, 6, rng)));
  }
  const Vocabulary voc = train_vocabulary(training, small_config(10, 4));
  const cv::Mat image = descriptors_to_mat(random_image(prototypes, 300, 6, rng));
  const cv::Mat other = descriptors_to_mat(random_image(prototypes, 300, 6, rng));
  const cv::Mat again =
      descriptors_to_mat(test::reobserve(descriptors_from_mat(image), 80, 6, rng));
  const BowVector bow = voc.transform(image);
  EXPECT_EQ(Vocabulary::score(bow, bow), 1.0);
  EXPECT_EQ(Vocabulary::score(bow, voc.transform(image)), 1.0);
  const double s_other = Vocabulary::score(bow, voc.transform(other));
  const double s_again = Vocabulary::score(bow, voc.transform(again));
  EXPECT_LT(s_other, 0.25);
  EXPECT_GT(s_again, 0.4);
  EXPECT_GT(s_again, 3.0 * s_other);
  std::printf("score vs another image %.3f, vs a noisy re-observation %.3f\n", s_other, s_again);
}

TEST(VocabularyTraining, TransformWithFeatureVectorListsEveryFeatureOnce) {
  const Vocabulary voc = train_vocabulary(clustered_training_images(30, 17), small_config(5, 3));
  std::mt19937_64 rng(3);
  const std::vector<Descriptor> d = random_descriptors(150, rng);
  BowVector bow;
  FeatureVector fv;
  voc.transform(descriptors_to_mat(d), 2, bow, fv);
  EXPECT_EQ(bow, voc.transform(descriptors_to_mat(d)));
  EXPECT_EQ(fv.feature_count(), d.size());
  for (const FeatureNode& node : fv) {
    for (std::uint32_t i : node.feature_indices) {
      EXPECT_EQ(voc.lookup(d[i], 2).node_id, node.node_id);
    }
  }
  EXPECT_NEAR(bow.l1_norm(), 1.0, 1e-12);
}

TEST(VocabularyTraining, RejectsBadInput) {
  EXPECT_THROW(train_vocabulary({}, small_config(3, 2)), Error);
  EXPECT_THROW(train_vocabulary({cv::Mat()}, small_config(3, 2)), Error);
  EXPECT_THROW(train_vocabulary({cv::Mat(4, 16, CV_8UC1, cv::Scalar(0))}, small_config(3, 2)),
               Error);
  EXPECT_THROW(train_vocabulary({cv::Mat(4, 32, CV_8UC1, cv::Scalar(0))}, small_config(1, 2)),
               ConfigError);
  EXPECT_THROW(Vocabulary().lookup(Descriptor{}), Error);
  EXPECT_TRUE(Vocabulary().transform(cv::Mat()).empty());
}

TEST(VocabularyTraining, StopFlagInterrupts) {
  std::atomic<bool> stop{true};
  TrainingHooks hooks;
  hooks.stop = &stop;
  EXPECT_THROW(train_vocabulary(clustered_training_images(5, 1), small_config(3, 2), hooks),
               Interrupted);
}

TEST(VocabularyTraining, IdenticalDescriptorsGiveASingleWord) {
  std::vector<Descriptor> same(50, Descriptor{1, 2, 3, 4});
  VocabularyConfig config = small_config(4, 3);
  config.weighting = Weighting::kBinary;  // one image: idf would weigh every word 0
  const Vocabulary voc = train_vocabulary({descriptors_to_mat(same)}, config);
  EXPECT_EQ(voc.word_count(), 1u);
  EXPECT_EQ(voc.node_count(), 2u);
}

TEST(VocabularyFromNodes, RejectsMalformedTrees) {
  const auto node = [](NodeId parent) { return VocabularyNode{parent, Descriptor{}, 0.0f}; };
  EXPECT_THROW(Vocabulary::from_nodes(2, 2, Weighting::kTfIdf, {}), Error);
  EXPECT_THROW(Vocabulary::from_nodes(2, 2, Weighting::kTfIdf, {node(kNoNode)}), Error);
  EXPECT_THROW(Vocabulary::from_nodes(2, 2, Weighting::kTfIdf, {node(0), node(0)}), Error);
  EXPECT_THROW(Vocabulary::from_nodes(2, 2, Weighting::kTfIdf, {node(kNoNode), node(1)}), Error);
  // three children with branching 2
  EXPECT_THROW(
      Vocabulary::from_nodes(2, 2, Weighting::kTfIdf, {node(kNoNode), node(0), node(0), node(0)}),
      Error);
  // depth 3 with levels 2
  EXPECT_THROW(
      Vocabulary::from_nodes(2, 2, Weighting::kTfIdf, {node(kNoNode), node(0), node(1), node(2)}),
      Error);
  // siblings 1 and 3 not consecutive
  EXPECT_THROW(
      Vocabulary::from_nodes(2, 2, Weighting::kTfIdf, {node(kNoNode), node(0), node(1), node(0)}),
      Error);
  auto bad_weight = std::vector<VocabularyNode>{node(kNoNode), node(0)};
  bad_weight[1].weight = -1.0f;
  EXPECT_THROW(Vocabulary::from_nodes(2, 2, Weighting::kTfIdf, bad_weight), Error);
  const Vocabulary ok =
      Vocabulary::from_nodes(2, 2, Weighting::kTfIdf, {node(kNoNode), node(0), node(0), node(1)});
  EXPECT_EQ(ok.word_count(), 2u);  // nodes 2 and 3
  EXPECT_EQ(ok.node_of_word(0), 2u);
  EXPECT_EQ(ok.node_of_word(1), 3u);
}

}  // namespace
}  // namespace ddl::vocabulary
