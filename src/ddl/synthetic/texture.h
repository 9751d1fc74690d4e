#pragma once
// Textures of the synthetic renderer: an 8-bit BGR image with its mip-map pyramid (and an optional
// coverage/alpha pyramid for cut-out billboards such as people), sampled bilinearly between two
// mip levels (trilinear filtering) so distant, high-frequency textures do not alias.
// Immutable after construction; safe to sample from several threads.

#include <bit>
#include <cmath>
#include <cstdint>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace ddl::synthetic {

struct Texture {
  std::vector<cv::Mat> color;  // CV_8UC3 BGR, level 0 = full resolution, each next level halved
  std::vector<cv::Mat> alpha;  // CV_8UC1 coverage (255 = opaque) per level; empty when opaque
  std::string source;          // where it came from: "procedural:<kind>" or an image path

  int width() const { return color.empty() ? 0 : color.front().cols; }
  int height() const { return color.empty() ? 0 : color.front().rows; }
  bool has_alpha() const { return !alpha.empty(); }
  int levels() const { return static_cast<int>(color.size()); }
};

/// Builds the mip pyramid (area-averaged halving down to a few texels). `alpha` may be empty;
/// otherwise CV_8UC1 of the same size. Throws ddl::Error on a wrong type or size.
Texture make_texture(const cv::Mat& bgr, const cv::Mat& alpha, std::string source);

/// Bilinear sample of level `level` at texture coordinates (s, t) in [0, 1]^2 (s along columns,
/// t along rows, (0, 0) = top-left corner of the image), clamped at the border. Writes B, G, R.
inline void sample_bilinear(const cv::Mat& img, float s, float t, float out[3]) {
  const float x = s * static_cast<float>(img.cols) - 0.5f;
  const float y = t * static_cast<float>(img.rows) - 0.5f;
  const int max_x = img.cols - 1;
  const int max_y = img.rows - 1;
  const float fx0 = std::floor(x);
  const float fy0 = std::floor(y);
  const float wx = x - fx0;
  const float wy = y - fy0;
  int x0 = static_cast<int>(fx0);
  int y0 = static_cast<int>(fy0);
  int x1 = x0 + 1;
  int y1 = y0 + 1;
  x0 = x0 < 0 ? 0 : (x0 > max_x ? max_x : x0);
  x1 = x1 < 0 ? 0 : (x1 > max_x ? max_x : x1);
  y0 = y0 < 0 ? 0 : (y0 > max_y ? max_y : y0);
  y1 = y1 < 0 ? 0 : (y1 > max_y ? max_y : y1);
  const auto* r0 = img.ptr<unsigned char>(y0);
  const auto* r1 = img.ptr<unsigned char>(y1);
  const float w00 = (1 - wx) * (1 - wy);
  const float w01 = wx * (1 - wy);
  const float w10 = (1 - wx) * wy;
  const float w11 = wx * wy;
  for (int c = 0; c < 3; ++c) {
    out[c] =
        w00 * r0[3 * x0 + c] + w01 * r0[3 * x1 + c] + w10 * r1[3 * x0 + c] + w11 * r1[3 * x1 + c];
  }
}

/// Bilinear sample of a single-channel 8-bit level (alpha), same conventions.
inline float sample_bilinear_gray(const cv::Mat& img, float s, float t) {
  const float x = s * static_cast<float>(img.cols) - 0.5f;
  const float y = t * static_cast<float>(img.rows) - 0.5f;
  const int max_x = img.cols - 1;
  const int max_y = img.rows - 1;
  const float fx0 = std::floor(x);
  const float fy0 = std::floor(y);
  const float wx = x - fx0;
  const float wy = y - fy0;
  int x0 = static_cast<int>(fx0);
  int y0 = static_cast<int>(fy0);
  int x1 = x0 + 1;
  int y1 = y0 + 1;
  x0 = x0 < 0 ? 0 : (x0 > max_x ? max_x : x0);
  x1 = x1 < 0 ? 0 : (x1 > max_x ? max_x : x1);
  y0 = y0 < 0 ? 0 : (y0 > max_y ? max_y : y0);
  y1 = y1 < 0 ? 0 : (y1 > max_y ? max_y : y1);
  const auto* r0 = img.ptr<unsigned char>(y0);
  const auto* r1 = img.ptr<unsigned char>(y1);
  return (1 - wx) * (1 - wy) * r0[x0] + wx * (1 - wy) * r0[x1] + (1 - wx) * wy * r1[x0] +
         wx * wy * r1[x1];
}

/// Trilinear sample: `lod` is log2 of the pixel footprint in level-0 texels (<= 0: magnified).
inline void sample_trilinear(const Texture& tex, float s, float t, float lod, float out[3]) {
  const int last = tex.levels() - 1;
  if (lod <= 0.0f || last == 0) {
    sample_bilinear(tex.color[0], s, t, out);
    return;
  }
  if (lod >= static_cast<float>(last)) {
    sample_bilinear(tex.color[static_cast<std::size_t>(last)], s, t, out);
    return;
  }
  const int l0 = static_cast<int>(lod);
  const float w = lod - static_cast<float>(l0);
  float a[3];
  float b[3];
  sample_bilinear(tex.color[static_cast<std::size_t>(l0)], s, t, a);
  sample_bilinear(tex.color[static_cast<std::size_t>(l0 + 1)], s, t, b);
  for (int c = 0; c < 3; ++c) out[c] = a[c] + w * (b[c] - a[c]);
}

/// Bilinear sample of the mip level nearest to `lod` (GL_LINEAR_MIPMAP_NEAREST): half the cost of
/// trilinear filtering, used for the per-frame shading.
inline void sample_mip_nearest(const Texture& tex, float s, float t, float lod, float out[3]) {
  const int last = tex.levels() - 1;
  int level = static_cast<int>(lod + 0.5f);
  level = level < 0 ? 0 : (level > last ? last : level);
  sample_bilinear(tex.color[static_cast<std::size_t>(level)], s, t, out);
}

/// log2 to about 0.01 (enough to pick a mip level), without a libm call.
inline float approx_log2(float x) {
  const auto bits = std::bit_cast<std::uint32_t>(x);
  const float exponent = static_cast<float>(static_cast<int>((bits >> 23U) & 255U) - 128);
  const float m = std::bit_cast<float>((bits & 0x007FFFFFU) | 0x3f800000U);  // in [1, 2)
  return exponent + (-0.34484843f * m + 2.02466578f) * m - 0.67487759f;
}

/// Coverage in [0, 255] at the level nearest to `lod` (no blending between levels, so a cut-out
/// edge stays one crisp contour). Opaque textures return 255.
inline float sample_alpha(const Texture& tex, float s, float t, float lod) {
  if (!tex.has_alpha()) return 255.0f;
  const int last = tex.levels() - 1;
  int level = static_cast<int>(lod + 0.5f);
  level = level < 0 ? 0 : (level > last ? last : level);
  return sample_bilinear_gray(tex.alpha[static_cast<std::size_t>(level)], s, t);
}

}  // namespace ddl::synthetic
