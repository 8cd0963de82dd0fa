#pragma once

#include <vector>

#include <Eigen/Core>

namespace imumatch {

// The translation direction of a camera pair whose rotation is known, from correspondences given
// as bearings (z = 1): ra = R x_a (A's bearing rotated into B's orientation) and x_b. Distances
// are epipolar distances in B in ideal pixels (f: the focal length). The length of the translation
// is not observable here: every function keeps the length it is given.

// The median epipolar distance (ideal px) of the correspondences (bearings in A already rotated
// into B's orientation, ra = R x_a) for translation t.
double MedianEpipolarDistancePx(const std::vector<Eigen::Vector3d>& ra,
                                const std::vector<Eigen::Vector3d>& xb, const Eigen::Vector3d& t,
                                double f, std::vector<double>& scratch);

// The translation direction that the epipolar constraints t . (R x_a x x_b) = 0 favour with the
// rotation held: the eigenvector of the smallest eigenvalue of sum w_i n_i n_i^T, each row
// weighted by 1 / |line_i|^2 (so that the algebraic error is the distance in B) and a Cauchy
// weight on that distance; three reweighted rounds from `start` (the sign kept on its side).
// Linear algebra only: the distances are strongly nonlinear in the direction when the epipole
// lies in the image (forward motion), where Gauss-Newton from a direction a few degrees off
// converges slowly.
Eigen::Vector3d EpipolarTranslationDirection(const std::vector<Eigen::Vector3d>& ra,
                                             const std::vector<Eigen::Vector3d>& xb,
                                             const Eigen::Vector3d& start, double f,
                                             double min_sigma, double cauchy_scale,
                                             std::vector<double>& scratch);

// The negative log-posterior of translation t (rotation held) up to a constant: the epipolar
// distances' Cauchy loss at scale c = cauchy_scale x sigma (ideal px) plus the prior's
// Mahalanobis term under its translation information.
double TranslationDirectionCost(const std::vector<Eigen::Vector3d>& ra,
                                const std::vector<Eigen::Vector3d>& xb, const Eigen::Vector3d& t,
                                double f, double sigma, double cauchy_scale,
                                const Eigen::Vector3d& t_prior, const Eigen::Matrix3d& t_info);

// A translation to start a second fit from (rotation held at the prior's, length the prior's):
// of `start`, the prior's direction and `hypotheses` directions through two correspondences each
// (t _|_ R x_a x x_b for both: their cross product), drawn from the half with the largest
// parallax angle |R x_a x x_b| (a point at infinity says nothing about the direction), the few of
// least TranslationDirectionCost refined by EpipolarTranslationDirection; the one of least cost
// (at `sigma`, over all correspondences), with that cost. The epipolar distance is far from
// linear in the direction: from a prior some tens of degrees off, the reweighted linear solution
// and Gauss-Newton both settle in a wrong minimum (EuRoC MH_05 at take-off, FAST+BRIEF frames
// 11 -> 12: a direction 57 degrees off, the true partners' median epipolar distance 2.5 px where
// the true direction gives 0.7 px). Throws InvalidArgument when ra and xb differ in size or
// t_prior is shorter than 1e-9.
struct TranslationSearchResult {
  Eigen::Vector3d translation;
  double cost = 0.0;  // its TranslationDirectionCost
};
TranslationSearchResult SearchTranslationDirection(
    const std::vector<Eigen::Vector3d>& ra, const std::vector<Eigen::Vector3d>& xb,
    const Eigen::Vector3d& start, const Eigen::Vector3d& t_prior, const Eigen::Matrix3d& t_info,
    double f, double sigma, double cauchy_scale, int hypotheses, std::vector<double>& scratch);

}  // namespace imumatch
