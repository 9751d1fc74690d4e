#include "ddl/loop/relative_pose.h"

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <random>

namespace ddl::loop {

std::optional<SE3> fit_rigid_transform(std::span<const Vec3d> src, std::span<const Vec3d> dst) {
  const std::size_t n = src.size();
  if (n < 3 || dst.size() != n) return std::nullopt;
  Vec3d mean_src = Vec3d::Zero();
  Vec3d mean_dst = Vec3d::Zero();
  for (std::size_t i = 0; i < n; ++i) {
    mean_src += src[i];
    mean_dst += dst[i];
  }
  mean_src /= static_cast<double>(n);
  mean_dst /= static_cast<double>(n);
  // Cross-covariance H = sum (dst - mean) (src - mean)^T; R = U diag(1, 1, det) V^T (Umeyama).
  Mat3d H = Mat3d::Zero();
  for (std::size_t i = 0; i < n; ++i) H += (dst[i] - mean_dst) * (src[i] - mean_src).transpose();
  const Eigen::JacobiSVD<Mat3d> svd(H, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Vec3d s = svd.singularValues();
  // Rank < 2: the points are coincident or collinear and the rotation about their line is free.
  if (!(s(1) > 1e-9 * std::max(1.0, s(0)))) return std::nullopt;
  Mat3d D = Mat3d::Identity();
  if ((svd.matrixU() * svd.matrixV().transpose()).determinant() < 0.0) D(2, 2) = -1.0;
  const Mat3d R = svd.matrixU() * D * svd.matrixV().transpose();
  const Vec3d t = mean_dst - R * mean_src;
  if (!R.allFinite() || !t.allFinite()) return std::nullopt;
  return SE3(R, t);
}

bool is_relative_pose_inlier(const PointCorrespondence& c, const SE3& T_1_2,
                             const optimization::CameraIntrinsics& camera, double chi2) {
  auto check = [&](const Vec3d& p_c, const Vec2d& uv, double sigma2) {
    if (p_c.z() <= 0.0) return false;
    const Vec2d proj(camera.fx * p_c.x() / p_c.z() + camera.cx,
                     camera.fy * p_c.y() / p_c.z() + camera.cy);
    return (proj - uv).squaredNorm() < chi2 * sigma2;
  };
  return check(T_1_2 * c.p2_c, c.uv1, c.sigma2_1) &&
         check(T_1_2.inverse() * c.p1_c, c.uv2, c.sigma2_2);
}

namespace {

int count_inliers(std::span<const PointCorrespondence> correspondences, const SE3& T_1_2,
                  const optimization::CameraIntrinsics& camera, double chi2,
                  std::vector<bool>& inliers) {
  inliers.assign(correspondences.size(), false);
  int count = 0;
  for (std::size_t i = 0; i < correspondences.size(); ++i) {
    if (is_relative_pose_inlier(correspondences[i], T_1_2, camera, chi2)) {
      inliers[i] = true;
      ++count;
    }
  }
  return count;
}

std::optional<SE3> fit_subset(std::span<const PointCorrespondence> correspondences,
                              const std::vector<bool>& use) {
  std::vector<Vec3d> src;
  std::vector<Vec3d> dst;
  for (std::size_t i = 0; i < correspondences.size(); ++i) {
    if (!use[i]) continue;
    src.push_back(correspondences[i].p2_c);
    dst.push_back(correspondences[i].p1_c);
  }
  return fit_rigid_transform(src, dst);
}

}  // namespace

std::optional<RelativePoseEstimate> estimate_relative_pose(
    std::span<const PointCorrespondence> correspondences,
    const optimization::CameraIntrinsics& camera, const RelativePoseRansacOptions& options) {
  const std::size_t n = correspondences.size();
  if (n < 3 || n < static_cast<std::size_t>(options.min_inliers)) return std::nullopt;

  std::mt19937_64 rng(options.seed);
  std::uniform_int_distribution<std::size_t> pick(0, n - 1);
  RelativePoseEstimate best;
  std::vector<bool> inliers;
  long needed = options.max_iterations;
  for (long it = 0; it < needed; ++it) {
    ++best.iterations;
    std::size_t idx[3];
    idx[0] = pick(rng);
    do {
      idx[1] = pick(rng);
    } while (idx[1] == idx[0]);
    do {
      idx[2] = pick(rng);
    } while (idx[2] == idx[0] || idx[2] == idx[1]);
    const Vec3d src[3] = {correspondences[idx[0]].p2_c, correspondences[idx[1]].p2_c,
                          correspondences[idx[2]].p2_c};
    const Vec3d dst[3] = {correspondences[idx[0]].p1_c, correspondences[idx[1]].p1_c,
                          correspondences[idx[2]].p1_c};
    const std::optional<SE3> T = fit_rigid_transform(src, dst);
    if (!T) continue;
    const int count = count_inliers(correspondences, *T, camera, options.chi2, inliers);
    if (count <= best.num_inliers) continue;
    best.num_inliers = count;
    best.T_1_2 = *T;
    best.inliers = inliers;
    // Adaptive stop: hypotheses needed to draw one all-inlier triple with the given probability.
    const double w = static_cast<double>(count) / static_cast<double>(n);
    const double p_good = w * w * w;
    if (p_good >= 1.0) {
      needed = std::min<long>(needed, it + 1);
    } else if (p_good > 0.0) {
      const double k = std::log(1.0 - options.probability) / std::log(1.0 - p_good);
      needed = std::min<long>(options.max_iterations, static_cast<long>(std::ceil(k)));
    }
  }
  if (best.num_inliers < options.min_inliers) return std::nullopt;

  // Refit on the inliers until the set stops growing (at most a few rounds).
  for (int round = 0; round < 5; ++round) {
    const std::optional<SE3> T = fit_subset(correspondences, best.inliers);
    if (!T) break;
    const int count = count_inliers(correspondences, *T, camera, options.chi2, inliers);
    if (count < best.num_inliers) break;
    const bool same = inliers == best.inliers;
    best.T_1_2 = *T;
    best.num_inliers = count;
    best.inliers = inliers;
    if (same) break;
  }
  if (best.num_inliers < options.min_inliers) return std::nullopt;
  return best;
}

}  // namespace ddl::loop
