#include "ddl/features/orb_extractor.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numbers>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>

#include "ddl/core/error.h"
#include "ddl/core/pixel.h"
#include "ddl/features/quadtree_distribution.h"

namespace ddl::features {
namespace {

// FAST needs 3 pixels around a corner (Bresenham circle of radius 3).
constexpr int kFastRadius = 3;
// Gaussian smoothing before the binary tests (ORB: 7x7 kernel, sigma 2), reducing the
// sensitivity of single-pixel comparisons to noise.
constexpr int kBlurKernel = 7;
constexpr double kBlurSigma = 2.0;

// Intensity-centroid orientation (Rosin 1999; ORB section 3.2): the angle of the vector from the
// keypoint to the centroid of intensity over the disc |(u, v)| <= r, in degrees [0, 360).
float intensity_centroid_angle(const cv::Mat& image, int x, int y,
                               const std::vector<int>& half_width) {
  const int radius = static_cast<int>(half_width.size()) - 1;
  const std::ptrdiff_t step = image.step1();
  const std::uint8_t* centre = image.ptr<std::uint8_t>(y) + x;
  int m10 = 0;
  int m01 = 0;
  for (int u = -radius; u <= radius; ++u) m10 += u * centre[u];
  // Rows +v and -v together: their x moments add, their y moments subtract.
  for (int v = 1; v <= radius; ++v) {
    const std::uint8_t* below = centre + v * step;
    const std::uint8_t* above = centre - v * step;
    const int w = half_width[v];
    int row_difference = 0;
    for (int u = -w; u <= w; ++u) {
      const int b = below[u];
      const int a = above[u];
      row_difference += b - a;
      m10 += u * (b + a);
    }
    m01 += v * row_difference;
  }
  float angle = static_cast<float>(std::atan2(static_cast<double>(m01), static_cast<double>(m10)) *
                                   (180.0 / std::numbers::pi));
  if (angle < 0.0f) angle += 360.0f;
  if (angle >= 360.0f) angle -= 360.0f;
  return angle;
}

}  // namespace

void smooth_for_descriptor(const cv::Mat& level_image, cv::Mat& smoothed) {
  cv::GaussianBlur(level_image, smoothed, cv::Size(kBlurKernel, kBlurKernel), kBlurSigma,
                   kBlurSigma, cv::BORDER_REFLECT_101);
}

namespace {

// Round to nearest, ties to even, for |v| < 2^22: adding 1.5 * 2^23 leaves the rounded integer
// in the low mantissa bits. Equal to cvRound() (which rounds ties to even too) but plain float
// arithmetic, so the offset loop below vectorizes.
inline int round_to_int(float v) {
  const float shifted = v + 12582912.0f;
  std::int32_t bits;
  std::memcpy(&bits, &shifted, sizeof(bits));
  return bits - 0x4B400000;
}

}  // namespace

void compute_steered_brief(const cv::Mat& smoothed, int x, int y, float angle_deg,
                           const BriefPair* pairs, int num_pairs, std::uint8_t* out) {
  const float angle = angle_deg * static_cast<float>(std::numbers::pi / 180.0);
  const float c = std::cos(angle);
  const float s = std::sin(angle);
  const int step = static_cast<int>(smoothed.step1());
  const std::uint8_t* centre = smoothed.ptr<std::uint8_t>(y) + x;
  // Chunks of 64 tests: first the rotated pixel offsets of both points (vectorizable), then the
  // comparisons.
  constexpr int kChunk = 64;
  alignas(16) int offset_a[kChunk];
  alignas(16) int offset_b[kChunk];
  for (int first = 0; first < num_pairs; first += kChunk) {
    const int n = std::min(kChunk, num_pairs - first);
    const BriefPair* chunk = pairs + first;
    for (int k = 0; k < n; ++k) {
      const float x1 = chunk[k].x1;
      const float y1 = chunk[k].y1;
      const float x2 = chunk[k].x2;
      const float y2 = chunk[k].y2;
      offset_a[k] = round_to_int(x1 * s + y1 * c) * step + round_to_int(x1 * c - y1 * s);
      offset_b[k] = round_to_int(x2 * s + y2 * c) * step + round_to_int(x2 * c - y2 * s);
    }
    for (int k = 0; k < n; k += 8) {
      const int last = std::min(k + 8, n);
      std::uint8_t bits = 0;
      for (int j = k; j < last; ++j) {
        bits |= static_cast<std::uint8_t>((centre[offset_a[j]] < centre[offset_b[j]]) << (j - k));
      }
      out[(first + k) / 8] = bits;
    }
  }
}

struct OrbExtractor::Scratch {
  struct Level {
    std::vector<cv::KeyPoint> candidates;  // FAST corners, level coordinates
    std::vector<cv::KeyPoint> keypoints;   // kept corners, level coordinates
    std::vector<std::uint8_t> cell_has_strong;
    QuadtreeScratch tree;
    std::vector<int> kept;
    cv::Mat blurred;
    cv::Mat descriptors;  // keypoints.size() x 32
  };
  std::vector<Level> levels;
  std::unique_ptr<tbb::task_arena> arena;  // only when config.num_threads > 1
};

void OrbExtractorConfig::validate() const {
  auto require = [](bool ok, const char* key, auto value, const char* what) {
    if (!ok) throw ConfigError::for_key(key, fmt::format("{} (got {})", what, value));
  };
  require(num_features > 0 && num_features <= 100000, "orb.num_features", num_features,
          "must be in 1..100000");
  require(std::isfinite(scale_factor) && scale_factor > 1.0 && scale_factor <= 4.0,
          "orb.scale_factor", scale_factor, "must be in (1, 4]");
  require(num_levels >= 1 && num_levels <= 32, "orb.num_levels", num_levels, "must be in 1..32");
  require(fast_threshold_initial >= 1 && fast_threshold_initial <= 254,
          "orb.fast_threshold_initial", fast_threshold_initial, "must be in 1..254");
  require(fast_threshold_min >= 1 && fast_threshold_min <= fast_threshold_initial,
          "orb.fast_threshold_min", fast_threshold_min, "must be in 1..orb.fast_threshold_initial");
  require(patch_size >= 7 && patch_size <= 63 && patch_size % 2 == 1, "orb.patch_size", patch_size,
          "must be odd and in 7..63");
  require(edge_threshold >= patch_size / 2 + 1 && edge_threshold <= 128, "orb.edge_threshold",
          edge_threshold, "must be in (orb.patch_size / 2)..128, so patches stay inside the image");
  require(cell_size_px >= 8 && cell_size_px <= 1024, "orb.cell_size_px", cell_size_px,
          "must be in 8..1024");
  require(num_threads >= 1 && num_threads <= 64, "orb.num_threads", num_threads,
          "must be in 1..64");
}

namespace {

// Size of pyramid level `level` of an image of `size` (level 0 is the image itself), as
// build_pyramid resizes it.
cv::Size level_size(const ScalePyramid& pyramid, int level, cv::Size size) {
  const float inv = pyramid.inv_scale_factors[level];
  return {cvRound(size.width * inv), cvRound(size.height * inv)};
}

}  // namespace

void OrbExtractorConfig::validate_for_image(int width, int height) const {
  validate();
  const ScalePyramid pyramid = make_scale_pyramid(num_levels, scale_factor);
  for (int level = 0; level < num_levels; ++level) {
    const cv::Size size = level_size(pyramid, level, {width, height});
    const int cols = size.width;
    const int rows = size.height;
    if (cols <= 2 * edge_threshold || rows <= 2 * edge_threshold) {
      if (level == 0) {
        throw ConfigError::for_key(
            "orb.edge_threshold",
            fmt::format("a {}x{} image is not more than 2 orb.edge_threshold ({}) px wide and "
                        "high: no keypoint fits",
                        width, height, 2 * edge_threshold));
      }
      throw ConfigError::for_key(
          "orb.num_levels",
          fmt::format("{} levels with scale factor {} make level {} of a {}x{} image {}x{} px, "
                      "not more than 2 orb.edge_threshold ({}) in {}: it could hold no keypoint "
                      "and its share of orb.num_features would be lost; use at most {} levels",
                      num_levels, scale_factor, level, width, height, cols, rows,
                      2 * edge_threshold, cols <= 2 * edge_threshold ? "width" : "height", level));
    }
  }
}

ScalePyramid make_scale_pyramid(int num_levels, double scale_factor) {
  ScalePyramid p;
  p.num_levels = num_levels;
  p.scale_factor = scale_factor;
  p.log_scale_factor = std::log(scale_factor);
  p.scale_factors.resize(num_levels);
  p.inv_scale_factors.resize(num_levels);
  p.level_sigma2.resize(num_levels);
  p.inv_level_sigma2.resize(num_levels);
  double scale = 1.0;
  for (int level = 0; level < num_levels; ++level) {
    p.scale_factors[level] = static_cast<float>(scale);
    p.inv_scale_factors[level] = static_cast<float>(1.0 / scale);
    p.level_sigma2[level] = static_cast<float>(scale * scale);
    p.inv_level_sigma2[level] = static_cast<float>(1.0 / (scale * scale));
    scale *= scale_factor;
  }
  return p;
}

std::vector<int> features_per_level(int num_features, int num_levels, double scale_factor) {
  // Level l gets N * (1 - f) / (1 - f^L) * f^l with f = 1 / scale_factor, rounded; the last
  // level takes what is left so the sum is exactly N (ORB-SLAM2's allocation).
  std::vector<int> counts(num_levels, 0);
  const double f = 1.0 / scale_factor;
  double wanted = num_features * (1.0 - f) / (1.0 - std::pow(f, num_levels));
  int assigned = 0;
  for (int level = 0; level + 1 < num_levels; ++level) {
    counts[level] = std::min(static_cast<int>(std::lround(wanted)), num_features - assigned);
    assigned += counts[level];
    wanted *= f;
  }
  counts[num_levels - 1] = std::max(num_features - assigned, 0);
  return counts;
}

OrbExtractor::OrbExtractor(const OrbExtractorConfig& config, const BriefPattern& pattern)
    : config_(config), pattern_(pattern) {
  config_.validate();
  const double radius_px = pattern_radius(pattern_);
  if (radius_px > config_.patch_size / 2 + 1e-9) {
    throw ConfigError::for_key(
        "orb.patch_size", fmt::format("the descriptor pattern reaches {:.2f} px from the keypoint, "
                                      "beyond the patch radius {} (patch size {})",
                                      radius_px, config_.patch_size / 2, config_.patch_size));
  }
  scale_pyramid_ = make_scale_pyramid(config_.num_levels, config_.scale_factor);
  level_targets_ =
      features_per_level(config_.num_features, config_.num_levels, config_.scale_factor);
  // Disc of the orientation patch: (u, v) with u^2 + v^2 <= r^2. Symmetric in u and v, so a
  // rotation by 90 degrees maps the disc onto itself.
  const int radius = config_.patch_size / 2;
  circle_half_width_.resize(radius + 1);
  for (int v = 0; v <= radius; ++v) {
    int u = 0;
    while ((u + 1) * (u + 1) + v * v <= radius * radius) ++u;
    circle_half_width_[v] = u;
  }
  levels_.resize(config_.num_levels);
  scratch_ = std::make_unique<Scratch>();
  scratch_->levels.resize(config_.num_levels);
  if (config_.num_threads > 1) {
    scratch_->arena = std::make_unique<tbb::task_arena>(config_.num_threads);
  }
}

OrbExtractor::~OrbExtractor() = default;
OrbExtractor::OrbExtractor(OrbExtractor&&) noexcept = default;
OrbExtractor& OrbExtractor::operator=(OrbExtractor&&) noexcept = default;

void OrbExtractor::build_pyramid(const cv::Mat& gray) {
  levels_[0] = gray;
  for (int level = 1; level < config_.num_levels; ++level) {
    const cv::Size size = level_size(scale_pyramid_, level, gray.size());
    if (size.width < 1 || size.height < 1) {
      levels_[level].release();
      continue;
    }
    const cv::Mat& previous = levels_[level - 1];
    if (previous.empty()) {
      levels_[level].release();
      continue;
    }
    cv::resize(previous, levels_[level], size, 0, 0, cv::INTER_LINEAR);
  }
}

void OrbExtractor::process_level(int level, const cv::Mat& ignore_mask) {
  Scratch::Level& out = scratch_->levels[level];
  out.keypoints.clear();
  out.candidates.clear();
  const cv::Mat& image = levels_[level];
  const int edge = config_.edge_threshold;
  if (image.empty() || image.cols <= 2 * edge || image.rows <= 2 * edge ||
      level_targets_[level] <= 0) {
    return;
  }

  // 1. FAST-9 once over the level at the lower threshold. A corner is detected at threshold t
  //    exactly when its FAST score (the response) is >= t, and non-maximum suppression compares
  //    scores, so the corners found at the higher threshold are exactly those with a response
  //    >= fast_threshold_initial. Per cell we then keep those, or everything if the cell has none:
  //    ORB-SLAM2's per-cell two-threshold search, at a third of the cost of running FAST per cell.
  const cv::Rect roi(edge - kFastRadius, edge - kFastRadius, image.cols - 2 * (edge - kFastRadius),
                     image.rows - 2 * (edge - kFastRadius));
  cv::FAST(image(roi), out.candidates, config_.fast_threshold_min, /*nonmaxSuppression=*/true,
           cv::FastFeatureDetector::TYPE_9_16);
  const float area_w = static_cast<float>(image.cols - 2 * edge);
  const float area_h = static_cast<float>(image.rows - 2 * edge);
  const int cells_x = std::max(1, static_cast<int>(area_w) / config_.cell_size_px);
  const int cells_y = std::max(1, static_cast<int>(area_h) / config_.cell_size_px);
  auto cell_of = [&](const cv::Point2f& p) {  // p in level coordinates
    const int cx = std::clamp(static_cast<int>((p.x - edge) * cells_x / area_w), 0, cells_x - 1);
    const int cy = std::clamp(static_cast<int>((p.y - edge) * cells_y / area_h), 0, cells_y - 1);
    return cy * cells_x + cx;
  };
  std::vector<std::uint8_t>& cell_has_strong = out.cell_has_strong;
  cell_has_strong.assign(static_cast<std::size_t>(cells_x) * cells_y, 0);
  const float strong = static_cast<float>(config_.fast_threshold_initial);
  for (cv::KeyPoint& kp : out.candidates) {
    kp.pt.x += static_cast<float>(roi.x);
    kp.pt.y += static_cast<float>(roi.y);
    if (kp.response >= strong) cell_has_strong[cell_of(kp.pt)] = 1;
  }

  // 2. Threshold fallback per cell, and the ignore mask at level-0 positions, before the
  //    distribution so the budget goes to the remaining areas. The cell threshold is chosen with
  //    the masked corners counted, on purpose: a cell whose strong corners lie on a masked person
  //    refuses the weak corners beside the mask, which lie mostly on the person's unmasked edge.
  //    Dropping masked corners first (so the cell falls back to the low threshold) was measured
  //    on 2026-11-26: syn_walking_rpy ATE 0.0033 -> 0.0042 m, syn_walking_static 0.0020 -> 0.0028,
  //    composite mask IoU 0.491 -> 0.441 (docs/RESULTS.md, stop 12).
  const float sx = static_cast<float>(levels_[0].cols) / static_cast<float>(image.cols);
  const float sy = static_cast<float>(levels_[0].rows) / static_cast<float>(image.rows);
  const bool use_mask = !ignore_mask.empty();
  auto keep = [&](const cv::KeyPoint& kp) {
    if (kp.response < strong && cell_has_strong[cell_of(kp.pt)]) return false;
    if (use_mask) {
      const int x0 =
          std::clamp(nearest_pixel((kp.pt.x + 0.5f) * sx - 0.5f), 0, ignore_mask.cols - 1);
      const int y0 =
          std::clamp(nearest_pixel((kp.pt.y + 0.5f) * sy - 0.5f), 0, ignore_mask.rows - 1);
      if (ignore_mask.at<std::uint8_t>(y0, x0) != 0) return false;
    }
    return true;
  };
  out.candidates.erase(std::remove_if(out.candidates.begin(), out.candidates.end(),
                                      [&](const cv::KeyPoint& kp) { return !keep(kp); }),
                       out.candidates.end());

  // 3. Even spatial distribution over the keypoint area.
  distribute_quadtree(
      out.candidates,
      cv::Rect2f(static_cast<float>(edge), static_cast<float>(edge), area_w, area_h),
      level_targets_[level], out.tree, out.kept);

  // 4. Orientation on the unsmoothed level image, then descriptors on the smoothed one.
  out.keypoints.reserve(out.kept.size());
  const float size = static_cast<float>(config_.patch_size) * scale_pyramid_.scale_factors[level];
  for (int i : out.kept) {
    cv::KeyPoint kp = out.candidates[i];
    kp.angle =
        intensity_centroid_angle(image, cvRound(kp.pt.x), cvRound(kp.pt.y), circle_half_width_);
    kp.octave = level;
    kp.size = size;
    out.keypoints.push_back(kp);
  }
  if (out.keypoints.empty()) return;
  smooth_for_descriptor(image, out.blurred);
  out.descriptors.create(static_cast<int>(out.keypoints.size()), kDescriptorBytes, CV_8U);
  for (std::size_t k = 0; k < out.keypoints.size(); ++k) {
    const cv::KeyPoint& kp = out.keypoints[k];
    compute_steered_brief(out.blurred, cvRound(kp.pt.x), cvRound(kp.pt.y), kp.angle,
                          pattern_.data(), kDescriptorBits,
                          out.descriptors.ptr<std::uint8_t>(static_cast<int>(k)));
  }
}

OrbFeatures OrbExtractor::extract(const cv::Mat& gray, const cv::Mat& ignore_mask) {
  if (gray.empty() || gray.type() != CV_8UC1) {
    throw InputError(
        fmt::format("ORB extractor: the image must be a non-empty CV_8UC1 (grayscale) "
                    "image, got type {} size {}x{}",
                    gray.type(), gray.cols, gray.rows));
  }
  if (!ignore_mask.empty() &&
      (ignore_mask.type() != CV_8UC1 || ignore_mask.size() != gray.size())) {
    throw InputError(
        fmt::format("ORB extractor: the ignore mask must be CV_8UC1 of the image size "
                    "{}x{}, got type {} size {}x{}",
                    gray.cols, gray.rows, ignore_mask.type(), ignore_mask.cols, ignore_mask.rows));
  }

  build_pyramid(gray);
  const int num_levels = config_.num_levels;
  if (scratch_->arena) {
    // Levels are independent once the pyramid exists and each writes only its own scratch, so
    // the result does not depend on the schedule.
    scratch_->arena->execute([&] {
      tbb::parallel_for(0, num_levels, [&](int level) { process_level(level, ignore_mask); });
    });
  } else {
    for (int level = 0; level < num_levels; ++level) process_level(level, ignore_mask);
  }

  OrbFeatures features;
  features.pyramid = scale_pyramid_;
  std::size_t total = 0;
  for (const Scratch::Level& out : scratch_->levels) total += out.keypoints.size();
  features.keypoints.reserve(total);
  features.descriptors.create(static_cast<int>(total), kDescriptorBytes, CV_8U);
  int row = 0;
  for (int level = 0; level < num_levels; ++level) {
    const Scratch::Level& out = scratch_->levels[level];
    if (out.keypoints.empty()) continue;
    const cv::Mat& image = levels_[level];
    const float sx = static_cast<float>(gray.cols) / static_cast<float>(image.cols);
    const float sy = static_cast<float>(gray.rows) / static_cast<float>(image.rows);
    for (const cv::KeyPoint& kp_level : out.keypoints) {
      cv::KeyPoint kp = kp_level;
      // Pixel centres map as x0 + 0.5 = (xL + 0.5) * (cols0 / colsL) under cv::resize.
      kp.pt.x = (kp_level.pt.x + 0.5f) * sx - 0.5f;
      kp.pt.y = (kp_level.pt.y + 0.5f) * sy - 0.5f;
      features.keypoints.push_back(kp);
    }
    out.descriptors.copyTo(
        features.descriptors.rowRange(row, row + static_cast<int>(out.keypoints.size())));
    row += static_cast<int>(out.keypoints.size());
  }
  return features;
}

}  // namespace ddl::features
