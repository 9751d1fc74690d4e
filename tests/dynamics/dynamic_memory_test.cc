#include "ddl/dynamics/dynamic_memory.h"

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include "config_error_check.h"
#include "ddl/core/error.h"
#include "ddl/dynamics/mask_fusion.h"
#include "ddl/synthetic/sequence.h"

namespace ddl::dynamics {
namespace {

// A wall at world z = 3 m and a "person": the rectangle [x0, x1] x [y0, y1] at world z = 2 m.
struct Person {
  double x0 = -0.25, x1 = 0.25, y0 = -0.6, y1 = 0.6, z = 2.0;
};
constexpr double kWallZ = 3.0;

// Depth image seen from T_w_c (camera looking along world +z) and the person's true mask.
struct View {
  cv::Mat depth_m;
  cv::Mat person_mask;
  cv::Mat bgr;  // wall light grey, person red
};
const cv::Vec3b kWallColour(200, 200, 200);
const cv::Vec3b kPersonColour(40, 60, 200);

View render(const camera::PinholeCamera& cam, const SE3& T_w_c,
            const std::optional<Person>& person) {
  View view{cv::Mat(cam.height, cam.width, CV_32FC1),
            cv::Mat::zeros(cam.height, cam.width, CV_8UC1),
            cv::Mat(cam.height, cam.width, CV_8UC3, cv::Scalar(kWallColour))};
  const Vec3d o = T_w_c.translation();
  const SE3 T_c_w = T_w_c.inverse();
  for (int v = 0; v < cam.height; ++v) {
    for (int u = 0; u < cam.width; ++u) {
      const Vec3d dir = T_w_c.rotation() * cam.unproject(u, v, 1.0);
      double t = (kWallZ - o.z()) / dir.z();
      if (person) {
        const double tp = (person->z - o.z()) / dir.z();
        const Vec3d p = o + tp * dir;
        if (tp > 0 && tp < t && p.x() >= person->x0 && p.x() <= person->x1 && p.y() >= person->y0 &&
            p.y() <= person->y1) {
          t = tp;
          view.person_mask.at<std::uint8_t>(v, u) = 255;
          view.bgr.at<cv::Vec3b>(v, u) = kPersonColour;
        }
      }
      view.depth_m.at<float>(v, u) = static_cast<float>((T_c_w * (o + t * dir)).z());
    }
  }
  return view;
}

SE3 camera_at(double x, double yaw_deg) {
  const double a = yaw_deg * M_PI / 180.0;
  return SE3(Mat3d(Eigen::AngleAxisd(a, Vec3d::UnitY())), Vec3d(x, 0.0, 0.0));
}

TEST(DynamicMemory, PersonCutByTheImageBorderIsRecalledFromAnEarlierFullView) {
  const camera::PinholeCamera cam = synthetic::tum3_camera();
  DynamicMemoryConfig config;
  config.erode_px = 0;        // the mask below is exact: no spill to erode
  config.recall_band_px = 0;  // recall everywhere: the cut person reaches beyond the band
  DynamicMemory memory(config, cam);
  // Frame 0: the person in full view, the CNN mask exact.
  const SE3 T_w_a = camera_at(0.0, 0.0);
  const View a = render(cam, T_w_a, Person{});
  memory.remember(0, T_w_a, a.person_mask, a.depth_m, a.bgr);
  // Frame 20: the camera has turned so the person is cut by the left image border.
  const SE3 T_w_b = camera_at(0.1, 34.0);
  const View b = render(cam, T_w_b, Person{});
  const int truth = cv::countNonZero(b.person_mask);
  ASSERT_GT(truth, 1000);
  ASSERT_LT(truth, cv::countNonZero(a.person_mask) / 2);  // really cut
  DynamicMemoryStats stats;
  const cv::Mat recalled = memory.recall(20, T_w_b.inverse(), b.depth_m, b.bgr, &stats);
  const MaskScore score = score_mask(recalled, b.person_mask);
  EXPECT_GT(score.recall, 0.9) << "IoU " << score.iou;
  EXPECT_GT(score.precision, 0.97);
  EXPECT_GT(stats.points_projected, 0);
  EXPECT_EQ(stats.pixels_marked, cv::countNonZero(recalled));
}

TEST(DynamicMemory, PlaceThePersonLeftIsNotRecalled) {
  const camera::PinholeCamera cam = synthetic::tum3_camera();
  DynamicMemory memory(DynamicMemoryConfig{}, cam);
  const SE3 T_w_c = camera_at(0.0, 0.0);
  const View before = render(cam, T_w_c, Person{});
  memory.remember(0, T_w_c, before.person_mask, before.depth_m, before.bgr);
  // The person walked 0.6 m to the right: where they stood, the wall 1 m behind shows.
  Person moved;
  moved.x0 += 0.6;
  moved.x1 += 0.6;
  const View after = render(cam, T_w_c, moved);
  const cv::Mat recalled = memory.recall(10, T_w_c.inverse(), after.depth_m, after.bgr);
  cv::Mat vacated = before.person_mask & ~after.person_mask;
  EXPECT_EQ(cv::countNonZero(recalled & vacated), 0);
  // Nothing of the moved person was remembered there either: the recalled mask is empty.
  EXPECT_EQ(cv::countNonZero(recalled), 0);
}

TEST(DynamicMemory, WallAPersonStoodAgainstIsNotRecalledOnceTheyLeft) {
  const camera::PinholeCamera cam = synthetic::tum3_camera();
  const SE3 T_w_c = camera_at(0.0, 0.0);
  Person against_wall;
  against_wall.z = kWallZ - 0.05;  // within the depth tolerance of the wall behind
  const View before = render(cam, T_w_c, against_wall);
  const View after = render(cam, T_w_c, std::nullopt);  // they walked out of view
  for (const int colour_tolerance : {-1, 60}) {
    DynamicMemoryConfig config;
    config.colour_tolerance = colour_tolerance;
    config.recall_band_px = 0;  // the person stood in the middle of the image
    DynamicMemory memory(config, cam);
    memory.remember(0, T_w_c, before.person_mask, before.depth_m, before.bgr);
    DynamicMemoryStats stats;
    const int recalled =
        cv::countNonZero(memory.recall(10, T_w_c.inverse(), after.depth_m, after.bgr, &stats));
    if (colour_tolerance < 0) {
      // Depth alone cannot tell the wall from the person who stood there.
      EXPECT_GT(recalled, cv::countNonZero(before.person_mask) / 2);
    } else {
      EXPECT_EQ(recalled, 0);
      EXPECT_EQ(stats.points_colour_rejected, stats.points_projected);
    }
  }
}

TEST(DynamicMemory, DetectionsOlderThanMaxAgeAreForgotten) {
  const camera::PinholeCamera cam = synthetic::tum3_camera();
  DynamicMemoryConfig config;
  config.max_age_frames = 30;
  config.recall_band_px = 0;  // the person stands in the middle of the image
  DynamicMemory memory(config, cam);
  const SE3 T_w_c = camera_at(0.0, 0.0);
  const View view = render(cam, T_w_c, Person{});
  memory.remember(100, T_w_c, view.person_mask, view.depth_m, view.bgr);
  EXPECT_GT(cv::countNonZero(memory.recall(130, T_w_c.inverse(), view.depth_m, view.bgr)), 0);
  EXPECT_TRUE(memory.recall(131, T_w_c.inverse(), view.depth_m, view.bgr).empty());
  EXPECT_EQ(memory.remembered_points(), 0U);
}

TEST(DynamicMemory, MaskSpillOntoTheBackgroundIsNotRemembered) {
  const camera::PinholeCamera cam = synthetic::tum3_camera();
  const SE3 T_w_c = camera_at(0.0, 0.0);
  const View view = render(cam, T_w_c, Person{});
  // The CNN's upsampled mask spills 3 px onto the wall around the person.
  const cv::Mat spilled = feature_exclusion_mask(view.person_mask, 3);
  const int person_px = cv::countNonZero(view.person_mask);
  const int wall_in_mask = cv::countNonZero(spilled & ~view.person_mask);
  ASSERT_GT(wall_in_mask, 1000);
  for (const int erode_px : {0, 4}) {
    DynamicMemoryConfig config;
    config.erode_px = erode_px;
    config.recall_band_px = 0;  // the person stands in the middle of the image
    DynamicMemory memory(config, cam);
    const cv::Mat before = spilled.clone();
    memory.remember(0, T_w_c, spilled, view.depth_m, view.bgr);
    EXPECT_EQ(cv::norm(spilled, before, cv::NORM_INF), 0.0) << "the caller's mask was changed";
    const cv::Mat recalled = memory.recall(5, T_w_c.inverse(), view.depth_m, view.bgr);
    const int wall_recalled = cv::countNonZero(recalled & ~view.person_mask);
    const MaskScore score = score_mask(recalled, view.person_mask);
    if (erode_px == 0) {
      EXPECT_GT(wall_recalled, wall_in_mask / 2);  // what was remembered stays
    } else {
      EXPECT_LT(wall_recalled, person_px / 100);
      EXPECT_GT(score.recall, 0.9) << "erosion costs the rim";
      EXPECT_GT(score.precision, 0.99);
    }
  }
}

TEST(DynamicMemory, RecallsOnlyNearTheImageBorderByDefault) {
  const camera::PinholeCamera cam = synthetic::tum3_camera();
  const SE3 T_w_a = camera_at(0.0, 0.0);
  const View a = render(cam, T_w_a, Person{});
  DynamicMemoryConfig config;
  config.erode_px = 0;
  DynamicMemory memory(config, cam);
  memory.remember(0, T_w_a, a.person_mask, a.depth_m, a.bgr);
  // In the middle of the image the CNN sees the whole person: nothing is recalled there.
  EXPECT_EQ(cv::countNonZero(memory.recall(2, T_w_a.inverse(), a.depth_m, a.bgr)), 0);
  // A sliver at the border, inside the band, is.
  const SE3 T_w_b = camera_at(0.1, 34.3);
  const View b = render(cam, T_w_b, Person{});
  const cv::Rect visible = cv::boundingRect(b.person_mask);
  ASSERT_GT(visible.width, 4);
  ASSERT_LT(visible.x + visible.width, config.recall_band_px);
  const MaskScore score =
      score_mask(memory.recall(4, T_w_b.inverse(), b.depth_m, b.bgr), b.person_mask);
  EXPECT_GT(score.recall, 0.9);
  EXPECT_GT(score.precision, 0.97);
}

TEST(DynamicMemory, SpillOntoSurfacesAKeyframeSawAsStaticIsNotRemembered) {
  const camera::PinholeCamera cam = synthetic::tum3_camera();
  const SE3 T_w_c = camera_at(0.0, 0.0);
  const View view = render(cam, T_w_c, Person{});
  const View empty_room = render(cam, camera_at(0.2, 5.0), std::nullopt);  // an earlier keyframe
  const cv::Mat spilled = feature_exclusion_mask(view.person_mask, 3);
  const int wall_in_mask = cv::countNonZero(spilled & ~view.person_mask);
  for (const int static_views : {0, 5}) {
    DynamicMemoryConfig config;
    config.erode_px = 0;        // only the veto removes the spill here
    config.recall_band_px = 0;  // the person stands in the middle of the image
    config.static_views = static_views;
    DynamicMemory memory(config, cam);
    memory.add_static_view(camera_at(0.2, 5.0), empty_room.depth_m, cv::Mat());
    memory.remember(0, T_w_c, spilled, view.depth_m, view.bgr);
    const cv::Mat recalled = memory.recall(5, T_w_c.inverse(), view.depth_m, view.bgr);
    const int wall_recalled = cv::countNonZero(recalled & ~view.person_mask);
    const MaskScore score = score_mask(recalled, view.person_mask);
    EXPECT_GT(score.recall, 0.97) << static_views;  // the keyframe saw the wall behind the person
    if (static_views == 0) {
      EXPECT_GT(wall_recalled, wall_in_mask / 2);
    } else {
      EXPECT_LT(wall_recalled, wall_in_mask / 20);
    }
  }
}

// A loop correction moves the keyframes around the camera, and with them the camera poses that
// follow, by a rigid T_new_old: what the memory keeps in the world frame must move too.
TEST(DynamicMemory, MoveWorldFollowsACorrectionOfTheMap) {
  const camera::PinholeCamera cam = synthetic::tum3_camera();
  DynamicMemoryConfig config;
  config.erode_px = 0;
  config.recall_band_px = 0;
  const SE3 T_w_a = camera_at(0.0, 0.0);  // in the world before the correction
  const View a = render(cam, T_w_a, Person{});
  const SE3 T_w_b = camera_at(0.1, 34.0);  // the person cut by the border
  const View b = render(cam, T_w_b, Person{});
  const SE3 T_new_old(Mat3d(Eigen::AngleAxisd(0.15, Vec3d::UnitY())), Vec3d(0.4, -0.1, 0.2));
  const SE3 T_c_new_b = (T_new_old * T_w_b).inverse();  // frame b's pose in the corrected map

  for (const bool move : {false, true}) {
    DynamicMemory memory(config, cam);
    memory.remember(0, T_w_a, a.person_mask, a.depth_m, a.bgr);
    if (move) memory.move_world(T_new_old);
    const MaskScore score =
        score_mask(memory.recall(20, T_c_new_b, b.depth_m, b.bgr), b.person_mask);
    if (move) {
      EXPECT_GT(score.recall, 0.9) << "IoU " << score.iou;
      EXPECT_GT(score.precision, 0.97);
    } else {
      EXPECT_LT(score.recall, 0.3) << "the correction is too small to tell";
    }
  }

  // The static views move too: spill onto the wall is still vetoed in the corrected world.
  config.static_views = 5;
  DynamicMemory memory(config, cam);
  const SE3 T_w_k = camera_at(0.2, 5.0);
  memory.add_static_view(T_w_k, render(cam, T_w_k, std::nullopt).depth_m, cv::Mat());
  memory.move_world(T_new_old);
  const cv::Mat spilled = feature_exclusion_mask(a.person_mask, 3);
  memory.remember(1, T_new_old * T_w_a, spilled, a.depth_m, a.bgr);
  const cv::Mat recalled = memory.recall(2, (T_new_old * T_w_a).inverse(), a.depth_m, a.bgr);
  const int wall_in_mask = cv::countNonZero(spilled & ~a.person_mask);
  EXPECT_LT(cv::countNonZero(recalled & ~a.person_mask), wall_in_mask / 20);
  EXPECT_GT(score_mask(recalled, a.person_mask).recall, 0.97);
}

// A remembered point just outside the image whose square reaches in marks the border pixels it
// reaches. The colour test looked at a window around the point's own pixel, which was empty
// outside the image, so every such point was rejected (review, stop 26).
TEST(DynamicMemory, PointsJustOutsideTheImageMarkTheBorderTheyReach) {
  const camera::PinholeCamera cam = synthetic::tum3_camera();
  DynamicMemoryConfig config;
  config.erode_px = 0;
  DynamicMemory memory(config, cam);
  const SE3 T_w_a = camera_at(0.0, 0.0);
  const View a = render(cam, T_w_a, Person{});
  // A small detection on the person: samples at u = 282 and 286 (stride 4, from 2).
  const cv::Rect block(280, 240, 8, 8);
  ASSERT_EQ(cv::countNonZero(a.person_mask(block)), 64);
  cv::Mat detection = cv::Mat::zeros(a.person_mask.size(), CV_8UC1);
  detection(block).setTo(255);
  memory.remember(0, T_w_a, detection, a.depth_m, a.bgr);
  // The camera moved right until the samples at u = 286 land at u = -1.5, outside the image; the
  // person (2 m away) still fills the left border, and the samples' squares (2 px) reach it.
  const SE3 T_w_b(Mat3d::Identity(), Vec3d(287.5 * Person{}.z / cam.fx, 0.0, 0.0));
  const View b = render(cam, T_w_b, Person{});
  ASSERT_EQ(b.person_mask.at<std::uint8_t>(244, 0), 255);
  DynamicMemoryStats stats;
  const cv::Mat recalled = memory.recall(1, T_w_b.inverse(), b.depth_m, b.bgr, &stats);
  EXPECT_GT(stats.points_projected, 0);
  EXPECT_EQ(stats.points_colour_rejected, 0);
  EXPECT_GT(stats.pixels_marked, 0);
  EXPECT_EQ(cv::countNonZero(recalled & ~b.person_mask), 0);
  EXPECT_EQ(cv::countNonZero(recalled.colRange(3, recalled.cols)), 0);
}

TEST(DynamicMemory, ConfigErrorsNameTheKey) {
  DynamicMemoryConfig config;
  config.max_age_frames = 0;
  EXPECT_TRUE(test_support::throws_config_error_for_key([&] { config.validate(); },
                                                        "dynamic.memory.max_age_frames"));
  config = {};
  config.max_depth_m = config.min_depth_m;
  EXPECT_THROW(config.validate(), ConfigError);
  EXPECT_NO_THROW(DynamicMemoryConfig{}.validate());
  // 0 is "no depth": a minimum of 0 would remember holes as points at the camera centre.
  config = {};
  config.min_depth_m = 0.0;
  EXPECT_TRUE(test_support::throws_config_error_for_key([&] { config.validate(); },
                                                        "dynamic.memory.min_depth_m"));
}

}  // namespace
}  // namespace ddl::dynamics
