#include "ddl/eval/dense_metrics.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace ddl::eval {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

void check_same(const cv::Mat& a, const cv::Mat& b, int type, const char* what) {
  if (a.empty() || b.empty() || a.type() != type || b.type() != type || a.size() != b.size()) {
    throw std::invalid_argument(std::string("dense metrics: ") + what +
                                " images missing or of different size or type");
  }
}

void check_mask(const cv::Mat& mask, const cv::Size& size, const char* what) {
  if (mask.type() != CV_8UC1 || mask.size() != size) {
    throw std::invalid_argument(std::string("dense metrics: ") + what +
                                " must be CV_8UC1 of the image size");
  }
}

/// 21 bits per axis (+-1M cells) in one key.
std::uint64_t cell_key(const Vec3d& p, double cell) {
  auto index = [&](double x) {
    return static_cast<std::uint64_t>(static_cast<std::int64_t>(std::floor(x / cell)) + (1 << 20)) &
           0x1FFFFFu;
  };
  return (index(p.x()) << 42) | (index(p.y()) << 21) | index(p.z());
}

}  // namespace

double ColourError::psnr_db() const {
  if (pixels == 0) return kNaN;
  const double mse = sum_squared / (3.0 * static_cast<double>(pixels));
  if (mse <= 0.0) return std::numeric_limits<double>::infinity();
  return 10.0 * std::log10(255.0 * 255.0 / mse);
}

ColourError& ColourError::operator+=(const ColourError& other) {
  sum_squared += other.sum_squared;
  pixels += other.pixels;
  return *this;
}

double DepthError::median_m() const {
  if (abs_m.empty()) return kNaN;
  std::vector<float> v = abs_m;
  const std::size_t mid = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(mid), v.end());
  const double upper = v[mid];
  if (v.size() % 2 == 1) return upper;
  const double lower = *std::max_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(mid));
  return 0.5 * (lower + upper);
}

DepthError& DepthError::operator+=(const DepthError& other) {
  abs_m.insert(abs_m.end(), other.abs_m.begin(), other.abs_m.end());
  missing += other.missing;
  return *this;
}

ColourError colour_error(const cv::Mat& bgr, const cv::Mat& reference_bgr, const cv::Mat& mask) {
  check_same(bgr, reference_bgr, CV_8UC3, "colour");
  check_mask(mask, bgr.size(), "colour mask");
  ColourError e;
  for (int v = 0; v < bgr.rows; ++v) {
    const auto* a = bgr.ptr<cv::Vec3b>(v);
    const auto* b = reference_bgr.ptr<cv::Vec3b>(v);
    const std::uint8_t* m = mask.ptr(v);
    for (int u = 0; u < bgr.cols; ++u) {
      if (m[u] == 0) continue;
      for (int c = 0; c < 3; ++c) {
        const double d = static_cast<double>(a[u][c]) - static_cast<double>(b[u][c]);
        e.sum_squared += d * d;
      }
      ++e.pixels;
    }
  }
  return e;
}

DepthError depth_error(const cv::Mat& depth_m, const cv::Mat& reference_depth_m,
                       const cv::Mat& mask) {
  check_same(depth_m, reference_depth_m, CV_32FC1, "depth");
  check_mask(mask, depth_m.size(), "depth mask");
  DepthError e;
  for (int v = 0; v < depth_m.rows; ++v) {
    const float* a = depth_m.ptr<float>(v);
    const float* b = reference_depth_m.ptr<float>(v);
    const std::uint8_t* m = mask.ptr(v);
    for (int u = 0; u < depth_m.cols; ++u) {
      if (m[u] == 0) continue;
      if (a[u] > 0.0f && b[u] > 0.0f) {
        e.abs_m.push_back(std::abs(a[u] - b[u]));
      } else {
        ++e.missing;
      }
    }
  }
  return e;
}

cv::Mat seen_background(const cv::Mat& dynamic_mask, const cv::Mat& background_depth_m,
                        const SE3& T_w_c, const std::vector<TrueView>& earlier,
                        const camera::PinholeCamera& camera, const SeenOptions& options) {
  check_mask(dynamic_mask, background_depth_m.size(), "dynamic mask");
  if (background_depth_m.type() != CV_32FC1) {
    throw std::invalid_argument("dense metrics: background depth must be CV_32FC1");
  }
  for (const TrueView& view : earlier) {
    check_mask(view.dynamic_mask, view.depth_m.size(), "earlier view's dynamic mask");
    if (view.depth_m.type() != CV_32FC1) {
      throw std::invalid_argument("dense metrics: earlier view's depth must be CV_32FC1");
    }
  }
  cv::Mat seen = cv::Mat::zeros(dynamic_mask.size(), CV_8UC1);
  std::vector<SE3> T_view_c;
  T_view_c.reserve(earlier.size());
  for (const TrueView& view : earlier) T_view_c.push_back(view.T_w_c.inverse() * T_w_c);
  for (int v = 0; v < dynamic_mask.rows; ++v) {
    const std::uint8_t* m = dynamic_mask.ptr(v);
    const float* bg = background_depth_m.ptr<float>(v);
    for (int u = 0; u < dynamic_mask.cols; ++u) {
      if (m[u] == 0 || bg[u] <= 0.0f) continue;
      const Vec3d p_c = camera.unproject(u, v, bg[u]);
      for (std::size_t k = 0; k < earlier.size(); ++k) {
        const Vec3d p = T_view_c[k] * p_c;
        if (p.z() <= 0.0) continue;
        const Vec2d uv = camera.project(p);
        const int x = static_cast<int>(std::lround(uv.x()));
        const int y = static_cast<int>(std::lround(uv.y()));
        const cv::Mat& depth = earlier[k].depth_m;
        if (x < 0 || y < 0 || x >= depth.cols || y >= depth.rows) continue;
        if (earlier[k].dynamic_mask.at<std::uint8_t>(y, x) != 0) continue;
        const double measured = depth.at<float>(y, x);
        const double tolerance =
            std::max(options.depth_tolerance_m, options.depth_tolerance_rel * p.z());
        if (measured <= 0.0 || std::abs(measured - p.z()) > tolerance) continue;
        seen.at<std::uint8_t>(v, u) = 255;
        break;
      }
    }
  }
  return seen;
}

