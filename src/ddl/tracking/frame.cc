#include "ddl/tracking/frame.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "ddl/core/error.h"
#include "ddl/core/pixel.h"

namespace ddl::tracking {

FrameGeometry FrameGeometry::from(const camera::PinholeCamera& camera, const FrameConfig& config) {
  camera.validate();
  FrameGeometry g;
  g.width = camera.width;
  g.height = camera.height;
  g.fx = camera.fx;
  g.fy = camera.fy;
  g.cx = camera.cx;
  g.cy = camera.cy;
  g.bf = config.bf;
  g.baseline_m = config.bf / camera.fx;
  g.close_depth_m = config.close_depth_baselines * g.baseline_m;
  g.min_depth_m = config.min_depth_m;
  g.max_depth_m = config.max_depth_m;
  g.depth_edge_radius_px = config.depth_edge_radius_px;
  g.depth_edge_ratio = config.depth_edge_ratio;
  return g;
}

Frame::Frame(FrameId id, double timestamp_s, std::shared_ptr<map::FrameFeatures> features,
             std::shared_ptr<const FrameGeometry> geometry)
    : id_(id),
      timestamp_s_(timestamp_s),
      features_(std::move(features)),
      geometry_(std::move(geometry)),
      map_points_(features_->size()),
      outliers_(features_->size(), 0) {}

void Frame::set_T_c_w(const SE3& T_c_w) {
  T_c_w_ = T_c_w;
  center_w_ = T_c_w.inverse().translation();
  has_pose_ = true;
}

void Frame::set_map_point(std::size_t i, map::MapPointPtr point) {
  map_points_[i] = std::move(point);
}

void Frame::clear_map_point(std::size_t i) {
  map_points_[i].reset();
  outliers_[i] = 0;
}

void Frame::clear_map_points() {
  for (auto& p : map_points_) p.reset();
  std::fill(outliers_.begin(), outliers_.end(), 0);
}

void Frame::set_map_points(std::vector<map::MapPointPtr> points) {
  map_points_ = std::move(points);
  map_points_.resize(size());
  std::fill(outliers_.begin(), outliers_.end(), 0);
}

int Frame::matched_count() const {
  return static_cast<int>(
      std::count_if(map_points_.begin(), map_points_.end(), [](const auto& p) { return p; }));
}

Vec3d Frame::unproject_w(std::size_t i) const {
  const cv::KeyPoint& kp = features_->keypoints[i];
  const double z = features_->depth_m[i];
  const Vec3d p_c((kp.pt.x - geometry_->cx) * z / geometry_->fx,
                  (kp.pt.y - geometry_->cy) * z / geometry_->fy, z);
  return T_c_w_.inverse() * p_c;
}

std::size_t Frame::drop_features_in(const cv::Mat& mask) {
  if (mask.empty() || !features_) return 0;
  if (mask.type() != CV_8UC1 || mask.cols != geometry_->width || mask.rows != geometry_->height) {
    throw Error(fmt::format("Frame::drop_features_in: the mask must be CV_8UC1 of size {}x{}",
                            geometry_->width, geometry_->height));
  }
  map::FrameFeatures& f = *features_;
  std::vector<std::size_t> keep;
  keep.reserve(f.size());
  for (std::size_t i = 0; i < f.size(); ++i) {
    const cv::Point2f& pt = f.keypoints[i].pt;
    const int x = std::clamp(nearest_pixel(pt.x), 0, mask.cols - 1);
    const int y = std::clamp(nearest_pixel(pt.y), 0, mask.rows - 1);
    if (mask.at<std::uint8_t>(y, x) == 0) keep.push_back(i);
  }
  const std::size_t removed = f.size() - keep.size();
  if (removed == 0) return 0;

  cv::Mat descriptors(static_cast<int>(keep.size()), f.descriptors.cols, f.descriptors.type());
  for (std::size_t k = 0; k < keep.size(); ++k) {
    const std::size_t i = keep[k];
    f.keypoints[k] = f.keypoints[i];
    f.depth_m[k] = f.depth_m[i];
    f.u_right[k] = f.u_right[i];
    f.descriptors.row(static_cast<int>(i)).copyTo(descriptors.row(static_cast<int>(k)));
    map_points_[k] = std::move(map_points_[i]);
    outliers_[k] = outliers_[i];
  }
  f.keypoints.resize(keep.size());
  f.depth_m.resize(keep.size());
  f.u_right.resize(keep.size());
  f.descriptors = descriptors;
  map_points_.resize(keep.size());
  outliers_.resize(keep.size());
  f.grid = features::FeatureGrid(f.keypoints, f.grid.bounds(), f.grid.cols(), f.grid.rows());
  f.bow = {};
  f.feature_vector = {};
  return removed;
}

void Frame::compute_bow(const vocabulary::Vocabulary& vocabulary, int levels_up) {
  if (features_->has_bow() || vocabulary.empty()) return;
  vocabulary.transform(features_->descriptors, levels_up, features_->bow,
                       features_->feature_vector);
}

float keypoint_depth(const cv::Mat& depth_m, float u, float v, const FrameGeometry& geometry) {
  // Pixel (0, 0) is centred on the top-left pixel, so the nearest pixel is the rounded position.
  const int x = nearest_pixel(u);
  const int y = nearest_pixel(v);
  if (x < 0 || y < 0 || x >= depth_m.cols || y >= depth_m.rows) return 0.0f;
  const auto valid = [&](float z) {
    return std::isfinite(z) && z > geometry.min_depth_m && z <= geometry.max_depth_m;
  };
  const float d = depth_m.at<float>(y, x);
  if (!valid(d)) return 0.0f;
  const int r = geometry.depth_edge_radius_px;
  if (r > 0) {
    // At a depth edge the reading may belong to either side: a corner on a silhouette, or a
    // sensor whose depth image lags the colour one (Freiburg 1: 20 ms) in a fast turn.
    const float jump = static_cast<float>(geometry.depth_edge_ratio) * d;
    const int y0 = std::max(0, y - r), y1 = std::min(depth_m.rows - 1, y + r);
    const int x0 = std::max(0, x - r), x1 = std::min(depth_m.cols - 1, x + r);
    for (int yy = y0; yy <= y1; ++yy) {
      const float* row = depth_m.ptr<float>(yy);
      for (int xx = x0; xx <= x1; ++xx) {
        if (valid(row[xx]) && std::abs(row[xx] - d) > jump) return 0.0f;
      }
    }
  }
  return d;
}

FrameBuilder::FrameBuilder(const camera::PinholeCamera& camera,
                           const features::OrbExtractorConfig& orb, const FrameConfig& config)
    : geometry_(std::make_shared<const FrameGeometry>(FrameGeometry::from(camera, config))),
      extractor_(orb) {
  // A level too small for a keypoint would take its share of the features and give none
  // (review, stop 26).
  orb.validate_for_image(geometry_->width, geometry_->height);
}

Frame FrameBuilder::build(const io::RgbdFrame& frame, const cv::Mat& dynamic_mask, FrameId id) {
  const FrameGeometry& g = *geometry_;
  const std::string& source = frame.rgb_path.empty() ? std::string("<rgb image>") : frame.rgb_path;
  if (frame.rgb.empty() || (frame.rgb.type() != CV_8UC3 && frame.rgb.type() != CV_8UC1) ||
      frame.rgb.cols != g.width || frame.rgb.rows != g.height) {
    throw InputError::at(
        source, fmt::format("tracking needs an 8-bit {}x{} colour image (got {}x{}, "
                            "type {})",
                            g.width, g.height, frame.rgb.cols, frame.rgb.rows, frame.rgb.type()));
  }
  const std::string& depth_source =
      frame.depth_path.empty() ? std::string("<depth image>") : frame.depth_path;
  if (frame.depth_m.type() != CV_32FC1 || frame.depth_m.size() != frame.rgb.size()) {
    throw InputError::at(depth_source,
                         fmt::format("tracking needs a CV_32FC1 depth image in metres of size "
                                     "{}x{} (got {}x{}, type {})",
                                     g.width, g.height, frame.depth_m.cols, frame.depth_m.rows,
                                     frame.depth_m.type()));
  }
  if (!dynamic_mask.empty() &&
      (dynamic_mask.type() != CV_8UC1 || dynamic_mask.size() != frame.rgb.size())) {
    throw InputError::at(source, fmt::format("the dynamic mask must be CV_8UC1 of size {}x{} (got "
                                             "{}x{}, type {})",
                                             g.width, g.height, dynamic_mask.cols,
                                             dynamic_mask.rows, dynamic_mask.type()));
  }

  const cv::Mat* gray = &frame.rgb;
  if (frame.rgb.channels() == 3) {
    cv::cvtColor(frame.rgb, gray_, cv::COLOR_BGR2GRAY);
    gray = &gray_;
  }
  features::OrbFeatures orb = extractor_.extract(*gray, dynamic_mask);

  auto features = std::make_shared<map::FrameFeatures>();
  features->keypoints = std::move(orb.keypoints);
  features->descriptors = orb.descriptors;
  features->pyramid = std::move(orb.pyramid);
  const std::size_t n = features->keypoints.size();
  features->depth_m.resize(n);
  features->u_right.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const cv::Point2f& pt = features->keypoints[i].pt;
    const float d = keypoint_depth(frame.depth_m, pt.x, pt.y, g);
    features->depth_m[i] = d;
    features->u_right[i] = d > 0.0f ? pt.x - static_cast<float>(g.bf) / d : -1.0f;
  }
  features->grid = features::FeatureGrid(
      features->keypoints,
      cv::Rect2f(0.0f, 0.0f, static_cast<float>(g.width), static_cast<float>(g.height)));
  return Frame(id, frame.timestamp_s, std::move(features), geometry_);
}

}  // namespace ddl::tracking
