#include "ddl/dynamics/free_space_check.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <string>

#include "ddl/core/error.h"

namespace ddl::dynamics {
namespace {

constexpr int kOverlapGridPx = 40;  // spacing of the coarse grid that measures a view's overlap
constexpr double kMaxPackedDepthM = 65.0;  // views' readings in mm fit 16 bits below this

/// The sample lattice of an image: sample (i, j) sits at pixel (j * s + s / 2, i * s + s / 2).
struct Lattice {
  int stride, rows, cols;
  Lattice(const cv::Size& size, int s)
      : stride(s),
        rows((size.height - s / 2 + s - 1) / s),
        cols((size.width - s / 2 + s - 1) / s) {}
  Lattice(const cv::Mat& image, int s) : Lattice(image.size(), s) {}
  int u(int j) const { return j * stride + stride / 2; }
  int v(int i) const { return i * stride + stride / 2; }
};

bool in_range(float z, const FreeSpaceConfig& config) {
  return z >= config.min_depth_m && z <= config.max_depth_m;
}

/// The votes must be those of an image of `size` (free_space_votes on it).
void check_votes_fit(const FreeSpaceVotes& votes, const cv::Size& size, const char* caller) {
  bool fit = votes.stride >= 1 && votes.depth_m.type() == CV_32FC1 && votes.depth_m.size() == size;
  if (fit) {
    const Lattice lattice(size, votes.stride);
    for (const cv::Mat* grid :
         {&votes.free_votes, &votes.static_votes, &votes.masked_votes, &votes.has_depth}) {
      fit = fit && grid->type() == CV_8UC1 && grid->rows == lattice.rows &&
            grid->cols == lattice.cols;
    }
  }
  if (!fit) {
    throw Error(
        fmt::format("{}: the votes (stride {}, {}x{} samples) are not those of a {}x{} "
                    "image",
                    caller, votes.stride, votes.free_votes.cols, votes.free_votes.rows, size.width,
                    size.height));
  }
}

}  // namespace

void FreeSpaceConfig::validate() const {
  auto fail = [](const char* key, const std::string& what) {
    throw ConfigError::for_key(std::string("dynamic.free_space.") + key, what);
  };
  if (max_reference_keyframes < 1 || max_reference_keyframes > 255)
    fail("max_reference_keyframes", "must be in 1..255");
  if (!(min_reference_age_s >= 0)) fail("min_reference_age_s", "must be >= 0");
  if (!(min_overlap >= 0 && min_overlap <= 1)) fail("min_overlap", "must be in [0, 1]");
  if (sample_stride_px < 1 || sample_stride_px > 32) fail("sample_stride_px", "must be in 1..32");
  if (!(depth_threshold_m > 0)) fail("depth_threshold_m", "must be > 0");
  if (!(depth_threshold_quadratic >= 0)) fail("depth_threshold_quadratic", "must be >= 0");
  if (!(min_depth_m > 0)) fail("min_depth_m", "must be > 0");
  if (!(max_depth_m > min_depth_m)) fail("max_depth_m", "must exceed min_depth_m");
  if (window_radius_px < 0 || window_radius_px > 10) fail("window_radius_px", "must be in 0..10");
  if (reference_mask_margin_px < 0 || reference_mask_margin_px > 50)
    fail("reference_mask_margin_px", "must be in 0..50");
  if (min_free_votes < 1 || min_free_votes > max_reference_keyframes)
    fail("min_free_votes", "must be in 1..max_reference_keyframes");
  if (!(max_static_per_free >= 0)) fail("max_static_per_free", "must be >= 0");
  if (min_region_px < 0 || min_region_px > 100'000'000)
    fail("min_region_px", "must be in 0..100000000");
  if (!(grow_step_m >= 0)) fail("grow_step_m", "must be >= 0 (0 = no growth)");
  if (!(grow_step_quadratic >= 0)) fail("grow_step_quadratic", "must be >= 0");
  if (!(grow_max_ratio >= 0 && grow_max_ratio <= 1000))
    fail("grow_max_ratio", "must be in [0, 1000]");
  if (!(max_static_region_share >= 0 && max_static_region_share <= 1))
    fail("max_static_region_share", "must be in [0, 1]");
}

FreeSpaceView prepare_free_space_view(const SE3& T_w_c, const cv::Mat& depth_m,
                                      const cv::Mat& dynamic_mask, const FreeSpaceConfig& config) {
  FreeSpaceView view;
  view.T_w_c = T_w_c;
  // Every reading counts, also those outside the samples' [min_depth_m, max_depth_m]: a far one
  // still saw the space before it empty, a near one hid what lies behind it. Only readings the
  // 16-bit packing cannot hold (65 m and beyond) are holes, like those without depth. The window
  // minimum over valid depths: holes must not count as near, so they become +inf for the
  // erosion and 0 again after it.
  cv::Mat valid_depth = depth_m.clone();
  const cv::Mat hole = (depth_m <= 0.0f) | (depth_m >= static_cast<float>(kMaxPackedDepthM));
  valid_depth.setTo(0.0f, hole);
  cv::Mat nearest = valid_depth.clone();
  nearest.setTo(std::numeric_limits<float>::infinity(), hole);
  const int r = config.window_radius_px;
  if (r > 0) {
    cv::erode(nearest, nearest, cv::getStructuringElement(cv::MORPH_RECT, {2 * r + 1, 2 * r + 1}));
  }
  nearest.setTo(0.0f, nearest == std::numeric_limits<float>::infinity());
  cv::Mat seen;
  valid_depth.convertTo(seen, CV_16U, 500.0);  // half millimetres: doubled, the low bit freed
  seen *= 2;
  if (!dynamic_mask.empty()) {
    cv::Mat masked = dynamic_mask != 0;
    const int m = config.reference_mask_margin_px;
    if (m > 0) {
      cv::dilate(masked, masked, cv::getStructuringElement(cv::MORPH_RECT, {2 * m + 1, 2 * m + 1}));
    }
    cv::add(seen, cv::Scalar(1), seen, masked & (seen > 0));
  }
  cv::Mat channels[2];
  nearest.convertTo(channels[0], CV_16U, 1000.0);  // below 65 000: readings of 65 m are holes
  channels[1] = seen;
  cv::merge(channels, 2, view.packed_mm);
  return view;
}

std::vector<std::size_t> select_free_space_views(const cv::Mat& depth_m, const SE3& T_c_w,
                                                 const std::vector<SE3>& views_T_w_c,
                                                 const camera::PinholeCamera& camera,
                                                 const FreeSpaceConfig& config) {
  const SE3 T_w_c = T_c_w.inverse();
  std::vector<Vec3d> grid_w;
  for (int v = kOverlapGridPx / 2; v < depth_m.rows; v += kOverlapGridPx) {
    for (int u = kOverlapGridPx / 2; u < depth_m.cols; u += kOverlapGridPx) {
      const float z = depth_m.at<float>(v, u);
      if (in_range(z, config)) grid_w.push_back(T_w_c * camera.unproject(u, v, z));
    }
  }
  std::vector<std::size_t> seeing;
  if (grid_w.empty()) return seeing;
  for (std::size_t k = 0; k < views_T_w_c.size(); ++k) {
    const SE3 T_r_w = views_T_w_c[k].inverse();
    std::size_t inside = 0;
    for (const Vec3d& p_w : grid_w) {
      const Vec3d p_r = T_r_w * p_w;
      if (p_r.z() >= config.min_depth_m && camera.in_image(camera.project(p_r))) ++inside;
    }
    if (static_cast<double>(inside) >= config.min_overlap * static_cast<double>(grid_w.size())) {
      seeing.push_back(k);
    }
  }
  const std::size_t n = static_cast<std::size_t>(config.max_reference_keyframes);
  if (seeing.size() <= n) return seeing;
  // Evenly spread from the first to the last, both included.
  std::vector<std::size_t> spread;
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t at = n == 1 ? seeing.size() - 1 : i * (seeing.size() - 1) / (n - 1);
    spread.push_back(seeing[at]);
  }
  return spread;
}

