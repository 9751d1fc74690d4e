#include "ddl/tracking/motion_model.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace ddl::tracking {

void MotionModel::update(const SE3& T_c_w_current, const SE3& T_c_w_previous, double interval_s) {
  velocity_ = T_c_w_current * T_c_w_previous.inverse();
  // Measured from a glitched stamp (reset() clears the flag when the frames are not consecutive).
  const bool after_glitch = last_interval_glitched_;
  const bool glitch = is_glitch(interval_s);
  const bool regular = interval_s > 0.0 && !glitch && !after_glitch;
  interval_s_ = regular ? interval_s : 0.0;
  last_interval_glitched_ = glitch;
  valid_ = true;
  if (regular) {
    recent_intervals_s_.push_back(interval_s);
    if (recent_intervals_s_.size() > kRateHistory) recent_intervals_s_.pop_front();
  }
}

double MotionModel::base_interval_s() const {
  if (recent_intervals_s_.size() < kMinRateHistory) return 0.0;
  std::vector<double> sorted(recent_intervals_s_.begin(), recent_intervals_s_.end());
  const auto nth = sorted.begin() + static_cast<std::ptrdiff_t>(kBaseRank - 1);
  std::nth_element(sorted.begin(), nth, sorted.end());
  return *nth;
}

bool MotionModel::is_glitch(double interval_s) const {
  const double base_s = base_interval_s();
  return interval_s > 0.0 && base_s > 0.0 && interval_s * kGlitchRatio <= base_s;
}

double MotionModel::gap_ratio(double elapsed_s) const {
  if (!(interval_s_ > 0.0) || !(elapsed_s > 0.0)) return 1.0;
  if (last_interval_glitched_ || is_glitch(elapsed_s)) return 1.0;
  const double ratio = elapsed_s / interval_s_;
  return ratio >= kGapRatio || ratio <= 1.0 / kGapRatio ? ratio : 1.0;
}

SE3 MotionModel::predict(const SE3& T_c_w_last, double elapsed_s) const {
  const double ratio = gap_ratio(elapsed_s);
  if (ratio == 1.0) return velocity_ * T_c_w_last;
  return SE3::exp(ratio * velocity_.log()) * T_c_w_last;
}

optimization::PosePrior MotionModel::prior(const SE3& T_c_w_predicted, double elapsed_s,
                                           const MotionPriorConfig& config) const {
  double scale = 1.0;
  if (gap_ratio(elapsed_s) != 1.0) {
    const double h = std::min(interval_s_, elapsed_s);
    scale = elapsed_s * (interval_s_ + elapsed_s) / (2.0 * h * h);
  }
  const double t = 1.0 / (scale * config.sigma_translation_m);
  const double r = 1.0 / (scale * config.sigma_rotation_deg * M_PI / 180.0);
  optimization::PosePrior prior;
  prior.T_c_w = T_c_w_predicted;
  prior.sqrt_information = Mat6d::Zero();
  prior.sqrt_information.diagonal() << t, t, t, r, r, r;
  return prior;
}

}  // namespace ddl::tracking
