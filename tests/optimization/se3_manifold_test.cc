#include "ddl/optimization/se3_manifold.h"

#include <ceres/manifold_test_utils.h>
#include <gtest/gtest.h>

#include <functional>
#include <random>

#include "ddl/optimization/cost_functions.h"
#include "synthetic.h"

namespace ddl::optimization {
namespace {

using ceres::Matrix;
using ceres::Vector;
using testing::tum1_camera;

SE3 random_pose(std::mt19937& rng, double max_angle = M_PI - 0.1) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const Vec3d axis = Vec3d(u(rng), u(rng), u(rng)).normalized();
  return SE3(Mat3d(Eigen::AngleAxisd(std::abs(u(rng)) * max_angle, axis)),
             Vec3d(2.0 * u(rng), 2.0 * u(rng), 2.0 * u(rng)));
}

Vec6d random_twist(std::mt19937& rng, double max_norm) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Vec6d xi;
  for (int i = 0; i < 6; ++i) xi[i] = u(rng);
  return xi.normalized() * (max_norm * std::abs(u(rng)));
}

Vector ambient(const SE3& T) {
  const PoseParameters p = to_parameters(T);
  return Eigen::Map<const Vector>(p.data(), kPoseAmbientSize);
}

/// Central differences of f: R^n -> R^m at 0, column by column.
Matrix numeric_jacobian(const std::function<Vector(const Vector&)>& f, int n, double h = 1e-6) {
  const Vector f0 = f(Vector::Zero(n));
  Matrix J(f0.size(), n);
  for (int k = 0; k < n; ++k) {
    Vector d = Vector::Zero(n);
    d[k] = h;
    J.col(k) = (f(d) - f(-d)) / (2.0 * h);
  }
  return J;
}

/// max |A - B| relative to max(1, max |B|).
double relative_difference(const Matrix& A, const Matrix& B) {
  return (A - B).cwiseAbs().maxCoeff() / std::max(1.0, B.cwiseAbs().maxCoeff());
}

TEST(SE3Manifold, CeresInvariantsHold) {
  // Ceres' own manifold checks: Plus(x, 0) = x, Minus(x, x) = 0, Minus(Plus(x, d), x) = d,
  // Plus(x, Minus(y, x)) = y, numeric vs analytic PlusJacobian / MinusJacobian (Ridders),
  // MinusJacobian * PlusJacobian = I.
  using namespace ceres;  // NOLINT: the invariants macro names its matchers unqualified
  const SE3Manifold manifold;
  std::mt19937 rng(7);
  for (int trial = 0; trial < 20; ++trial) {
    const SE3 X = random_pose(rng);
    const Vector x = ambient(X);
    const Vector delta = random_twist(rng, 1.0);
    // q and -q are the same pose and Plus keeps the sign of q_delta * q_x with w(q_delta) >= 0;
    // store y on that hemisphere so the ambient comparison of Plus(x, Minus(y, x)) is fair.
    const SE3 Y = SE3::exp(random_twist(rng, 2.0)) * X;
    Vector y = ambient(Y);
    const Vec3d phi = so3_log(Y.rotation() * X.rotation().transpose());
    const Quatd q_ref = Quatd(Eigen::AngleAxisd(phi.norm(), phi.normalized())) * X.quaternion();
    if (Y.quaternion().coeffs().dot(q_ref.coeffs()) < 0.0) y.head<4>() = -y.head<4>();
    EXPECT_THAT_MANIFOLD_INVARIANTS_HOLD(manifold, x, delta, y, 1e-6);
  }
}

