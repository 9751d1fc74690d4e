#include "ddl/vocabulary/bow_database.h"

#include <gtest/gtest.h>

#include <random>
#include <thread>

#include "ddl/vocabulary/vocabulary.h"
#include "ddl/vocabulary/vocabulary_training.h"
#include "synthetic_descriptors.h"

namespace ddl::vocabulary {
namespace {

class BowDatabaseTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    std::mt19937_64 rng(31);
    prototypes_ = new std::vector<Descriptor>(test::random_descriptors(3000, rng));
    std::vector<cv::Mat> training;
    for (int i = 0; i < 60; ++i) {
      training.push_back(descriptors_to_mat(test::random_image(*prototypes_, 300, 6, rng)));
    }
    VocabularyConfig config;
    config.branching = 10;
    config.levels = 4;
    vocabulary_ = new Vocabulary(train_vocabulary(training, config));
  }
  static void TearDownTestSuite() {
    delete vocabulary_;
    delete prototypes_;
  }

  static std::vector<Descriptor>* prototypes_;
  static Vocabulary* vocabulary_;
};

std::vector<Descriptor>* BowDatabaseTest::prototypes_ = nullptr;
Vocabulary* BowDatabaseTest::vocabulary_ = nullptr;

// 50 "keyframes" of 300 features each; every query is a noisy re-observation of one of them (70%
// of its features kept, 8 bits flipped in each). The true keyframe must rank first every time.
TEST_F(BowDatabaseTest, NoisyReobservationRanksTheTrueEntryFirst) {
  std::mt19937_64 rng(77);
  BowDatabase db;
  std::vector<std::vector<Descriptor>> images;
  for (EntryId id = 0; id < 50; ++id) {
    images.push_back(test::random_image(*prototypes_, 300, 6, rng));
    db.add(1000 + id, vocabulary_->transform(images.back()));
  }
  ASSERT_EQ(db.size(), 50u);
  double worst_margin = 1.0;
  for (EntryId id = 0; id < 50; ++id) {
    const BowVector q = vocabulary_->transform(test::reobserve(images[id], 70, 8, rng));
    const std::vector<QueryResult> results = db.query(q, 5);
    ASSERT_FALSE(results.empty());
    EXPECT_EQ(results[0].entry_id, 1000 + id);
    EXPECT_NEAR(results[0].score, l1_score(q, vocabulary_->transform(images[id])), 1e-9);
    EXPECT_GT(results[0].shared_words, 50u);
    ASSERT_GE(results.size(), 2u);
    EXPECT_GE(results[0].score, results[1].score);
    worst_margin = std::min(worst_margin, results[0].score - results[1].score);
  }
  std::printf("worst margin between the true entry and the runner-up: %.3f\n", worst_margin);
  EXPECT_GT(worst_margin, 0.1);
}

TEST_F(BowDatabaseTest, QueryHonoursLimitsExclusionAndErase) {
  std::mt19937_64 rng(5);
  BowDatabase db;
  std::vector<BowVector> bows;
  for (EntryId id = 0; id < 20; ++id) {
    bows.push_back(vocabulary_->transform(test::random_image(*prototypes_, 300, 6, rng)));
    db.add(id, bows.back());
  }
  const BowVector& q = bows[7];
  std::vector<QueryResult> all = db.query(q, 0);
  ASSERT_GE(all.size(), 10u);
  EXPECT_EQ(all[0].entry_id, 7u);
  EXPECT_DOUBLE_EQ(all[0].score, 1.0);
  EXPECT_EQ(all[0].shared_words, q.size());
  for (const QueryResult& r : all) {
    EXPECT_NEAR(r.score, l1_score(q, bows[r.entry_id]), 1e-9);
  }

  EXPECT_EQ(db.query(q, 3).size(), 3u);
  const std::vector<QueryResult> excluded = db.query(q, 0, 0.0, {7, 3});
  for (const QueryResult& r : excluded) {
    EXPECT_NE(r.entry_id, 7u);
    EXPECT_NE(r.entry_id, 3u);
  }
  EXPECT_EQ(excluded.size(), all.size() - 2);

  const double cut = all[4].score;
  for (const QueryResult& r : db.query(q, 0, cut)) EXPECT_GE(r.score, cut);

  const std::uint32_t shared_cut = all[0].shared_words / 2;
  for (const QueryResult& r : db.query(q, 0, 0.0, {}, shared_cut)) {
    EXPECT_GE(r.shared_words, shared_cut);
  }

  EXPECT_TRUE(db.erase(7));
  EXPECT_FALSE(db.erase(7));
  EXPECT_FALSE(db.contains(7));
  EXPECT_EQ(db.size(), 19u);
  for (const QueryResult& r : db.query(q, 0)) EXPECT_NE(r.entry_id, 7u);

  // Re-adding an id replaces its vector.
  db.add(3, q);
  const std::vector<QueryResult> replaced = db.query(q, 1);
  ASSERT_EQ(replaced.size(), 1u);
  EXPECT_EQ(replaced[0].entry_id, 3u);
  EXPECT_DOUBLE_EQ(replaced[0].score, 1.0);
  EXPECT_EQ(db.size(), 19u);

  db.clear();
  EXPECT_EQ(db.size(), 0u);
  EXPECT_TRUE(db.query(q, 0).empty());
  EXPECT_TRUE(db.query(BowVector{}, 0).empty());
}

// Writers and readers at once (run under the tsan preset to check the locking).
TEST_F(BowDatabaseTest, ConcurrentAddEraseAndQuery) {
  std::mt19937_64 rng(9);
  std::vector<BowVector> bows;
  for (int i = 0; i < 40; ++i) {
    bows.push_back(vocabulary_->transform(test::random_image(*prototypes_, 200, 6, rng)));
  }
  BowDatabase db;
  std::thread writer([&] {
    for (EntryId id = 0; id < 40; ++id) {
      db.add(id, bows[id]);
      if (id % 3 == 0) db.erase(id);
    }
  });
  std::thread reader([&] {
    for (int i = 0; i < 200; ++i) {
      for (const QueryResult& r : db.query(bows[i % 40], 3)) EXPECT_LT(r.entry_id, 40u);
    }
  });
  writer.join();
  reader.join();
  EXPECT_EQ(db.size(), 40u - 14u);  // ids 0, 3, ..., 39 erased
  for (EntryId id = 0; id < 40; ++id) {
    if (id % 3 == 0) continue;
    const std::vector<QueryResult> r = db.query(bows[id], 1);
    ASSERT_EQ(r.size(), 1u);
    EXPECT_EQ(r[0].entry_id, id);
  }
}

}  // namespace
}  // namespace ddl::vocabulary
