// MaskEvaluator: ground-truth masks of a sequence folder, and the void pixels it leaves unscored.

#include "ddl/pipeline/mask_evaluator.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>

#include "ddl/core/error.h"

namespace ddl::pipeline {
namespace {
namespace fs = std::filesystem;

class MaskEvaluatorTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("ddl_mask_evaluator_" + std::to_string(static_cast<long long>(::getpid())));
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "dynamic_mask");
    fs::create_directories(dir_ / "void_mask");
    camera_.width = 40;
    camera_.height = 30;
    // Truth: columns 0-9 (300 px). Void: columns 30-39 (300 px), where the prediction below puts
    // 300 false pixels that must not count.
    cv::Mat truth(30, 40, CV_8UC1, cv::Scalar(0));
    truth.colRange(0, 10).setTo(255);
    cv::Mat void_mask(30, 40, CV_8UC1, cv::Scalar(0));
    void_mask.colRange(30, 40).setTo(255);
    ASSERT_TRUE(cv::imwrite((dir_ / "dynamic_mask/1.000000.png").string(), truth));
    ASSERT_TRUE(cv::imwrite((dir_ / "void_mask/1.000000.png").string(), void_mask));
    write("dynamic_mask.txt", "# timestamp filename\n1.000000 dynamic_mask/1.000000.png\n");
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  void write(const std::string& name, const std::string& text) {
    std::ofstream(dir_ / name) << text;
  }
  /// Scores one frame at stamp 1 whose every mask is columns 5-9 plus 30-39.
  eval::MaskSummary score_frame(std::unique_ptr<MaskEvaluator>& evaluator) {
    io::RgbdFrame frame;
    frame.timestamp_s = 1.0;
    cv::Mat predicted(30, 40, CV_8UC1, cv::Scalar(0));
    predicted.colRange(5, 10).setTo(255);
    predicted.colRange(30, 40).setTo(255);
    DynamicMasks masks;
    masks.cnn = masks.geometry = masks.combined = predicted;
    evaluator->add(frame, masks);
    return evaluator->summary("combined");
  }

  fs::path dir_;
  camera::PinholeCamera camera_;
};

TEST_F(MaskEvaluatorTest, WithoutAVoidListEveryPixelIsScored) {
  auto evaluator = MaskEvaluator::open(dir_.string(), camera_);
  ASSERT_NE(evaluator, nullptr);
  const eval::MaskSummary s = score_frame(evaluator);
  EXPECT_EQ(s.total.true_positive, 150u);
  EXPECT_EQ(s.total.false_positive, 300u);
  EXPECT_EQ(s.total.false_negative, 150u);
  EXPECT_NEAR(s.mean_iou, 150.0 / 600.0, 1e-12);
  EXPECT_TRUE(evaluator->to_json()["void"].is_null());
}

TEST_F(MaskEvaluatorTest, VoidPixelsCountNeitherWay) {
  write("void_mask.txt", "# timestamp filename\n1.000000 void_mask/1.000000.png\n");
  auto evaluator = MaskEvaluator::open(dir_.string(), camera_);
  ASSERT_NE(evaluator, nullptr);
  const eval::MaskSummary s = score_frame(evaluator);
  EXPECT_EQ(s.total.true_positive, 150u);
  EXPECT_EQ(s.total.false_positive, 0u);
  EXPECT_EQ(s.total.false_negative, 150u);
  EXPECT_NEAR(s.mean_iou, 0.5, 1e-12);
  EXPECT_EQ(evaluator->to_json()["void"]["px"].get<std::uint64_t>(), 300u);
}

TEST_F(MaskEvaluatorTest, AFrameMissingFromTheVoidListIsAnErrorNamingIt) {
  write("void_mask.txt", "# timestamp filename\n2.000000 void_mask/1.000000.png\n");
  auto evaluator = MaskEvaluator::open(dir_.string(), camera_);
  ASSERT_NE(evaluator, nullptr);
  try {
    score_frame(evaluator);
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("void_mask.txt"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("1.000000"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace ddl::pipeline
