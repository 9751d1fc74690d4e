#include "ddl/pipeline/dense_mapper.h"

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

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

}  // namespace
}  // namespace ddl::pipeline
