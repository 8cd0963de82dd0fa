#include "imumatch/sim/spline_trajectory.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>

#include "imumatch/core/error.h"

namespace imumatch {
namespace {

// Uniform cubic B-spline basis (derivative 0, 1, 2 with respect to u in [0, 1]).
Eigen::Vector4d Basis(double u, int derivative) {
  switch (derivative) {
    case 0: {
      const double v = 1.0 - u;
      return Eigen::Vector4d(v * v * v, 3 * u * u * u - 6 * u * u + 4,
                             -3 * u * u * u + 3 * u * u + 3 * u + 1, u * u * u) /
             6.0;
    }
    case 1:
      return Eigen::Vector4d(-(1 - u) * (1 - u), 3 * u * u - 4 * u, -3 * u * u + 2 * u + 1, u * u) /
             2.0;
    default:
      return Eigen::Vector4d(1 - u, 3 * u - 2, -3 * u + 1, u);
  }
}

}  // namespace

void SplineFitOptions::Check() const {
  IMUMATCH_CHECK(std::isfinite(knot_spacing_s) && knot_spacing_s >= 1e-4 && knot_spacing_s <= 10.0,
                 "SplineFitOptions.knot_spacing_s must be in [1e-4, 10] s, got " << knot_spacing_s);
  IMUMATCH_CHECK(std::isfinite(smoothing) && smoothing >= 0.0,
                 "SplineFitOptions.smoothing must be >= 0, got " << smoothing);
}

SplineTrajectory::SplineTrajectory(const std::vector<StampedPose>& poses,
                                   const SplineFitOptions& options) {
  options.Check();
  IMUMATCH_CHECK(poses.size() >= 4,
                 "SplineTrajectory needs at least 4 poses, got " << poses.size());
  for (size_t i = 0; i < poses.size(); ++i) {
    const Rigid3d& p = poses[i].world_from_body;
    IMUMATCH_CHECK(
        p.translation.allFinite() && p.rotation.coeffs().allFinite() && p.rotation.norm() > 0.5,
        "SplineTrajectory: pose " << i << " is not finite or has no valid rotation");
    if (i > 0) {
      IMUMATCH_CHECK(poses[i].t_ns > poses[i - 1].t_ns,
                     "SplineTrajectory: timestamps must be strictly increasing; pose "
                         << i << " (t_ns=" << poses[i].t_ns
                         << ") follows t_ns=" << poses[i - 1].t_ns);
    }
  }
  t0_ns_ = poses.front().t_ns;
  duration_s_ = TimeOf(poses.back().t_ns);
  // Bounded work: the fit allocates per knot.
  IMUMATCH_CHECK(duration_s_ / options.knot_spacing_s <= kMaxSegments,
                 "SplineTrajectory: " << duration_s_ << " s at knots every "
                                      << options.knot_spacing_s << " s needs more than "
                                      << kMaxSegments << " knots");
  num_segments_ =
      std::max(1, static_cast<int>(std::ceil(duration_s_ / options.knot_spacing_s - 1e-9)));
  knot_spacing_ = duration_s_ / num_segments_;
  const int n = num_segments_ + 3;

  // Data: translation and sign-continuous quaternion coefficients.
  const int m = static_cast<int>(poses.size());
  Eigen::Matrix<double, Eigen::Dynamic, 7> y(m, 7);
  Eigen::Vector4d previous = poses.front().world_from_body.rotation.normalized().coeffs();
  for (int i = 0; i < m; ++i) {
    Eigen::Vector4d q = poses[i].world_from_body.rotation.normalized().coeffs();
    if (q.dot(previous) < 0.0) q = -q;
    previous = q;
    y.row(i).head<3>() = poses[i].world_from_body.translation.transpose();
    y.row(i).tail<4>() = q.transpose();
  }

  // Normal equations (A^T A + lambda D^T D) c = A^T y, banded.
  std::vector<Eigen::Triplet<double>> triplets;
  Eigen::Matrix<double, Eigen::Dynamic, 7> rhs =
      Eigen::Matrix<double, Eigen::Dynamic, 7>::Zero(n, 7);
  for (int i = 0; i < m; ++i) {
    const double s = TimeOf(poses[i].t_ns) / knot_spacing_;
    const int seg = std::min(static_cast<int>(s), num_segments_ - 1);
    const Eigen::Vector4d b = Basis(s - seg, 0);
    for (int r = 0; r < 4; ++r) {
      rhs.row(seg + r) += b[r] * y.row(i);
      for (int c = 0; c < 4; ++c) triplets.emplace_back(seg + r, seg + c, b[r] * b[c]);
    }
  }
  // Scale the penalty with the number of samples per knot so `smoothing` is rate independent.
  const double lambda = options.smoothing * static_cast<double>(m) / n;
  const double diff[3] = {1.0, -2.0, 1.0};
  for (int j = 0; j + 2 < n; ++j) {
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) triplets.emplace_back(j + r, j + c, lambda * diff[r] * diff[c]);
    }
  }
  // A tiny ridge keeps the system definite when knots have no samples and smoothing is 0. It
  // pulls each control point toward the poses' linear interpolation at its knot, not toward zero:
  // across a gap of many knots the second-difference penalty weakens as (1/gap)^4 and a ridge
  // toward zero made the fit sag there (poses at rest 10 s apart came out 6 m off, mid-gap).
  constexpr double kRidge = 1e-12;
  std::vector<double> pose_s(static_cast<size_t>(m));
  for (int i = 0; i < m; ++i)
    pose_s[static_cast<size_t>(i)] = TimeOf(poses[i].t_ns) / knot_spacing_;
  for (int j = 0; j < n; ++j) {
    triplets.emplace_back(j, j, kRidge);
    // Control point j weighs most at knot j - 1.
    const double s =
        std::clamp(static_cast<double>(j - 1), 0.0, static_cast<double>(num_segments_));
    const size_t hi =
        static_cast<size_t>(std::upper_bound(pose_s.begin(), pose_s.end(), s) - pose_s.begin());
    Eigen::Matrix<double, 1, 7> prior;
    if (hi == 0) {
      prior = y.row(0);
    } else if (hi >= pose_s.size()) {
      prior = y.row(m - 1);
    } else {
      const double w = (s - pose_s[hi - 1]) / (pose_s[hi] - pose_s[hi - 1]);
      prior = (1.0 - w) * y.row(static_cast<int>(hi) - 1) + w * y.row(static_cast<int>(hi));
    }
    rhs.row(j) += kRidge * prior;
  }
  Eigen::SparseMatrix<double> normal(n, n);
  normal.setFromTriplets(triplets.begin(), triplets.end());
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(normal);
  IMUMATCH_CHECK(solver.info() == Eigen::Success,
                 "SplineTrajectory: the fit is singular (too few poses per knot; increase "
                 "knot_spacing_s or smoothing)");
  control_ = solver.solve(rhs);
  IMUMATCH_CHECK(control_.allFinite(), "SplineTrajectory: the fit failed (non-finite result)");
}

