#pragma once
// Closed-form alignment of two corresponding 3D point sets (columns of 3xN matrices).
//
// align_horn reproduces evaluate_ate.py's align() of the TUM RGB-D benchmark step by step:
//   W = sum_i outer(model_i - mean(model), data_i - mean(data));  U, d, Vh = svd(W^T);
//   S = I, S(2,2) = -1 if det(U) * det(Vh) < 0;  R = U S Vh;  t = mean(data) - R mean(model).
// align_umeyama adds Umeyama's (1991, eq. 42) scale: c = trace(diag(d) S) / sum_i |model_i -
// mean(model)|^2, t = mean(data) - c R mean(model); with scale disabled it equals align_horn.
// "model" is the estimate, "data" the ground truth, so the result maps estimate-world
// coordinates into ground-truth-world coordinates.

#include <Eigen/Core>

#include "ddl/core/se3.h"
#include "ddl/core/types.h"

namespace ddl::eval {

/// Similarity p_gt = scale * R_gt_est * p_est + t_gt_est.
struct Alignment {
  Mat3d R_gt_est = Mat3d::Identity();
  Vec3d t_gt_est = Vec3d::Zero();
  double scale = 1.0;

  Vec3d apply(const Vec3d& p_est) const { return scale * (R_gt_est * p_est) + t_gt_est; }
  Eigen::Matrix3Xd apply(const Eigen::Matrix3Xd& p_est) const;
};

/// Rigid alignment (scale 1) of `model` onto `data` as evaluate_ate.py's align(). Throws
/// ddl::Error if the sizes differ or there are no points.
Alignment align_horn(const Eigen::Matrix3Xd& model, const Eigen::Matrix3Xd& data);

/// Umeyama alignment; with_scale = false is the same as align_horn. Throws ddl::Error if the sizes
/// differ, there are no points, or (with scale) all model points coincide.
Alignment align_umeyama(const Eigen::Matrix3Xd& model, const Eigen::Matrix3Xd& data,
                        bool with_scale = true);

/// Rigid alignment from corresponding poses, orientations included: R = the rotation nearest
/// (polar decomposition) to sum_i R_gt_i R_est_i^T, t = mean_i (t_gt_i - R t_est_i). Unlike the
/// position-only fit it stays determined when the camera hardly moves (a camera on a tripod
/// whose positions span millimetres leaves the rotation of align_horn to noise). Throws
/// ddl::Error if the sizes differ or there are no poses.
Alignment align_poses(const std::vector<SE3>& T_gt_w_c, const std::vector<SE3>& T_est_w_c);

}  // namespace ddl::eval
