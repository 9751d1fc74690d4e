#include "ddl/dynamics/geometry_check.h"

#include <gtest/gtest.h>

#include <random>

#include "config_error_check.h"
#include "ddl/core/error.h"
#include "ddl/dynamics/mask_fusion.h"
#include "ddl/synthetic/depth_model.h"
#include "ddl/synthetic/sequence.h"

namespace ddl::dynamics {
namespace {

// Depth image of a fronto-parallel wall at wall_z (world z, camera looking along +z from
// T_w_c), with optional boxes [x0,x1]x[y0,y1] at z in world coordinates and an optional floor,
// the plane y = floor_y (world y points down). `cos_incidence`, when given, receives |cos| of the
// angle between each ray and the surface normal (for the sensor model).
struct Box {
  double x0, x1, y0, y1, z;
};
constexpr double kNoFloor = 1e9;

// The room corner of the noisy-scene tests: a desk and a cabinet in front of the wall, on the
// floor y = kRoomFloorY.
constexpr double kRoomFloorY = 0.9;
std::vector<Box> room_furniture() {
  return {{-0.7, 0.3, 0.15, 0.9, 2.2}, {0.6, 1.3, -0.6, 0.9, 2.9}};
}

cv::Mat render_depth(const camera::PinholeCamera& cam, const SE3& T_w_c, double wall_z,
                     const std::vector<Box>& boxes, double floor_y = kNoFloor,
                     cv::Mat* cos_incidence = nullptr) {
  cv::Mat depth(cam.height, cam.width, CV_32FC1);
  if (cos_incidence != nullptr) cos_incidence->create(cam.height, cam.width, CV_32FC1);
  const Vec3d o = T_w_c.translation();
  for (int v = 0; v < cam.height; ++v) {
    for (int u = 0; u < cam.width; ++u) {
      const Vec3d dir = T_w_c.rotation() * cam.unproject(u, v, 1.0);
      double t = (wall_z - o.z()) / dir.z();
      Vec3d normal = Vec3d::UnitZ();
      for (const Box& b : boxes) {
        const double tb = (b.z - o.z()) / dir.z();
        const Vec3d p = o + tb * dir;
        if (tb > 0 && tb < t && p.x() >= b.x0 && p.x() <= b.x1 && p.y() >= b.y0 && p.y() <= b.y1) {
          t = tb;
        }
      }
      if (floor_y != kNoFloor && dir.y() > 1e-9) {
        const double tf = (floor_y - o.y()) / dir.y();
        if (tf > 0 && tf < t) {
          t = tf;
          normal = Vec3d::UnitY();
        }
      }
      // Camera-frame z of the hit point.
      depth.at<float>(v, u) = static_cast<float>((T_w_c.inverse() * (o + t * dir)).z());
      if (cos_incidence != nullptr) {
        cos_incidence->at<float>(v, u) = static_cast<float>(std::abs(dir.normalized().dot(normal)));
      }
    }
  }
  return depth;
}

// The Kinect-like sensor model of the synthetic sequences (axial noise growing with z^2,
// disparity quantisation, dropouts at grazing angles and along depth edges), frame `frame`.
cv::Mat with_sensor_noise(const cv::Mat& depth_m, const cv::Mat& cos_incidence,
                          std::uint64_t frame) {
  const synthetic::DepthNoiseConfig kinect;
  const cv::Mat raw =
      synthetic::apply_depth_model(depth_m, cos_incidence, kinect, 5000.0, 7, frame);
  cv::Mat out;
  raw.convertTo(out, CV_32FC1, 1.0 / 5000.0);
  return out;
}

// A noisy rendering from T_w_c.
cv::Mat noisy_depth(const camera::PinholeCamera& cam, const SE3& T_w_c, double wall_z,
                    const std::vector<Box>& boxes, double floor_y, std::uint64_t frame) {
  cv::Mat cos_incidence;
  const cv::Mat exact = render_depth(cam, T_w_c, wall_z, boxes, floor_y, &cos_incidence);
  return with_sensor_noise(exact, cos_incidence, frame);
}

ReferenceView reference_from(const camera::PinholeCamera& cam, const SE3& T_w_c,
                             const cv::Mat& depth, int count, unsigned seed) {
  ReferenceView ref;
  ref.T_w_c = T_w_c;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(5, cam.width - 6), v(5, cam.height - 6);
  for (int i = 0; i < count; ++i) {
    const cv::Point2f p(u(rng), v(rng));
    const float z = depth.at<float>(cvRound(p.y), cvRound(p.x));
    if (z <= 0.0f) continue;  // no depth (sensor dropout)
    ref.pixels.push_back(p);
    ref.depth_m.push_back(z);
  }
  ref.depth_image_m = depth;
  return ref;
}

cv::Mat truth_mask(const cv::Mat& with, const cv::Mat& without) {
  cv::Mat diff;
  cv::absdiff(with, without, diff);
  return diff > 0.01f;
}

TEST(GeometryCheck, FindsAnObjectThatAppearedInFront) {
  const auto cam = synthetic::tum3_camera();
  const SE3 T_w_ref(Mat3d::Identity(), Vec3d(0, 0, 0));
  const SE3 T_w_cur(Mat3d(Eigen::AngleAxisd(0.05, Vec3d::UnitY())), Vec3d(0.1, 0.0, 0.05));
  const cv::Mat ref_depth = render_depth(cam, T_w_ref, 3.0, {});
  const std::vector<Box> person = {{-0.3, 0.2, -0.6, 0.9, 1.6}};
  const cv::Mat cur_depth = render_depth(cam, T_w_cur, 3.0, person);
  const cv::Mat truth = truth_mask(cur_depth, render_depth(cam, T_w_cur, 3.0, {}));
  GeometryCheckConfig config;
  // One large object hides a quarter of the reference's points and no CNN mask takes it: the
  // plausibility gate (ImplausiblyManySeedsMeanABadPose) is not what is tested here.
  config.max_seed_fraction = 1.0;
  GeometryCheckStats stats;
  const cv::Mat mask = geometry_dynamic_mask(cur_depth, T_w_cur.inverse(),
                                             {reference_from(cam, T_w_ref, ref_depth, 1000, 1)},
                                             cam, config, &stats);
  const MaskScore score = score_mask(mask, truth);
  EXPECT_GT(stats.points_dynamic, 20);
  EXPECT_GT(score.iou, 0.85) << "precision " << score.precision << " recall " << score.recall;
}

TEST(GeometryCheck, StaticSceneGivesAnEmptyMask) {
  const auto cam = synthetic::tum3_camera();
  const SE3 T_w_ref;
  const SE3 T_w_cur(Mat3d(Eigen::AngleAxisd(0.1, Vec3d::UnitX())), Vec3d(0.2, -0.1, 0.3));
  const std::vector<Box> table = {{-0.5, 0.5, 0.2, 0.8, 2.2}};
  const cv::Mat ref_depth = render_depth(cam, T_w_ref, 3.0, table);
  const cv::Mat cur_depth = render_depth(cam, T_w_cur, 3.0, table);
  const cv::Mat mask = geometry_dynamic_mask(cur_depth, T_w_cur.inverse(),
                                             {reference_from(cam, T_w_ref, ref_depth, 1000, 2)},
                                             cam, GeometryCheckConfig{});
  // Depth edges of a static box seen from two viewpoints: at most a few stray pixels.
  EXPECT_LT(cv::countNonZero(mask), 0.005 * static_cast<double>(mask.total()));
}

// A room corner with a desk and a cabinet, seen from three keyframes and a current view with
// realistic sensor noise and a small error of the current pose (what the low-cost tracking
// leaves): depth edges everywhere, nothing moved. The earlier check (one seed grown over whole
// surfaces, no window, back-check that accepted on no evidence) marked about 12 % of such frames.
TEST(GeometryCheck, NoisyStaticSceneWithPoseErrorGivesAnAlmostEmptyMask) {
  const auto cam = synthetic::tum3_camera();
  const double floor_y = kRoomFloorY;
  const std::vector<Box> furniture = room_furniture();
  const std::vector<SE3> keyframes = {
      SE3(), SE3(Mat3d(Eigen::AngleAxisd(0.06, Vec3d::UnitY())), Vec3d(-0.12, 0.02, 0.05)),
      SE3(Mat3d(Eigen::AngleAxisd(-0.05, Vec3d::UnitX())), Vec3d(0.1, -0.05, -0.1))};
  std::vector<ReferenceView> refs;
  for (std::size_t k = 0; k < keyframes.size(); ++k) {
    refs.push_back(reference_from(cam, keyframes[k],
                                  noisy_depth(cam, keyframes[k], 3.5, furniture, floor_y, k), 1000,
                                  static_cast<unsigned>(10 + k)));
  }
  const SE3 T_w_cur(Mat3d(Eigen::AngleAxisd(0.04, Vec3d(0.3, 1.0, 0.1).normalized())),
                    Vec3d(0.08, 0.03, 0.12));
  const cv::Mat cur_depth = noisy_depth(cam, T_w_cur, 3.5, furniture, floor_y, 99);
  // Pose error of 3 mm and 0.1 degrees.
  const SE3 error(Mat3d(Eigen::AngleAxisd(0.1 * M_PI / 180.0, Vec3d(1, -1, 0.5).normalized())),
                  Vec3d(0.002, -0.002, 0.001));
  GeometryCheckStats stats;
  const cv::Mat mask = geometry_dynamic_mask(cur_depth, (T_w_cur * error).inverse(), refs, cam,
                                             GeometryCheckConfig{}, &stats);
  EXPECT_GT(stats.points_tested, 2000);
  EXPECT_LT(cv::countNonZero(mask), 0.001 * static_cast<double>(mask.total()))
      << "seeds " << stats.points_dynamic;
}

// The static room with a grossly wrong pose (3 cm, 2 degrees: what fast motion or an RGB-depth
// time offset does on real data): seeds all over the image. Without the gates they grow into most
// of the frame; with either gate (seed fraction; median depth residual, the default) the frame
// gets no geometry mask.
TEST(GeometryCheck, ImplausiblyManySeedsMeanABadPose) {
  const auto cam = synthetic::tum3_camera();
  const double floor_y = kRoomFloorY;
  const std::vector<Box> furniture = room_furniture();
  const SE3 T_w_ref;
  const cv::Mat ref_depth = noisy_depth(cam, T_w_ref, 3.5, furniture, floor_y, 3);
  const SE3 T_w_cur(Mat3d(Eigen::AngleAxisd(0.04, Vec3d::UnitY())), Vec3d(0.08, 0.0, 0.1));
  const cv::Mat cur_depth = noisy_depth(cam, T_w_cur, 3.5, furniture, floor_y, 4);
  const SE3 error(Mat3d(Eigen::AngleAxisd(2.0 * M_PI / 180.0, Vec3d(1, -1, 0.5).normalized())),
                  Vec3d(0.03, -0.02, 0.01));
  const std::vector<ReferenceView> refs = {reference_from(cam, T_w_ref, ref_depth, 1000, 7)};
  GeometryCheckConfig ungated;
  ungated.max_seed_fraction = 1.0;
  ungated.max_median_residual_ratio = 1e9;
  GeometryCheckStats stats;
  const cv::Mat flooded =
      geometry_dynamic_mask(cur_depth, (T_w_cur * error).inverse(), refs, cam, ungated, &stats);
  ASSERT_GT(stats.points_dynamic, 0.05 * (stats.points_tested - stats.points_skipped_parallax));
  EXPECT_FALSE(stats.implausible);
  EXPECT_GT(cv::countNonZero(flooded), 0.05 * static_cast<double>(flooded.total()));
  GeometryCheckConfig gated_config = ungated;
  gated_config.max_seed_fraction = 0.05;
  const cv::Mat gated = geometry_dynamic_mask(cur_depth, (T_w_cur * error).inverse(), refs, cam,
                                              gated_config, &stats);
  EXPECT_TRUE(stats.implausible);
  EXPECT_EQ(cv::countNonZero(gated), 0);
}

// The pose-quality gate (max_median_residual_ratio, on by default): the static room and a person
// 1.6 m away who hides about a third of the reference's points. With the right pose the median
// depth residual is the sensor noise and the person is found; with the current pose 12 cm off
// along the optical axis (and 1 degree), every depth disagrees, and the frame gets no mask
// instead of one flooded by seeds.
TEST(GeometryCheck, AMedianDepthResidualAboveTauMeansABadPose) {
  const auto cam = synthetic::tum3_camera();
  const double floor_y = kRoomFloorY;
  const std::vector<Box> furniture = room_furniture();
  const SE3 T_w_ref;
  const std::vector<ReferenceView> refs = {
      reference_from(cam, T_w_ref, noisy_depth(cam, T_w_ref, 3.5, furniture, floor_y, 5), 1000, 8)};
  const SE3 T_w_cur(Mat3d(Eigen::AngleAxisd(0.03, Vec3d::UnitY())), Vec3d(0.05, 0.0, 0.05));
  std::vector<Box> scene = furniture;
  scene.push_back({-0.45, 0.1, -0.8, 0.9, 1.6});
  const cv::Mat cur_depth = noisy_depth(cam, T_w_cur, 3.5, scene, floor_y, 6);
  const cv::Mat truth = truth_mask(render_depth(cam, T_w_cur, 3.5, scene, floor_y),
                                   render_depth(cam, T_w_cur, 3.5, furniture, floor_y));
  GeometryCheckStats stats;
  const cv::Mat mask =
      geometry_dynamic_mask(cur_depth, T_w_cur.inverse(), refs, cam, GeometryCheckConfig{}, &stats);
  EXPECT_FALSE(stats.implausible);
  EXPECT_LT(stats.median_residual_ratio, 0.3);
  const MaskScore score = score_mask(mask, truth);
  EXPECT_GT(score.recall, 0.8) << "precision " << score.precision;

  const SE3 error(Mat3d(Eigen::AngleAxisd(1.0 * M_PI / 180.0, Vec3d::UnitX())),
                  Vec3d(0.0, 0.0, 0.12));
  const cv::Mat bad = geometry_dynamic_mask(cur_depth, (T_w_cur * error).inverse(), refs, cam,
                                            GeometryCheckConfig{}, &stats);
  EXPECT_GT(stats.median_residual_ratio, 0.6);
  EXPECT_TRUE(stats.implausible);
  EXPECT_EQ(cv::countNonZero(bad), 0);
}

// Fast rotation on a real sensor: 3 degrees per frame (90 deg/s at 30 fps, as at the peaks of
// fr1_rpy), and the depth image taken half a frame before the colour image that gave the pose,
// so depth and pose disagree by 1.5 degrees (14 px) at every depth edge. With fixed 9x9 windows
// that floods the frame with seeds; windows grown by the image motion since the previous frame
// (motion_window_gain) absorb it, and a person who walked in front is still found.
TEST(GeometryCheck, RgbDepthTimeOffsetOnFastMotionIsNotTakenForMotion) {
  const auto cam = synthetic::tum3_camera();
  const double floor_y = kRoomFloorY;
  const std::vector<Box> furniture = room_furniture();
  const SE3 T_w_ref;
  const cv::Mat ref_depth = noisy_depth(cam, T_w_ref, 3.5, furniture, floor_y, 3);
  const std::vector<ReferenceView> refs = {reference_from(cam, T_w_ref, ref_depth, 1000, 7)};
  const Vec3d axis = Vec3d(0.2, 1.0, 0.3).normalized();
  auto rotated = [&](double deg) {
    return SE3(Mat3d(Eigen::AngleAxisd(deg * M_PI / 180.0, axis)), Vec3d(0.04, 0.0, 0.05));
  };
  const SE3 T_w_cur = rotated(7.5);       // the colour image's pose
  const SE3 T_w_depth = rotated(6.0);     // where the depth image was taken
  const SE3 T_w_previous = rotated(4.5);  // the previous frame
  GeometryCheckConfig fixed_window;
  fixed_window.motion_window_gain = 0.0;
  fixed_window.max_seed_fraction = 1.0;
  GeometryCheckConfig config;  // defaults: motion-grown windows
  config.max_seed_fraction = 1.0;

  const cv::Mat static_depth = noisy_depth(cam, T_w_depth, 3.5, furniture, floor_y, 4);
  GeometryCheckStats fixed_stats;
  const cv::Mat flooded = geometry_dynamic_mask(static_depth, T_w_cur.inverse(), refs, cam,
                                                fixed_window, &fixed_stats, T_w_previous.inverse());
  EXPECT_GT(cv::countNonZero(flooded), 0.01 * static_cast<double>(flooded.total()))
      << "seeds " << fixed_stats.points_dynamic;
  GeometryCheckStats stats;
  const cv::Mat mask = geometry_dynamic_mask(static_depth, T_w_cur.inverse(), refs, cam, config,
                                             &stats, T_w_previous.inverse());
  EXPECT_GT(stats.median_motion_px, 10.0);
  EXPECT_LT(cv::countNonZero(mask), 0.002 * static_cast<double>(mask.total()))
      << "seeds " << stats.points_dynamic;

  std::vector<Box> with_person = furniture;
  with_person.push_back({-0.2, 0.25, -0.8, floor_y, 1.6});
  const cv::Mat person_depth = noisy_depth(cam, T_w_depth, 3.5, with_person, floor_y, 5);
  const cv::Mat truth = truth_mask(render_depth(cam, T_w_depth, 3.5, with_person, floor_y),
                                   render_depth(cam, T_w_depth, 3.5, furniture, floor_y));
  const cv::Mat found = geometry_dynamic_mask(person_depth, T_w_cur.inverse(), refs, cam, config,
                                              &stats, T_w_previous.inverse());
  const MaskScore score = score_mask(found, truth);
  EXPECT_GT(score.recall, 0.8) << "precision " << score.precision;
  EXPECT_GT(score.precision, 0.8) << "recall " << score.recall;
}

// A person steps in front of the camera and stands on the floor: the region grown from the seeds
// on the person must not spread over the floor around the feet (same depth, continuous surface),
// which the keyframes saw as static.
TEST(GeometryCheck, PersonOnTheFloorIsFoundWithoutTheFloor) {
  const auto cam = synthetic::tum3_camera();
  const double floor_y = 0.9;
  const SE3 T_w_ref;
  const SE3 T_w_cur(Mat3d(Eigen::AngleAxisd(0.03, Vec3d::UnitY())), Vec3d(0.05, 0.0, 0.03));
  const std::vector<Box> person = {{-0.25, 0.2, -0.8, floor_y, 3.0}};
  const cv::Mat ref_depth = noisy_depth(cam, T_w_ref, 3.5, {}, floor_y, 1);
  const cv::Mat cur_depth = noisy_depth(cam, T_w_cur, 3.5, person, floor_y, 2);
  const cv::Mat truth = truth_mask(render_depth(cam, T_w_cur, 3.5, person, floor_y),
                                   render_depth(cam, T_w_cur, 3.5, {}, floor_y));
  GeometryCheckStats stats;
  GeometryCheckConfig config;
  config.max_seed_fraction = 1.0;  // a large object, no CNN mask: see FindsAnObjectThatAppeared...
  const cv::Mat mask = geometry_dynamic_mask(cur_depth, T_w_cur.inverse(),
                                             {reference_from(cam, T_w_ref, ref_depth, 1000, 5)},
                                             cam, config, &stats);
  const MaskScore score = score_mask(mask, truth);
  EXPECT_GT(score.precision, 0.9) << "recall " << score.recall;
  EXPECT_GT(score.recall, 0.85) << "precision " << score.precision;
}

// growth_veto: the person on the floor again, with a second reference that looks away (the floor
// around the feet is out of its view). With "all" a reference that cannot see a pixel lets the
// region in, so it spreads over the floor; with "any_unrefuted" the first reference, which saw the
// floor there outside its own dynamic mask, stops it. Where that reference's own mask covers the
// floor, its view is no evidence and the region may spread again.
TEST(GeometryCheck, GrowthVetoByAReferenceThatSawTheSurfaceUnmasked) {
  const auto cam = synthetic::tum3_camera();
  const double floor_y = 0.9;
  const SE3 T_w_ref;
  const SE3 T_w_away(Mat3d(Eigen::AngleAxisd(0.7, Vec3d::UnitY())), Vec3d(0.0, 0.0, 0.0));
  const SE3 T_w_cur(Mat3d(Eigen::AngleAxisd(0.03, Vec3d::UnitY())), Vec3d(0.05, 0.0, 0.03));
  const std::vector<Box> person = {{-0.25, 0.2, -0.8, floor_y, 3.0}};
  const cv::Mat cur_depth = noisy_depth(cam, T_w_cur, 3.5, person, floor_y, 2);
  const cv::Mat truth = truth_mask(render_depth(cam, T_w_cur, 3.5, person, floor_y),
                                   render_depth(cam, T_w_cur, 3.5, {}, floor_y));
  std::vector<ReferenceView> refs = {
      reference_from(cam, T_w_ref, noisy_depth(cam, T_w_ref, 3.5, {}, floor_y, 1), 1000, 5),
      reference_from(cam, T_w_away, noisy_depth(cam, T_w_away, 3.5, {}, floor_y, 3), 1000, 6)};
  GeometryCheckConfig config;
  const auto score_with = [&](GrowthVeto veto) {
    config.growth_veto = veto;
    return score_mask(geometry_dynamic_mask(cur_depth, T_w_cur.inverse(), refs, cam, config),
                      truth);
  };
  const MaskScore all = score_with(GrowthVeto::kAll);
  const MaskScore unrefuted = score_with(GrowthVeto::kAnyUnrefuted);
  refs[0].dynamic_mask = cv::Mat(cam.height, cam.width, CV_8UC1, cv::Scalar(255));
  const MaskScore masked = score_with(GrowthVeto::kAnyUnrefuted);
  EXPECT_GT(unrefuted.precision, 0.9) << "recall " << unrefuted.recall;
  EXPECT_GT(unrefuted.recall, 0.85);
  EXPECT_LT(all.precision, unrefuted.precision - 0.1);
  EXPECT_LT(masked.precision, unrefuted.precision - 0.1);
}

// Without a depth image the reference cannot confirm a candidate: no seeds from it.
TEST(GeometryCheck, ReferenceWithoutDepthImageGivesNoSeeds) {
  const auto cam = synthetic::tum3_camera();
  const SE3 T_w_ref;
  const cv::Mat ref_depth = render_depth(cam, T_w_ref, 3.0, {});
  const cv::Mat cur_depth = render_depth(cam, T_w_ref, 3.0, {{-0.3, 0.2, -0.6, 0.9, 1.6}});
  ReferenceView ref = reference_from(cam, T_w_ref, ref_depth, 1000, 6);
  ref.depth_image_m.release();
  GeometryCheckStats stats;
  const cv::Mat mask = geometry_dynamic_mask(cur_depth, T_w_ref.inverse(), {ref}, cam,
                                             GeometryCheckConfig{}, &stats);
  EXPECT_EQ(stats.points_dynamic, 0);
  EXPECT_EQ(cv::countNonZero(mask), 0);
}

TEST(GeometryCheck, ThresholdGrowsWithTheSquareOfDepth) {
  GeometryCheckConfig config;
  config.depth_threshold_m = 0.03;
  config.depth_threshold_quadratic = 0.01;
  EXPECT_DOUBLE_EQ(config.threshold_at(0.0), 0.03);
  EXPECT_NEAR(config.threshold_at(2.0), 0.07, 1e-12);
  EXPECT_NEAR(config.threshold_at(4.0), 0.19, 1e-12);
}

TEST(GeometryCheck, CatchesAMovedObjectOfAStaticClass) {
  const auto cam = synthetic::tum3_camera();
  const SE3 T_w_ref;
  const SE3 T_w_cur(Mat3d::Identity(), Vec3d(0.05, 0, 0));
  const Box book_before{-0.8, -0.5, 0.0, 0.3, 2.0};
  const Box book_after{0.4, 0.7, 0.0, 0.3, 2.0};
  const cv::Mat ref_depth = render_depth(cam, T_w_ref, 3.0, {book_before});
  const cv::Mat cur_depth = render_depth(cam, T_w_cur, 3.0, {book_after});
  const cv::Mat truth = truth_mask(cur_depth, render_depth(cam, T_w_cur, 3.0, {}));
  const cv::Mat mask = geometry_dynamic_mask(cur_depth, T_w_cur.inverse(),
                                             {reference_from(cam, T_w_ref, ref_depth, 1500, 3)},
                                             cam, GeometryCheckConfig{});
  const MaskScore score = score_mask(mask, truth);
  EXPECT_GT(score.iou, 0.8) << "precision " << score.precision << " recall " << score.recall;
}

TEST(GeometryCheck, WideParallaxPointsAreSkipped) {
  const auto cam = synthetic::tum3_camera();
  // Reference 2 m to the side looking at the same wall point: rays differ by more than 30 deg
  // for the points in the middle of the current view.
  const SE3 T_w_ref(Mat3d(Eigen::AngleAxisd(-0.6, Vec3d::UnitY())), Vec3d(2.0, 0, 0));
  const SE3 T_w_cur;
  const cv::Mat ref_depth = render_depth(cam, T_w_ref, 3.0, {});
  const cv::Mat cur_depth = render_depth(cam, T_w_cur, 3.0, {});
  GeometryCheckConfig config;
  GeometryCheckStats stats;
  geometry_dynamic_mask(cur_depth, T_w_cur.inverse(),
                        {reference_from(cam, T_w_ref, ref_depth, 500, 4)}, cam, config, &stats);
  EXPECT_GT(stats.points_skipped_parallax, 0);
  config.max_parallax_deg = 89.0;
  GeometryCheckStats wide;
  geometry_dynamic_mask(cur_depth, T_w_cur.inverse(),
                        {reference_from(cam, T_w_ref, ref_depth, 500, 4)}, cam, config, &wide);
  EXPECT_EQ(wide.points_skipped_parallax, 0);
}

TEST(MaskFusion, CombineAndScore) {
  cv::Mat a = cv::Mat::zeros(10, 10, CV_8UC1);
  cv::Mat b = cv::Mat::zeros(10, 10, CV_8UC1);
  a(cv::Rect(0, 0, 5, 10)).setTo(255);
  b(cv::Rect(5, 0, 5, 10)).setTo(255);
  EXPECT_EQ(cv::countNonZero(combine_masks(a, b)), 100);
  EXPECT_EQ(cv::countNonZero(combine_masks(a, cv::Mat())), 50);
  const MaskScore s = score_mask(a, combine_masks(a, b));
  EXPECT_DOUBLE_EQ(s.iou, 0.5);
  EXPECT_DOUBLE_EQ(s.precision, 1.0);
  EXPECT_DOUBLE_EQ(s.recall, 0.5);
  EXPECT_GT(cv::countNonZero(feature_exclusion_mask(a, 2)), 50);
}

TEST(GeometryCheck, ConfigErrorsNameTheKey) {
  GeometryCheckConfig config;
  config.max_parallax_deg = 0;
  EXPECT_TRUE(test_support::throws_config_error_for_key([&] { config.validate(); },
                                                        "dynamic.geometry.max_parallax_deg"));
  GeometryCheckConfig gate;
  gate.max_median_residual_ratio = 0;
  EXPECT_THROW(gate.validate(), ConfigError);
  // 0 is "no depth": a minimum of 0 took holes for measurements (review, stop 26).
  GeometryCheckConfig zero;
  zero.min_depth_m = 0.0;
  EXPECT_TRUE(test_support::throws_config_error_for_key([&] { zero.validate(); },
                                                        "dynamic.geometry.min_depth_m"));
}

}  // namespace
}  // namespace ddl::dynamics
