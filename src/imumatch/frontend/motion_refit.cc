#include "imumatch/frontend/motion_refit.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include "imumatch/core/error.h"
#include "imumatch/core/so3.h"
#include "imumatch/core/statistics.h"
#include "imumatch/frontend/translation_direction.h"

namespace imumatch {
namespace {

// The x with P(chi-square, 6 dof <= x) = p: 1 - exp(-x/2) (1 + x/2 + x^2/8) = p, by bisection.
double ChiSquare6Quantile(double p) {
  auto cdf = [](double x) { return 1.0 - std::exp(-0.5 * x) * (1.0 + 0.5 * x + 0.125 * x * x); };
  double lo = 0.0, hi = 200.0;
  for (int i = 0; i < 100; ++i) {
    const double mid = 0.5 * (lo + hi);
    (cdf(mid) < p ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

// The ray of an ideal pixel, at z = 1.
Eigen::Vector3d Bearing(const PinholeCamera& camera, const Eigen::Vector2d& ideal) {
  return camera.IdealToNormalized(ideal).homogeneous();
}

// A match as bearings (z = 1) in A and B, and the depth in A (NaN: none).
struct Correspondence {
  Eigen::Vector3d xa, xb;
  double z;
};

// One correspondence's residual (ideal px) and its Jacobian; rows 0 when it has none (behind
// camera B, or B's bearing on the epipole).
struct Row {
  Eigen::Matrix<double, 2, 6> j;
  Eigen::Vector2d e;
  int rows;  // 2: reprojection; 1: epipolar (e[1] and j's second row zero); 0: none
  // The row's weight factor: below 1 for an epipolar row that would say more about the
  // translation than a reprojection row at the scene's nearest depth could (MaxEpipolarDedt2).
  double scale;
};

// An epipolar row is a reprojection row at the depth its match triangulates to: d e / d t is
// about f / z there. Near the epipole, or when the translation is tiny (a turn on the spot), that
// depth is ill-conditioned and the linearised row claims a certainty about the translation that
// no point of the scene can give (on a synthetic turn, rows of 0.1 mm translation shrank two of
// the fit's six covariance axes 100-fold and left the truth at squared Mahalanobis 1e4-1e5).
// Such a row keeps the weight of one whose |d e / d t| is f / segment_min_depth: a point at the
// nearest depth the predictions consider. The bound on |d e / d t|^2:
double MaxEpipolarDedt2(double f, const PredictionOptions& prediction) {
  return (f / prediction.segment_min_depth) * (f / prediction.segment_min_depth);
}

// The row of correspondence c at the motion (r, t): a reprojection error when A's keypoint has a
// depth, else the distance from B's keypoint to the epipolar line (both in ideal pixels, f).
void ComputeRow(const Correspondence& c, const Eigen::Matrix3d& r, const Eigen::Vector3d& t,
                double f, double max_dedt2, Row& row) {
  row.rows = 0;
  row.scale = 1.0;
  const Eigen::Vector3d ra = r * c.xa;
  if (std::isfinite(c.z)) {
    const Eigen::Vector3d pr = ra * c.z;
    const Eigen::Vector3d q = pr + t;
    if (!(q.z() > 1e-6)) return;
    row.e = Eigen::Vector2d(f * (q.x() / q.z() - c.xb.x()), f * (q.y() / q.z() - c.xb.y()));
    Eigen::Matrix<double, 2, 3> dpi;
    dpi << f / q.z(), 0.0, -f * q.x() / (q.z() * q.z()), 0.0, f / q.z(),
        -f * q.y() / (q.z() * q.z());
    // dq / d(dtheta) = -Hat(R p), dq / d(dt) = I; a row a of dpi gives -a Hat(p) = -(a x p)^T.
    row.j.block<1, 3>(0, 0) = -dpi.row(0).cross(pr.transpose());
    row.j.block<1, 3>(1, 0) = -dpi.row(1).cross(pr.transpose());
    row.j.rightCols<3>() = dpi;
    row.rows = 2;
    return;
  }
  // Epipolar line l = t x R x_a in B; e = f (x_b . l) / |(l_x, l_y)|.
  const Eigen::Vector3d l = t.cross(ra);
  const double n = std::sqrt(l.x() * l.x() + l.y() * l.y());
  if (!(n > 1e-12)) return;
  row.e = Eigen::Vector2d(f * c.xb.dot(l) / n, 0.0);
  // de / dl = f / n (x_b - (x_b . l) / n^2 (l_x, l_y, 0)): zero along l, so e does not change
  // with t's length. dl / d(dtheta) = -Hat(t) Hat(R x_a), dl / d(dt) = -Hat(R x_a).
  const Eigen::RowVector3d de_dl =
      (f / n) *
      (c.xb.transpose() - (c.xb.dot(l) / (n * n)) * Eigen::RowVector3d(l.x(), l.y(), 0.0));
  // a Hat(v) = (a x v)^T for a row a: -a Hat(t) Hat(ra) = -((a x t) x ra)^T.
  row.j.setZero();
  row.j.block<1, 3>(0, 0) = -(de_dl.cross(t.transpose())).cross(ra.transpose());
  row.j.block<1, 3>(0, 3) = -de_dl.cross(ra.transpose());
  row.rows = 1;
  const double dedt2 = row.j.block<1, 3>(0, 3).squaredNorm();
  if (dedt2 > max_dedt2) row.scale = max_dedt2 / dedt2;
}

// Cauchy weight of a row at squared scale c2 (per residual row).
double CauchyWeight(const Row& row, double c2) {
  return 1.0 / (1.0 + row.e.squaredNorm() / (row.rows * c2));
}

// h's upper triangle += w j^T j and g += w j^T e over a row's `rows` residual rows: rank-one
// updates of the 21 entries that the symmetric normal matrix has (the product of the whole 6 x 2
// by 2 x 6 block costs 72 multiply-adds and a temporary, half of them on an epipolar row's zero
// second row). MirrorUpper fills the lower triangle once per system.
template <int kRows>
[[gnu::always_inline]] inline void AccumulateRowsUpper(const Eigen::Matrix<double, 2, 6>& j,
                                                       const Eigen::Vector2d& e, double w,
                                                       Eigen::Matrix<double, 6, 6>& h,
                                                       Eigen::Matrix<double, 6, 1>& g) {
  for (int k = 0; k < kRows; ++k) {
    double v[6], wv[6];
    for (int a = 0; a < 6; ++a) {
      v[a] = j(k, a);
      wv[a] = w * v[a];
    }
    for (int b = 0; b < 6; ++b) {
      for (int a = 0; a <= b; ++a) h(a, b) += wv[a] * v[b];
      g[b] += wv[b] * e[k];
    }
  }
}

[[gnu::always_inline]] inline void AccumulateUpper(const Eigen::Matrix<double, 2, 6>& j,
                                                   const Eigen::Vector2d& e, int rows, double w,
                                                   Eigen::Matrix<double, 6, 6>& h,
                                                   Eigen::Matrix<double, 6, 1>& g) {
  if (rows == 1) {
    AccumulateRowsUpper<1>(j, e, w, h, g);
  } else if (rows == 2) {
    AccumulateRowsUpper<2>(j, e, w, h, g);
  }
}

void MirrorUpper(Eigen::Matrix<double, 6, 6>& h) {
  for (int b = 0; b < 6; ++b) {
    for (int a = b + 1; a < 6; ++a) h(a, b) = h(b, a);
  }
}

// The robust sigma of residuals (pixels) from the median of their absolute values: 1.4826 x the
// median (a Gaussian's sigma), never below the floor min_residual_px.
double SigmaFromMedianPx(double median_abs_px, double min_residual_px) {
  return std::max(1.4826 * median_abs_px, min_residual_px);
}

// The prior's covariance with 1e-12 on its diagonal: invertible, and an exact prior (zero
// covariance) stays as good as exact.
Eigen::Matrix<double, 6, 6> RegularisedCovariance(const CameraMotion& prior) {
  Eigen::Matrix<double, 6, 6> cov = prior.covariance;
  cov.diagonal().array() += 1e-12;
  return cov;
}

// The perturbation [dtheta; dt] from the prior (r_prior, t_prior) to the motion (r, t), in
// CameraMotion's convention (MotionPerturbation), on the iterated rotation matrices.
Eigen::Matrix<double, 6, 1> PriorOffset(const Eigen::Matrix3d& r, const Eigen::Vector3d& t,
                                        const Eigen::Matrix3d& r_prior,
                                        const Eigen::Vector3d& t_prior) {
  Eigen::Matrix<double, 6, 1> d;
  d.head<3>() = LogSO3(Eigen::Quaterniond(r * r_prior.transpose()));
  d.tail<3>() = t - t_prior;
  return d;
}

// Gauss-Newton from the prior's rotation and translation t_from (see RefitMotion). When the fit
// holds, *r_out (if given) receives its rotation as iterated.
MotionRefit SolveFrom(const Eigen::Vector3d& t_from, const std::vector<Correspondence>& cs,
                      const MotionRefit& base, const Eigen::Matrix3d& r_prior,
                      const Eigen::Vector3d& t_prior, const Eigen::Matrix<double, 6, 6>& prior_info,
                      double f, const PredictionOptions& prediction,
                      const MotionRefitOptions& options, Eigen::Matrix3d* r_out) {
  MotionRefit out = base;
  Eigen::Matrix3d r = r_prior;
  Eigen::Vector3d t = t_from;
  auto from_prior = [&] { return PriorOffset(r, t, r_prior, t_prior); };

  double sigma = options.min_residual_px;
  const double max_dedt2 = MaxEpipolarDedt2(f, prediction);

  // Per iteration: every residual and Jacobian once; while reweighting, their robust sigma and
  // Cauchy weights; then the normal equations of the weighted residuals and the prior.
  // Reweighting every step converges only linearly (about halving the error per step on MH_05),
  // so the sigma and the weights are kept once the sigma settles (or after
  // options.reweight_steps): Gauss-Newton on the fixed weighted problem then converges in a few.
  std::vector<Row> rs(cs.size());
  std::vector<double> weight(cs.size(), 0.0);
  std::vector<double> abs_rows;
  abs_rows.reserve(2 * cs.size());
  Eigen::Matrix<double, 6, 6> info = Eigen::Matrix<double, 6, 6>::Zero();
  double last_step2 = std::numeric_limits<double>::infinity();  // squared, in the fit's sigmas
  bool reweight = true;
  for (int iteration = 0; iteration <= options.iterations; ++iteration) {
    // Reweight until the sigma settles (within 1 % of the previous step's) or reweight_steps.
    reweight = reweight && iteration < options.reweight_steps;
    abs_rows.clear();
    for (size_t i = 0; i < cs.size(); ++i) {
      Row& row = rs[i];
      ComputeRow(cs[i], r, t, f, max_dedt2, row);
      if (row.rows == 0) continue;
      abs_rows.push_back(std::fabs(row.e[0]));
      if (row.rows == 2) abs_rows.push_back(std::fabs(row.e[1]));
    }
    if (abs_rows.empty()) break;
    bool reweighted = false;
    if (reweight) {
      const double next = SigmaFromMedianPx(UpperMedianInPlace(abs_rows), options.min_residual_px);
      reweight = iteration == 0 || std::fabs(next - sigma) > 0.01 * sigma;
      reweighted = true;
      sigma = next;
    }
    const double c2 = options.cauchy_scale * options.cauchy_scale * sigma * sigma;
    const double inlier2 = options.inlier_sigmas * options.inlier_sigmas * sigma * sigma;
    Eigen::Matrix<double, 6, 6> h = Eigen::Matrix<double, 6, 6>::Zero();
    Eigen::Matrix<double, 6, 1> g = Eigen::Matrix<double, 6, 1>::Zero();
    out.inliers = 0;
    for (size_t i = 0; i < cs.size(); ++i) {
      const Row& row = rs[i];
      if (row.rows == 0) continue;
      const bool inlier = row.e.squaredNorm() <= inlier2 * row.rows;
      out.inliers += inlier ? 1 : 0;
      if (reweighted) weight[i] = CauchyWeight(row, c2);
      const double w =
          (!reweighted && options.reject_beyond_inliers && !inlier ? 0.0 : weight[i]) * row.scale;
      AccumulateUpper(row.j, row.e, row.rows, w, h, g);
    }
    MirrorUpper(h);
    info = h / (sigma * sigma);
    if (iteration == options.iterations) break;  // the last pass only evaluates
    ++out.iterations;
    const Eigen::Matrix<double, 6, 1> step =
        -(prior_info + info).ldlt().solve(prior_info * from_prior() + g / (sigma * sigma));
    if (!step.allFinite()) break;
    r = ExpSO3(step.head<3>()).toRotationMatrix() * r;
    t += step.tail<3>();
    // Converged: the step is below a tenth of the fit's own standard deviation (the windows
    // around the predictions are at least the keypoints' noise, far wider).
    last_step2 = step.dot((prior_info + info) * step);
    if (!reweighted && last_step2 < 1e-2) {
      iteration = options.iterations - 1;  // one more pass to evaluate at the final motion
    }
  }
  out.sigma_px = sigma;
  // The last pass's residuals, at the final motion.
  if (!abs_rows.empty()) out.median_residual_px = UpperMedianInPlace(abs_rows);
  const Eigen::Matrix<double, 6, 1> d = from_prior();
  out.mahalanobis2 = d.dot(prior_info * d);
  if (out.inliers < options.min_inliers) {
    out.reason = "motion fit: " + std::to_string(out.inliers) + " inliers";
    return out;
  }
  // The windows assume the keypoints' localisation noise in both frames (sqrt(2) x
  // keypoint_sigma_px per axis, before the size scaling): residuals beyond it mean the motion
  // does not explain the pair (a moving object, a wrong depth map, two motions) and the IMU's
  // wider windows stand.
  const double noise_px = std::sqrt(2.0) * prediction.keypoint_sigma_px;
  if (!(sigma <= noise_px)) {
    out.reason = "motion fit: residuals (robust sigma " + std::to_string(sigma) +
                 " px) beyond the keypoints' noise (" + std::to_string(noise_px) + " px)";
    return out;
  }
  // Not converged: the last step was more than the fit's own standard deviation, so the windows
  // would be centred farther from the optimum than their motion part is wide.
  if (!(last_step2 <= 1.0)) {
    out.not_converged = true;
    out.reason = "motion fit: not converged in " + std::to_string(options.iterations) + " steps";
    return out;
  }
  const double gate = MotionAgreementGate(options.agreement_probability);
  if (!(out.mahalanobis2 <= gate) || !r.allFinite() || !t.allFinite()) {
    out.disagrees = true;
    out.reason = "the fit disagrees with the prior motion (squared Mahalanobis distance " +
                 std::to_string(out.mahalanobis2) + " > " + std::to_string(gate) + ")";
    return out;
  }
  Eigen::Matrix<double, 6, 6> cov = (prior_info + info).inverse();
  out.ok = cov.allFinite();
  if (!out.ok) {
    out.reason = "motion fit: singular information";
    return out;
  }
  out.motion.cam_b_from_cam_a = Rigid3d(Eigen::Quaterniond(r).normalized(), t);
  out.motion.covariance = 0.5 * (cov + cov.transpose());
  if (r_out != nullptr) *r_out = r;
  return out;
}

// The rotation the matches alone measure (MotionRefit::rotation_from_matches and its covariance,
// set in out when the solve converges) from a fit that holds: r, t the fit's motion (its rotation
// as SolveFrom left it), then where the solve ended; sigma the residuals' robust sigma.
void MeasureRotationFromMatches(const std::vector<Correspondence>& cs, Eigen::Matrix3d& r,
                                Eigen::Vector3d& t, double sigma, const Eigen::Matrix3d& r_prior,
                                const Eigen::Vector3d& t_prior,
                                const Eigen::Matrix<double, 6, 6>& prior_cov, double f,
                                const PredictionOptions& prediction,
                                const MotionRefitOptions& options, MotionRefit& out) {
  out.rotation_from_matches_ok = false;
  const double max_dedt2 = MaxEpipolarDedt2(f, prediction);
  auto from_prior = [&] { return PriorOffset(r, t, r_prior, t_prior); };

  // The rotation the matches alone measure, for a gyro bias filter (ImuRotationFromFit): the
  // same residuals from the fit on, with the prior's translation information only (the epipolar
  // residuals do not see the translation's length) and the Cauchy weights recomputed every step
  // (iteratively reweighted least squares at the fit's sigma). Weights kept from the fit would be
  // those of a motion the prior pulled: on 40 scenes with a prior 3 sigma off in rotation, one
  // step from the fit with its weights kept 9 % of the prior's offset.
  Eigen::Matrix<double, 6, 6> translation_info = Eigen::Matrix<double, 6, 6>::Zero();
  translation_info.bottomRightCorner<3, 3>() = prior_cov.bottomRightCorner<3, 3>().inverse();
  const double c2 = options.cauchy_scale * options.cauchy_scale * sigma * sigma;
  Eigen::Matrix<double, 6, 6> alone = Eigen::Matrix<double, 6, 6>::Zero();
  bool converged = false;
  for (int iteration = 0; iteration < 3 * options.iterations && !converged; ++iteration) {
    Eigen::Matrix<double, 6, 6> h = Eigen::Matrix<double, 6, 6>::Zero();
    Eigen::Matrix<double, 6, 1> g = Eigen::Matrix<double, 6, 1>::Zero();
    for (const Correspondence& c : cs) {
      Row row;
      ComputeRow(c, r, t, f, max_dedt2, row);
      if (row.rows == 0) continue;
      const double w = CauchyWeight(row, c2) * row.scale;
      AccumulateUpper(row.j, row.e, row.rows, w, h, g);
    }
    MirrorUpper(h);
    alone = translation_info + h / (sigma * sigma);
    const Eigen::LDLT<Eigen::Matrix<double, 6, 6>> ldlt(alone);
    if (ldlt.info() != Eigen::Success || !ldlt.isPositive()) break;
    const Eigen::Matrix<double, 6, 1> step =
        -ldlt.solve(translation_info * from_prior() + g / (sigma * sigma));
    if (!step.allFinite()) break;
    r = ExpSO3(step.head<3>()).toRotationMatrix() * r;
    t += step.tail<3>();
    converged = step.dot(alone * step) < 1e-4;  // a hundredth of its own sigma
  }
  if (converged) {
    const Eigen::Matrix<double, 6, 6> alone_cov = alone.inverse();
    const Eigen::Matrix3d cov_theta =
        0.5 * (alone_cov.topLeftCorner<3, 3>() + alone_cov.topLeftCorner<3, 3>().transpose());
    if (cov_theta.allFinite() && Eigen::LLT<Eigen::Matrix3d>(cov_theta).info() == Eigen::Success) {
      out.rotation_from_matches_ok = true;
      out.rotation_from_matches = Eigen::Quaterniond(r).normalized();
      out.rotation_from_matches_covariance = cov_theta;
    }
  }
}

// Of two fits of the same matches from different starts: one that holds beats one that does not;
// of two that hold, the one whose residuals are smaller (median, by more than 1 %), else the
// one nearer the prior.
bool FitIsBetter(const MotionRefit& a, const MotionRefit& b) {
  if (a.ok != b.ok) return a.ok;
  if (!a.ok) return false;
  const double ma = a.median_residual_px, mb = b.median_residual_px;
  if (std::fabs(ma - mb) > 0.01 * std::max(ma, mb)) return ma < mb;
  return a.mahalanobis2 < b.mahalanobis2;
}

}  // namespace

void MotionRefitOptions::Check() const {
  IMUMATCH_CHECK(std::isfinite(min_residual_px) && min_residual_px > 0.0,
                 "min_residual_px=" << min_residual_px);
  IMUMATCH_CHECK(std::isfinite(cauchy_scale) && cauchy_scale > 0.0,
                 "cauchy_scale=" << cauchy_scale);
  IMUMATCH_CHECK(std::isfinite(inlier_sigmas) && inlier_sigmas > 0.0,
                 "inlier_sigmas=" << inlier_sigmas);
  IMUMATCH_CHECK(min_inliers >= 6, "min_inliers=" << min_inliers << " (a motion has 6 dof)");
  IMUMATCH_CHECK(iterations >= 1 && iterations <= 100, "iterations=" << iterations);
  IMUMATCH_CHECK(reweight_steps >= 1 && reweight_steps <= iterations,
                 "reweight_steps=" << reweight_steps << " (1 .. iterations=" << iterations << ")");
  IMUMATCH_CHECK(direction_hypotheses >= 0 && direction_hypotheses <= 10000,
                 "direction_hypotheses=" << direction_hypotheses << " (0 .. 10000)");
  IMUMATCH_CHECK(agreement_probability > 0.0 && agreement_probability < 1.0,
                 "agreement_probability=" << agreement_probability << " (must be in (0, 1))");
}

Eigen::Vector2d PositionInB(const Match& m, const std::vector<cv::KeyPoint>& keypoints_b) {
  if (m.refined_uv_b.allFinite()) return m.refined_uv_b.cast<double>();
  const cv::Point2f& p = keypoints_b[static_cast<size_t>(m.train_idx)].pt;
  return Eigen::Vector2d(p.x, p.y);
}

std::vector<float> FitDepths(const cv::Mat& depth_a, double depth_scale,
                             const std::vector<cv::KeyPoint>& keypoints_a,
                             const std::vector<float>& depths_a,
                             const MotionRefitOptions& options) {
  std::vector<float> out = depths_a;
  if (!out.empty()) {
    ClearDepthsNearEdges(depth_a, depth_scale, keypoints_a, options.depth_edges, &out);
  }
  return out;
}

namespace {

// The matches as correspondences (bearings, z = 1, in A and B, B's at the refined or tracked
// position; A's depth or NaN), those whose bearings are finite; *with_depth counts those with a
// usable depth. Throws InvalidArgument for a match outside the keypoints.
std::vector<Correspondence> ToCorrespondences(
    const std::vector<Match>& matches, const std::vector<cv::KeyPoint>& keypoints_a,
    const std::vector<cv::KeyPoint>& keypoints_b, const std::vector<float>& depths_a,
    const PredictionOptions& prediction, const PixelUndistorter& undistorter, int* with_depth) {
  IMUMATCH_CHECK(depths_a.empty() || depths_a.size() == keypoints_a.size(),
                 depths_a.size() << " depths for " << keypoints_a.size() << " keypoints of A");
  const PinholeCamera& camera = undistorter.camera();
  *with_depth = 0;
  std::vector<Correspondence> cs;
  cs.reserve(matches.size());
  for (const Match& m : matches) {
    IMUMATCH_CHECK(
        m.query_idx >= 0 && static_cast<size_t>(m.query_idx) < keypoints_a.size(),
        "match query " << m.query_idx << " outside A's " << keypoints_a.size() << " keypoints");
    IMUMATCH_CHECK(
        m.refined_uv_b.allFinite() ||
            (m.train_idx >= 0 && static_cast<size_t>(m.train_idx) < keypoints_b.size()),
        "match train " << m.train_idx << " outside B's " << keypoints_b.size() << " keypoints");
    const cv::Point2f& ka = keypoints_a[static_cast<size_t>(m.query_idx)].pt;
    Correspondence c;
    c.xa = Bearing(camera, undistorter.ToIdeal(Eigen::Vector2d(ka.x, ka.y)));
    c.xb = Bearing(camera, undistorter.ToIdeal(PositionInB(m, keypoints_b)));
    if (!c.xa.allFinite() || !c.xb.allFinite()) continue;
    c.z = std::numeric_limits<double>::quiet_NaN();
    if (!depths_a.empty()) {
      const double z = depths_a[static_cast<size_t>(m.query_idx)];
      if (prediction.IsUsableDepth(z)) {
        c.z = z;
        ++*with_depth;
      }
    }
    cs.push_back(c);
  }
  return cs;
}

}  // namespace

double MotionAgreementGate(double probability) {
  IMUMATCH_CHECK(probability > 0.0 && probability < 1.0,
                 "agreement probability " << probability << " must be in (0, 1)");
  return ChiSquare6Quantile(probability);
}

MotionRefit RefitMotion(const CameraMotion& prior, const std::vector<Match>& matches,
                        const std::vector<cv::KeyPoint>& keypoints_a,
                        const std::vector<cv::KeyPoint>& keypoints_b,
                        const std::vector<float>& depths_a, const PredictionOptions& prediction,
                        const PixelUndistorter& undistorter, const MotionRefitOptions& options) {
  options.Check();
  IMUMATCH_CHECK(prior.covariance.allFinite(), "prior motion covariance is not finite");
  MotionRefit base;
  base.motion = prior;
  const PinholeCamera& camera = undistorter.camera();
  const double f = 0.5 * (camera.fx + camera.fy);
  const std::vector<Correspondence> cs = ToCorrespondences(
      matches, keypoints_a, keypoints_b, depths_a, prediction, undistorter, &base.with_depth);
  base.correspondences = static_cast<int>(cs.size());
  if (base.correspondences < options.min_inliers) {
    base.reason = "too few matches (" + std::to_string(base.correspondences) + ")";
    return base;
  }

  const Eigen::Matrix<double, 6, 6> prior_cov = RegularisedCovariance(prior);
  const Eigen::Matrix<double, 6, 6> prior_info = prior_cov.inverse();
  const Eigen::Matrix3d r_prior = prior.cam_b_from_cam_a.RotationMatrix();
  const Eigen::Vector3d& t_prior = prior.cam_b_from_cam_a.translation;
  // Start: the prior's rotation and length, and the translation direction the epipolar
  // constraints favour when it explains the matches better than the prior's (a translation
  // under 1 mm has no direction to estimate). A second start from SearchTranslationDirection when
  // its direction differs (by more than a degree) and explains the matches better than where the
  // fit from the first ended: then the fit runs again from it and the better fit is kept
  // (FitIsBetter).
  Eigen::Vector3d t_start = t_prior;
  bool second_start = false;  // a searched start that differs from t_start
  TranslationSearchResult searched{t_prior, 0.0};
  std::vector<Eigen::Vector3d> ra_prior, xb_all;  // R_prior x_a, x_b
  double start_sigma = options.min_residual_px;
  if (t_prior.norm() >= 1e-3) {
    ra_prior.resize(cs.size());
    xb_all.resize(cs.size());
    for (size_t i = 0; i < cs.size(); ++i) {
      ra_prior[i] = r_prior * cs[i].xa;
      xb_all[i] = cs[i].xb;
    }
    std::vector<double> scratch;
    const Eigen::Vector3d dir = EpipolarTranslationDirection(
        ra_prior, xb_all, t_prior, f, options.min_residual_px, options.cauchy_scale, scratch);
    double start_median = MedianEpipolarDistancePx(ra_prior, xb_all, t_prior, f, scratch);
    const double dir_median = MedianEpipolarDistancePx(ra_prior, xb_all, dir, f, scratch);
    if (dir_median < start_median) {
      t_start = t_prior.norm() * dir;
      start_median = dir_median;
    }
    if (options.direction_hypotheses > 0) {
      start_sigma = SigmaFromMedianPx(start_median, options.min_residual_px);
      searched = SearchTranslationDirection(
          ra_prior, xb_all, t_start, t_prior, prior_info.bottomRightCorner<3, 3>(), f, start_sigma,
          options.cauchy_scale, options.direction_hypotheses, scratch);
      second_start = searched.translation.normalized().dot(t_start.normalized()) <
                     std::cos(1.0 * M_PI / 180.0);
    }
  }

  auto solve = [&](const Eigen::Vector3d& t_from, Eigen::Matrix3d* r_fit) {
    return SolveFrom(t_from, cs, base, r_prior, t_prior, prior_info, f, prediction, options, r_fit);
  };
  // The rotation the matches alone show, of the fit returned only (not of a fit that a second
  // start replaces).
  auto measured = [&](MotionRefit fit, const Eigen::Matrix3d& r_fit) {
    if (fit.ok && options.measure_rotation) {
      Eigen::Matrix3d r = r_fit;
      Eigen::Vector3d t = fit.motion.cam_b_from_cam_a.translation;
      MeasureRotationFromMatches(cs, r, t, fit.sigma_px, r_prior, t_prior, prior_cov, f, prediction,
                                 options, fit);
    }
    return fit;
  };
  Eigen::Matrix3d r_first = r_prior, r_second = r_prior;
  MotionRefit first = solve(t_start, &r_first);
  if (!second_start) return measured(first, r_first);
  // The first fit's direction at the prior's length, under the search's cost: when the searched
  // start explains the matches better, the first fit settled in a wrong minimum.
  const double cost_first = TranslationDirectionCost(
      ra_prior, xb_all, t_prior.norm() * first.motion.cam_b_from_cam_a.translation.normalized(), f,
      start_sigma, options.cauchy_scale, t_prior, prior_info.bottomRightCorner<3, 3>());
  if (!(searched.cost < cost_first)) return measured(first, r_first);
  MotionRefit second = solve(searched.translation, &r_second);
  return FitIsBetter(second, first) ? measured(second, r_second) : measured(first, r_first);
}

void MeasureRotationFromMatches(const CameraMotion& prior, const std::vector<Match>& matches,
                                const std::vector<cv::KeyPoint>& keypoints_a,
                                const std::vector<cv::KeyPoint>& keypoints_b,
                                const std::vector<float>& depths_a,
                                const PredictionOptions& prediction,
                                const PixelUndistorter& undistorter,
                                const MotionRefitOptions& options, MotionRefit* refit) {
  IMUMATCH_CHECK(refit != nullptr, "MeasureRotationFromMatches needs a fit");
  options.Check();
  IMUMATCH_CHECK(prior.covariance.allFinite(), "prior motion covariance is not finite");
  refit->rotation_from_matches_ok = false;
  if (!refit->ok) return;
  int with_depth = 0;
  const std::vector<Correspondence> cs = ToCorrespondences(
      matches, keypoints_a, keypoints_b, depths_a, prediction, undistorter, &with_depth);
  if (static_cast<int>(cs.size()) < options.min_inliers) return;
  const PinholeCamera& camera = undistorter.camera();
  const double f = 0.5 * (camera.fx + camera.fy);
  Eigen::Matrix3d r = refit->motion.cam_b_from_cam_a.RotationMatrix();
  Eigen::Vector3d t = refit->motion.cam_b_from_cam_a.translation;
  const Eigen::Matrix<double, 6, 6> prior_cov = RegularisedCovariance(prior);
  const Eigen::Matrix3d r_prior = prior.cam_b_from_cam_a.RotationMatrix();
  const double max_dedt2 = MaxEpipolarDedt2(f, prediction);
  // These matches' own robust sigma, as SolveFrom measures its rows': at the fit first, then at
  // the rotation they measure until it settles (within 1 %). At the fit alone it would be too
  // wide when the fit leaned towards the prior (on 40 synthetic scenes with a prior 4 mrad off,
  // the mean chi-square of the measurement was 0.44 instead of 3).
  std::vector<double> abs_rows;
  abs_rows.reserve(2 * cs.size());
  double sigma = 0.0;
  for (int pass = 0; pass < 4; ++pass) {
    abs_rows.clear();
    for (const Correspondence& c : cs) {
      Row row;
      ComputeRow(c, r, t, f, max_dedt2, row);
      if (row.rows >= 1) abs_rows.push_back(std::fabs(row.e[0]));
      if (row.rows == 2) abs_rows.push_back(std::fabs(row.e[1]));
    }
    if (abs_rows.empty()) return;
    const double next = SigmaFromMedianPx(UpperMedianInPlace(abs_rows), options.min_residual_px);
    if (pass > 0 && std::fabs(next - sigma) <= 0.01 * sigma) break;
    sigma = next;
    MeasureRotationFromMatches(cs, r, t, sigma, r_prior, prior.cam_b_from_cam_a.translation,
                               prior_cov, f, prediction, options, *refit);
    if (!refit->rotation_from_matches_ok) return;
  }
}

}  // namespace imumatch
