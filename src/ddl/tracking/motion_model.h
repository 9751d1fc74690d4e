#pragma once
// Constant-velocity motion model (ORB-SLAM2 Tracking::TrackWithMotionModel): the relative motion
// between the last two tracked frames is assumed to repeat, T_c_w(k+1) = V * T_c_w(k) with
// V = T_c_w(k) * T_w_c(k-1) (the previous camera in the current camera's frame).
//
// Unlike ORB-SLAM2 it knows the time V was learnt over: across a gap (dropped frames, or a
// velocity learnt across one) the motion is scaled to the time that passed, V^(elapsed/learnt).
// Within kGapRatio of the learnt interval (a regular camera's timestamp jitter) V repeats as is.
// Timestamp glitches: an interval kGlitchRatio or more times shorter than the camera's base
// interval (the kBaseRank-th smallest of the last kRateHistory regular intervals) is a stamp no
// camera delivers: a driver's glitch, or a frame delivered twice. Around such a stamp V repeats
// once per frame: predicted over the glitched interval itself (instead of V^0.03 for 1 ms at
// 30 Hz), learnt over it (instead of being stretched 65-fold to the next frame), and learnt or
// predicted over the interval after it (measured from the wrong stamp). Glitched intervals and the
// ones after them stay out of the history, so glitches on every second frame do not lower the
// base; a camera that really turned four times faster would be treated the same way (V once per
// frame, right at a constant rate).

#include <cstddef>
#include <deque>

#include "ddl/core/se3.h"
#include "ddl/optimization/pose_optimization.h"
#include "ddl/tracking/tracker_config.h"

namespace ddl::tracking {

class MotionModel {
 public:
  /// Intervals that differ by this factor or more are a gap, not jitter.
  static constexpr double kGapRatio = 1.5;
  /// An interval this many times shorter than the base interval is a timestamp glitch.
  static constexpr double kGlitchRatio = 4.0;
  /// The base interval is the kBaseRank-th smallest of the last kRateHistory regular intervals
  /// (dropped frames, longer intervals, do not raise it; a camera that turns up to twice as fast
  /// establishes its new rate after kBaseRank frames), judged once kMinRateHistory are known.
  static constexpr std::size_t kRateHistory = 15;
  static constexpr std::size_t kBaseRank = 3;
  static constexpr std::size_t kMinRateHistory = 5;

  bool valid() const { return valid_; }
  void reset() {
    valid_ = false;
    last_interval_glitched_ = false;
  }
  /// Learns V from the pose of the frame just tracked and the pose of the one before it, taken
  /// interval_s apart (0: unknown; a glitch, see above, counts as unknown).
  void update(const SE3& T_c_w_current, const SE3& T_c_w_previous, double interval_s = 0.0);
  /// The camera's base frame interval from the recent regular intervals given to update() (see
  /// kRateHistory; 0 while fewer than kMinRateHistory). reset() keeps them: they describe the
  /// camera, not its motion.
  double base_interval_s() const;
  /// Whether an interval is a timestamp glitch (see above; false while the base is unknown).
  bool is_glitch(double interval_s) const;
  /// elapsed_s / interval_s() when that is a gap (see kGapRatio), else 1 (also when either time
  /// is unknown or not positive, when elapsed_s is a glitch, and when it is measured from a
  /// glitched stamp).
  double gap_ratio(double elapsed_s) const;
  /// Predicted T_c_w of a frame elapsed_s after the last one (precondition: valid()); elapsed_s
  /// 0 (unknown) repeats V once.
  SE3 predict(const SE3& T_c_w_last, double elapsed_s = 0.0) const;
  /// The prediction T_c_w_predicted (of a frame elapsed_s after the last one) as a Gaussian pose
  /// prior: config's sigmas for one regular interval, widened across a gap (a velocity learnt
  /// over L and extrapolated over E misses a E (L + E) / 2 under an acceleration a, against
  /// a h^2 over one interval h = min(L, E)).
  optimization::PosePrior prior(const SE3& T_c_w_predicted, double elapsed_s,
                                const MotionPriorConfig& config) const;
  /// V = T_current_previous.
  const SE3& velocity() const { return velocity_; }
  /// Time between the two frames V was learnt from [s] (0: unknown).
  double interval_s() const { return interval_s_; }

 private:
  SE3 velocity_;
  double interval_s_ = 0.0;
  std::deque<double> recent_intervals_s_;  // regular intervals given to update(), newest last
  bool last_interval_glitched_ = false;    // V's own interval was a glitch: the last stamp is wrong
  bool valid_ = false;
};

}  // namespace ddl::tracking
