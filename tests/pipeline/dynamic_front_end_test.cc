// The dynamic front end's use of the segmentation backends (review findings of stop 13).

#include "ddl/pipeline/dynamic_front_end.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <optional>

#include "ddl/core/error.h"
#include "ddl/map/keyframe.h"
#include "ddl/map/map.h"
#include "ddl/synthetic/sequence.h"
#include "shared_data.h"

namespace ddl::pipeline {
namespace {
namespace fs = std::filesystem;

class FolderBackend : public ::testing::Test {
 protected:
  void SetUp() override {
    // One folder per test and process: ctest -j runs the tests of this fixture side by side.
    dir_ = fs::temp_directory_path() /
           ("ddl_front_end_masks_" +
            std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()) + "_" +
            std::to_string(static_cast<long long>(getpid())));
    fs::create_directories(dir_);
    // Frame "a": the left half dynamic; frame "b": the top-right corner.
    cv::Mat a = cv::Mat::zeros(camera_.height, camera_.width, CV_8UC1);
    a.colRange(0, camera_.width / 2).setTo(255);
    cv::Mat b = cv::Mat::zeros(camera_.height, camera_.width, CV_8UC1);
    b(cv::Rect(camera_.width - 50, 0, 50, 40)).setTo(255);
    cv::imwrite((dir_ / "a.png").string(), a);
    cv::imwrite((dir_ / "b.png").string(), b);
    config_.segmentation.backend = segmentation::Backend::kFolder;
    config_.segmentation.mask_folder = dir_.string();
  }
  void TearDown() override { fs::remove_all(dir_); }

  io::RgbdFrame frame(std::size_t index, const std::string& name) const {
    io::RgbdFrame f;
    f.index = index;
    f.rgb = cv::Mat(camera_.height, camera_.width, CV_8UC3, cv::Scalar(90, 90, 90));
    f.rgb_path = "rgb/" + name + ".png";  // no depth: the depth trim leaves the mask alone
    return f;
  }