InpaintingFrameMetrics& InpaintingFrameMetrics::operator+=(const InpaintingFrameMetrics& other) {
  dynamic_px += other.dynamic_px;
  seen_px += other.seen_px;
  filled_px += other.filled_px;
  filled_seen_px += other.filled_seen_px;
  repair_mask_px += other.repair_mask_px;
  filled_rgb += other.filled_rgb;
  filled_rgb_original += other.filled_rgb_original;
  dynamic_rgb += other.dynamic_rgb;
  dynamic_rgb_original += other.dynamic_rgb_original;
  filled_depth += other.filled_depth;
  filled_depth_original += other.filled_depth_original;
  return *this;
}

InpaintingFrameMetrics evaluate_inpainted_frame(const InpaintingFrameInputs& in) {
  check_same(in.repaired_bgr, in.background_bgr, CV_8UC3, "repaired/background colour");
  check_same(in.original_bgr, in.background_bgr, CV_8UC3, "original/background colour");
  const cv::Size size = in.background_bgr.size();
  check_mask(in.dynamic_mask, size, "dynamic mask");
  check_mask(in.repair_mask, size, "repair mask");
  check_mask(in.unfilled, size, "unfilled mask");
  const cv::Mat dynamic = in.dynamic_mask != 0;
  cv::Mat seen = cv::Mat::zeros(size, CV_8UC1);
  if (!in.seen.empty()) {
    check_mask(in.seen, size, "seen mask");
    seen = (in.seen != 0) & dynamic;
  }
  const cv::Mat filled = dynamic & (in.repair_mask != 0) & (in.unfilled == 0);

  InpaintingFrameMetrics m;
  m.dynamic_px = static_cast<std::uint64_t>(cv::countNonZero(dynamic));
  m.seen_px = static_cast<std::uint64_t>(cv::countNonZero(seen));
  m.filled_px = static_cast<std::uint64_t>(cv::countNonZero(filled));
  m.filled_seen_px = static_cast<std::uint64_t>(cv::countNonZero(filled & seen));
  m.repair_mask_px = static_cast<std::uint64_t>(cv::countNonZero(in.repair_mask));
  m.filled_rgb = colour_error(in.repaired_bgr, in.background_bgr, filled);
  m.filled_rgb_original = colour_error(in.original_bgr, in.background_bgr, filled);
  m.dynamic_rgb = colour_error(in.repaired_bgr, in.background_bgr, dynamic);
  m.dynamic_rgb_original = colour_error(in.original_bgr, in.background_bgr, dynamic);
  m.filled_depth = depth_error(in.repaired_depth_m, in.background_depth_m, filled);
  m.filled_depth_original = depth_error(in.original_depth_m, in.background_depth_m, filled);
  return m;
}

PointGrid::PointGrid(double cell_m, double merge_m) : cell_(cell_m), merge_(merge_m) {
  if (!(cell_m > 0.0) || !(merge_m > 0.0) || merge_m > cell_m) {
    throw std::invalid_argument("PointGrid: need 0 < merge_m <= cell_m");
  }
}

void PointGrid::insert(const Vec3d& p) {
  if (!fine_.insert(cell_key(p, merge_)).second) return;
  const Vec3d centre = (((p / merge_).array().floor() + 0.5) * merge_).matrix();
  cells_[cell_key(centre, cell_)].push_back(centre.cast<float>());
  ++stored_;
}

bool PointGrid::any_within(const Vec3d& q, double radius_m) const {
  if (radius_m > cell_) throw std::invalid_argument("PointGrid: radius larger than the cell");
  const float r2 = static_cast<float>(radius_m * radius_m);
  const Eigen::Vector3f qf = q.cast<float>();
  for (int dx = -1; dx <= 1; ++dx) {
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dz = -1; dz <= 1; ++dz) {
        const auto it = cells_.find(cell_key(q + Vec3d(dx, dy, dz) * cell_, cell_));
        if (it == cells_.end()) continue;
        for (const Eigen::Vector3f& p : it->second) {
          if ((p - qf).squaredNorm() <= r2) return true;
        }
      }
    }
  }
  return false;
}

VoxelClasses classify_voxels(const std::vector<Vec3d>& centres, const PointGrid& static_points,
                             const PointGrid& dynamic_points, double radius_m,
                             std::vector<VoxelClass>* labels) {
  VoxelClasses c;
  c.occupied = centres.size();
  if (labels != nullptr) labels->clear();
  for (const Vec3d& p : centres) {
    VoxelClass label = VoxelClass::kOther;
    if (static_points.any_within(p, radius_m)) {
      ++c.true_static;
      label = VoxelClass::kStatic;
    } else if (dynamic_points.any_within(p, radius_m)) {
      ++c.ghost;
      label = VoxelClass::kGhost;
    } else {
      ++c.other;
    }
    if (labels != nullptr) labels->push_back(label);
  }
  return c;
}

}  // namespace ddl::eval
