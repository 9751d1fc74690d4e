#include "ddl/map/map_point.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "ddl/features/matcher.h"
#include "ddl/map/keyframe.h"

namespace ddl::map {
namespace {
// ORB-SLAM2 widens the scale-invariance range by these factors when testing visibility.
constexpr double kMinDistanceMargin = 0.8;
constexpr double kMaxDistanceMargin = 1.2;
}  // namespace

MapPoint::MapPoint(MapPointId id, const Vec3d& p_w,
                   const std::shared_ptr<KeyFrame>& reference_keyframe)
    : id_(id),
      first_keyframe_id_(reference_keyframe ? reference_keyframe->id() : 0),
      p_w_(p_w),
      reference_keyframe_(reference_keyframe) {}

Vec3d MapPoint::position_w() const {
  std::lock_guard lock(mutex_);
  return p_w_;
}

void MapPoint::set_position_w(const Vec3d& p_w) {
  std::lock_guard lock(mutex_);
  p_w_ = p_w;
}

void MapPoint::add_observation(const std::shared_ptr<KeyFrame>& keyframe, std::size_t feature_index,
                               bool stereo) {
  std::lock_guard lock(mutex_);
  if (observations_.count(keyframe->id()) != 0) return;
  observations_[keyframe->id()] = Obs{keyframe, feature_index, stereo};
  num_obs_ += stereo ? 2 : 1;
}

bool MapPoint::erase_observation(KeyFrameId keyframe_id) {
  bool became_bad = false;
  {
    std::lock_guard lock(mutex_);
    auto it = observations_.find(keyframe_id);
    if (it == observations_.end()) return false;
    num_obs_ -= it->second.stereo ? 2 : 1;
    const bool was_reference = [&] {
      auto ref = reference_keyframe_.lock();
      return !ref || ref->id() == keyframe_id;
    }();
    observations_.erase(it);
    if (was_reference && !observations_.empty()) {
      reference_keyframe_ = observations_.begin()->second.keyframe;
    }
    became_bad = num_obs_ <= 2 && !bad_;
  }
  if (became_bad) set_bad();
  return became_bad;
}

std::vector<MapPoint::Observation> MapPoint::observations() const {
  std::lock_guard lock(mutex_);
  std::vector<Observation> out;
  out.reserve(observations_.size());
  for (const auto& [id, obs] : observations_) {
    if (auto kf = obs.keyframe.lock())
      out.push_back({std::move(kf), obs.feature_index, obs.stereo});
  }
  return out;
}

long MapPoint::index_in(KeyFrameId keyframe_id) const {
  std::lock_guard lock(mutex_);
  auto it = observations_.find(keyframe_id);
  return it == observations_.end() ? -1 : static_cast<long>(it->second.feature_index);
}

int MapPoint::num_observations() const {
  std::lock_guard lock(mutex_);
  return num_obs_;
}

std::size_t MapPoint::num_keyframes() const {
  std::lock_guard lock(mutex_);
  return observations_.size();
}

std::shared_ptr<KeyFrame> MapPoint::reference_keyframe() const {
  std::lock_guard lock(mutex_);
  return reference_keyframe_.lock();
}

cv::Mat MapPoint::descriptor() const {
  // A private copy: cv::Mat reference counts are updated inside OpenCV, where ThreadSanitizer
  // cannot see their atomics, so no descriptor buffer is shared between threads.
  std::lock_guard lock(mutex_);
  if (!has_descriptor_) return {};
  cv::Mat out(1, static_cast<int>(descriptor_.size()), CV_8UC1);
  std::copy(descriptor_.begin(), descriptor_.end(), out.ptr<std::uint8_t>());
  return out;
}

void MapPoint::compute_distinctive_descriptor() {
  // Keyframe features are immutable and the observations keep their keyframes alive, so raw
  // row pointers stay valid here (and no cv::Mat header is shared across threads).
  const std::vector<Observation> observations = this->observations();
  std::vector<const std::uint8_t*> descriptors;
  for (const Observation& obs : observations) {
    if (obs.keyframe->is_bad()) continue;
    descriptors.push_back(obs.keyframe->features().descriptors.ptr<std::uint8_t>(
        static_cast<int>(obs.feature_index)));
  }
  if (descriptors.empty()) return;
  const std::size_t n = descriptors.size();
  std::vector<int> distances(n * n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t j = i + 1; j < n; ++j) {
      const int d = features::hamming_distance(descriptors[i], descriptors[j]);
      distances[i * n + j] = d;
      distances[j * n + i] = d;
    }
  }
  int best_median = std::numeric_limits<int>::max();
  std::size_t best = 0;
  std::vector<int> row(n);
  for (std::size_t i = 0; i < n; ++i) {
    std::copy(distances.begin() + static_cast<long>(i * n),
              distances.begin() + static_cast<long>((i + 1) * n), row.begin());
    std::nth_element(row.begin(), row.begin() + static_cast<long>((n - 1) / 2), row.end());
    const int med = row[(n - 1) / 2];
    if (med < best_median) {
      best_median = med;
      best = i;
    }
  }
  std::lock_guard lock(mutex_);
  std::copy(descriptors[best], descriptors[best] + descriptor_.size(), descriptor_.begin());
  has_descriptor_ = true;
}

