#include "ddl/inpainting/background_inpainter.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <opencv2/photo.hpp>
#include <optional>
#include <vector>

#include "ddl/core/error.h"

namespace ddl::inpainting {

void InpaintingConfig::validate() const {
  auto fail = [](const char* key, const char* what) {
    throw ConfigError::for_key(std::string("dense.inpainting.") + key, what);
  };
  if (num_keyframes < 1 || num_keyframes > 255) fail("num_keyframes", "must be in 1..255");
  if (extra_keyframes < 0 || extra_keyframes > 255 - num_keyframes) {
    fail("extra_keyframes", "must be >= 0, with num_keyframes + extra_keyframes <= 255");
  }
  if (splat_radius_px < 0 || splat_radius_px > 4) fail("splat_radius_px", "must be in 0..4");
  if (!(depth_tolerance_m >= 0)) fail("depth_tolerance_m", "must be >= 0");
  if (!(depth_tolerance_rel >= 0 && depth_tolerance_rel < 1))
    fail("depth_tolerance_rel", "must be in [0, 1)");
  if (!(max_depth_m > 0)) fail("max_depth_m", "must be > 0");
  if (max_hole_area_px < 0) fail("max_hole_area_px", "must be >= 0");
  if (source_stride_px < 1) fail("source_stride_px", "must be >= 1");
  if (see_through_votes < 0) fail("see_through_votes", "must be >= 0");
}

namespace {

// Samples nearer than this to the current camera are ignored (below any RGB-D sensor's range);
// it bounds the source window of each keyframe.
constexpr double kMinSampleDepth = 0.3;

/// Splatting copies a source pixel to the nearest target pixels, which shifts fine texture by up
/// to half a pixel (more with the splat radius). Each filled pixel instead takes its colour from
/// the winning source, at the position where its splatted 3-D point lands there, bilinearly;
/// positions next to excluded source pixels, or whose four source pixels do not all see that
/// point (depth off by more than the tolerance: an occluder or a depth edge), keep the splatted
/// colour.
void resample_colour(InpaintingResult& out, const cv::Mat& zbuf, const cv::Mat& winner,
                     const SE3& T_c_w, const std::vector<SourceView>& sources,
                     const camera::PinholeCamera& camera, const InpaintingConfig& config) {
  std::vector<SE3> T_src_cur;
  for (const SourceView& src : sources) T_src_cur.push_back(src.T_w_c.inverse() * T_c_w.inverse());
  for (int y = 0; y < out.filled.rows; ++y) {
    const std::uint8_t* frow = out.filled.ptr(y);
    const float* zrow = zbuf.ptr<float>(y);
    const std::uint8_t* wrow = winner.ptr(y);
    cv::Vec3b* crow = out.bgr.ptr<cv::Vec3b>(y);
    for (int x = 0; x < out.filled.cols; ++x) {
      if (frow[x] == 0) continue;
      const SourceView& src = sources[wrow[x]];
      const double z = zrow[x];
      const Vec3d p = T_src_cur[wrow[x]] *
                      Vec3d((x - camera.cx) / camera.fx * z, (y - camera.cy) / camera.fy * z, z);
      if (p.z() <= 0.05) continue;
      const double us = camera.fx * p.x() / p.z() + camera.cx;
      const double vs = camera.fy * p.y() / p.z() + camera.cy;
      const int u0 = static_cast<int>(std::floor(us));
      const int v0 = static_cast<int>(std::floor(vs));
      if (u0 < 0 || v0 < 0 || u0 + 1 >= src.bgr.cols || v0 + 1 >= src.bgr.rows) continue;
      if (!src.exclude_mask.empty() && (src.exclude_mask.at<std::uint8_t>(v0, u0) |
                                        src.exclude_mask.at<std::uint8_t>(v0, u0 + 1) |
                                        src.exclude_mask.at<std::uint8_t>(v0 + 1, u0) |
                                        src.exclude_mask.at<std::uint8_t>(v0 + 1, u0 + 1)) != 0) {
        continue;
      }
      const float tol =
          static_cast<float>(config.depth_tolerance_m + config.depth_tolerance_rel * p.z());
      bool consistent = true;
      for (int dv = 0; dv <= 1 && consistent; ++dv) {
        for (int du = 0; du <= 1 && consistent; ++du) {
          consistent = std::abs(src.depth_m.at<float>(v0 + dv, u0 + du) - p.z()) <= tol;
        }
      }
      if (!consistent) continue;
      const double a = us - u0;
      const double b = vs - v0;
      const cv::Vec3b& c00 = src.bgr.at<cv::Vec3b>(v0, u0);
      const cv::Vec3b& c01 = src.bgr.at<cv::Vec3b>(v0, u0 + 1);
      const cv::Vec3b& c10 = src.bgr.at<cv::Vec3b>(v0 + 1, u0);
      const cv::Vec3b& c11 = src.bgr.at<cv::Vec3b>(v0 + 1, u0 + 1);
      for (int k = 0; k < 3; ++k) {
        const double value =
            (1 - b) * ((1 - a) * c00[k] + a * c01[k]) + b * ((1 - a) * c10[k] + a * c11[k]);
        crow[x][k] = cv::saturate_cast<std::uint8_t>(value);
      }
    }
  }
}

/// Where the frustum through the pixel rectangle [x0, x1] x [y0, y1] of one camera, between depths
/// z_near and z_far, lands in another camera (p_other = R * p + t): the bounding box of its 8
/// corners' projections, 1 px wider on the low side and 2 on the high side (rounding, and
/// cv::Rect's exclusive end). The frustum is convex, and so is its image when every corner lies
/// in front of the other camera, so the box bounds the projection of every point inside; none
/// when a corner lies less than 5 cm in front of it. `z_min_other`, when given, receives the
/// smallest depth of the frustum in the other camera (that of a corner, as depth is linear).
std::optional<cv::Rect> projected_frustum_box(int x0, int y0, int x1, int y1, double z_near,
                                              double z_far, const Mat3d& R, const Vec3d& t,
                                              const camera::PinholeCamera& camera,
                                              double* z_min_other = nullptr) {
  double u_min = std::numeric_limits<double>::infinity(), v_min = u_min;
  double u_max = -u_min, v_max = -u_min;
  double z_min = u_min;
  for (const double z : {z_near, z_far}) {
    for (const int x : {x0, x1}) {
      for (const int y : {y0, y1}) {
        const Vec3d p =
            R * Vec3d((x - camera.cx) / camera.fx * z, (y - camera.cy) / camera.fy * z, z) + t;
        if (p.z() <= 0.05) return std::nullopt;
        z_min = std::min(z_min, p.z());
        const double u = camera.fx * p.x() / p.z() + camera.cx;
        const double v = camera.fy * p.y() / p.z() + camera.cy;
        u_min = std::min(u_min, u);
        u_max = std::max(u_max, u);
        v_min = std::min(v_min, v);
        v_max = std::max(v_max, v);
      }
    }
  }
  if (z_min_other != nullptr) *z_min_other = z_min;
  const double big = 1e6;  // keeps the casts defined for far-off projections
  return cv::Rect(cv::Point(static_cast<int>(std::floor(std::clamp(u_min, -big, big))) - 1,
                            static_cast<int>(std::floor(std::clamp(v_min, -big, big))) - 1),
                  cv::Point(static_cast<int>(std::ceil(std::clamp(u_max, -big, big))) + 2,
                            static_cast<int>(std::ceil(std::clamp(v_max, -big, big))) + 2));
}

/// The source pixels whose samples can land in `target_box` of the current image: the part of
/// the current view through that box (and the pixel ring around it) between kMinSampleDepth and
/// max_depth_m, projected into the source. The whole source image when a corner lies behind the
/// source camera.
cv::Rect source_window(const cv::Rect& target_box, const SE3& T_src_cur,
                       const camera::PinholeCamera& camera, double max_depth_m,
                       cv::Size source_size) {
  const cv::Rect whole({0, 0}, source_size);
  const std::optional<cv::Rect> box =
      projected_frustum_box(target_box.x - 1, target_box.y - 1, target_box.x + target_box.width,
                            target_box.y + target_box.height, kMinSampleDepth, max_depth_m,
                            T_src_cur.rotation(), T_src_cur.translation(), camera);
  return box ? *box & whole : whole;
}

/// Source blocks of kCullBlock x kCullBlock pixels (aligned to the image origin) whose samples
/// cannot land in the reach mask are skipped without projecting each pixel. The samples of a block
/// a pass uses lie, in the source camera, inside the frustum through its pixel rectangle between
/// the smallest and the largest depth of those samples, so projected_frustum_box bounds every
/// sample's target pixel. A block whose box holds no reach pixel is skipped: the splatted result is
/// the same, sample for sample and in the same order.
constexpr int kCullBlock = DepthBlocks::kBlock;

/// DepthBlocks over the blocks that overlap `window` (the others are left without depth), of the
/// samples outside `exclude` (may be empty), split by `repaired` (may be empty).
DepthBlocks block_depth_range(const cv::Mat& depth_m, const cv::Mat& exclude,
                              const cv::Mat& repaired, const cv::Rect& window) {
  DepthBlocks range;
  range.blocks_x = (depth_m.cols + kCullBlock - 1) / kCullBlock;
  range.blocks_y = (depth_m.rows + kCullBlock - 1) / kCullBlock;
  const std::size_t n = static_cast<std::size_t>(range.blocks_x) * range.blocks_y;
  constexpr float kInf = std::numeric_limits<float>::infinity();
  for (DepthBlocks::Range* r : {&range.all, &range.observed, &range.repaired}) {
    r->z_min.assign(n, kInf);
    r->z_max.assign(n, 0.0f);
  }
  if (window.empty()) return range;
  const int bx_begin = window.x / kCullBlock;
  const int bx_end = (window.x + window.width - 1) / kCullBlock;  // inclusive
  const int y_begin = window.y / kCullBlock * kCullBlock;
  const int y_end =
      std::min(((window.y + window.height - 1) / kCullBlock + 1) * kCullBlock, depth_m.rows);
  for (int y = y_begin; y < y_end; ++y) {
    const float* row = depth_m.ptr<float>(y);
    const std::uint8_t* xrow = exclude.empty() ? nullptr : exclude.ptr(y);
    const std::uint8_t* rrow = repaired.empty() ? nullptr : repaired.ptr(y);
    const std::size_t base = static_cast<std::size_t>(y / kCullBlock) * range.blocks_x;
    for (int bx = bx_begin; bx <= bx_end; ++bx) {
      const int x1 = std::min((bx + 1) * kCullBlock, depth_m.cols);
      // [0] observed, [1] repaired.
      float lo[2] = {range.observed.z_min[base + bx], range.repaired.z_min[base + bx]};
      float hi[2] = {range.observed.z_max[base + bx], range.repaired.z_max[base + bx]};
      for (int x = bx * kCullBlock; x < x1; ++x) {
        // Finite positive depths only (an infinite one would make the corners NaN, which min
        // and max skip); samples of any other depth are rejected by the splat loop anyway, as
        // are excluded ones.
        const float z = row[x];
        const bool usable = z > 0.0f && z < kInf && (xrow == nullptr || xrow[x] == 0);
        const int k = (rrow != nullptr && rrow[x] != 0) ? 1 : 0;
        lo[k] = std::min(lo[k], usable ? z : kInf);
        hi[k] = std::max(hi[k], usable ? z : 0.0f);
      }
      range.observed.z_min[base + bx] = lo[0];
      range.observed.z_max[base + bx] = hi[0];
      range.repaired.z_min[base + bx] = lo[1];
      range.repaired.z_max[base + bx] = hi[1];
      range.all.z_min[base + bx] = std::min(lo[0], lo[1]);
      range.all.z_max[base + bx] = std::max(hi[0], hi[1]);
    }
  }
  return range;
}

/// Per block of the source: 1 = some sample of it may land in the reach mask.
std::vector<std::uint8_t> active_blocks(const DepthBlocks::Range& range, int blocks_x,
                                        const cv::Rect& window, const SE3& T_cur_src,
                                        const camera::PinholeCamera& camera,
                                        const cv::Mat& reach_sum, const cv::Rect& reach_box) {
  std::vector<std::uint8_t> active(range.z_min.size(), 0);
  if (window.empty()) return active;
  const Mat3d R = T_cur_src.rotation();
  const Vec3d t = T_cur_src.translation();
  const int bx_end = (window.x + window.width - 1) / kCullBlock;
  const int by_end = (window.y + window.height - 1) / kCullBlock;
  for (int by = window.y / kCullBlock; by <= by_end; ++by) {
    for (int bx = window.x / kCullBlock; bx <= bx_end; ++bx) {
      const std::size_t i = static_cast<std::size_t>(by) * blocks_x + bx;
      if (range.z_max[i] <= 0.0f) continue;  // no usable depth in the block
      const int x0 = bx * kCullBlock;
      const int y0 = by * kCullBlock;
      const std::optional<cv::Rect> frustum =
          projected_frustum_box(x0, y0, x0 + kCullBlock - 1, y0 + kCullBlock - 1, range.z_min[i],
                                range.z_max[i], R, t, camera);
      if (!frustum) {
        active[i] = 1;  // a corner behind the current camera: no bound
        continue;
      }
      const cv::Rect box = *frustum & reach_box;
      if (box.empty()) continue;
      const int reached = reach_sum.at<int>(box.y + box.height, box.x + box.width) -
                          reach_sum.at<int>(box.y, box.x + box.width) -
                          reach_sum.at<int>(box.y + box.height, box.x) +
                          reach_sum.at<int>(box.y, box.x);
      active[i] = reached > 0 ? 1 : 0;
    }
  }
  return active;
}

/// Multi-view check of the filled pixels: a filled point that at least see_through_votes other
/// sources saw through (their observed, unexcluded depth at its projection lies farther than it
/// by more than the tolerance) was empty space when they were taken, so it is a piece of a moving
/// object that its source's mask missed; the pixel is left unfilled (the original frame's values
/// come back). Static background is never seen through, except across depth edges within pose
/// and depth error, hence more than one vote. Only a finite, positive source depth votes. The
/// pixels are taken in tiles of kCullBlock x kCullBlock; with skip_unreachable_blocks a source
/// that cannot vote for any pixel of a tile is not asked for each: the tile's filled points
/// (between their smallest and largest depth) land outside its image, or nothing it observed
/// there (its DepthBlocks, when given) lies farther than the nearest of them by the tolerance.
/// The votes, and so the result, are the same.
void reject_seen_through(InpaintingResult& out, const cv::Mat& zbuf, const cv::Mat& winner,
                         const cv::Mat& bgr, const cv::Mat& depth_m, const SE3& T_c_w,
                         const std::vector<SourceView>& sources, std::size_t count,
                         const camera::PinholeCamera& camera, const InpaintingConfig& config) {
  std::vector<SE3> T_src_cur;
  for (std::size_t s = 0; s < count; ++s) {
    T_src_cur.push_back(sources[s].T_w_c.inverse() * T_c_w.inverse());
  }
  // Two depths count as one surface within this (the z-buffer's tolerance).
  auto tolerance = [&](double z) {
    return config.depth_tolerance_m + config.depth_tolerance_rel * z;
  };
  std::vector<std::size_t> candidates;
  candidates.reserve(count);
  for (int ty = 0; ty < out.filled.rows; ty += kCullBlock) {
    for (int tx = 0; tx < out.filled.cols; tx += kCullBlock) {
      const int tx1 = std::min(tx + kCullBlock, out.filled.cols);  // exclusive
      const int ty1 = std::min(ty + kCullBlock, out.filled.rows);
      float z_lo = std::numeric_limits<float>::infinity();
      float z_hi = 0.0f;
      for (int y = ty; y < ty1; ++y) {
        const std::uint8_t* frow = out.filled.ptr(y);
        const float* zrow = zbuf.ptr<float>(y);
        for (int x = tx; x < tx1; ++x) {
          if (frow[x] == 0) continue;
          z_lo = std::min(z_lo, zrow[x]);
          z_hi = std::max(z_hi, zrow[x]);
        }
      }
      if (z_hi <= 0.0f) continue;  // no filled pixel in the tile
      candidates.clear();
      for (std::size_t s = 0; s < count; ++s) {
        const SourceView& src = sources[s];
        if (!config.skip_unreachable_blocks) {  // every source asked for every pixel
          candidates.push_back(s);
          continue;
        }
        double z_near = 0.0;
        const std::optional<cv::Rect> box =
            projected_frustum_box(tx, ty, tx1 - 1, ty1 - 1, z_lo, z_hi, T_src_cur[s].rotation(),
                                  T_src_cur[s].translation(), camera, &z_near);
        if (box) {
          const cv::Rect in_image = *box & cv::Rect({0, 0}, src.depth_m.size());
          if (in_image.empty()) continue;
          if (src.blocks) {
            // The farthest observed depth under the box, against the nearest vote threshold.
            const DepthBlocks& blocks = *src.blocks;
            float farthest = 0.0f;
            for (int by = in_image.y / kCullBlock;
                 by <= (in_image.y + in_image.height - 1) / kCullBlock; ++by) {
              for (int bx = in_image.x / kCullBlock;
                   bx <= (in_image.x + in_image.width - 1) / kCullBlock; ++bx) {
                farthest = std::max(
                    farthest,
                    blocks.observed.z_max[static_cast<std::size_t>(by) * blocks.blocks_x + bx]);
              }
            }
            // A voter's point lies at least this deep in the source (the frustum's nearest
            // corner, and a vote needs kMinSampleDepth).
            const double z_vote = std::max(z_near, kMinSampleDepth);
            if (farthest < z_vote + tolerance(z_vote) - 1e-4) continue;
          }
        }
        candidates.push_back(s);
      }
      if (candidates.empty()) continue;
      for (int y = ty; y < ty1; ++y) {
        std::uint8_t* frow = out.filled.ptr(y);
        const float* zrow = zbuf.ptr<float>(y);
        const std::uint8_t* wrow = winner.ptr(y);
        for (int x = tx; x < tx1; ++x) {
          if (frow[x] == 0) continue;
          const double z = zrow[x];
          const Vec3d p_cur((x - camera.cx) / camera.fx * z, (y - camera.cy) / camera.fy * z, z);
          int votes = 0;
          for (const std::size_t s : candidates) {
            if (votes >= config.see_through_votes) break;
            if (s == wrow[x]) continue;
            const SourceView& src = sources[s];
            const Vec3d p = T_src_cur[s] * p_cur;
            if (p.z() < kMinSampleDepth) continue;
            const int u = cvRound(camera.fx * p.x() / p.z() + camera.cx);
            const int v = cvRound(camera.fy * p.y() / p.z() + camera.cy);
            if (u < 0 || v < 0 || u >= src.depth_m.cols || v >= src.depth_m.rows) continue;
            if (!src.exclude_mask.empty() && src.exclude_mask.at<std::uint8_t>(v, u) != 0) {
              continue;
            }
            if (!src.repaired_mask.empty() && src.repaired_mask.at<std::uint8_t>(v, u) != 0) {
              continue;
            }
            const float d = src.depth_m.at<float>(v, u);
            if (d > 0.0f && d < std::numeric_limits<float>::infinity() &&
                d > p.z() + tolerance(p.z())) {
              ++votes;  // a finite depth only, as the blocks bound (none is infinite from a sensor)
            }
          }
          if (votes >= config.see_through_votes) {
            frow[x] = 0;
            out.bgr.at<cv::Vec3b>(y, x) = bgr.at<cv::Vec3b>(y, x);
            out.depth_m.at<float>(y, x) = depth_m.at<float>(y, x);
          }
        }
      }
    }
  }
}

/// Whether `blocks` has the layout of depth_blocks(depth_m) and was computed with the source's
/// masks (their buffers; it cannot tell the depths or the mask contents apart).
bool matches(const DepthBlocks& blocks, const SourceView& src) {
  const cv::Mat& depth_m = src.depth_m;
  if (blocks.exclude_data != (src.exclude_mask.empty() ? nullptr : src.exclude_mask.data) ||
      blocks.repaired_data != (src.repaired_mask.empty() ? nullptr : src.repaired_mask.data)) {
    return false;
  }
  const int bx = (depth_m.cols + kCullBlock - 1) / kCullBlock;
  const int by = (depth_m.rows + kCullBlock - 1) / kCullBlock;
  const std::size_t n = static_cast<std::size_t>(bx) * static_cast<std::size_t>(by);
  for (const DepthBlocks::Range* r : {&blocks.all, &blocks.observed, &blocks.repaired}) {
    if (r->z_min.size() != n || r->z_max.size() != n) return false;
  }
  return blocks.blocks_x == bx && blocks.blocks_y == by;
}

}  // namespace

DepthBlocks depth_blocks(const cv::Mat& depth_m, const cv::Mat& exclude_mask,
                         const cv::Mat& repaired_mask) {
  if (depth_m.type() != CV_32FC1) throw Error("depth_blocks: expects CV_32FC1 depth");
  for (const cv::Mat* m : {&exclude_mask, &repaired_mask}) {
    if (!m->empty() && (m->type() != CV_8UC1 || m->size() != depth_m.size())) {
      throw Error("depth_blocks: masks must be CV_8UC1 of the depth's size (or empty)");
    }
  }
  DepthBlocks blocks =
      block_depth_range(depth_m, exclude_mask, repaired_mask, cv::Rect({0, 0}, depth_m.size()));
  blocks.exclude_data = exclude_mask.empty() ? nullptr : exclude_mask.data;
  blocks.repaired_data = repaired_mask.empty() ? nullptr : repaired_mask.data;
  return blocks;
}

InpaintingResult inpaint(const cv::Mat& bgr, const cv::Mat& depth_m, const cv::Mat& mask,
                         const SE3& T_c_w, const std::vector<SourceView>& sources,
                         const camera::PinholeCamera& camera, const InpaintingConfig& config) {
  if (bgr.type() != CV_8UC3 || depth_m.type() != CV_32FC1 || mask.type() != CV_8UC1 ||
      bgr.size() != depth_m.size() || bgr.size() != mask.size()) {
    throw Error("inpaint: expects CV_8UC3 colour, CV_32FC1 depth and CV_8UC1 mask of one size");
  }
  InpaintingResult out;
  out.bgr = bgr.clone();
  out.depth_m = depth_m.clone();
  out.filled = cv::Mat::zeros(mask.size(), CV_8UC1);
  out.image_filled = cv::Mat::zeros(mask.size(), CV_8UC1);
  out.masked_pixels = cv::countNonZero(mask);
  if (out.masked_pixels == 0) {
    out.unfilled = out.filled.clone();
    return out;
  }
  // z-buffer over the masked pixels only; +inf = nothing yet.
  cv::Mat zbuf(mask.size(), CV_32FC1, cv::Scalar(std::numeric_limits<float>::infinity()));
  const int w = mask.cols;
  const int h = mask.rows;
  const int r = config.splat_radius_px;
  const float tol_abs = static_cast<float>(config.depth_tolerance_m);
  const float tol_rel = static_cast<float>(config.depth_tolerance_rel);
  const double fx = camera.fx, fy = camera.fy, cx = camera.cx, cy = camera.cy;
  // (u - cx) / fx of every source column, the same value the expression gives in the loop.
  int source_cols = 0;
  for (const SourceView& src : sources) source_cols = std::max(source_cols, src.depth_m.cols);
  std::vector<double> x_norm(static_cast<std::size_t>(source_cols));
  for (int u = 0; u < source_cols; ++u) x_norm[static_cast<std::size_t>(u)] = (u - cx) / fx;
  // Most source pixels land outside the mask: reject them with one lookup in the mask grown by
  // the splat radius (and its bounding box) instead of testing every splat position. Passes after
  // the first reach only the masked pixels still empty.
  cv::Mat reach;
  cv::Rect reach_box;
  cv::Mat reach_sum;  // integral image: reach pixels in any rectangle in O(1)
  auto set_reach = [&](const cv::Mat& open) {
    cv::dilate(open, reach, cv::getStructuringElement(cv::MORPH_RECT, {2 * r + 1, 2 * r + 1}));
    reach_box = cv::boundingRect(reach);
    cv::integral(reach, reach_sum, CV_32S);
  };

  const std::size_t newest =
      std::min<std::size_t>(sources.size(), static_cast<std::size_t>(config.num_keyframes));
  const std::size_t count = std::min<std::size_t>(
      sources.size(), static_cast<std::size_t>(config.num_keyframes + config.extra_keyframes));
  // Which source won each pixel (for the colour resampling below).
  cv::Mat winner(mask.size(), CV_8UC1, cv::Scalar(0));
  // The passes, in order; each after the first only fills target pixels the earlier ones left
  // empty (`locked`). The newest num_keyframes sources first: with observed_first their observed
  // pixels, then their repaired ones; the extra_keyframes older sources after them, likewise.
  enum class Take { kAny, kObserved, kRepaired };
  struct Pass {
    std::size_t begin, end;
    Take take;
  };
  std::vector<Pass> passes;
  if (config.observed_first) {
    passes = {{0, newest, Take::kObserved},
              {0, newest, Take::kRepaired},
              {newest, count, Take::kObserved},
              {newest, count, Take::kRepaired}};
  } else {
    passes = {{0, newest, Take::kAny}, {newest, count, Take::kAny}};
  }
  // Every source used, also those the passes do not reach (the see-through check reads them all).
  for (std::size_t s = 0; s < count; ++s) {
    const SourceView& src = sources[s];
    if (src.bgr.type() != CV_8UC3 || src.depth_m.type() != CV_32FC1 ||
        src.bgr.size() != src.depth_m.size()) {
      throw Error("inpaint: a source needs CV_8UC3 colour and CV_32FC1 depth of one size");
    }
    for (const cv::Mat* m : {&src.exclude_mask, &src.repaired_mask}) {
      if (!m->empty() && (m->type() != CV_8UC1 || m->size() != src.depth_m.size())) {
        throw Error("inpaint: a source's masks must be CV_8UC1 of its depth's size (or empty)");
      }
    }
    if (src.blocks && !matches(*src.blocks, src)) {
      throw Error(
          "inpaint: a source's depth blocks were not computed for its depth image's size and "
          "its masks");
    }
  }
  cv::Mat locked;  // target pixels filled by an earlier pass
  struct CachedRange {
    cv::Rect window;
    DepthBlocks range;
  };
  std::vector<CachedRange> depth_ranges(count);  // sources without blocks: computed when needed
  for (std::size_t pass = 0; pass < passes.size(); ++pass) {
    const Take take = passes[pass].take;
    if (passes[pass].begin >= passes[pass].end) continue;
    if (pass == 0) {
      set_reach(mask != 0);
    } else {
      locked = out.filled != 0;
      const cv::Mat open = (mask != 0) & ~locked;
      if (cv::countNonZero(open) == 0) break;  // nothing left to fill
      set_reach(open);
    }
    for (std::size_t s = passes[pass].begin; s < passes[pass].end; ++s) {
      const SourceView& src = sources[s];
      if (take == Take::kRepaired && src.repaired_mask.empty()) continue;
      const SE3 T_cur_src = T_c_w * src.T_w_c;
      const Mat3d R = T_cur_src.rotation();
      const Vec3d t = T_cur_src.translation();
      // Only the source pixels that can reach the target's box (stride-aligned).
      const cv::Rect window = source_window(reach_box, T_cur_src.inverse(), camera,
                                            config.max_depth_m, src.depth_m.size());
      const int stride = config.source_stride_px;
      const int v_begin = (window.y + stride - 1) / stride * stride;
      const int u_begin = (window.x + stride - 1) / stride * stride;
      const int blocks_x = (src.depth_m.cols + kCullBlock - 1) / kCullBlock;
      std::vector<std::uint8_t> active;
      if (config.skip_unreachable_blocks) {
        const DepthBlocks* blocks = src.blocks.get();
        if (blocks == nullptr) {
          // A later pass of the same source reaches fewer pixels: its window lies inside.
          CachedRange& cached = depth_ranges[s];
          if (cached.range.all.z_min.empty() || (cached.window & window) != window) {
            cached = {window,
                      block_depth_range(src.depth_m, src.exclude_mask, src.repaired_mask, window)};
          }
          blocks = &cached.range;
        }
        const DepthBlocks::Range& range = take == Take::kObserved   ? blocks->observed
                                          : take == Take::kRepaired ? blocks->repaired
                                                                    : blocks->all;
        active = active_blocks(range, blocks_x, window, T_cur_src, camera, reach_sum, reach_box);
      } else {
        active.assign(
            static_cast<std::size_t>(blocks_x) * ((src.depth_m.rows + kCullBlock - 1) / kCullBlock),
            1);
      }
      const int u_end = window.x + window.width;
      for (int v = v_begin; v < window.y + window.height; v += stride) {
        const float* drow = src.depth_m.ptr<float>(v);
        const cv::Vec3b* crow = src.bgr.ptr<cv::Vec3b>(v);
        const std::uint8_t* xrow = src.exclude_mask.empty() ? nullptr : src.exclude_mask.ptr(v);
        const std::uint8_t* rrow = src.repaired_mask.empty() ? nullptr : src.repaired_mask.ptr(v);
        const std::uint8_t* active_row =
            active.data() + static_cast<std::size_t>(v / kCullBlock) * blocks_x;
        const double y_norm = (v - cy) / fy;
        // The samples of the active blocks, in increasing u (the order decides ties).
        for (int bx = window.x / kCullBlock; bx * kCullBlock < u_end; ++bx) {
          if (active_row[bx] == 0) continue;
          const int u_first = std::max(u_begin, (bx * kCullBlock + stride - 1) / stride * stride);
          const int u_last = std::min(u_end, (bx + 1) * kCullBlock);  // exclusive
          for (int u = u_first; u < u_last; u += stride) {
            const float z = drow[u];
            if (z <= 0.0f || z > config.max_depth_m || (xrow != nullptr && xrow[u] != 0)) continue;
            if (take != Take::kAny) {
              const bool repaired = rrow != nullptr && rrow[u] != 0;
              if (repaired != (take == Take::kRepaired)) continue;
            }
            const Vec3d p_src(x_norm[u] * z, y_norm * z, z);
            const Vec3d p = R * p_src + t;
            if (p.z() < kMinSampleDepth || p.z() > config.max_depth_m) continue;
            const double uc = fx * p.x() / p.z() + cx;
            const double vc = fy * p.y() / p.z() + cy;
            if (!(std::abs(uc) < 1e6 && std::abs(vc) < 1e6)) continue;
            const int iu = cvRound(uc);
            const int iv = cvRound(vc);
            if (!reach_box.contains({iu, iv}) || reach.at<std::uint8_t>(iv, iu) == 0) continue;
            const float zc = static_cast<float>(p.z());
            const float tol = tol_abs + tol_rel * zc;
            for (int dv = -r; dv <= r; ++dv) {
              const int y = iv + dv;
              if (y < 0 || y >= h) continue;
              const std::uint8_t* mrow = mask.ptr(y);
              const float* drow_cur = depth_m.ptr<float>(y);
              float* zrow = zbuf.ptr<float>(y);
              const std::uint8_t* lrow = pass > 0 ? locked.ptr(y) : nullptr;
              for (int du = -r; du <= r; ++du) {
                const int x = iu + du;
                if (x < 0 || x >= w || mrow[x] == 0) continue;
                if (lrow != nullptr && lrow[x] != 0) continue;
                if (config.free_space_check && drow_cur[x] > 0.0f && zc < drow_cur[x] - tol) {
                  continue;
                }
                if (config.behind_current_only && drow_cur[x] > 0.0f && zc <= drow_cur[x] + tol) {
                  continue;
                }
                // Centre sample beats a neighbour's splat at equal depth; nearer beats farther.
                if (zc < zrow[x] - tol || (du == 0 && dv == 0 && zc < zrow[x] + tol &&
                                           out.filled.at<std::uint8_t>(y, x) != 2)) {
                  zrow[x] = zc;
                  out.bgr.at<cv::Vec3b>(y, x) = crow[u];
                  out.depth_m.at<float>(y, x) = zc;
                  out.filled.at<std::uint8_t>(y, x) = (du == 0 && dv == 0) ? 2 : 1;
                  winner.at<std::uint8_t>(y, x) = static_cast<std::uint8_t>(s);
                }
              }
            }
          }
        }
      }
    }
  }
  if (config.see_through_votes > 0) {
    reject_seen_through(out, zbuf, winner, bgr, depth_m, T_c_w, sources, count, camera, config);
  }
  out.filled = out.filled != 0;
  out.filled_pixels = cv::countNonZero(out.filled);
  if (config.resample_colour) resample_colour(out, zbuf, winner, T_c_w, sources, camera, config);

  cv::Mat unfilled;
  cv::bitwise_and(mask != 0, out.filled == 0, unfilled);
  // Pixels under the mask that no keyframe saw keep no depth: it would be the moving object's.
  out.depth_m.setTo(0.0f, unfilled);
  if (config.image_fill_small_holes && config.max_hole_area_px > 0 &&
      cv::countNonZero(unfilled) > 0) {
    cv::Mat labels, stats, centroids;
    const int n = cv::connectedComponentsWithStats(unfilled, labels, stats, centroids, 8);
    // One pass over the labels (not one image comparison per component).
    std::vector<std::uint8_t> is_small(static_cast<std::size_t>(n), 0);
    for (int i = 1; i < n; ++i) {
      if (stats.at<int>(i, cv::CC_STAT_AREA) <= config.max_hole_area_px) is_small[i] = 255;
    }
    cv::Mat small(mask.size(), CV_8UC1);
    for (int y = 0; y < labels.rows; ++y) {
      const int* lrow = labels.ptr<int>(y);
      std::uint8_t* srow = small.ptr(y);
      for (int x = 0; x < labels.cols; ++x) srow[x] = is_small[static_cast<std::size_t>(lrow[x])];
    }
    if (cv::countNonZero(small) > 0) {
      cv::Mat filled_bgr;
      cv::inpaint(out.bgr, small, filled_bgr, 3, cv::INPAINT_TELEA);
      // Depth: grown in from the known depth around the hole, one pixel ring per pass, until the
      // hole is full or nothing known touches what is left (a hole inside unknown depth). Eight
      // passes used to be the limit, which left the middle of holes wider than 16 px without
      // depth while they counted as filled (found by review, 2026-11-26).
      cv::Mat depth_fill = out.depth_m.clone();
      int left = cv::countNonZero(small & (depth_fill == 0));
      while (left > 0) {
        cv::Mat grown;
        cv::dilate(depth_fill, grown, cv::Mat());  // max of neighbours: background-biased
        const cv::Mat holes = small & (depth_fill == 0);
        grown.copyTo(depth_fill, holes);
        const int now = cv::countNonZero(small & (depth_fill == 0));
        if (now == left) break;
        left = now;
      }
      depth_fill.copyTo(out.depth_m, small);
      // Filled are the hole pixels that got both colour and depth; the rest stay unfilled.
      cv::Mat with_depth;
      cv::bitwise_and(small, depth_fill > 0, with_depth);
      // Only those take the image-inpainted colour: an unfilled pixel keeps what the camera saw
      // (until 2026-11-27 it took the colour too, and no longer showed the person it marks).
      filled_bgr.copyTo(out.bgr, with_depth);
      out.image_filled = with_depth;
      unfilled.setTo(0, with_depth);
    }
  }
  out.unfilled = unfilled;
  return out;
}

}  // namespace ddl::inpainting