TEST(SE3Manifold, PlusIsLeftMultiplicationByExp) {
  const SE3Manifold manifold;
  std::mt19937 rng(3);
  for (int trial = 0; trial < 50; ++trial) {
    const SE3 X = random_pose(rng);
    const Vec6d delta = random_twist(rng, 2.5);
    const Vector x = ambient(X);
    PoseParameters out{};
    ASSERT_TRUE(manifold.Plus(x.data(), delta.data(), out.data()));
    const SE3 expected = SE3::exp(delta) * X;
    EXPECT_LT((from_parameters(out.data()).matrix() - expected.matrix()).norm(), 1e-12);
    Vec6d back;
    ASSERT_TRUE(manifold.Minus(out.data(), x.data(), back.data()));
    EXPECT_LT((back - delta).norm(), 1e-9);
  }
}

TEST(SE3Manifold, PlusAndMinusJacobiansMatchCentralDifferences) {
  const SE3Manifold manifold;
  std::mt19937 rng(11);
  for (int trial = 0; trial < 20; ++trial) {
    const Vector x = ambient(random_pose(rng));
    Matrix plus_analytic(7, 6);
    Eigen::Matrix<double, 7, 6, Eigen::RowMajor> plus_rm;
    ASSERT_TRUE(manifold.PlusJacobian(x.data(), plus_rm.data()));
    plus_analytic = plus_rm;
    const Matrix plus_numeric = numeric_jacobian(
        [&](const Vector& d) {
          Vector out(7);
          manifold.Plus(x.data(), d.data(), out.data());
          return out;
        },
        6);
    EXPECT_LT(relative_difference(plus_analytic, plus_numeric), 1e-6);

    MinusJacobianMatrix minus_rm;
    ASSERT_TRUE(manifold.MinusJacobian(x.data(), minus_rm.data()));
    const Matrix minus_numeric = numeric_jacobian(
        [&](const Vector& d) {
          const Vector y = x + d;
          Vector out(6);
          manifold.Minus(y.data(), x.data(), out.data());
          return out;
        },
        7);
    EXPECT_LT(relative_difference(Matrix(minus_rm), minus_numeric), 1e-6);
    EXPECT_LT((Matrix(minus_rm) * plus_analytic - Matrix::Identity(6, 6)).norm(), 1e-12);
  }
}

TEST(SE3Manifold, LeftJacobianLinearisesComposition) {
  // log(exp(a) exp(xi)) ~= xi + J_l(xi)^-1 a, checked numerically, including the series branch.
  std::mt19937 rng(5);
  for (double norm : {1e-9, 1e-4, 0.05, 0.5, 2.0, 3.0}) {
    Vec6d xi = random_twist(rng, 1.0).normalized() * norm;
    xi.head<3>() = random_twist(rng, 1.0).head<3>().normalized();  // translation part O(1)
    const Matrix numeric = numeric_jacobian(
        [&](const Vector& a) {
          Vector out = (SE3::exp(Vec6d(a)) * SE3::exp(xi)).log();
          return out;
        },
        6, 1e-7);
    const Mat6d J_inv = se3_left_jacobian_inverse(xi);
    EXPECT_LT(relative_difference(Matrix(J_inv), numeric), 1e-6) << "|phi| = " << norm;
    EXPECT_LT((se3_left_jacobian(xi) * J_inv - Mat6d::Identity()).norm(), 1e-12)
        << "|phi| = " << norm;
  }
}

TEST(SE3Manifold, LeftJacobianSeriesBranchJoinsClosedForm) {
  // The coupling term Q switches from its Taylor series to the closed form at |phi| = 0.1; both
  // must agree there far below the 1e-6 Jacobian tolerance (a wrong series coefficient shows up
  // as a ~1e-9 jump).
  std::mt19937 rng(9);
  for (int trial = 0; trial < 10; ++trial) {
    Vec6d xi = random_twist(rng, 1.0);
    xi.head<3>().normalize();
    const Vec3d axis = xi.tail<3>().normalized();
    xi.tail<3>() = axis * (0.1 - 1e-12);
    const Mat6d below = se3_left_jacobian(xi);
    xi.tail<3>() = axis * (0.1 + 1e-12);
    const Mat6d above = se3_left_jacobian(xi);
    EXPECT_LT((below - above).cwiseAbs().maxCoeff(), 1e-11);
  }
}

