#include <gtest/gtest.h>

#include <cmath>

#include "ddl/core/error.h"
#include "ddl/eval/stats.h"
#include "ddl/eval/tracked.h"
#include "eval_test_support.h"

namespace ddl::eval {
namespace {

TEST(StatsTest, NumpyConventions) {
  const ErrorStats s = compute_stats({4.0, 1.0, 3.0, 2.0});
  EXPECT_EQ(s.count, 4u);
  EXPECT_DOUBLE_EQ(s.rmse, std::sqrt(30.0 / 4.0));
  EXPECT_DOUBLE_EQ(s.mean, 2.5);
  EXPECT_DOUBLE_EQ(s.median, 2.5);           // mean of the two middle values
  EXPECT_DOUBLE_EQ(s.std, std::sqrt(1.25));  // population std (divisor n)
  EXPECT_DOUBLE_EQ(s.min, 1.0);
  EXPECT_DOUBLE_EQ(s.max, 4.0);

  const ErrorStats odd = compute_stats({5.0, 1.0, 9.0});
  EXPECT_DOUBLE_EQ(odd.median, 5.0);
  EXPECT_DOUBLE_EQ(odd.std, std::sqrt(32.0 / 3.0));

  const ErrorStats deg = odd.scaled(2.0);
  EXPECT_DOUBLE_EQ(deg.median, 10.0);
  EXPECT_EQ(deg.count, 3u);

  const ErrorStats empty = compute_stats({});
  EXPECT_EQ(empty.count, 0u);
  EXPECT_TRUE(std::isnan(empty.rmse));
}

io::Trajectory stamps_only(const std::vector<double>& stamps) {
  io::Trajectory t;
  for (double s : stamps) {
    io::StampedPose p;
    p.timestamp_s = s;
    t.push_back(p);
  }
  return t;
}

TEST(TrackedTest, CountsFramesInsideTheGroundTruthSpanThatHaveAPose) {
  const io::Trajectory gt = stamps_only({10.0, 10.5, 11.0, 11.5, 12.0});
  // Frames 9.0 and 12.5 lie outside the ground truth: not counted.
  const std::vector<double> frames{9.0, 10.0, 10.25, 10.5, 10.75, 11.0, 11.25, 12.0, 12.5};
  // Poses for 10.0, 10.25 (stamp off by 5 ms) and 11.0 only; the pose at 9.0 is outside.
  const io::Trajectory est = stamps_only({9.0, 10.0, 10.255, 11.0});
  const TrackedStats s = compute_tracked(frames, gt, est);
  EXPECT_EQ(s.frames_total, 9u);
  EXPECT_EQ(s.frames_in_gt_span, 7u);
  EXPECT_EQ(s.tracked_frames, 3u);
  EXPECT_EQ(s.est_poses_in_gt_span, 3u);
  EXPECT_DOUBLE_EQ(s.ratio, 3.0 / 7.0);

  const TrackedStats none = compute_tracked({1.0, 2.0}, gt, est);
  EXPECT_EQ(none.frames_in_gt_span, 0u);
  EXPECT_TRUE(std::isnan(none.ratio));
}

// The frames and the estimate share a clock; the ground truth is `offset` ahead of it. Found by
// review (stop 32): the offset was applied between frames and estimate instead of against the
// ground-truth span, so an estimate with a pose for every frame counted 484 of 694 at 0.05 s.
TEST(TrackedTest, TheOffsetShiftsTheFramesAgainstTheGroundTruthOnly) {
  const io::Trajectory gt = stamps_only({10.05, 10.55, 11.05, 11.55, 12.05});  // clock + 0.05 s
  const std::vector<double> frames{9.0, 10.0, 10.25, 10.5, 11.0, 12.0, 12.5};
  const io::Trajectory est = stamps_only({9.0, 10.0, 10.25, 10.5, 11.0, 12.0, 12.5});
  const TrackedStats s = compute_tracked(frames, gt, est, 0.05, 0.02);
  EXPECT_EQ(s.frames_in_gt_span, 5u);  // 10.0 .. 12.0: t + 0.05 inside [10.05, 12.05]
  EXPECT_EQ(s.tracked_frames, 5u);
  EXPECT_DOUBLE_EQ(s.ratio, 1.0);
  EXPECT_EQ(s.est_poses_in_gt_span, 5u);
}

TEST(TrackedTest, ReadsRgbAndAssociationListsByFirstColumn) {
  const test::TempDir dir("frames");
  const std::string rgb = test::write_text(
      dir.file("rgb.txt"), "# color images\n# timestamp filename\n2.0 rgb/2.png\n1.0 rgb/1.png\n");
  EXPECT_EQ(read_frame_stamps(rgb), (std::vector<double>{1.0, 2.0}));
  const std::string assoc = test::write_text(
      dir.file("associations.txt"), "1.5 rgb/a.jpg 1.51 depth/a.png\n1.5 rgb/a.jpg 1.51 d.png\n");
  EXPECT_EQ(read_frame_stamps(assoc), (std::vector<double>{1.5}));
  const std::string empty = test::write_text(dir.file("empty.txt"), "# nothing\n");
  try {
    read_frame_stamps(empty);
    ADD_FAILURE() << "no InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(empty), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace ddl::eval