void MapPoint::update_normal_and_depth() {
  const std::vector<Observation> obs = observations();
  std::shared_ptr<KeyFrame> ref = reference_keyframe();
  if (obs.empty() || !ref) return;
  const Vec3d p_w = position_w();
  Vec3d normal = Vec3d::Zero();
  int n = 0;
  for (const Observation& o : obs) {
    const Vec3d dir = p_w - o.keyframe->camera_center_w();
    const double norm = dir.norm();
    if (norm <= 0.0) continue;
    normal += dir / norm;
    ++n;
  }
  const long ref_index = index_in(ref->id());
  if (ref_index < 0 || n == 0) return;
  const double distance = (p_w - ref->camera_center_w()).norm();
  const auto& features = ref->features();
  const int level = features.keypoints[static_cast<std::size_t>(ref_index)].octave;
  const double level_scale = features.pyramid.scale_factors[static_cast<std::size_t>(level)];
  const double top_scale =
      features.pyramid.scale_factors[static_cast<std::size_t>(features.pyramid.num_levels - 1)];
  std::lock_guard lock(mutex_);
  max_distance_ = distance * level_scale;
  min_distance_ = max_distance_ / top_scale;
  normal_w_ = normal / static_cast<double>(n);
}

Vec3d MapPoint::normal_w() const {
  std::lock_guard lock(mutex_);
  return normal_w_;
}

double MapPoint::min_distance() const {
  std::lock_guard lock(mutex_);
  return kMinDistanceMargin * min_distance_;
}

double MapPoint::max_distance() const {
  std::lock_guard lock(mutex_);
  return kMaxDistanceMargin * max_distance_;
}

namespace {
int predict_level(double level0_distance_m, double distance_m,
                  const features::ScalePyramid& pyramid) {
  const double ratio = level0_distance_m / distance_m;
  if (ratio <= 0.0) return 0;
  int level = static_cast<int>(std::ceil(std::log(ratio) / pyramid.log_scale_factor));
  return std::clamp(level, 0, pyramid.num_levels - 1);
}
}  // namespace

int MapPoint::predict_scale(double distance_m, const features::ScalePyramid& pyramid) const {
  double level0_distance_m = 0.0;
  {
    std::lock_guard lock(mutex_);
    level0_distance_m = max_distance_;
  }
  return predict_level(level0_distance_m, distance_m, pyramid);
}

int MapPoint::ViewSummary::predict_scale(double distance_m,
                                         const features::ScalePyramid& pyramid) const {
  return predict_level(level0_distance_m, distance_m, pyramid);
}

MapPoint::ViewSummary MapPoint::view_summary() const {
  std::lock_guard lock(mutex_);
  ViewSummary s;
  s.p_w = p_w_;
  s.normal_w = normal_w_;
  s.min_distance = kMinDistanceMargin * min_distance_;
  s.max_distance = kMaxDistanceMargin * max_distance_;
  s.bad = bad_;
  s.level0_distance_m = max_distance_;
  return s;
}

void MapPoint::increase_visible(int n) {
  std::lock_guard lock(mutex_);
  visible_ += n;
}

void MapPoint::increase_found(int n) {
  std::lock_guard lock(mutex_);
  found_ += n;
}

double MapPoint::found_ratio() const {
  std::lock_guard lock(mutex_);
  return static_cast<double>(found_) / static_cast<double>(visible_);
}

int MapPoint::found_count() const {
  std::lock_guard lock(mutex_);
  return found_;
}

int MapPoint::visible_count() const {
  std::lock_guard lock(mutex_);
  return visible_;
}

bool MapPoint::is_bad() const {
  std::lock_guard lock(mutex_);
  return bad_;
}

void MapPoint::set_bad() {
  std::map<KeyFrameId, Obs> detached;
  {
    std::lock_guard lock(mutex_);
    bad_ = true;
    detached.swap(observations_);
    num_obs_ = 0;
  }
  for (const auto& [id, obs] : detached) {
    if (auto kf = obs.keyframe.lock()) kf->erase_map_point(*this);
  }
}

void MapPoint::replace_with(const std::shared_ptr<MapPoint>& other) {
  if (!other || other.get() == this) return;
  std::map<KeyFrameId, Obs> moved;
  int visible = 0;
  int found = 0;
  {
    std::lock_guard lock(mutex_);
    moved.swap(observations_);
    num_obs_ = 0;
    bad_ = true;
    visible = visible_;
    found = found_;
    replaced_by_ = other;
  }
  for (const auto& [id, obs] : moved) {
    auto kf = obs.keyframe.lock();
    if (!kf) continue;
    if (!other->is_in(id)) {
      kf->set_map_point(obs.feature_index, other);
      other->add_observation(kf, obs.feature_index, obs.stereo);
    } else {
      kf->erase_map_point(*this);
    }
  }
  other->increase_found(found);
  other->increase_visible(visible);
  other->compute_distinctive_descriptor();
}

std::shared_ptr<MapPoint> MapPoint::replaced_by() const {
  std::lock_guard lock(mutex_);
  return replaced_by_.lock();
}

}  // namespace ddl::map
