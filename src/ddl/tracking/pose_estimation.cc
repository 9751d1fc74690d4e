#include "ddl/tracking/pose_estimation.h"

namespace ddl::tracking {

FramePoseEstimator::FramePoseEstimator(const FrameGeometry& geometry,
                                       const optimization::OptimizerConfig& config)
    : config_(config) {
  intrinsics_.fx = geometry.fx;
  intrinsics_.fy = geometry.fy;
  intrinsics_.cx = geometry.cx;
  intrinsics_.cy = geometry.cy;
  intrinsics_.bf = geometry.bf;
  intrinsics_.validate();
  config_.validate();
}

int FramePoseEstimator::optimize(Frame& frame) { return run(frame, nullptr); }

int FramePoseEstimator::optimize_with_prior(Frame& frame, const optimization::PosePrior& prior) {
  return run(frame, &prior);
}

int FramePoseEstimator::run(Frame& frame, const optimization::PosePrior* prior) {
  const map::FrameFeatures& f = frame.features();
  observations_.clear();
  slots_.clear();
  for (std::size_t i = 0; i < frame.size(); ++i) {
    const map::MapPointPtr& point = frame.map_point(i);
    if (!point) continue;
    frame.set_outlier(i, false);
    const cv::KeyPoint& kp = f.keypoints[i];
    optimization::PoseObservation obs;
    obs.p_w = point->position_w();
    obs.measurement.uv_px = Vec2d(kp.pt.x, kp.pt.y);
    obs.measurement.stereo = f.is_stereo(i);
    obs.measurement.u_right_px = obs.measurement.stereo ? f.u_right[i] : 0.0;
    obs.measurement.inv_sigma2 = f.pyramid.inv_level_sigma2[static_cast<std::size_t>(kp.octave)];
    observations_.push_back(obs);
    slots_.push_back(i);
  }
  const optimization::PoseOptimizationResult result =
      optimization::optimize_pose(intrinsics_, frame.T_c_w(), observations_, config_, prior);
  if (!result.optimized) return 0;
  frame.set_T_c_w(result.T_c_w);
  for (std::size_t k = 0; k < slots_.size(); ++k) frame.set_outlier(slots_[k], !result.inliers[k]);
  return result.num_inliers;
}

int discard_outliers(Frame& frame) {
  int with_observations = 0;
  for (std::size_t i = 0; i < frame.size(); ++i) {
    const map::MapPointPtr& point = frame.map_point(i);
    if (!point) continue;
    if (frame.is_outlier(i)) {
      frame.add_rejected_point(point->id());
      frame.clear_map_point(i);
    } else if (point->num_observations() > 0) {
      ++with_observations;
    }
  }
  return with_observations;
}

}  // namespace ddl::tracking