/// Checks, block by block, the Jacobian the solver sees (J_amb * PlusJacobian for poses, J_amb
/// for points) against central differences of the residual along the tangent directions.
template <int N, int... Sizes>
void expect_cost_jacobians_match(const ceres::SizedCostFunction<N, Sizes...>& cost,
                                 std::vector<Vector> params, const std::vector<bool>& is_pose) {
  const SE3Manifold manifold;
  constexpr int kBlocks = sizeof...(Sizes);
  const int sizes[kBlocks] = {Sizes...};
  std::vector<double*> jac_ptrs;
  jac_ptrs.reserve(kBlocks);
  std::vector<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> rm(kBlocks);
  for (int b = 0; b < kBlocks; ++b) {
    rm[b].resize(N, sizes[b]);
    jac_ptrs.push_back(rm[b].data());
  }
  std::vector<const double*> ptrs;
  ptrs.reserve(params.size());
  for (auto& p : params) ptrs.push_back(p.data());
  Vector r(N);
  ASSERT_TRUE(cost.Evaluate(ptrs.data(), r.data(), jac_ptrs.data()));

  for (int b = 0; b < kBlocks; ++b) {
    Matrix analytic = rm[b];
    const int tangent = is_pose[b] ? 6 : sizes[b];
    if (is_pose[b]) {
      Eigen::Matrix<double, 7, 6, Eigen::RowMajor> plus;
      manifold.PlusJacobian(params[b].data(), plus.data());
      analytic = analytic * Matrix(plus);
    }
    const Matrix numeric = numeric_jacobian(
        [&](const Vector& d) {
          std::vector<Vector> moved = params;
          if (is_pose[b]) {
            manifold.Plus(params[b].data(), d.data(), moved[b].data());
          } else {
            moved[b] += d;
          }
          std::vector<const double*> mp;
          mp.reserve(moved.size());
          for (auto& p : moved) mp.push_back(p.data());
          Vector out(N);
          cost.Evaluate(mp.data(), out.data(), nullptr);
          return out;
        },
        tangent);
    EXPECT_LT(relative_difference(analytic, numeric), 1e-6) << "parameter block " << b;
  }
}

TEST(CostFunctions, ReprojectionJacobiansMatchCentralDifferences) {
  const CameraIntrinsics cam = tum1_camera();
  std::mt19937 rng(21);
  for (int trial = 0; trial < 20; ++trial) {
    const SE3 T = random_pose(rng);
    const Vec3d p_w = testing::random_visible_point(cam, T, 0.5, 5.0, rng);
    for (bool stereo : {false, true}) {
      Measurement m = testing::measure(cam, T, p_w, stereo, trial % 8);
      testing::add_noise(&m, 3.0, rng);  // non-zero residuals
      const Vector x = ambient(T);
      const Vector p = p_w;
      if (stereo) {
        expect_cost_jacobians_match(PoseReprojectionCost<3>(cam, p_w, m), {x}, {true});
        expect_cost_jacobians_match(BaReprojectionCost<3>(cam, m), {x, p}, {true, false});
      } else {
        expect_cost_jacobians_match(PoseReprojectionCost<2>(cam, p_w, m), {x}, {true});
        expect_cost_jacobians_match(BaReprojectionCost<2>(cam, m), {x, p}, {true, false});
      }
    }
  }
}