FreeSpaceVotes free_space_votes(const cv::Mat& depth_m, const SE3& T_c_w,
                                const std::vector<FreeSpaceView>& views,
                                const camera::PinholeCamera& camera,
                                const FreeSpaceConfig& config) {
  const Lattice lattice(depth_m, config.sample_stride_px);
  FreeSpaceVotes votes;
  votes.stride = config.sample_stride_px;
  votes.free_votes = cv::Mat::zeros(lattice.rows, lattice.cols, CV_8UC1);
  votes.static_votes = cv::Mat::zeros(lattice.rows, lattice.cols, CV_8UC1);
  votes.masked_votes = cv::Mat::zeros(lattice.rows, lattice.cols, CV_8UC1);
  votes.has_depth = cv::Mat::zeros(lattice.rows, lattice.cols, CV_8UC1);
  votes.depth_m = depth_m;
  std::vector<cv::Point> samples;
  std::vector<Eigen::Vector3f> points_c;
  for (int i = 0; i < lattice.rows; ++i) {
    for (int j = 0; j < lattice.cols; ++j) {
      const float z = depth_m.at<float>(lattice.v(i), lattice.u(j));
      if (!in_range(z, config)) continue;
      votes.has_depth.at<std::uint8_t>(i, j) = 1;
      samples.emplace_back(j, i);
      points_c.push_back(camera.unproject(lattice.u(j), lattice.v(i), z).cast<float>());
    }
  }
  const SE3 T_w_c = T_c_w.inverse();
  const auto fx = static_cast<float>(camera.fx), fy = static_cast<float>(camera.fy);
  const auto cx = static_cast<float>(camera.cx) + 0.5f, cy = static_cast<float>(camera.cy) + 0.5f;
  const auto min_z = static_cast<float>(config.min_depth_m);
  const auto tau0 = static_cast<float>(config.depth_threshold_m);
  const auto tau2 = static_cast<float>(config.depth_threshold_quadratic);
  std::uint8_t* free_votes = votes.free_votes.ptr<std::uint8_t>();
  std::uint8_t* static_votes = votes.static_votes.ptr<std::uint8_t>();
  std::uint8_t* masked_votes = votes.masked_votes.ptr<std::uint8_t>();
  const int grid_cols = lattice.cols;
  for (const FreeSpaceView& view : views) {
    const SE3 T_r_c = view.T_w_c.inverse() * T_w_c;
    const Eigen::Matrix3f R = T_r_c.rotation().cast<float>();
    const Eigen::Vector3f t = T_r_c.translation().cast<float>();
    const int w = view.packed_mm.cols, h = view.packed_mm.rows;
    const auto* packed = view.packed_mm.ptr<std::uint16_t>();  // continuous: made by cv::merge
    for (std::size_t k = 0; k < samples.size(); ++k) {
      const Eigen::Vector3f p_r = R * points_c[k] + t;
      const float z = p_r.z();
      if (z < min_z) continue;
      // +0.5 in cx, cy and truncation round the non-negative coordinates that matter.
      const float uf = fx * p_r.x() / z + cx, vf = fy * p_r.y() / z + cy;
      if (!(uf >= 0.0f && vf >= 0.0f && uf < static_cast<float>(w) && vf < static_cast<float>(h))) {
        continue;
      }
      const std::uint16_t* seen = packed + 2 * (static_cast<int>(vf) * w + static_cast<int>(uf));
      const float z_mm = 1000.0f * z;
      const float tau_mm = 1000.0f * (tau0 + tau2 * z * z);
      const int cell = samples[k].y * grid_cols + samples[k].x;
      if (static_cast<float>(seen[0]) > z_mm + tau_mm) {  // no valid depth is 0, never beyond z
        if (free_votes[cell] < 255) ++free_votes[cell];
      } else if (seen[1] >= 2 && std::abs(static_cast<float>(seen[1] & ~1u) - z_mm) < tau_mm) {
        std::uint8_t* vote = (seen[1] & 1u) != 0 ? &masked_votes[cell] : &static_votes[cell];
        if (*vote < 255) ++*vote;
      }
    }
  }
  return votes;
}

