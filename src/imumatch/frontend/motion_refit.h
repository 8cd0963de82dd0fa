#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "imumatch/camera/pixel_undistorter.h"
#include "imumatch/imu/camera_motion.h"
#include "imumatch/matching/depth_edges.h"
#include "imumatch/matching/match_types.h"
#include "imumatch/matching/predictor.h"

namespace imumatch {

// The motion that a first guided pass's matches show, with the fit's own covariance, for a second
// pass whose windows shrink to it: the IMU's prediction is good to a few pixels (velocity, gravity
// and bias errors), a pose fitted on hundreds of matches to a fraction of one.
struct MotionRefitOptions {
  // The residuals' scale is their robust sigma (1.4826 x median absolute residual), at least
  // min_residual_px (ideal px): a residual below the keypoints' own noise is luck, not accuracy.
  double min_residual_px = 0.5;
  // Cauchy loss at cauchy_scale robust sigmas (2.3849: 95 % efficiency on Gaussian residuals):
  // the first pass's matches all lie in the IMU's windows, but a few are wrong or moving.
  double cauchy_scale = 2.3849;
  // A match within inlier_sigmas robust sigmas of the fitted geometry counts as an inlier; fewer
  // than min_inliers inliers: no fit.
  double inlier_sigmas = 3.0;
  int min_inliers = 12;
  // Gauss-Newton steps. The residuals' sigma and Cauchy weights are re-estimated each step until
  // the sigma settles (within 1 %) or for reweight_steps, then kept: reweighting every step
  // converges only linearly (about halving the error per step on EuRoC MH_05). It stops once a
  // step with fixed weights is below a tenth of the fit's standard deviation; a fit whose last
  // step was more than one is not used.
  int reweight_steps = 8;
  int iterations = 12;
  // Once the weights are kept, a row beyond inlier_sigmas robust sigmas of the current motion
  // gets no weight (it is looked at again each step). Cauchy's influence decays only as 1 / e: a
  // fifth of wrong matches 3-15 px off pulled a fit without depth by degrees and added their rows'
  // information to its covariance, which then excluded the truth. 40 synthetic take-off scenes
  // (MotionRefitTest.AtTakeOffAPriorFarOffInDirectionIsCorrected): truth outside the 99.9 %
  // ellipsoid 17 -> 8 of 39 fits, direction error 11.1 -> 7.9 deg; without wrong matches no change.
  bool reject_beyond_inliers = true;
  // The fit replaces the prior motion only when the two agree: the squared Mahalanobis distance of
  // the fitted motion from the prior under the prior's covariance within the chi-square quantile
  // (6 degrees of freedom) of this probability. A fit outside it has locked onto a wrong structure
  // (a repeated texture, a moving object) or the prior is wrong; either way the prior's wider
  // windows are the safe ones.
  double agreement_probability = 0.9999;
  // The fit starts from the prior's translation direction or the one the epipolar constraints
  // favour near it; from a prior tens of degrees off in direction (a short translation: hovering,
  // take-off) that start can lead to a wrong minimum. direction_hypotheses directions through
  // pairs of matches are scored as well, and when the best explains the matches better than the
  // first fit, the fit runs again from it and the better of the two is kept. 0: no second start.
  int direction_hypotheses = 48;
  // Also solve for the rotation the matches alone measure (MotionRefit::rotation_from_matches,
  // for a gyro bias filter): a second, reweighted solve from the fit on, so only when asked.
  bool measure_rotation = false;
  // FitDepths clears, from the depths the callers give the fit, the readings near an edge of the
  // depth image (ClearDepthsNearEdges): such a keypoint gives an epipolar residual instead. The
  // length of the translation rests on the few nearest keypoints with depth (their parallax is
  // largest), so a handful of corners read with the foreground's depth set it: on EuRoC MH_05's
  // take-off, three frames apart, a dozen corners along a beam's outline at 0.6 m pulled the fit
  // to 3 mm of a 24 mm translation with a stated sigma of 0.6 mm, and its windows lost 9 % of the
  // pair's correct matches. The predictions keep those depths (a wrong one costs its own keypoint
  // only).
  DepthEdgeOptions depth_edges;
  void Check() const;  // throws InvalidArgument
};

struct MotionRefit {
  bool ok = false;             // motion holds the fit; otherwise it is the prior, unchanged
  bool disagrees = false;      // not ok because the fit lies beyond the prior's uncertainty
  bool not_converged = false;  // not ok because the last step exceeded the fit's own sigma
  std::string reason;          // why not ok
  int correspondences = 0;
  int with_depth = 0;  // of them, with a usable depth in A (reprojection residuals)
  int inliers = 0;
  int iterations = 0;     // Gauss-Newton steps taken
  double sigma_px = 0.0;  // the residuals' robust sigma (ideal px), at least min_residual_px
  double median_residual_px = 0.0;  // median absolute residual row (ideal px) at the motion
  double mahalanobis2 = 0.0;        // of the fit from the prior
  CameraMotion motion;
  // The rotation cam_b_from_cam_a that the matches alone measure (without the prior's rotation,
  // with its translation: see ImuRotationFromFit) and its covariance (3x3, left perturbation as
  // CameraMotion's); set when ok, options.measure_rotation and that solve converged.
  bool rotation_from_matches_ok = false;
  Eigen::Quaterniond rotation_from_matches = Eigen::Quaterniond::Identity();
  Eigen::Matrix3d rotation_from_matches_covariance = Eigen::Matrix3d::Zero();
};

// The rotation that other matches of the same pair alone measure, from refit's fit on: replaces
// refit's rotation_from_matches (and _ok, _covariance) as RefitMotion sets them with
// measure_rotation, but from matches found in the fit's own windows (a second pass, refined)
// instead of the first pass's. The first pass's were found in the prior's windows, and where the
// prior's rotation is off (a camera clock offset, a gyro bias), the matches at a window's edge that
// it cut or kept lean the rotation measured from them towards the prior's: on EuRoC MH_05 with the
// camera's clock shifted by +10 / -20 ms, the offset read from the first pass's rotations was
// -8.9 / +18.6 ms, from the final matches' -9.9 / +20.0 ms (ORB, 199 pairs). prior: the motion
// RefitMotion started from (its translation information is used, not its rotation). The
// residuals' robust sigma is these matches' at the fit. Not set (ok false) when refit does not
// hold, fewer than options.min_inliers matches remain or the solve does not converge.
void MeasureRotationFromMatches(const CameraMotion& prior, const std::vector<Match>& matches,
                                const std::vector<cv::KeyPoint>& keypoints_a,
                                const std::vector<cv::KeyPoint>& keypoints_b,
                                const std::vector<float>& depths_a,
                                const PredictionOptions& prediction,
                                const PixelUndistorter& undistorter,
                                const MotionRefitOptions& options, MotionRefit* refit);

// Where a correspondence ends in B (image pixels): the refined position or the track's, else the
// matched keypoint.
Eigen::Vector2d PositionInB(const Match& m, const std::vector<cv::KeyPoint>& keypoints_b);

// The squared Mahalanobis distance (6 degrees of freedom) within which a motion agrees with a
// prior with the given probability: the chi-square quantile of RefitMotion's agreement test
// (MotionRefitOptions::agreement_probability; 0.9999: 27.86). InvalidArgument outside (0, 1).
double MotionAgreementGate(double probability);

// The depths to give RefitMotion for A's keypoints: depths_a (SampleDepths of depth_a, metres, NaN
// for none) with the readings near an edge of depth_a cleared as options.depth_edges says; empty
// when depths_a is (then depth_a is not read). Throws InvalidArgument as ClearDepthsNearEdges.
std::vector<float> FitDepths(const cv::Mat& depth_a, double depth_scale,
                             const std::vector<cv::KeyPoint>& keypoints_a,
                             const std::vector<float>& depths_a, const MotionRefitOptions& options);

// The maximum a posteriori motion A -> B given the prior (the IMU's motion and covariance) and the
// matches (query: keypoints_a, train: keypoints_b, image pixels; the refined position in B when
// there is one), with its covariance (the prior's information plus the matches'):
//  - a match whose keypoint of A has a usable depth (depths_a: metres per keypoint of A, or
//    empty; prediction.IsUsableDepth) gives its reprojection error in B (2 rows, ideal px);
//  - one without gives its epipolar distance (1 row, ideal px), which says nothing about the
//    translation's length: that stays the prior's (the IMU's scale);
// Gauss-Newton from the prior on the perturbation [dtheta; dt] of CameraMotion (R_true =
// Exp(dtheta) R, t_true = t + dt), Cauchy-weighted residuals, started from the prior with the
// translation direction the epipolar constraints favour. Not ok (the prior returned, with the
// reason) when: too few matches or inliers; the residuals' robust sigma exceeds the keypoints'
// noise, sqrt(2) x prediction.keypoint_sigma_px (the motion does not explain the pair); no
// convergence; the fit is beyond agreement_probability of the prior. Throws InvalidArgument for
// indices outside the keypoints or depths_a of another size.
MotionRefit RefitMotion(const CameraMotion& prior, const std::vector<Match>& matches,
                        const std::vector<cv::KeyPoint>& keypoints_a,
                        const std::vector<cv::KeyPoint>& keypoints_b,
                        const std::vector<float>& depths_a, const PredictionOptions& prediction,
                        const PixelUndistorter& undistorter, const MotionRefitOptions& options);

}  // namespace imumatch