Eigen::Matrix<double, 7, 1> SplineTrajectory::Eval(double t, int derivative) const {
  t = std::min(std::max(t, 0.0), duration_s_);
  const double s = t / knot_spacing_;
  const int seg = std::min(static_cast<int>(s), num_segments_ - 1);
  const Eigen::Vector4d b = Basis(s - seg, derivative) / std::pow(knot_spacing_, derivative);
  return (control_.middleRows<4>(seg).transpose() * b);
}

Rigid3d SplineTrajectory::WorldFromBody(double t) const {
  const Eigen::Matrix<double, 7, 1> v = Eval(t, 0);
  Eigen::Quaterniond q;
  q.coeffs() = v.tail<4>();
  return Rigid3d(q.normalized(), v.head<3>());
}

Eigen::Vector3d SplineTrajectory::VelocityInWorld(double t) const { return Eval(t, 1).head<3>(); }

Eigen::Vector3d SplineTrajectory::AccelerationInWorld(double t) const {
  return Eval(t, 2).head<3>();
}

Eigen::Vector3d SplineTrajectory::AngularVelocityInBody(double t) const {
  const Eigen::Vector4d c = Eval(t, 0).tail<4>();
  const Eigen::Vector4d dc = Eval(t, 1).tail<4>();
  const double norm = c.norm();
  const Eigen::Vector4d q = c / norm;
  const Eigen::Vector4d dq = (dc - q * q.dot(dc)) / norm;  // derivative of c / |c|
  Eigen::Quaterniond qq, dqq;
  qq.coeffs() = q;
  dqq.coeffs() = dq;
  return 2.0 * (qq.conjugate() * dqq).vec();
}

}  // namespace imumatch