namespace {

/// Breadth-first growth of the kept samples (FreeSpaceConfig::grow_step_m): each region in
/// `labels` grows from its own samples, by at most grow_max_ratio times their count.
void grow_over_depth(const FreeSpaceVotes& votes, const Lattice& lattice, const cv::Mat& labels,
                     const std::vector<bool>& keep, const cv::Mat& region_stats,
                     const FreeSpaceConfig& config, cv::Mat& kept) {
  const int rows = lattice.rows, cols = lattice.cols;
  const auto z_at = [&](int i, int j) {
    return votes.depth_m.at<float>(lattice.v(i), lattice.u(j));
  };
  std::vector<int> budget(keep.size(), 0);
  for (std::size_t r = 1; r < keep.size(); ++r) {
    if (keep[r]) {
      budget[r] = static_cast<int>(config.grow_max_ratio *
                                   region_stats.at<int>(static_cast<int>(r), cv::CC_STAT_AREA));
    }
  }
  // The region each sample belongs to (0 = none); grown samples take their seed's region.
  cv::Mat owner = cv::Mat::zeros(rows, cols, CV_32S);
  std::vector<std::pair<int, int>> queue;
  for (int i = 0; i < rows; ++i) {
    for (int j = 0; j < cols; ++j) {
      if (kept.at<std::uint8_t>(i, j) == 0) continue;
      owner.at<int>(i, j) = labels.at<int>(i, j);
      queue.emplace_back(i, j);
    }
  }
  constexpr int kDi[4] = {-1, 1, 0, 0}, kDj[4] = {0, 0, -1, 1};
  for (std::size_t head = 0; head < queue.size(); ++head) {
    const auto [i, j] = queue[head];
    const int r = owner.at<int>(i, j);
    if (budget[static_cast<std::size_t>(r)] <= 0) continue;
    const float z = z_at(i, j);
    const double step = config.grow_step_m + config.grow_step_quadratic * z * z;
    for (int k = 0; k < 4; ++k) {
      const int ni = i + kDi[k], nj = j + kDj[k];
      if (ni < 0 || nj < 0 || ni >= rows || nj >= cols) continue;
      if (owner.at<int>(ni, nj) != 0 || votes.has_depth.at<std::uint8_t>(ni, nj) == 0) continue;
      if (votes.static_votes.at<std::uint8_t>(ni, nj) > 0 || std::abs(z_at(ni, nj) - z) >= step)
        continue;
      if (budget[static_cast<std::size_t>(r)]-- <= 0) break;
      owner.at<int>(ni, nj) = r;
      kept.at<std::uint8_t>(ni, nj) = 1;
      queue.emplace_back(ni, nj);
    }
  }
}

/// The full-resolution mask of the kept samples (FreeSpaceConfig and free_space_mask's doc).
cv::Mat lattice_to_pixels(const cv::Mat& depth_m, const FreeSpaceVotes& votes,
                          const Lattice& lattice, const cv::Mat& kept,
                          const FreeSpaceConfig& config) {
  const auto is_kept = [&](int i, int j) {
    return i >= 0 && j >= 0 && i < lattice.rows && j < lattice.cols &&
           kept.at<std::uint8_t>(i, j) != 0;
  };
  // Each pixel looks at the (up to) four samples around it: it joins when one of them is kept and
  // its own depth is within tau of that sample's; a pixel without depth takes its nearest sample.
  // Only the pixels near kept samples can join.
  const int s = votes.stride;
  const cv::Rect box = cv::boundingRect(kept);
  const int v_begin = std::max(0, box.y * s - s),
            v_end = std::min(depth_m.rows, (box.y + box.height + 1) * s);
  const int u_begin = std::max(0, box.x * s - s),
            u_end = std::min(depth_m.cols, (box.x + box.width + 1) * s);
  cv::Mat mask = cv::Mat::zeros(depth_m.size(), CV_8UC1);
  for (int v = v_begin; v < v_end; ++v) {
    const int i0 = (v - s / 2) >= 0 ? (v - s / 2) / s : -1;
    const int i_near = std::min(lattice.rows - 1, v / s);
    const float* z_row = depth_m.ptr<float>(v);
    std::uint8_t* out = mask.ptr<std::uint8_t>(v);
    for (int u = u_begin; u < u_end; ++u) {
      const int j0 = (u - s / 2) >= 0 ? (u - s / 2) / s : -1;
      const float z = z_row[u];
      if (z <= 0.0f) {
        if (is_kept(i_near, std::min(lattice.cols - 1, u / s))) out[u] = 255;
        continue;
      }
      for (int di = 0; di < 2 && out[u] == 0; ++di) {
        for (int dj = 0; dj < 2; ++dj) {
          const int i = i0 + di, j = j0 + dj;
          if (!is_kept(i, j)) continue;
          const float zs = depth_m.at<float>(lattice.v(i), lattice.u(j));
          if (std::abs(z - zs) < config.threshold_at(zs)) {
            out[u] = 255;
            break;
          }
        }
      }
    }
  }
  return mask;
}

}  // namespace

