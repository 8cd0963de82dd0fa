#include "imumatch/frontend/front_end.h"

// FrontEnd's matching passes and its pose fit (front_end.cc: the frame's other stages).

#include <algorithm>
#include <iomanip>
#include <sstream>

#include "imumatch/core/statistics.h"
#include "imumatch/frontend/second_pass.h"
#include "imumatch/matching/baseline_matchers.h"
#include "imumatch/matching/scene_depth.h"

namespace imumatch {

std::vector<Match> FrontEnd::MatchPass(const CameraMotion& motion, const Features& features,
                                       const std::vector<KeypointInfo>& ideal, const cv::Mat& image,
                                       bool patch_look, const std::vector<Match>* first_pass,
                                       SceneNearDepth& scene,
                                       std::vector<KeypointPrediction>& predictions,
                                       int& from_tracks) {
  const Previous& prev = *previous_;
  const PinholeCamera& camera = undistorter_.camera();
  GridIndex grid;
  grid.Build(ideal, camera.width, camera.height,
             static_cast<float>(options_.guided.grid_cell_size));
  GuidedCandidates candidates;  // B prepared once for the pilot and the search
  PrepareGuidedCandidates(ideal, grid, DescriptorView::FromMat(features.descriptors), &candidates);
  GuidedSearchScratch scratch;
  const KeypointPredictor predictor(undistorter_, motion, options_.prediction);
  if (first_pass != nullptr && options_.neighbour_depth.enabled) {
    // Second pass: the first pass's near end, and each keypoint without depth along its
    // neighbours' inverse depths where it has enough of them (no second pilot).
    PredictKeypointsNearMatches(predictor.WithSceneNearEnd(scene), prev.ideal, prev.depths,
                                *first_pass, ideal, options_.neighbour_depth, &predictions);
  } else {
    scene = PredictKeypointsInScene(predictor, prev.ideal, prev.depths,
                                    DescriptorView::FromMat(prev.features.descriptors), ideal,
                                    candidates, options_.guided, &predictions, &scratch);
  }
  std::vector<Match> out;
  std::vector<KeypointPrediction> rest;
  const std::vector<KeypointPrediction>* guided_predictions = &predictions;
  from_tracks = 0;
  if (options_.hybrid) {
    const TrackingPyramid pa = TrackingPyramid::Build(prev.image, options_.klt.max_level);
    const TrackingPyramid pb = TrackingPyramid::Build(image, options_.klt.max_level);
    TrackResult tracks =
        TrackSeeded(pa, pb, prev.features.keypoints, predictions, undistorter_, options_.klt);
    rest = PredictionsOfFailedTracks(predictions, tracks);
    guided_predictions = &rest;
    from_tracks = static_cast<int>(tracks.tracks.size());
    out = std::move(tracks.tracks);
  }
  MatchResult r = MatchGuided(*guided_predictions, prev.ideal,
                              DescriptorView::FromMat(prev.features.descriptors), candidates,
                              options_.guided, &scratch);
  if (patch_look && options_.patch_second_look) {
    MatchByPatch(*guided_predictions, prev.ideal, prev.features.keypoints,
                 DescriptorView::FromMat(prev.features.descriptors), ideal, grid,
                 features.keypoints, DescriptorView::FromMat(features.descriptors), prev.image,
                 image, camera, options_.guided, options_.patch, &r);
  }
  if (options_.refine_subpixel) {
    RefineMatches(prev.image, image, prev.features.keypoints, features.keypoints, predictions,
                  camera, options_.subpixel, r.matches);
  }
  out.insert(out.end(), r.matches.begin(), r.matches.end());
  return out;
}

void FrontEnd::FirstPass(const Features& features, const std::vector<KeypointInfo>& ideal,
                         const cv::Mat& gray, bool imu_ok, SceneNearDepth& scene,
                         FrontEndResult& result) {
  const Previous& prev = *previous_;
  const bool enough_features =
      prev.features.keypoints.size() >= 2 && features.keypoints.size() >= 2;
  if (imu_ok && enough_features) {
    std::vector<KeypointPrediction> predictions;
    result.matches_pass1 =
        MatchPass(result.imu_motion, features, ideal, gray, !options_.second_pass, nullptr, scene,
                  predictions, result.from_tracks);
  }
  result.status = FrameStatus::kGuided;
  if (!imu_ok || !enough_features ||
      static_cast<int>(result.matches_pass1.size()) < options_.min_matches) {
    if (imu_ok && !enough_features) {
      result.event = "too few features (previous frame " +
                     std::to_string(prev.features.keypoints.size()) + ", this frame " +
                     std::to_string(features.keypoints.size()) + ")";
    } else if (imu_ok) {
      result.event = "lost: " + std::to_string(result.matches_pass1.size()) +
                     " guided matches (fewer than " + std::to_string(options_.min_matches) + ")";
    }
    result.status = FrameStatus::kBruteForce;
    result.from_tracks = 0;
    if (enough_features) {
      BruteForceOptions bf;
      result.matches_pass1 = MatchBruteForce(prev.features.descriptors, features.descriptors, bf);
    } else {
      result.matches_pass1.clear();
    }
  }
  result.matches = result.matches_pass1;
}

FrontEnd::PoseFitError FrontEnd::FitPose(const Features& features, bool imu_ok,
                                         FrontEndResult& result) const {
  const Previous& prev = *previous_;
  const PinholeCamera& camera = undistorter_.camera();
  std::vector<Eigen::Vector3d> points_a;
  std::vector<Eigen::Vector2d> pixels_a, pixels_b, pixels_b3;
  std::vector<double> depths_used;
  for (const Match& m : result.matches) {
    const cv::Point2f& ka = prev.features.keypoints[static_cast<size_t>(m.query_idx)].pt;
    const Eigen::Vector2d pb = PositionInB(m, features.keypoints);
    pixels_a.emplace_back(ka.x, ka.y);
    pixels_b.push_back(pb);
    if (prev.depths.empty()) continue;
    const double z = prev.depths[static_cast<size_t>(m.query_idx)];
    if (!options_.prediction.IsUsableDepth(z)) continue;
    const Eigen::Vector2d ia = undistorter_.ToIdeal(Eigen::Vector2d(ka.x, ka.y));
    points_a.push_back(z * Eigen::Vector3d(camera.IdealToNormalized(ia).homogeneous()));
    pixels_b3.push_back(pb);
    depths_used.push_back(z);
  }
  const Rigid3d guess = imu_ok ? result.imu_motion.cam_b_from_cam_a : Rigid3d();
  if (static_cast<int>(points_a.size()) >= options_.pose.min_inliers) {
    result.pose = FitPosePnp(points_a, pixels_b3, undistorter_, guess, options_.pose);
    result.pose_from_depth = result.pose.ok;
  }
  if (!result.pose.ok && imu_ok) {
    result.pose = FitPoseEpipolar(pixels_a, pixels_b, undistorter_, guess, options_.pose);
  }
  result.cam_from_prev = result.pose.ok ? result.pose.cam_b_from_cam_a : guess;
  // The PnP fit's error: rms residual over sqrt(inliers), as an angle and at the median depth
  // (the second pass's window and the velocity measurement's weight).
  PoseFitError fit;
  if (result.pose_from_depth) {
    const double median_depth = UpperMedianInPlace(depths_used);
    const double f = 0.5 * (camera.fx + camera.fy);
    fit.angle_sigma = 2.0 * std::max(result.pose.rms_px, 0.5) / f /
                      std::sqrt(static_cast<double>(result.pose.inliers));
    fit.translation_sigma = fit.angle_sigma * median_depth;
  }
  return fit;
}

bool FrontEnd::SecondPass(const Features& features, const std::vector<KeypointInfo>& ideal,
                          const cv::Mat& gray, int64_t t_ns, const PoseFitError& fit,
                          SceneNearDepth& scene, FrontEndResult& result) {
  const Previous& prev = *previous_;
  const PinholeCamera& camera = undistorter_.camera();
  CameraMotion refined = result.imu_motion;
  refined.cam_b_from_cam_a = result.pose.cam_b_from_cam_a;
  if (result.pose_from_depth) {
    refined.covariance.setZero();
    refined.covariance.topLeftCorner<3, 3>().diagonal().setConstant(fit.angle_sigma *
                                                                    fit.angle_sigma);
    refined.covariance.bottomRightCorner<3, 3>().diagonal().setConstant(fit.translation_sigma *
                                                                        fit.translation_sigma);
  }
  // The windows: the motion and covariance RefitMotion finds from the IMU's prior and the first
  // pass's matches when it can; else the pose fit's with the covariance above.
  // The rotation the matches alone show is measured from the second pass's (below).
  Rigid3d fitted = result.pose.cam_b_from_cam_a;
  const std::vector<float> fit_depths = FitDepths(
      prev.depth, camera.depth_scale, prev.features.keypoints, prev.depths, options_.refit);
  MotionRefitOptions refit_options = options_.refit;
  refit_options.measure_rotation = false;
  MotionRefit refit =
      RefitMotion(result.imu_motion, result.matches_pass1, prev.features.keypoints,
                  features.keypoints, fit_depths, options_.prediction, undistorter_, refit_options);
  // Where the motion fit of all matches did not converge, PnP's pose on the ~100 matches with
  // depth would be the frame's motion, its velocity and the second pass's windows. It must then
  // agree with the IMU's motion as the fit must, under both covariances: at MH_05's take-off
  // (pair 0 -> 1, 0.2 mm of motion, a translation direction the matches cannot tell) the fit
  // wandered and PnP read the wrong depths there as 20 mm of motion. A fit that failed
  // otherwise (beyond the prior, residuals beyond the keypoints' noise) says the IMU's motion
  // is off (after an IMU gap, its attitude): then PnP stands.
  if (refit.not_converged && result.pose_from_depth) {
    CameraMotion both = result.imu_motion;
    both.covariance += refined.covariance;  // refined: PnP's pose and covariance (above)
    const double m2 = SquaredMahalanobis(both, result.pose.cam_b_from_cam_a);
    const double gate = MotionAgreementGate(options_.refit.agreement_probability);
    if (!(m2 <= gate)) {
      result.cam_from_prev = result.imu_motion.cam_b_from_cam_a;
      std::ostringstream note;
      note << refit.reason << "; PnP pose disagrees with the IMU's motion (squared Mahalanobis "
           << "distance " << std::setprecision(3) << m2 << " > " << gate
           << "): the IMU's motion kept, no second pass";
      result.event = result.event.empty() ? note.str() : result.event + "; " + note.str();
      return false;
    }
  }
  if (refit.ok) {
    refined = refit.motion;
    fitted = refit.motion.cam_b_from_cam_a;
    // Where frame A has depth, the estimated motion as well: the fit of all the first pass's
    // matches (reprojection rows where A has depth, epipolar rows elsewhere) with the IMU's
    // motion as its prior, rather than PnP on the matches with depth alone (RANSAC on about
    // 100 of MH_05's 800 matches per frame). On MH_05's 35 pairs with depth, ORB, relative
    // pose error RMSE per frame: rotation 0.071 -> 0.0076 deg, translation 12.9 -> 1.4 mm.
    // Without depth the epipolar fit stays: the fit's rotation there carries the IMU
    // translation's error (0.0035 -> 0.015 deg on the 164 pairs without depth).
    if (result.pose_from_depth) result.cam_from_prev = fitted;
  }
  std::vector<KeypointPrediction> predictions2;
  int tracks2 = 0;
  const std::vector<Match> second = MatchPass(refined, features, ideal, gray, true,
                                              &result.matches_pass1, scene, predictions2, tracks2);
  // Keep the matches the fitted geometry explains, within the fit's inlier threshold.
  result.matches = MatchesExplainedByFit(
      second, fitted, result.pose_from_depth, prev.features.keypoints, prev.depths,
      features.keypoints, undistorter_, options_.prediction, options_.pose.ransac_px);
  result.from_tracks =
      static_cast<int>(std::count_if(result.matches.begin(), result.matches.end(),
                                     [](const Match& m) { return m.train_idx < 0; }));
  if (refit.ok && options_.refit.measure_rotation) {
    // From the matches found in the fit's windows: the first pass's, found in the IMU's, lean
    // towards its rotation (MeasureRotationFromMatches).
    MeasureRotationFromMatches(result.imu_motion, result.matches, prev.features.keypoints,
                               features.keypoints, fit_depths, options_.prediction, undistorter_,
                               options_.refit, &refit);
    UseFittedRotation(refit, prev.t_ns, t_ns);
  }
  result.second_pass = true;
  return true;
}

}  // namespace imumatch
