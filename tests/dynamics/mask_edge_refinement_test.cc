#include "ddl/dynamics/mask_edge_refinement.h"

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>
#include <string>

#include "config_error_check.h"
#include "ddl/dynamics/mask_fusion.h"

namespace ddl::dynamics {
namespace {

// A textured wall (noise around mid grey, fixed seed) and a person: an ellipse of another colour
// with a darker head on top.
struct Scene {
  cv::Mat bgr = cv::Mat(480, 640, CV_8UC3);
  cv::Mat person{480, 640, CV_8UC1, cv::Scalar(0)};
  Scene() {
    cv::RNG rng(7);
    rng.fill(bgr, cv::RNG::NORMAL, cv::Scalar::all(128), cv::Scalar::all(12));
    cv::ellipse(person, cv::Point(320, 280), cv::Size(60, 130), 0, 0, 360, 255, cv::FILLED);
    cv::circle(person, cv::Point(320, 130), 35, 255, cv::FILLED);
    bgr.setTo(cv::Scalar(40, 90, 200), person);
    cv::Mat head = cv::Mat::zeros(person.size(), CV_8UC1);
    cv::circle(head, cv::Point(320, 130), 35, 255, cv::FILLED);
    bgr.setTo(cv::Scalar(60, 70, 90), head);
  }
};

cv::Mat shifted(const cv::Mat& mask, int dx, int dy) {
  cv::Mat out;
  const cv::Mat shift = (cv::Mat_<double>(2, 3) << 1, 0, dx, 0, 1, dy);
  cv::warpAffine(mask, out, shift, mask.size(), cv::INTER_NEAREST);
  return out;
}

TEST(MaskEdgeRefinement, AMaskOffTheOutlineIsPulledOntoIt) {
  const Scene scene;
  // What the sources give: the outline missed by a few pixels (the mask shifted off it).
  cv::Mat mask = shifted(scene.person, 7, 5);
  const cv::Mat before = mask.clone();
  const cv::Mat refined = refine_mask_edges(mask, scene.bgr, EdgeRefinementConfig{});
  EXPECT_EQ(cv::norm(mask, before, cv::NORM_INF), 0.0) << "the input mask was changed";
  const double raw = score_mask(mask, scene.person).iou;
  const double snapped = score_mask(refined, scene.person).iou;
  EXPECT_LT(raw, 0.90);
  EXPECT_GT(snapped, 0.96) << "from " << raw;
}

TEST(MaskEdgeRefinement, WithoutEdgesTheMaskKeepsItsShape) {
  const cv::Mat flat(480, 640, CV_8UC3, cv::Scalar::all(128));
  cv::Mat mask = cv::Mat::zeros(480, 640, CV_8UC1);
  mask(cv::Rect(200, 150, 160, 200)).setTo(255);
  const cv::Mat refined = refine_mask_edges(mask, flat, EdgeRefinementConfig{});
  // With no edge to follow each pass is a blur: the threshold below 0.5 leans the rim outward
  // (6 px after the four passes) and the corners are rounded off (8 px), nothing more.
  const cv::Mat grown = feature_exclusion_mask(mask, 8);
  cv::Mat core;
  cv::erode(mask, core, cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(21, 21)));
  EXPECT_EQ(cv::countNonZero(refined & ~grown), 0);
  EXPECT_EQ(cv::countNonZero(core & ~refined), 0);
  EXPECT_GT(cv::countNonZero(refined), cv::countNonZero(mask));
}

TEST(MaskEdgeRefinement, TheFilterNeverReachesFarFromTheMask) {
  const Scene scene;
  cv::Mat mask = cv::Mat::zeros(480, 640, CV_8UC1);
  mask(cv::Rect(270, 230, 60, 60)).setTo(255);  // a part of the person, near its left side
  EdgeRefinementConfig config;
  const cv::Mat refined = refine_mask_edges(mask, scene.bgr, config);
  // Each pass reaches at most twice its radius past the mask it starts from.
  const int reach = 2 * config.radius_px + 2 * config.follow_up_radius_px * config.follow_up_passes;
  const cv::Mat allowed = feature_exclusion_mask(mask, reach);
  EXPECT_EQ(cv::countNonZero(refined & ~allowed), 0);
  EXPECT_GT(cv::countNonZero(refined), cv::countNonZero(mask));  // it grew along the person
  EXPECT_EQ(cv::countNonZero(refined & ~scene.person), 0) << "it left the person";
}

TEST(MaskEdgeRefinement, MasksAtTheImageBorderAndEmptyMasks) {
  const Scene scene;
  EXPECT_TRUE(refine_mask_edges(cv::Mat(), scene.bgr, EdgeRefinementConfig{}).empty());
  const cv::Mat none = cv::Mat::zeros(480, 640, CV_8UC1);
  EXPECT_EQ(cv::countNonZero(refine_mask_edges(none, scene.bgr, EdgeRefinementConfig{})), 0);
  // A person cut by the top border (the head out of view), its mask short of the border.
  const cv::Mat cut = shifted(scene.person, 0, -120);
  cv::Mat bgr = cv::Mat(480, 640, CV_8UC3, cv::Scalar::all(128));
  bgr.setTo(cv::Scalar(40, 90, 200), cut);
  cv::Mat mask = cut.clone();
  mask(cv::Rect(0, 0, 640, 6)).setTo(0);
  const cv::Mat refined = refine_mask_edges(mask, bgr, EdgeRefinementConfig{});
  EXPECT_GT(score_mask(refined, cut).iou, score_mask(mask, cut).iou);
}

TEST(MaskEdgeRefinement, BadSettingsAreRejectedByName) {
  EXPECT_NO_THROW(EdgeRefinementConfig{}.validate());
  // One bad value at a time, on the defaults: the error names the key.
  const auto rejects = [](auto set, const std::string& key) {
    EdgeRefinementConfig config;
    set(config);
    return test_support::throws_config_error_naming([&] { config.validate(); }, key);
  };
  using C = EdgeRefinementConfig;
  EXPECT_TRUE(rejects([](C& c) { c.scale = 0.0; }, "dynamic.edge_refinement.scale"));
  EXPECT_TRUE(rejects([](C& c) { c.radius_px = 0; }, "radius_px"));
  EXPECT_TRUE(rejects([](C& c) { c.eps = -1.0; }, "eps"));
  EXPECT_TRUE(rejects([](C& c) { c.threshold = 1.0; }, "threshold"));
  EXPECT_TRUE(rejects([](C& c) { c.follow_up_passes = -1; }, "follow_up_passes"));
  EXPECT_TRUE(rejects([](C& c) { c.follow_up_radius_px = 0; }, "follow_up_radius_px"));
  EXPECT_TRUE(rejects([](C& c) { c.keep_core_px = -1; }, "keep_core_px"));
}

// A box of the wall's colour with a dark logo printed on it (syn_desk_person's moved box): the
// outline gives the filter no edge, the logo a strong one, and the refined mask shrinks towards
// the logo. keep_core_px keeps the mask's inside.
TEST(MaskEdgeRefinement, KeepCoreHoldsTheInsideOfAnObjectWithoutAnOutline) {
  cv::Mat bgr(480, 640, CV_8UC3, cv::Scalar(150, 170, 190));
  const cv::Rect box(280, 200, 60, 44);
  cv::rectangle(bgr, cv::Rect(295, 214, 30, 10), cv::Scalar(30, 30, 30), cv::FILLED);
  cv::Mat mask = cv::Mat::zeros(480, 640, CV_8UC1);
  mask(box).setTo(255);
  EdgeRefinementConfig config;
  const double recall_free = score_mask(refine_mask_edges(mask, bgr, config), mask).recall;
  config.keep_core_px = 4;
  const cv::Mat kept = refine_mask_edges(mask, bgr, config);
  cv::Mat core;
  cv::erode(mask, core, cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(9, 9)));
  EXPECT_EQ(cv::countNonZero(core & ~kept), 0);
  EXPECT_LT(recall_free, 0.85);  // 0.76: the mask shrank towards the logo
  EXPECT_GT(score_mask(kept, mask).recall, recall_free + 0.03);  // 0.81
}

}  // namespace
}  // namespace ddl::dynamics