  camera::PinholeCamera camera_ = synthetic::tum3_camera();
  DynamicConfig config_;
  fs::path dir_;
};

// The CNN schedule (dynamic.segmentation_interval, default 2) reused the previous mask, grown, on
// every second frame; precomputed masks cost nothing, and each frame has its own.
TEST_F(FolderBackend, EveryFrameGetsItsOwnMask) {
  ASSERT_GE(config_.segmentation_interval, 2);
  DynamicFrontEnd front_end(config_, camera_, "");
  ASSERT_TRUE(front_end.has_segmenter());
  const CnnMask first = front_end.cnn_mask(frame(0, "a"));
  const CnnMask second = front_end.cnn_mask(frame(1, "b"));
  EXPECT_FALSE(second.reused);
  EXPECT_EQ(cv::countNonZero(first.mask), camera_.height * camera_.width / 2);
  EXPECT_EQ(cv::countNonZero(second.mask), 50 * 40);
}

// Masks made for the stored RGB files (e.g. the distorted TUM images) are moved onto the grid of
// the undistorted frames by the dataset's mapping.
TEST_F(FolderBackend, MasksGoThroughTheStoredToFrameMapping) {
  DynamicFrontEnd front_end(config_, camera_, "");
  front_end.set_stored_mask_mapping([](const cv::Mat& stored) {
    cv::Mat mirrored;
    cv::flip(stored, mirrored, 1);
    return mirrored;
  });
  const cv::Mat mask = front_end.cnn_mask(frame(0, "a")).mask;
  EXPECT_EQ(cv::countNonZero(mask.colRange(0, camera_.width / 2)), 0);
  EXPECT_EQ(cv::countNonZero(mask.colRange(camera_.width / 2, camera_.width)),
            camera_.height * camera_.width / 2);
}

// A mask region on a flat wall is a picture (dynamic.picture_veto): the front end drops it before
// the mask reaches tracking or the dynamic memory, and counts it; standing in front of the wall,
// the same region is kept.
TEST_F(FolderBackend, APictureOnTheWallIsDroppedAndCounted) {
  const cv::Rect corner(camera_.width - 50, 0, 50, 40);  // frame "b"'s mask
  io::RgbdFrame wall = frame(0, "b");
  wall.depth_m = cv::Mat(camera_.height, camera_.width, CV_32FC1, cv::Scalar(2.5f));
  io::RgbdFrame standing = frame(1, "b");
  standing.depth_m = wall.depth_m.clone();
  standing.depth_m(corner).setTo(1.5f);

  DynamicFrontEnd front_end(config_, camera_, "");
  const CnnMask picture = front_end.cnn_mask(wall);
  EXPECT_EQ(cv::countNonZero(picture.mask), 0);
  EXPECT_EQ(picture.pictures_dropped, 1);
  const CnnMask object = front_end.cnn_mask(standing);
  EXPECT_EQ(cv::countNonZero(object.mask), corner.area());
  EXPECT_EQ(object.pictures_dropped, 0);

  config_.picture_veto.enabled = false;
  DynamicFrontEnd without_veto(config_, camera_, "");
  EXPECT_EQ(cv::countNonZero(without_veto.cnn_mask(wall).mask), corner.area());
}

// A distorted camera's frames have a blank margin without depth after undistortion. Beside a
// picture it reads as a depth hole (something out of range behind it) until the front end knows
// where the sensor's image lies (io::DatasetReader::source_area); then the picture is dropped.
TEST_F(FolderBackend, TheUndistortionMarginIsNoHoleBesideAPicture) {
  const cv::Rect corner(camera_.width - 50, 0, 50, 40);  // frame "b"'s mask
  cv::Mat area(camera_.height, camera_.width, CV_8UC1, cv::Scalar(0));
  area(cv::Rect(12, 12, camera_.width - 24, camera_.height - 24)).setTo(255);
  io::RgbdFrame wall = frame(0, "b");
  wall.depth_m = cv::Mat(camera_.height, camera_.width, CV_32FC1, cv::Scalar(2.5f));
  wall.depth_m.setTo(0.0f, area == 0);

  DynamicFrontEnd margin_unknown(config_, camera_, "");
  const CnnMask kept = margin_unknown.cnn_mask(wall);
  EXPECT_EQ(cv::countNonZero(kept.mask), corner.area());
  EXPECT_EQ(kept.pictures_dropped, 0);

  DynamicFrontEnd margin_known(config_, camera_, "");
  margin_known.set_source_area(area);
  const CnnMask dropped = margin_known.cnn_mask(wall);
  EXPECT_EQ(cv::countNonZero(dropped.mask), 0);
  EXPECT_EQ(dropped.pictures_dropped, 1);
}

// Only a missing model file may turn into geometry-only operation; a mistyped mask folder ran
// without any masks and a warning about model_path.
TEST_F(FolderBackend, AMissingFolderEndsTheRunInsteadOfFallingBack) {
  ASSERT_TRUE(config_.fallback_without_model);
  config_.segmentation.mask_folder = (dir_ / "typo").string();
  EXPECT_THROW(DynamicFrontEnd(config_, camera_, ""), InputError);
}

// The geometry check's references keep their depth images while they are alive: culled (or
// gone) keyframes leave the cache first, then the oldest. Until stop 26 the oldest left first,
// with a limit of 30, and a camera back where it had been 30 keyframes before tested nothing.
TEST(DynamicFrontEndCache, CulledKeyframesLeaveFirstThenTheOldest) {
  DynamicConfig config;
  config.segmentation.backend = segmentation::Backend::kNone;
  config.use_geometry = true;  // reference_views() serves the sparse geometry check
  config.keyframe_depth_cache = 3;
  const camera::PinholeCamera camera = synthetic::tum3_camera();
  DynamicFrontEnd front_end(config, camera, "");
  map::Map map;
  auto keyframe = [&] {
    return std::make_shared<map::KeyFrame>(map.next_keyframe_id(), 0.0,
                                           std::make_shared<map::FrameFeatures>(), SE3());
  };
  const cv::Mat depth(camera.height, camera.width, CV_32FC1, cv::Scalar(2.0f));
  const cv::Mat none = cv::Mat::zeros(camera.height, camera.width, CV_8UC1);
  cv::Mat person = none.clone();
  person(cv::Rect(10, 10, 20, 20)).setTo(255);
  auto has_depth = [&](const map::KeyFramePtr& kf) {
    return !front_end.reference_views({kf}).front().depth_image_m.empty();
  };
  const map::KeyFramePtr oldest = keyframe();
  front_end.remember_keyframe(oldest, depth, person);
  map::KeyFramePtr gone = keyframe();
  front_end.remember_keyframe(gone, depth, none);
  const map::KeyFramePtr third = keyframe();
  front_end.remember_keyframe(third, depth, none);
  gone.reset();  // culled and freed
  const map::KeyFramePtr fourth = keyframe();
  front_end.remember_keyframe(fourth, depth, none);
  EXPECT_TRUE(has_depth(oldest)) << "the oldest left before a culled keyframe";
  EXPECT_TRUE(has_depth(third));
  EXPECT_TRUE(has_depth(fourth));
  // Only a mask that marks something is kept.
  EXPECT_FALSE(front_end.reference_views({oldest}).front().dynamic_mask.empty());
  EXPECT_TRUE(front_end.reference_views({third}).front().dynamic_mask.empty());
  // With every cached keyframe alive, the oldest leaves.
  const map::KeyFramePtr fifth = keyframe();
  front_end.remember_keyframe(fifth, depth, none);
  EXPECT_FALSE(has_depth(oldest));
  EXPECT_TRUE(has_depth(third));
  EXPECT_TRUE(has_depth(fifth));
}

// The free-space check's voters: a map reset leaves none of the old map's keyframes, although
// they may live on a while (the dense stage holds them until it takes its reset); keyframes of a
// loaded map vote whatever their stamps, this session's only once they are old enough
// (review, stop 34).
TEST(DynamicFrontEndCache, FreeSpaceVotersOfTheSessionsMap) {
  DynamicConfig config;
  config.segmentation.backend = segmentation::Backend::kNone;
  config.free_space.enabled = true;
  config.free_space.min_reference_age_s = 0.3;
  const camera::PinholeCamera camera = synthetic::tum3_camera();
  map::Map map;
  auto keyframe = [&](double timestamp_s) {
    return std::make_shared<map::KeyFrame>(map.next_keyframe_id(), timestamp_s,
                                           std::make_shared<map::FrameFeatures>(), SE3());
  };
  const cv::Mat depth(camera.height, camera.width, CV_32FC1, cv::Scalar(2.0f));
  io::RgbdFrame frame;
  frame.timestamp_s = 10.0;
  frame.depth_m = depth;
  {
    DynamicFrontEnd front_end(config, camera, "");
    const std::vector<map::KeyFramePtr> old_map{keyframe(1.0), keyframe(2.0)};
    for (const auto& kf : old_map) front_end.remember_keyframe(kf, depth, cv::Mat());
    const map::KeyFrameId first_new = map.next_keyframe_id();
    const map::KeyFramePtr fresh = keyframe(3.0);
    front_end.remember_keyframe(fresh, depth, cv::Mat());
    ASSERT_EQ(front_end.free_space_views(frame, SE3()).size(), 3u) << "precondition";
    front_end.forget_keyframes_before(first_new);
    EXPECT_EQ(front_end.free_space_views(frame, SE3()).size(), 1u);
  }
  {
    DynamicFrontEnd front_end(config, camera, "");
    const map::KeyFramePtr later_this_session = keyframe(12.0);
    front_end.remember_keyframe(later_this_session, depth, cv::Mat());
    const map::KeyFramePtr too_young = keyframe(9.9);
    front_end.remember_keyframe(too_young, depth, cv::Mat());
    EXPECT_EQ(front_end.free_space_views(frame, SE3()).size(), 0u);
    const map::KeyFramePtr loaded = keyframe(12.0);
    front_end.remember_loaded_keyframe(loaded, depth, cv::Mat());
    EXPECT_EQ(front_end.free_space_views(frame, SE3()).size(), 1u);
  }
}

TEST(DynamicFrontEndModel, AMissingModelFallsBackToGeometryOnly) {
  DynamicConfig config;
  config.segmentation.model_path = "/nonexistent/model.onnx";
  const DynamicFrontEnd front_end(config, synthetic::tum3_camera(), "");
  EXPECT_FALSE(front_end.has_segmenter());
  config.fallback_without_model = false;
  EXPECT_THROW(DynamicFrontEnd(config, synthetic::tum3_camera(), ""), InputError);
}

// Upright segmentation (dynamic.segmentation.upright): an upside-down frame is turned for the CNN
// only when it is asked for, the frame's up is known and its roll reaches the threshold.
TEST(DynamicFrontEndModel, AFrameIsTurnedUprightOnlyWhenAskedAndItsUpIsKnown) {
  const std::string shared = test_support::shared_dir();
  const std::string photo = test_support::kBasketballPhoto;
  DynamicConfig config;
  if (!fs::exists(fs::path(shared) / config.segmentation.model_path)) GTEST_SKIP() << "no model";
  if (!fs::exists(photo)) GTEST_SKIP() << "opencv-doc not installed: " << photo;
  config.segmentation_interval = 1;
  config.fallback_without_model = false;
  const cv::Mat upright = cv::imread(photo, cv::IMREAD_COLOR);
  ASSERT_EQ(upright.size(), cv::Size(640, 480));
  const camera::PinholeCamera camera = synthetic::tum3_camera();
  std::size_t index = 0;
  const auto frame = [&](const cv::Mat& bgr, std::optional<Vec3d> up_c) {
    io::RgbdFrame f;
    f.index = index++;
    f.rgb = bgr;
    f.rgb_path = photo;  // no depth: the depth trim leaves the mask alone
    f.up_c = up_c;
    return f;
  };
  cv::Mat truth;
  cv::flip(DynamicFrontEnd(config, camera, shared).cnn_mask(frame(upright, std::nullopt)).mask,
           truth, -1);
  ASSERT_GT(cv::countNonZero(truth), 0.05 * static_cast<double>(truth.total()));
  const auto iou = [&](const cv::Mat& mask) {
    return cv::countNonZero(mask & truth) / static_cast<double>(cv::countNonZero(mask | truth));
  };
  cv::Mat upside_down;
  cv::flip(upright, upside_down, -1);
  const Vec3d down(0, 1, 0);  // up points down the image

  const CnnMask off = DynamicFrontEnd(config, camera, shared).cnn_mask(frame(upside_down, down));
  EXPECT_FALSE(off.turned);
  EXPECT_LT(iou(off.mask), 0.2);

  config.segmentation.upright = true;
  DynamicFrontEnd front_end(config, camera, shared);
  const CnnMask unknown = front_end.cnn_mask(frame(upside_down, std::nullopt));
  EXPECT_FALSE(unknown.turned);
  const CnnMask turned = front_end.cnn_mask(frame(upside_down, down));
  EXPECT_TRUE(turned.turned);
  EXPECT_GT(iou(turned.mask), 0.9);
  // Rolled by 5 degrees, under the 10-degree threshold: not turned.
  const double roll = 5.0 * M_PI / 180.0;
  EXPECT_FALSE(
      front_end.cnn_mask(frame(upright, Vec3d(std::sin(roll), -std::cos(roll), 0))).turned);
}

// finish_masks refines the combined mask (dynamic.edge_refinement) and, with
// keep_free_space_regions, keeps the free-space regions the colour edges would take away: a box of
// the wall's colour with a logo on it, found by the free-space check.
TEST(DynamicFrontEndRefinement, TheFreeSpaceRegionsCanBeKeptThroughTheRefinement) {
  DynamicConfig config;
  config.segmentation.backend = segmentation::Backend::kNone;
  const camera::PinholeCamera camera = synthetic::tum3_camera();
  cv::Mat bgr(camera.height, camera.width, CV_8UC3, cv::Scalar(150, 170, 190));
  cv::rectangle(bgr, cv::Rect(295, 214, 30, 10), cv::Scalar(30, 30, 30), cv::FILLED);
  cv::Mat box = cv::Mat::zeros(camera.height, camera.width, CV_8UC1);
  box(cv::Rect(280, 200, 60, 44)).setTo(255);
  const auto combined = [&](bool keep) {
    config.edge_refinement.keep_free_space_regions = keep;
    const DynamicFrontEnd front_end(config, camera, "");
    DynamicMasks masks;
    masks.free_space = box.clone();
    masks.free_space_regions = box.clone();
    front_end.finish_masks(masks, bgr, cv::Mat(), cv::Mat());
    EXPECT_TRUE(masks.refined);
    return masks.combined;
  };
  const cv::Mat refined = combined(false);
  EXPECT_GT(cv::countNonZero(box & ~refined), 300) << "the refinement left the box whole";
  EXPECT_EQ(cv::countNonZero(box & ~combined(true)), 0);
}

}  // namespace
}  // namespace ddl::pipeline
