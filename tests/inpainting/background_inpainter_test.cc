#include "ddl/inpainting/background_inpainter.h"

#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/imgproc.hpp>

#include "config_error_check.h"
#include "ddl/core/error.h"
#include "ddl/synthetic/sequence.h"

namespace ddl::inpainting {
namespace {

// Smooth colour texture on the wall plane z = 3 (world), a function of world x, y.
cv::Vec3b wall_colour(double x, double y) {
  auto ch = [](double a) { return static_cast<std::uint8_t>(127.5 + 120.0 * std::sin(a)); };
  return {ch(4.0 * x + 1.0), ch(5.0 * y + 2.0), ch(3.0 * (x + y))};
}

struct View {
  cv::Mat bgr, depth;
};

// Renders the wall and, optionally, a grey box (a "person") at z = 1.5 covering
// x in [-0.3, 0.3], y in [-0.7, 0.7] (world).
View render(const camera::PinholeCamera& cam, const SE3& T_w_c, bool with_person) {
  View view{cv::Mat(cam.height, cam.width, CV_8UC3), cv::Mat(cam.height, cam.width, CV_32FC1)};
  const Vec3d o = T_w_c.translation();
  const SE3 T_c_w = T_w_c.inverse();
  for (int v = 0; v < cam.height; ++v) {
    for (int u = 0; u < cam.width; ++u) {
      const Vec3d dir = T_w_c.rotation() * cam.unproject(u, v, 1.0);
      Vec3d hit = o + (3.0 - o.z()) / dir.z() * dir;
      cv::Vec3b colour = wall_colour(hit.x(), hit.y());
      if (with_person) {
        const Vec3d p = o + (1.5 - o.z()) / dir.z() * dir;
        if (std::abs(p.x()) <= 0.3 && std::abs(p.y()) <= 0.7) {
          hit = p;
          colour = {90, 90, 90};
        }
      }
      view.bgr.at<cv::Vec3b>(v, u) = colour;
      view.depth.at<float>(v, u) = static_cast<float>((T_c_w * hit).z());
    }
  }
  return view;
}

double psnr_over(const cv::Mat& a, const cv::Mat& b, const cv::Mat& where) {
  cv::Mat diff;
  cv::absdiff(a, b, diff);
  diff.convertTo(diff, CV_64FC3);
  diff = diff.mul(diff);
  const cv::Scalar sum = cv::sum(diff.setTo(0, where == 0));
  const double n = 3.0 * cv::countNonZero(where);
  const double mse = (sum[0] + sum[1] + sum[2]) / n;
  return 10.0 * std::log10(255.0 * 255.0 / mse);
}

// Paints a pure red remnant of a person (40x40 px at `depth_m`) into a keyframe whose mask missed
// it; the box projects into the person's pixels of the current frame at the origin. Returns it.
cv::Rect paint_red_remnant(View& view, float depth_m) {
  const cv::Rect remnant(200, 200, 40, 40);
  view.depth(remnant).setTo(depth_m);
  view.bgr(remnant).setTo(cv::Scalar(0, 0, 255));
  return remnant;
}

// Filled pixels of a pure red remnant (BGR 0, 0, 255).
int red_pixels(const InpaintingResult& r) {
  cv::Mat red;
  cv::inRange(r.bgr, cv::Scalar(0, 0, 250), cv::Scalar(5, 5, 255), red);
  return cv::countNonZero(red & r.filled);
}

// Pixels (channel values) in which two images differ.
int differing(const cv::Mat& a, const cv::Mat& b) {
  cv::Mat d;
  cv::compare(a.reshape(1), b.reshape(1), d, cv::CMP_NE);
  return cv::countNonZero(d);
}

// Filled pixels of the rendered grey person (BGR 90, 90, 90).
int grey_pixels(const InpaintingResult& r) {
  cv::Mat grey;
  cv::inRange(r.bgr, cv::Scalar(88, 88, 88), cv::Scalar(92, 92, 92), grey);
  return cv::countNonZero(grey & r.filled);
}

TEST(Inpainting, FillsThePersonFromAnEarlierKeyframe) {
  const auto cam = synthetic::tum3_camera();
  const SE3 T_w_kf(Mat3d(Eigen::AngleAxisd(0.05, Vec3d::UnitY())), Vec3d(0.4, 0.0, 0.0));
  const SE3 T_w_cur(Mat3d::Identity(), Vec3d(0.0, 0.05, 0.1));
  // The keyframe saw the wall with the person elsewhere (off to the right): its mask excludes it.
  View kf = render(cam, T_w_kf, false);
  View cur = render(cam, T_w_cur, true);
  const View truth = render(cam, T_w_cur, false);
  const cv::Mat mask = cur.depth < 2.0f;  // the person's pixels
  ASSERT_GT(cv::countNonZero(mask), 10000);

  InpaintingConfig config;
  config.image_fill_small_holes = false;
  const auto result = inpaint(cur.bgr, cur.depth, mask, T_w_cur.inverse(),
                              {{T_w_kf, kf.bgr, kf.depth, {}, {}}}, cam, config);
  EXPECT_EQ(result.masked_pixels, cv::countNonZero(mask));
  EXPECT_GT(result.filled_pixels, 0.98 * result.masked_pixels);
  const double psnr = psnr_over(result.bgr, truth.bgr, result.filled);
  EXPECT_GT(psnr, 30.0);
  cv::Mat depth_err;
  cv::absdiff(result.depth_m, truth.depth, depth_err);
  double max_err = 0;
  cv::minMaxLoc(depth_err, nullptr, &max_err, nullptr, nullptr, result.filled);
  EXPECT_LT(max_err, 0.02);
  // Pixels outside the mask are untouched.
  cv::Mat changed;
  cv::absdiff(result.bgr, cur.bgr, changed);
  cv::cvtColor(changed, changed, cv::COLOR_BGR2GRAY);
  EXPECT_EQ(cv::countNonZero(changed & (mask == 0)), 0);
}

TEST(Inpainting, ExcludedSourcePixelsAreNotUsedAndStayUnfilled) {
  const auto cam = synthetic::tum3_camera();
  const SE3 T_w(Mat3d::Identity(), Vec3d::Zero());
  View kf = render(cam, T_w, true);
  View cur = render(cam, T_w, true);
  const cv::Mat mask = cur.depth < 2.0f;
  // The keyframe's person is masked out there too, and nothing else saw behind it. (Splats of
  // radius 0: with a larger radius, wall pixels next to the mask spread into its rim.)
  InpaintingConfig config;
  config.image_fill_small_holes = false;
  config.splat_radius_px = 0;
  const auto result = inpaint(cur.bgr, cur.depth, mask, T_w.inverse(),
                              {{T_w, kf.bgr, kf.depth, kf.depth < 2.0f, {}}}, cam, config);
  EXPECT_EQ(result.filled_pixels, 0);
  EXPECT_EQ(cv::countNonZero(result.unfilled), cv::countNonZero(mask));
  // Unknown pixels carry no depth (not the person's).
  EXPECT_EQ(cv::countNonZero(result.depth_m == 0.0f), cv::countNonZero(mask));
}

TEST(Inpainting, ContentInFrontOfTheCurrentDepthIsRejected) {
  // The keyframe saw the wall, but a remnant its mask missed (red, 1.0 m away) sits where the
  // current frame's person (1.5 m) is: the current ray is free up to 1.5 m, so the remnant is gone.
  const auto cam = synthetic::tum3_camera();
  const SE3 T_w_kf(Mat3d::Identity(), Vec3d(0.3, 0.0, 0.0));
  const SE3 T_w_cur;
  View kf = render(cam, T_w_kf, false);
  paint_red_remnant(kf, 1.0f);
  View cur = render(cam, T_w_cur, true);
  const cv::Mat mask = cur.depth < 2.0f;
  InpaintingConfig config;
  config.image_fill_small_holes = false;
  const auto checked = inpaint(cur.bgr, cur.depth, mask, T_w_cur.inverse(),
                               {{T_w_kf, kf.bgr, kf.depth, {}, {}}}, cam, config);
  EXPECT_EQ(red_pixels(checked), 0);
  config.free_space_check = false;
  config.behind_current_only = false;  // it would reject the remnant too
  const auto unchecked = inpaint(cur.bgr, cur.depth, mask, T_w_cur.inverse(),
                                 {{T_w_kf, kf.bgr, kf.depth, {}, {}}}, cam, config);
  EXPECT_GT(red_pixels(unchecked), 500);
}

// The newest keyframe's own repair let a remnant through (red, 2 m: behind the current person,
// so the free-space check cannot reject it); an older keyframe observed the wall there. What was
// observed wins, so one repair's mistake is not copied into the next.
TEST(Inpainting, ObservedBackgroundWinsOverAnEarlierRepair) {
  const auto cam = synthetic::tum3_camera();
  const SE3 T_w_newest(Mat3d::Identity(), Vec3d(0.3, 0.0, 0.0));
  const SE3 T_w_older(Mat3d::Identity(), Vec3d(-0.4, 0.0, 0.0));
  const SE3 T_w_cur;
  View newest = render(cam, T_w_newest, false);
  const cv::Rect remnant = paint_red_remnant(newest, 2.0f);
  cv::Mat repaired = cv::Mat::zeros(newest.depth.size(), CV_8UC1);
  repaired(remnant).setTo(255);
  const View older = render(cam, T_w_older, false);
  const View cur = render(cam, T_w_cur, true);
  const cv::Mat mask = cur.depth < 2.0f;
  const std::vector<SourceView> sources = {{T_w_newest, newest.bgr, newest.depth, {}, repaired},
                                           {T_w_older, older.bgr, older.depth, {}, {}}};
  InpaintingConfig config;
  config.image_fill_small_holes = false;
  const auto observed_first =
      inpaint(cur.bgr, cur.depth, mask, T_w_cur.inverse(), sources, cam, config);
  EXPECT_EQ(red_pixels(observed_first), 0);
  EXPECT_GT(observed_first.filled_pixels, 0.98 * observed_first.masked_pixels);
  config.observed_first = false;
  const auto one_pass = inpaint(cur.bgr, cur.depth, mask, T_w_cur.inverse(), sources, cam, config);
  EXPECT_GT(red_pixels(one_pass), 500);
}

// A keyframe whose mask missed the person saw it at the same place: its person pixels land at
// the current person's own depth. The background lies behind what the mask covers, so they are
// rejected (the free-space check alone lets them through: they are not in front).
TEST(Inpainting, SamplesAtTheMaskedSurfacesOwnDepthAreRejected) {
  const auto cam = synthetic::tum3_camera();
  const SE3 T_w_kf(Mat3d::Identity(), Vec3d(0.1, 0.0, 0.0));
  const SE3 T_w_cur;
  const View kf = render(cam, T_w_kf, true);  // unmasked person
  const View cur = render(cam, T_w_cur, true);
  const cv::Mat mask = cur.depth < 2.0f;
  const std::vector<SourceView> sources = {{T_w_kf, kf.bgr, kf.depth, {}, {}}};
  InpaintingConfig config;
  config.image_fill_small_holes = false;
  const auto behind_only =
      inpaint(cur.bgr, cur.depth, mask, T_w_cur.inverse(), sources, cam, config);
  EXPECT_EQ(grey_pixels(behind_only), 0);
  EXPECT_GT(behind_only.filled_pixels, 1000);  // the wall the keyframe saw beside the person
  config.behind_current_only = false;
  const auto any_depth = inpaint(cur.bgr, cur.depth, mask, T_w_cur.inverse(), sources, cam, config);
  EXPECT_GT(grey_pixels(any_depth), 5000);
}

// The scene of the see-through tests: the current frame at the origin (the person at 1.5 m
// before the wall at 3 m, masked) and three keyframes of the wall; the newest, at x = 0.3 m,
// observed a red remnant at `remnant_depth_m` that its mask missed.
struct SeeThroughScene {
  View cur;
  cv::Mat mask;
  std::vector<SourceView> sources;  // newest first
};

SeeThroughScene see_through_scene(const camera::PinholeCamera& cam, const SE3& T_w_older,
                                  const SE3& T_w_oldest, float remnant_depth_m) {
  const SE3 T_w_newest(Mat3d::Identity(), Vec3d(0.3, 0.0, 0.0));
  View newest = render(cam, T_w_newest, false);
  paint_red_remnant(newest, remnant_depth_m);
  const View older = render(cam, T_w_older, false);
  const View oldest = render(cam, T_w_oldest, false);
  SeeThroughScene scene{render(cam, SE3(), true), cv::Mat(), {}};
  scene.mask = scene.cur.depth < 2.0f;
  scene.sources = {{T_w_newest, newest.bgr, newest.depth, {}, {}},
                   {T_w_older, older.bgr, older.depth, {}, {}},
                   {T_w_oldest, oldest.bgr, oldest.depth, {}, {}}};
  return scene;
}

// The newest keyframe observed a remnant its mask missed (red, 2 m: behind the current person and
// in front of the wall, like the other walker of a crossing), and two other keyframes saw the wall
// through the place where it was. It was gone by then, so the multi-view check rejects it.
TEST(Inpainting, ContentOtherKeyframesSawThroughIsRejected) {
  const auto cam = synthetic::tum3_camera();
  const SE3 T_w_cur;
  const SeeThroughScene scene =
      see_through_scene(cam, SE3(Mat3d::Identity(), Vec3d(-0.4, 0.0, 0.0)),
                        SE3(Mat3d::Identity(), Vec3d(-0.2, 0.3, 0.0)), 2.0f);
  const View& cur = scene.cur;
  const cv::Mat& mask = scene.mask;
  const std::vector<SourceView>& sources = scene.sources;
  InpaintingConfig config;
  config.image_fill_small_holes = false;
  const auto checked = inpaint(cur.bgr, cur.depth, mask, T_w_cur.inverse(), sources, cam, config);
  EXPECT_EQ(red_pixels(checked), 0);
  // What was rejected stays unfilled; the rest of the person is filled from the wall.
  EXPECT_GT(checked.filled_pixels, 0.85 * checked.masked_pixels);
  const View truth = render(cam, T_w_cur, false);
  EXPECT_GT(psnr_over(checked.bgr, truth.bgr, checked.filled), 30.0);
  // With the sources' depth blocks the check skips, per tile, the sources that cannot vote there;
  // the votes and so the result are the same (a bound that skips a voter lets the remnant in).
  std::vector<SourceView> with_blocks = sources;
  for (SourceView& v : with_blocks) {
    v.blocks = std::make_shared<const DepthBlocks>(depth_blocks(v.depth_m));
  }
  const auto culled =
      inpaint(cur.bgr, cur.depth, mask, T_w_cur.inverse(), with_blocks, cam, config);
  EXPECT_EQ(red_pixels(culled), 0);
  EXPECT_EQ(culled.filled_pixels, checked.filled_pixels);
  EXPECT_EQ(differing(culled.bgr, checked.bgr), 0);
  EXPECT_EQ(differing(culled.depth_m, checked.depth_m), 0);
  config.see_through_votes = 0;
  const auto unchecked = inpaint(cur.bgr, cur.depth, mask, T_w_cur.inverse(), sources, cam, config);
  EXPECT_GT(red_pixels(unchecked), 500);
}

// The see-through check skips, per tile, the sources whose observed depth under the tile cannot
// exceed the nearest vote threshold. Votes just above the threshold, from sources turned against
// the current camera (so depths in the source and the current camera differ), must survive
// that: a remnant 14 cm in front of the wall (the threshold is 2 cm + 3% of the depth, about
// 10.6 cm there) is rejected with depth blocks exactly as without the skip.
TEST(Inpainting, SeeThroughVotesNearTheThresholdSurviveTheTileSkip) {
  const auto cam = synthetic::tum3_camera();
  const SE3 T_w_cur;
  SeeThroughScene scene = see_through_scene(
      cam, SE3(Mat3d(Eigen::AngleAxisd(0.14, Vec3d::UnitY())), Vec3d(-0.4, 0.0, 0.0)),
      SE3(Mat3d(Eigen::AngleAxisd(-0.12, Vec3d::UnitX())), Vec3d(-0.2, 0.3, 0.0)), 2.86f);
  const View& cur = scene.cur;
  const cv::Mat& mask = scene.mask;
  std::vector<SourceView>& sources = scene.sources;
  InpaintingConfig config;
  config.image_fill_small_holes = false;
  config.skip_unreachable_blocks = false;  // every source asked for every pixel
  const auto reference = inpaint(cur.bgr, cur.depth, mask, T_w_cur.inverse(), sources, cam, config);
  config.see_through_votes = 0;
  const auto unchecked = inpaint(cur.bgr, cur.depth, mask, T_w_cur.inverse(), sources, cam, config);
  ASSERT_GT(red_pixels(unchecked), 500);
  ASSERT_LT(red_pixels(reference), red_pixels(unchecked) / 10);  // the votes reject it
  config = InpaintingConfig{};
  config.image_fill_small_holes = false;
  for (SourceView& v : sources) {
    v.blocks = std::make_shared<const DepthBlocks>(depth_blocks(v.depth_m));
  }
  const auto skipped = inpaint(cur.bgr, cur.depth, mask, T_w_cur.inverse(), sources, cam, config);
  EXPECT_EQ(skipped.filled_pixels, reference.filled_pixels);
  EXPECT_EQ(red_pixels(skipped), red_pixels(reference));
  EXPECT_EQ(differing(skipped.bgr, reference.bgr), 0);
  EXPECT_EQ(differing(skipped.depth_m, reference.depth_m), 0);
}

TEST(Inpainting, SmallHolesAreClosedByTheImageFill) {
  const auto cam = synthetic::tum3_camera();
  const SE3 T_w;
  View cur = render(cam, T_w, false);
  cv::Mat mask = cv::Mat::zeros(cur.depth.size(), CV_8UC1);
  mask(cv::Rect(300, 200, 10, 10)).setTo(255);
  InpaintingConfig config;
  const auto result = inpaint(cur.bgr, cur.depth, mask, T_w.inverse(), {}, cam, config);
  EXPECT_EQ(cv::countNonZero(result.image_filled), 100);
  EXPECT_EQ(cv::countNonZero(result.unfilled), 0);
  EXPECT_GT(cv::countNonZero(result.depth_m(cv::Rect(300, 200, 10, 10))), 99);
  // A 20 x 20 hole (the largest of max_hole_area_px 400): depth reaches its middle too, so every
  // pixel counted as filled has depth (eight growth passes used to leave its 4 x 4 core empty).
  cv::Mat wide = cv::Mat::zeros(cur.depth.size(), CV_8UC1);
  wide(cv::Rect(300, 200, 20, 20)).setTo(255);
  const auto wide_result = inpaint(cur.bgr, cur.depth, wide, T_w.inverse(), {}, cam, config);
  EXPECT_EQ(cv::countNonZero(wide_result.image_filled), 400);
  EXPECT_EQ(cv::countNonZero(wide_result.unfilled), 0);
  EXPECT_EQ(cv::countNonZero(wide_result.depth_m(cv::Rect(300, 200, 20, 20))), 400);
  // A hole inside unknown depth gets colour but stays unfilled: no depth to give it.
  View blank = render(cam, T_w, false);
  blank.depth.setTo(0.0f);
  const auto no_depth = inpaint(blank.bgr, blank.depth, mask, T_w.inverse(), {}, cam, config);
  EXPECT_EQ(cv::countNonZero(no_depth.image_filled), 0);
  EXPECT_EQ(cv::countNonZero(no_depth.unfilled), 100);
}

// extra_keyframes: older keyframes fill only what the newest num_keyframes left empty. The newest
// keyframe saw the wall behind the person only in the right half of the image (its left half is
// excluded), an older one saw all of it, in other colours (tinted) and 15 cm nearer: the right half
// keeps the newest's colours, the left half gets the older's, and without the older one it stays
// empty.
TEST(Inpainting, ExtraKeyframesFillOnlyWhatTheNewestLeftEmpty) {
  const auto cam = synthetic::tum3_camera();
  const SE3 T_w_cur(Mat3d::Identity(), Vec3d(0.0, 0.05, 0.1));
  const SE3 T_w_kf(Mat3d::Identity(), Vec3d(0.02, 0.0, 0.0));
  const View cur = render(cam, T_w_cur, true);
  const View truth = render(cam, T_w_cur, false);
  const View newest = render(cam, T_w_kf, false);
  View older = render(cam, T_w_kf, false);
  older.bgr += cv::Scalar(40, 40, 40);
  older.depth -= 0.15;  // nearer by more than the tolerance: it would win the z-buffer if let in
  cv::Mat newest_excluded = cv::Mat::zeros(newest.depth.size(), CV_8UC1);
  newest_excluded.colRange(0, cam.width / 2).setTo(255);
  const cv::Mat mask = cur.depth < 2.0f;
  const std::vector<SourceView> sources = {{T_w_kf, newest.bgr, newest.depth, newest_excluded, {}},
                                           {T_w_kf, older.bgr, older.depth, {}, {}}};
  InpaintingConfig config;
  config.image_fill_small_holes = false;
  config.see_through_votes = 0;
  config.num_keyframes = 1;
  config.extra_keyframes = 0;
  const auto newest_only =
      inpaint(cur.bgr, cur.depth, mask, T_w_cur.inverse(), sources, cam, config);
  EXPECT_LT(newest_only.filled_pixels, 0.6 * cv::countNonZero(mask));
  config.extra_keyframes = 1;
  const auto both = inpaint(cur.bgr, cur.depth, mask, T_w_cur.inverse(), sources, cam, config);
  EXPECT_GT(both.filled_pixels, 0.98 * cv::countNonZero(mask));
  // Mean colour difference to the true background on each side (well inside the halves).
  auto mean_diff = [&](int u0, int u1, const cv::Mat& reference) {
    cv::Mat diff;
    cv::absdiff(both.bgr.colRange(u0, u1), reference.colRange(u0, u1), diff);
    const cv::Mat where = both.filled.colRange(u0, u1);
    const cv::Scalar m = cv::mean(diff, where);
    return (m[0] + m[1] + m[2]) / 3.0;
  };
  EXPECT_LT(mean_diff(cam.width / 2 + 20, cam.width, truth.bgr), 3.0);  // the newest's colours
  const cv::Mat tinted_truth = truth.bgr + cv::Scalar(40, 40, 40);      // saturated like older's
  EXPECT_LT(mean_diff(0, cam.width / 2 - 20, tinted_truth), 3.0);       // the older's colours
  EXPECT_GT(mean_diff(0, cam.width / 2 - 20, truth.bgr), 25.0);
}

// Skipping the source blocks that cannot reach the mask changes nothing: on a room of the
// generator (furniture, so blocks straddle depth edges) seen from a half-sphere path whose views
// differ by up to tens of degrees, with repaired source pixels (the second pass), both ways give
// the same images, byte for byte. (A bound computed wrongly, e.g. with half the translation,
// changes thousands of pixels.)
TEST(Inpainting, SkippingUnreachableBlocksChangesNothing) {
  const auto source =
      synthetic::make_sequence_source(synthetic::find_preset("syn_walking_halfsphere").config);
  const auto& cam = source->camera();
  auto view_of = [&](std::size_t index, cv::Mat* dynamic) {
    const synthetic::FrameData f = source->render_frame(index);
    cv::Mat depth;
    f.depth_raw.convertTo(depth, CV_32F, 1.0 / cam.depth_factor);
    *dynamic = f.dynamic_mask;
    return std::make_pair(f, depth);
  };
  cv::Mat target_mask;
  const auto [target, target_depth] = view_of(400, &target_mask);
  cv::dilate(target_mask, target_mask, cv::Mat(), {-1, -1}, 6);
  ASSERT_GT(cv::countNonZero(target_mask), 5000);
  std::vector<SourceView> sources;
  int k = 0;
  for (const std::size_t index : {385, 360, 320, 250, 150}) {
    cv::Mat dynamic;
    const auto [f, depth] = view_of(index, &dynamic);
    cv::Mat repaired = cv::Mat::zeros(dynamic.size(), CV_8UC1);
    cv::rectangle(repaired, cv::Rect(40 * k, 30 + 50 * k, 260, 200), cv::Scalar(255), cv::FILLED);
    sources.push_back({f.T_w_c, f.rgb, depth, dynamic, repaired});
    ++k;
  }
  // Also with a source stride (the skip lands on the next sample of the stride) and images whose
  // size is no multiple of the block size (partial blocks at the right and bottom edges).
  // And with sources repaired everywhere outside their exclude masks: then only the passes over
  // repaired samples fill, whose blocks are bounded by the repaired samples' depths.
  // And with a remnant in the newest source that its mask missed: the points halfway between the
  // target's people and the background behind them, painted red into it where it would see them.
  // It lands behind the target's people, the other sources saw the background through it, and
  // the see-through check rejects it (the views differ by rotations, so depths in the source and
  // in the current camera differ).
  SourceView with_remnant = sources.front();
  int painted = 0;
  {
    with_remnant.bgr = with_remnant.bgr.clone();
    with_remnant.depth_m = with_remnant.depth_m.clone();
    with_remnant.exclude_mask = with_remnant.exclude_mask.clone();
    with_remnant.repaired_mask = with_remnant.repaired_mask.clone();
    cv::Mat background_depth;
    target.background_depth_raw.convertTo(background_depth, CV_32F, 1.0 / cam.depth_factor);
    const SE3 T_src_cur = with_remnant.T_w_c.inverse() * target.T_w_c;
    for (int v = 0; v < cam.height; ++v) {
      for (int u = 0; u < cam.width; ++u) {
        const float near = target_depth.at<float>(v, u);
        const float far = background_depth.at<float>(v, u);
        if (target_mask.at<std::uint8_t>(v, u) == 0 || near <= 0.0f || far < near + 1.0f) continue;
        const Vec3d p = T_src_cur * cam.unproject(u, v, 0.5 * (near + far));
        const int us = cvRound(cam.fx * p.x() / p.z() + cam.cx);
        const int vs = cvRound(cam.fy * p.y() / p.z() + cam.cy);
        if (p.z() <= 0.3 || us < 0 || vs < 0 || us >= cam.width || vs >= cam.height) continue;
        float& d = with_remnant.depth_m.at<float>(vs, us);
        if (d > 0.0f && p.z() >= d) continue;  // hidden in the source
        d = static_cast<float>(p.z());
        with_remnant.bgr.at<cv::Vec3b>(vs, us) = {0, 0, 255};
        with_remnant.exclude_mask.at<std::uint8_t>(vs, us) = 0;
        with_remnant.repaired_mask.at<std::uint8_t>(vs, us) = 0;
        ++painted;
      }
    }
  }
  ASSERT_GT(painted, 2000);
  struct Variant {
    int stride;
    cv::Size size;
    bool all_repaired;
    bool remnant;
  };
  for (const auto& [stride, size, all_repaired, remnant] :
       {Variant{1, {640, 480}, false, false}, Variant{3, {636, 478}, false, false},
        Variant{1, {640, 480}, true, false}, Variant{1, {640, 480}, false, true}}) {
    SCOPED_TRACE(::testing::Message()
                 << "stride " << stride << ", " << size << (all_repaired ? ", all repaired" : "")
                 << (remnant ? ", remnant" : ""));
    const cv::Rect crop({0, 0}, size);
    std::vector<SourceView> cropped;
    for (const SourceView& source_view : sources) {
      const SourceView& v = remnant && cropped.empty() ? with_remnant : source_view;
      const cv::Mat repaired = all_repaired ? cv::Mat(cv::Mat(v.exclude_mask == 0))
                               : remnant ? cv::Mat(cv::Mat::zeros(v.exclude_mask.size(), CV_8UC1))
                                         : v.repaired_mask;
      cropped.push_back(
          {v.T_w_c, v.bgr(crop), v.depth_m(crop), v.exclude_mask(crop), repaired(crop)});
    }
    InpaintingConfig config;
    config.source_stride_px = stride;
    config.num_keyframes = 2;  // and 3 older ones: every pass, the later ones on fewer pixels
    config.extra_keyframes = 3;
    // One other source sees most of the remnant's place (the views are far apart): one vote.
    if (remnant) config.see_through_votes = 1;
    const auto skipped = inpaint(target.rgb(crop), target_depth(crop), target_mask(crop),
                                 target.T_w_c.inverse(), cropped, cam, config);
    // The same with each source's depth blocks computed beforehand (as the dense stage keeps them).
    std::vector<SourceView> with_blocks = cropped;
    for (SourceView& v : with_blocks) {
      v.blocks = std::make_shared<const DepthBlocks>(
          depth_blocks(v.depth_m, v.exclude_mask, v.repaired_mask));
    }
    const auto kept = inpaint(target.rgb(crop), target_depth(crop), target_mask(crop),
                              target.T_w_c.inverse(), with_blocks, cam, config);
    config.skip_unreachable_blocks = false;
    const auto every = inpaint(target.rgb(crop), target_depth(crop), target_mask(crop),
                               target.T_w_c.inverse(), cropped, cam, config);
    ASSERT_GT(every.filled_pixels, 2000);
    // The see-through check rejects pixels of the remnant, whether it skips sources per tile
    // (`skipped`, `kept`) or asks every one (`every`).
    if (remnant) {
      config.see_through_votes = 0;
      const auto unchecked = inpaint(target.rgb(crop), target_depth(crop), target_mask(crop),
                                     target.T_w_c.inverse(), cropped, cam, config);
      EXPECT_GT(unchecked.filled_pixels - every.filled_pixels, 100);  // the check's rejections
      EXPECT_LT(red_pixels(every), red_pixels(unchecked) - 100);
    }
    EXPECT_EQ(skipped.filled_pixels, every.filled_pixels);
    EXPECT_EQ(differing(skipped.bgr, every.bgr), 0);
    EXPECT_EQ(differing(skipped.depth_m, every.depth_m), 0);
    EXPECT_EQ(differing(skipped.filled, every.filled), 0);
    EXPECT_EQ(differing(skipped.unfilled, every.unfilled), 0);
    EXPECT_EQ(differing(kept.bgr, every.bgr), 0);
    EXPECT_EQ(differing(kept.depth_m, every.depth_m), 0);
    EXPECT_EQ(differing(kept.filled, every.filled), 0);
    EXPECT_EQ(differing(kept.unfilled, every.unfilled), 0);
    EXPECT_EQ(kept.filled_pixels, every.filled_pixels);
  }
  // Depth blocks of another image size are an error, not a silently wrong skip.
  std::vector<SourceView> foreign = sources;
  cv::Mat small_depth;
  cv::resize(foreign.back().depth_m, small_depth, {320, 240}, 0, 0, cv::INTER_NEAREST);
  foreign.back().blocks = std::make_shared<const DepthBlocks>(depth_blocks(small_depth));
  EXPECT_THROW(inpaint(target.rgb, target_depth, target_mask, target.T_w_c.inverse(), foreign, cam,
                       InpaintingConfig{}),
               Error);
  // So are blocks computed without the source's masks: they would skip its repaired samples.
  // (On the oldest source: the passes may stop before it, the see-through check reads it.)
  std::vector<SourceView> maskless = sources;
  maskless.back().blocks =
      std::make_shared<const DepthBlocks>(depth_blocks(maskless.back().depth_m));
  EXPECT_THROW(inpaint(target.rgb, target_depth, target_mask, target.T_w_c.inverse(), maskless, cam,
                       InpaintingConfig{}),
               Error);
}

TEST(Inpainting, ConfigErrorsNameTheKey) {
  InpaintingConfig config;
  config.num_keyframes = 0;
  EXPECT_TRUE(test_support::throws_config_error_for_key([&] { config.validate(); },
                                                        "dense.inpainting.num_keyframes"));
}

}  // namespace
}  // namespace ddl::inpainting
