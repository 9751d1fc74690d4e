#include "ddl/pipeline/dense_mapper.h"

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>
#include <tuple>

#include "ddl/map/map.h"
#include "ddl/synthetic/sequence.h"

namespace ddl::pipeline {
namespace {

// The dense stage shares the keyframe's images and mask with tracking and dynamic removal (the
// dynamic memory and the geometry check keep the keyframe's mask): it must never write into them.
// Before 2026-11-26 the border band around the mask was assigned into the caller's mask buffer
// when inpainting was off, so the keyframe masks those stages kept grew by mask_border_px.
TEST(DenseMapper, LeavesTheSubmittedImagesAndMaskUntouched) {
  const camera::PinholeCamera camera = synthetic::tum3_camera();
  for (const bool inpainting : {false, true}) {
    auto map = std::make_shared<map::Map>();
    DenseMapperConfig config;
    config.inpainting_enabled = inpainting;
    config.octomap_enabled = true;
    config.mask_border_px = 12;
    DenseMapper dense(config, camera, map);
    for (int k = 0; k < 3; ++k) {
      const SE3 T_c_w(Mat3d::Identity(), Vec3d(0.05 * k, 0.0, 0.0));
      auto kf = std::make_shared<map::KeyFrame>(map->next_keyframe_id(), k,
                                                std::make_shared<map::FrameFeatures>(), T_c_w);
      map->add_keyframe(kf);
      cv::Mat bgr(camera.height, camera.width, CV_8UC3, cv::Scalar(40, 80, 120));
      cv::Mat depth(camera.height, camera.width, CV_32FC1, cv::Scalar(2.0f));
      cv::Mat mask = cv::Mat::zeros(camera.height, camera.width, CV_8UC1);
      cv::rectangle(mask, cv::Rect(200 + 20 * k, 150, 120, 200), cv::Scalar(255), cv::FILLED);
      depth.setTo(1.2f, mask);
      const cv::Mat bgr_before = bgr.clone();
      const cv::Mat depth_before = depth.clone();
      const cv::Mat mask_before = mask.clone();
      dense.submit({kf, bgr, depth, mask});
      EXPECT_EQ(cv::countNonZero(mask != mask_before), 0) << "inpainting " << inpainting;
      EXPECT_EQ(cv::countNonZero(depth != depth_before), 0) << "inpainting " << inpainting;
      cv::Mat diff;
      cv::absdiff(bgr, bgr_before, diff);
      EXPECT_EQ(cv::countNonZero(diff.reshape(1)), 0) << "inpainting " << inpainting;
    }
    dense.finish();
    EXPECT_EQ(dense.stats().keyframes, 3u);
  }
}

// A map reset (tracking lost while the map was young) starts a new world frame: the keyframes
// stored before it must neither fill later keyframes nor stay in the octree. Until 2026-11-26 the
// dense stage was not told, and pasted old-frame pixels and kept old-frame voxels.
TEST(DenseMapper, AMapResetDropsTheStoredKeyframesAndTheOctree) {
  const camera::PinholeCamera camera = synthetic::tum3_camera();
  auto keyframe_images = [&](int k, bool masked) {
    cv::Mat bgr(camera.height, camera.width, CV_8UC3, cv::Scalar(40 + 30 * k, 80, 120));
    cv::Mat depth(camera.height, camera.width, CV_32FC1, cv::Scalar(2.0f + 0.3f * k));
    cv::Mat mask = cv::Mat::zeros(camera.height, camera.width, CV_8UC1);
    if (masked) {
      cv::rectangle(mask, cv::Rect(260, 180, 100, 120), cv::Scalar(255), cv::FILLED);
      depth.setTo(1.0f, mask);
    }
    return std::make_tuple(bgr, depth, mask);
  };
  for (const bool threaded : {false, true}) {
    auto run = [&](bool with_old_keyframes, bool reset) {
      auto map = std::make_shared<map::Map>();
      DenseMapperConfig config;
      config.threaded = threaded;
      config.mask_border_px = 0;
      auto dense = std::make_unique<DenseMapper>(config, camera, map);
      auto submit = [&](int k, bool masked) {
        auto kf = std::make_shared<map::KeyFrame>(map->next_keyframe_id(), k,
                                                  std::make_shared<map::FrameFeatures>(), SE3());
        map->add_keyframe(kf);
        auto [bgr, depth, mask] = keyframe_images(k, masked);
        dense->submit({kf, bgr, depth, mask});
      };
      if (with_old_keyframes) {
        submit(0, false);
        submit(1, false);
      }
      if (reset) dense->reset();
      submit(2, true);
      dense->finish();
      return dense;
    };
    const auto fresh = run(false, false);
    const auto kept = run(true, false);
    const auto reset = run(true, true);
    // Without the reset the old keyframes fill the new keyframe's masked pixels.
    EXPECT_GT(kept->stats().filled_pixels, 10000) << "threaded " << threaded;
    EXPECT_EQ(reset->stats().filled_pixels, 0) << "threaded " << threaded;
    EXPECT_EQ(reset->stats().resets, 1u);
    EXPECT_EQ(reset->stats().keyframes, 3u);
    ASSERT_NE(reset->octree(), nullptr);
    EXPECT_EQ(reset->octree()->stats().scans_integrated, 1u) << "threaded " << threaded;
    EXPECT_EQ(reset->octree()->stats().occupied_leaves, fresh->octree()->stats().occupied_leaves)
        << "threaded " << threaded;
    EXPECT_NE(kept->octree()->stats().occupied_leaves, fresh->octree()->stats().occupied_leaves);
  }
}

}  // namespace
}  // namespace ddl::pipeline