cv::Mat free_space_mask(const cv::Mat& depth_m, const FreeSpaceVotes& votes,
                        const FreeSpaceConfig& config, FreeSpaceStats* stats, cv::Mat* ungrown) {
  if (ungrown != nullptr) *ungrown = cv::Mat();
  if (votes.free_votes.empty()) return {};
  check_votes_fit(votes, depth_m.size(), "free_space_mask");
  const Lattice lattice(depth_m, votes.stride);
  cv::Mat dynamic = cv::Mat::zeros(lattice.rows, lattice.cols, CV_8UC1);
  int samples = 0, samples_dynamic = 0;
  for (int i = 0; i < lattice.rows; ++i) {
    for (int j = 0; j < lattice.cols; ++j) {
      if (votes.has_depth.at<std::uint8_t>(i, j) == 0) continue;
      ++samples;
      const int free = votes.free_votes.at<std::uint8_t>(i, j);
      const int fixed = votes.static_votes.at<std::uint8_t>(i, j);
      if (free >= config.min_free_votes && fixed <= config.max_static_per_free * free) {
        dynamic.at<std::uint8_t>(i, j) = 255;
        ++samples_dynamic;
      }
    }
  }
  if (stats != nullptr) {
    stats->samples = samples;
    stats->samples_dynamic = samples_dynamic;
  }
  if (samples_dynamic == 0) return {};
  // Lone samples and one-sample-wide lines are the noise of depth edges; then small regions go.
  cv::morphologyEx(dynamic, dynamic, cv::MORPH_OPEN,
                   cv::getStructuringElement(cv::MORPH_RECT, {3, 3}));
  cv::Mat labels, region_stats, centroids;
  const int n = cv::connectedComponentsWithStats(dynamic, labels, region_stats, centroids, 8);
  const int min_samples =
      (config.min_region_px + votes.stride * votes.stride - 1) / (votes.stride * votes.stride);
  std::vector<bool> keep(static_cast<std::size_t>(n), false);
  int regions = 0;
  for (int r = 1; r < n; ++r) {
    keep[static_cast<std::size_t>(r)] = region_stats.at<int>(r, cv::CC_STAT_AREA) >= min_samples;
    if (keep[static_cast<std::size_t>(r)]) ++regions;
  }
  if (stats != nullptr) stats->regions = regions;
  if (regions == 0) return {};
  cv::Mat kept = cv::Mat::zeros(lattice.rows, lattice.cols, CV_8UC1);
  for (int i = 0; i < lattice.rows; ++i) {
    for (int j = 0; j < lattice.cols; ++j) {
      if (keep[static_cast<std::size_t>(labels.at<int>(i, j))]) kept.at<std::uint8_t>(i, j) = 1;
    }
  }
  if (config.grow_step_m <= 0.0) {
    cv::Mat mask = lattice_to_pixels(depth_m, votes, lattice, kept, config);
    if (ungrown != nullptr) *ungrown = mask;
    return mask;
  }
  if (ungrown != nullptr) *ungrown = lattice_to_pixels(depth_m, votes, lattice, kept, config);
  grow_over_depth(votes, lattice, labels, keep, region_stats, config, kept);
  return lattice_to_pixels(depth_m, votes, lattice, kept, config);
}

