#pragma once
// ORB feature extraction in the manner of ORB-SLAM2 (Mur-Artal & Tardos, T-RO 2017, section
// III-A; Rublee et al., ICCV 2011): an image pyramid, FAST-9 corners found per grid cell with a
// lower threshold as fallback, an even spatial spread by quadtree subdivision, orientation by
// intensity centroid and steered 256-bit BRIEF descriptors. See docs/features.md.
//
// Coordinates: keypoints are reported in level-0 (input image) pixel coordinates, (0, 0) the
// centre of the top-left pixel; y down. A level-L pixel x_L maps to level 0 by
// x_0 = (x_L + 0.5) * (cols_0 / cols_L) - 0.5 (the pixel-centre convention of cv::resize), which
// ORB-SLAM2 approximates by x_L * scale^L.
//
// Threading: an OrbExtractor keeps per-call scratch buffers, so extract() must not be called on
// one instance from two threads at once; use one extractor per thread. Output is deterministic:
// the same image and mask always give identical keypoints and descriptors, whatever the number
// of threads.

#include <cstdint>
#include <memory>
#include <opencv2/core.hpp>
#include <vector>

#include "ddl/features/brief_pattern.h"

namespace ddl::features {

/// Settings of the ORB extractor. Defaults are ORB-SLAM2's TUM settings (DDL-SLAM paper, section
/// IV). Keys in error messages are "orb.<field>".
struct OrbExtractorConfig {
  int num_features = 1000;          // total keypoints wanted over all levels
  double scale_factor = 1.2;        // size ratio between consecutive pyramid levels (> 1)
  int num_levels = 8;               // pyramid levels, level 0 = input image
  int fast_threshold_initial = 20;  // FAST intensity threshold tried first in every cell
  int fast_threshold_min = 7;       // FAST threshold used in cells where the first finds nothing
  int edge_threshold = 19;          // keypoints keep this many pixels from each level's border
  int patch_size = 31;              // descriptor/orientation patch diameter in pixels (odd)
  int cell_size_px = 30;            // side of the FAST grid cells, level pixels (ORB-SLAM2: 30)
  int num_threads = 1;              // threads computing pyramid levels (1 = calling thread only)

  /// Throws ddl::ConfigError naming the key ("orb.num_features", ...) on a bad value.
  void validate() const;
  /// validate(), and for images of `width` x `height`: throws ddl::ConfigError naming
  /// "orb.num_levels" when a pyramid level is too small to hold a keypoint (not more than
  /// 2 edge_threshold pixels wide or high). Such a level's share of num_features would be lost.
  void validate_for_image(int width, int height) const;
};

/// Per-level scale values that tracking needs (ORB-SLAM2's mvScaleFactors, mvLevelSigma2, ...).
/// Index = pyramid level (keypoint octave).
struct ScalePyramid {
  int num_levels = 0;
  double scale_factor = 1.0;             // ratio between consecutive levels
  double log_scale_factor = 0.0;         // ln(scale_factor), to predict a level from distance
  std::vector<float> scale_factors;      // scale_factor^level
  std::vector<float> inv_scale_factors;  // 1 / scale_factor^level
  std::vector<float> level_sigma2;       // scale_factor^(2 level): keypoint position variance
  std::vector<float> inv_level_sigma2;   // 1 / level_sigma2 (information weight)
};

/// Builds the ScalePyramid of `num_levels` levels with ratio `scale_factor`.
ScalePyramid make_scale_pyramid(int num_levels, double scale_factor);

/// The keypoints of one image and their descriptors. Keypoints are grouped by level (level 0
/// first), in raster order (row by row) within a level.
struct OrbFeatures {
  /// pt: level-0 pixel coordinates; octave: pyramid level; angle: orientation in degrees [0, 360);
  /// response: FAST score; size: patch_size * scale_factor^octave (level-0 pixels).
  std::vector<cv::KeyPoint> keypoints;
  /// keypoints.size() x 32, CV_8U: row i is the 256-bit descriptor of keypoints[i].
  cv::Mat descriptors;
  /// Scale values of the pyramid the keypoints come from.
  ScalePyramid pyramid;
};

/// Number of keypoints wanted on each level: ORB-SLAM2's geometric series with ratio
/// 1 / scale_factor, summing to num_features (the last level takes the remainder).
std::vector<int> features_per_level(int num_features, int num_levels, double scale_factor);

/// Smooths a pyramid level before the binary tests: 7x7 Gaussian, sigma 2, reflected border (as
/// ORB), which makes single-pixel comparisons robust to noise.
void smooth_for_descriptor(const cv::Mat& level_image, cv::Mat& smoothed);

/// Steered BRIEF (ORB section 4.1): test k compares the smoothed image at the keypoint (x, y)
/// (level pixels) plus pairs[k]'s two points rotated by `angle_deg`: bit k = I(a) < I(b), packed
/// least significant bit first into out[k / 8]. (x, y) must be at least the pattern radius + 1
/// pixels inside the image. Writes ceil(num_pairs / 8) bytes.
void compute_steered_brief(const cv::Mat& smoothed, int x, int y, float angle_deg,
                           const BriefPair* pairs, int num_pairs, std::uint8_t* out);

class OrbExtractor {
 public:
  /// Validates the config (throws ddl::ConfigError naming the key). `pattern` defaults to the
  /// project's learned pattern; its points must lie within the orientation patch.
  explicit OrbExtractor(const OrbExtractorConfig& config,
                        const BriefPattern& pattern = default_brief_pattern());
  ~OrbExtractor();
  OrbExtractor(OrbExtractor&&) noexcept;
  OrbExtractor& operator=(OrbExtractor&&) noexcept;
  OrbExtractor(const OrbExtractor&) = delete;
  OrbExtractor& operator=(const OrbExtractor&) = delete;

  /// Extracts keypoints and descriptors from a grayscale CV_8UC1 image. `ignore_mask` is empty or
  /// a CV_8UC1 image of the same size whose non-zero pixels must not hold keypoints (the dynamic
  /// mask): candidates whose level-0 position falls there are dropped before the spatial
  /// distribution, so the feature budget goes to the rest of the image. Throws ddl::InputError
  /// on an image or mask of the wrong type or size.
  OrbFeatures extract(const cv::Mat& gray, const cv::Mat& ignore_mask = cv::Mat());

  const OrbExtractorConfig& config() const { return config_; }
  const ScalePyramid& scale_pyramid() const { return scale_pyramid_; }
  const BriefPattern& pattern() const { return pattern_; }
  /// Target keypoint count per level (features_per_level of the config).
  const std::vector<int>& level_targets() const { return level_targets_; }
  /// Pyramid images of the last extract() call (level 0 shares the input's pixels).
  const std::vector<cv::Mat>& pyramid_images() const { return levels_; }

 private:
  struct Scratch;  // per-level buffers and the thread arena (orb_extractor.cc)

  void build_pyramid(const cv::Mat& gray);
  void process_level(int level, const cv::Mat& ignore_mask);

  OrbExtractorConfig config_;
  ScalePyramid scale_pyramid_;
  std::vector<int> level_targets_;
  BriefPattern pattern_;
  std::vector<int> circle_half_width_;  // u_max(v) of the orientation disc, v = 0..radius
  std::vector<cv::Mat> levels_;
  std::unique_ptr<Scratch> scratch_;
};

}  // namespace ddl::features
