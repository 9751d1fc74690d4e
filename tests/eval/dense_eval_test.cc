// evaluate_dense: repaired keyframes of a run against a generated sequence's exact background.

#include "ddl/eval/dense_eval.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>

#include "ddl/core/error.h"
#include "ddl/io/text_table.h"
#include "ddl/synthetic/sequence.h"
#include "half_resolution.h"

namespace ddl::eval {
namespace {
namespace fs = std::filesystem;

class DenseEvalTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    root_ = fs::temp_directory_path() /
            ("ddl_dense_eval_" + std::to_string(static_cast<long long>(::getpid())));
    fs::remove_all(root_);
    synthetic::SequenceConfig config = synthetic::find_preset("syn_walking_static").config;
    config.frames = 6;
    config.camera = test_support::half_resolution(config.camera);
    const auto source = synthetic::make_sequence_source(config);
    camera_ = source->camera();
    synthetic::write_sequence(*source, (root_ / "seq").string());
  }
  static void TearDownTestSuite() {
    std::error_code ec;
    fs::remove_all(root_, ec);
  }
  void SetUp() override {
    run_ = root_ /
           ("run_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(run_);
    fs::create_directories(run_ / "inpainted");
  }
  /// Writes frame `index` of the sequence as a repaired keyframe whose repair is the exact
  /// background over the dynamic mask.
  void write_perfect_repair(std::size_t index) const {
    const auto rows = io::read_text_table((root_ / "seq" / "dynamic_mask.txt").string());
    const std::string stamp = rows.at(index).fields[0];
    const fs::path seq = root_ / "seq";
    const cv::Mat background = cv::imread((seq / "background/rgb" / (stamp + ".png")).string());
    const auto assoc = io::read_text_table((seq / "background/associations.txt").string());
    const cv::Mat depth =
        cv::imread((seq / "background" / assoc.at(index).fields[3]).string(), cv::IMREAD_UNCHANGED);
    const cv::Mat mask =
        cv::imread((seq / rows.at(index).fields[1]).string(), cv::IMREAD_GRAYSCALE);
    const fs::path stem = run_ / "inpainted" / stamp;
    ASSERT_TRUE(cv::imwrite(stem.string() + "_rgb.png", background));
    ASSERT_TRUE(cv::imwrite(stem.string() + "_depth.png", depth));
    ASSERT_TRUE(cv::imwrite(stem.string() + "_mask.png", mask));
    ASSERT_TRUE(cv::imwrite(stem.string() + "_unfilled.png", cv::Mat::zeros(mask.size(), CV_8UC1)));
  }
  DenseEvalInputs inputs() const { return {(root_ / "seq").string(), run_.string(), camera_, {}}; }

  static inline fs::path root_;
  static inline camera::PinholeCamera camera_;
  fs::path run_;
};

TEST_F(DenseEvalTest, ThePerfectRepairScoresPerfectly) {
  write_perfect_repair(2);
  write_perfect_repair(4);
  const DenseEvalResult r = evaluate_dense(inputs());
  ASSERT_EQ(r.keyframes.size(), 2u);
  ASSERT_GT(r.total.dynamic_px, 0u) << "precondition: people in frames 2 and 4";
  EXPECT_EQ(r.total.filled_px, r.total.dynamic_px);
  EXPECT_TRUE(std::isinf(r.total.filled_rgb.psnr_db()));
  EXPECT_EQ(r.total.filled_depth.median_m(), 0.0);
  EXPECT_LT(r.total.filled_rgb_original.psnr_db(), 30.0);  // the people were there
}

// The stem must be a whole finite stamp: "nan" used to be taken for frame 0.
TEST_F(DenseEvalTest, ARepairedKeyframeNamedByNoStampIsAnErrorNamingIt) {
  write_perfect_repair(2);
  for (const std::string bad : {"nan", "12.5x"}) {
    const fs::path file = run_ / "inpainted" / (bad + "_rgb.png");
    fs::copy_file(fs::directory_iterator(run_ / "inpainted")->path(), file,
                  fs::copy_options::overwrite_existing);
    try {
      evaluate_dense(inputs());
      ADD_FAILURE() << "no error for " << file;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(file.string()), std::string::npos) << e.what();
    }
    fs::remove(file);
  }
}

}  // namespace
}  // namespace ddl::eval
