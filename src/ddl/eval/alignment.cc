#include "ddl/eval/alignment.h"

#include <fmt/format.h>

#include <Eigen/SVD>

#include "ddl/core/error.h"

namespace ddl::eval {

Eigen::Matrix3Xd Alignment::apply(const Eigen::Matrix3Xd& p_est) const {
  return ((scale * R_gt_est) * p_est).colwise() + t_gt_est;
}

Alignment align_umeyama(const Eigen::Matrix3Xd& model, const Eigen::Matrix3Xd& data,
                        bool with_scale) {
  if (model.cols() != data.cols()) {
    throw Error(
        fmt::format("alignment: {} model points but {} data points", model.cols(), data.cols()));
  }
  if (model.cols() == 0) throw Error("alignment: no points to align");

  const Vec3d model_mean = model.rowwise().mean();
  const Vec3d data_mean = data.rowwise().mean();
  const Eigen::Matrix3Xd model_centered = model.colwise() - model_mean;
  const Eigen::Matrix3Xd data_centered = data.colwise() - data_mean;

  // W = sum of outer(model_centered_i, data_centered_i); the script decomposes W^T.
  const Mat3d W = model_centered * data_centered.transpose();
  const Eigen::JacobiSVD<Mat3d> svd(W.transpose(), Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Mat3d U = svd.matrixU();
  const Mat3d Vh = svd.matrixV().transpose();
  Mat3d S = Mat3d::Identity();
  if (U.determinant() * Vh.determinant() < 0.0) S(2, 2) = -1.0;

  Alignment out;
  out.R_gt_est = U * S * Vh;
  if (with_scale) {
    const double model_sq = model_centered.squaredNorm();
    if (!(model_sq > 0.0)) throw Error("alignment: all model points coincide, scale undefined");
    out.scale = (svd.singularValues().asDiagonal() * S).trace() / model_sq;
  }
  out.t_gt_est = data_mean - out.scale * (out.R_gt_est * model_mean);
  return out;
}

Alignment align_horn(const Eigen::Matrix3Xd& model, const Eigen::Matrix3Xd& data) {
  return align_umeyama(model, data, /*with_scale=*/false);
}

Alignment align_poses(const std::vector<SE3>& T_gt_w_c, const std::vector<SE3>& T_est_w_c) {
  if (T_gt_w_c.size() != T_est_w_c.size()) {
    throw Error(fmt::format("alignment: {} ground-truth poses but {} estimated poses",
                            T_gt_w_c.size(), T_est_w_c.size()));
  }
  if (T_gt_w_c.empty()) throw Error("alignment: no poses to align");
  Mat3d M = Mat3d::Zero();
  for (std::size_t i = 0; i < T_gt_w_c.size(); ++i) {
    M += T_gt_w_c[i].rotation() * T_est_w_c[i].rotation().transpose();
  }
  const Eigen::JacobiSVD<Mat3d> svd(M, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Mat3d S = Mat3d::Identity();
  if ((svd.matrixU() * svd.matrixV().transpose()).determinant() < 0.0) S(2, 2) = -1.0;
  Alignment out;
  out.R_gt_est = svd.matrixU() * S * svd.matrixV().transpose();
  Vec3d t = Vec3d::Zero();
  for (std::size_t i = 0; i < T_gt_w_c.size(); ++i) {
    t += T_gt_w_c[i].translation() - out.R_gt_est * T_est_w_c[i].translation();
  }
  out.t_gt_est = t / static_cast<double>(T_gt_w_c.size());
  return out;
}

}  // namespace ddl::eval
