// Checks of the shipped default vocabulary (vocab/ddl_orb_k10_l5.dvoc) against this build's ORB
// extractor. Skipped when the file is absent (e.g. before scripts/make-vocabulary.sh has run).

#include <gtest/gtest.h>

#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <string>

#include "ddl/features/orb_extractor.h"
#include "ddl/vocabulary/vocabulary.h"

namespace ddl::vocabulary {
namespace {

const std::string kDefaultVocabulary = std::string(DDL_SOURCE_DIR) + "/vocab/ddl_orb_k10_l5.dvoc";
const std::string kOpencvData = "/usr/share/doc/opencv-doc/examples/data/";

class DefaultVocabulary : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!std::filesystem::exists(kDefaultVocabulary)) {
      GTEST_SKIP() << kDefaultVocabulary << " is absent (run scripts/make-vocabulary.sh)";
    }
    vocabulary_ = Vocabulary::load(kDefaultVocabulary);
  }

  Vocabulary vocabulary_;
};

// A relearned BRIEF pattern makes every vocabulary useless: retrain with make-vocabulary.sh.
TEST_F(DefaultVocabulary, WasTrainedForThisBuildsOrbDescriptor) {
  const features::OrbExtractor extractor{features::OrbExtractorConfig{}};
  EXPECT_EQ(vocabulary_.descriptor_tag(),
            descriptor_fingerprint(extractor.pattern().data(), sizeof(features::BriefPattern)))
      << "the ORB descriptor changed since " << kDefaultVocabulary
      << " was trained: run scripts/make-vocabulary.sh";
  EXPECT_EQ(vocabulary_.branching(), 10);
  EXPECT_EQ(vocabulary_.levels(), 5);
  EXPECT_EQ(vocabulary_.weighting(), Weighting::kTfIdf);
  EXPECT_GT(vocabulary_.word_count(), 50000u);
}

// basketball1/2 (two frames of one indoor scene, 640x480) were kept out of training. They must
// score far higher against each other than against an unrelated photo.
TEST_F(DefaultVocabulary, SeparatesTwoViewsOfOneSceneFromAnotherScene) {
  const cv::Mat a = cv::imread(kOpencvData + "basketball1.png", cv::IMREAD_GRAYSCALE);
  const cv::Mat b = cv::imread(kOpencvData + "basketball2.png", cv::IMREAD_GRAYSCALE);
  const cv::Mat other = cv::imread(kOpencvData + "building.jpg", cv::IMREAD_GRAYSCALE);
  if (a.empty() || b.empty() || other.empty()) {
    GTEST_SKIP() << "opencv-doc example images absent (apt-get install opencv-doc)";
  }
  features::OrbExtractor extractor{features::OrbExtractorConfig{}};
  const BowVector bow_a = vocabulary_.transform(extractor.extract(a).descriptors);
  const BowVector bow_b = vocabulary_.transform(extractor.extract(b).descriptors);
  const BowVector bow_other = vocabulary_.transform(extractor.extract(other).descriptors);
  const double same_scene = l1_score(bow_a, bow_b);
  const double other_scene = l1_score(bow_a, bow_other);
  std::printf("basketball1 vs basketball2 %.3f, vs building %.3f\n", same_scene, other_scene);
  EXPECT_GT(same_scene, 3.0 * other_scene);
  EXPECT_GT(same_scene, 0.1);
}

}  // namespace
}  // namespace ddl::vocabulary