cv::Mat drop_static_regions(const cv::Mat& mask, const FreeSpaceVotes& votes,
                            const FreeSpaceConfig& config, FreeSpaceStats* stats) {
  if (mask.empty() || votes.free_votes.empty() || config.max_static_region_share >= 1.0) {
    return mask;
  }
  check_votes_fit(votes, mask.size(), "drop_static_regions");
  cv::Mat binary = mask != 0;
  cv::Mat labels;
  const int n = cv::connectedComponents(binary, labels, 8, CV_32S);
  if (n <= 1) return mask;
  std::vector<int> with_depth(static_cast<std::size_t>(n), 0), seen_static(with_depth);
  const Lattice lattice(mask, votes.stride);
  for (int i = 0; i < lattice.rows; ++i) {
    for (int j = 0; j < lattice.cols; ++j) {
      const int r = labels.at<int>(lattice.v(i), lattice.u(j));
      if (r == 0 || votes.has_depth.at<std::uint8_t>(i, j) == 0) continue;
      ++with_depth[static_cast<std::size_t>(r)];
      if (votes.seen_static(i, j)) ++seen_static[static_cast<std::size_t>(r)];
    }
  }
  std::vector<bool> drop(static_cast<std::size_t>(n), false);
  int dropped = 0;
  for (std::size_t r = 1; r < drop.size(); ++r) {
    drop[r] = seen_static[r] > config.max_static_region_share * with_depth[r];
    if (drop[r]) ++dropped;
  }
  if (stats != nullptr) stats->regions_dropped += dropped;
  if (dropped == 0 && !config.carve_static_samples) return mask;
  cv::Mat out = mask.clone();
  const int s = votes.stride;
  for (int v = 0; v < out.rows; ++v) {
    const int* l = labels.ptr<int>(v);
    std::uint8_t* o = out.ptr<std::uint8_t>(v);
    const int i = std::min(lattice.rows - 1, v / s);
    for (int u = 0; u < out.cols; ++u) {
      if (l[u] == 0) continue;
      if (drop[static_cast<std::size_t>(l[u])]) {
        o[u] = 0;
      } else if (config.carve_static_samples) {
        const int j = std::min(lattice.cols - 1, u / s);
        if (votes.has_depth.at<std::uint8_t>(i, j) == 0 || !votes.clearly_static(i, j)) continue;
        // A pixel of the cell at another depth (a person in front of the wall sample) stays.
        const float z = votes.depth_m.at<float>(v, u);
        const float zs = votes.depth_m.at<float>(lattice.v(i), lattice.u(j));
        if (z <= 0.0f || std::abs(z - zs) < config.threshold_at(zs)) o[u] = 0;
      }
    }
  }
  return out;
}

}  // namespace ddl::dynamics