TEST(CostFunctions, PoseGraphEdgeJacobiansMatchCentralDifferences) {
  std::mt19937 rng(31);
  for (int trial = 0; trial < 20; ++trial) {
    const SE3 T_i_w = random_pose(rng);
    const SE3 T_j_w = random_pose(rng);
    // Measurement near (not at) the current relative pose: residuals of a few degrees / cm, plus
    // a far one to exercise the large-angle branch of J_l^-1.
    const double noise = trial % 4 == 0 ? 1.5 : 0.05;
    const SE3 T_i_j = SE3::exp(random_twist(rng, noise)) * T_i_w * T_j_w.inverse();
    Mat6d A = Mat6d::Random();
    const Mat6d information = A * A.transpose() + Mat6d::Identity();
    const Mat6d sqrt_info = Eigen::LLT<Mat6d>(information).matrixU();
    const PoseGraphEdgeCost cost(T_i_j, sqrt_info);
    const Vector x_i = ambient(T_i_w);
    const Vector x_j = ambient(T_j_w);
    expect_cost_jacobians_match(cost, {x_i, x_j}, {true, true});
    // The residual is the weighted twist log(T_i_j^-1 T_i_w T_j_w^-1).
    const double* ptrs[2] = {x_i.data(), x_j.data()};
    Vec6d r;
    ASSERT_TRUE(cost.Evaluate(ptrs, r.data(), nullptr));
    const Vec6d e = (T_i_j.inverse() * T_i_w * T_j_w.inverse()).log();
    EXPECT_LT((r - sqrt_info * e).norm(), 1e-9);
    EXPECT_NEAR(r.squaredNorm(), e.dot(information * e), 1e-8 * (1.0 + r.squaredNorm()));
  }
}

TEST(CostFunctions, PosePriorJacobianMatchesCentralDifferences) {
  std::mt19937 rng(41);
  for (int trial = 0; trial < 20; ++trial) {
    const SE3 T_c_w = random_pose(rng);
    const double noise = trial % 4 == 0 ? 1.5 : 0.05;  // far from the prior now and then
    const SE3 T_prior = SE3::exp(random_twist(rng, noise)) * T_c_w;
    Mat6d A = Mat6d::Random();
    const Mat6d information = A * A.transpose() + Mat6d::Identity();
    const Mat6d sqrt_info = Eigen::LLT<Mat6d>(information).matrixU();
    const PosePriorCost cost(T_prior, sqrt_info);
    const Vector x = ambient(T_c_w);
    expect_cost_jacobians_match(cost, {x}, {true});
    // The residual is the weighted twist log(T_c_w T_prior^-1): zero at the prior.
    const double* ptrs[1] = {x.data()};
    Vec6d r;
    ASSERT_TRUE(cost.Evaluate(ptrs, r.data(), nullptr));
    EXPECT_LT((r - sqrt_info * (T_c_w * T_prior.inverse()).log()).norm(), 1e-9);
    const Vector x_prior = ambient(T_prior);
    const double* at_prior[1] = {x_prior.data()};
    ASSERT_TRUE(cost.Evaluate(at_prior, r.data(), nullptr));
    EXPECT_LT(r.norm(), 1e-9);
  }
}

TEST(CostFunctions, Chi2MatchesWhitenedResidual) {
  const CameraIntrinsics cam = tum1_camera();
  const SE3 T = SE3::exp((Vec6d() << 0.1, -0.2, 0.3, 0.05, 0.1, -0.02).finished());
  const Vec3d p_w(0.3, -0.2, 2.5);
  Measurement m = testing::measure(cam, T, p_w, true, 2);
  m.uv_px += Vec2d(3.0, -4.0);  // 5 px off
  m.u_right_px += 3.0;
  double depth = 0.0;
  const double chi2 = reprojection_chi2(cam, T, p_w, m, &depth);
  EXPECT_NEAR(depth, (T * p_w).z(), 1e-12);
  EXPECT_NEAR(chi2, (9.0 + 16.0 + 9.0) * m.inv_sigma2, 1e-9);
  m.stereo = false;
  EXPECT_NEAR(reprojection_chi2(cam, T, p_w, m), 25.0 * m.inv_sigma2, 1e-9);
}

}  // namespace
}  // namespace ddl::optimization
