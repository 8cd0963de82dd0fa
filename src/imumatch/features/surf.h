#pragma once

#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>

#include "imumatch/features/strict_feature2d.h"

namespace imumatch {

// Options of the SURF detector/descriptor (Bay, Ess, Tuytelaars, Van Gool, "Speeded-Up Robust
// Features (SURF)", CVIU 110(3), 2008; ECCV 2006).
struct SurfOptions {
  // Minimum determinant-of-Hessian response of a keypoint. Same scale as OpenCV's
  // xfeatures2d::SURF hessianThreshold on 0-255 images (each box lobe is normalised by its area),
  // so the OpenCV default of 100 gives a comparable number of keypoints. Must be >= 0.
  double hessian_threshold = 100.0;
  // Number of octaves. Octave o uses filter sizes L = 3 * (2^(o+1) * (i+1) + 1), i =
  // 0..n_intervals+1 (9,15,21,27; 15,27,39,51; 27,51,75,99; ...) sampled every 2^o pixels. 1..8.
  int n_octaves = 4;
  // Scale layers per octave in which extrema are searched (OpenCV's nOctaveLayers): each octave
  // evaluates n_intervals + 2 filter sizes. 2 is the paper's 4 filters per octave. 1..8.
  int n_intervals = 2;
  // U-SURF: skip the orientation assignment, descriptors are computed in the image axes and every
  // keypoint angle is 0.
  bool upright = false;
  // 0 keeps every keypoint above the threshold; otherwise only the max_keypoints strongest
  // (largest response). Only applies to detection, not to keypoints passed to compute().
  int max_keypoints = 0;

  void Check() const;
};

// SURF detector and 64-dimensional descriptor, written from the paper, usable through the
// cv::Feature2D interface (detect / compute / detectAndCompute).
//
// Keypoint conventions (size, response, octave and class_id as in OpenCV's xfeatures2d::SURF; the
// angle as in OpenCV's SIFT/ORB/AKAZE). Differences from OpenCV's SURF: the filter sizes of octave
// o > 0 follow the paper (15,27,39,51; ...) where OpenCV doubles those of octave 0 (18,30,42,54;
// ...), and OpenCV's SURF measures angles counter-clockwise on screen (atan2(-dy, dx)).
//   - pt: sub-pixel, sub-scale interpolated position; integer coordinates are pixel centres.
//   - size: the (interpolated, not rounded) side L of the box filter that fired, in pixels. The
//     scale of the keypoint, i.e. the sigma of the Gaussian that the filter approximates, is
//     s = 1.2 * size / 9 (a 9x9 filter approximates sigma = 1.2). OpenCV rounds size to an
//     integer; it is kept fractional here. Note that the box-filter determinant of a Gaussian blob
//     of standard deviation sigma_b peaks at s ~= 0.72 sigma_b (not at sigma_b as the exact
//     Gaussian determinant would): sizes are scale-covariant but not equal to the blob sigma.
//   - angle: dominant orientation in degrees in [0, 360), measured like OpenCV's SIFT and ORB:
//     atan2(dy, dx) in image coordinates (x right, y down), i.e. clockwise on screen. Rotating the
//     image by +a degrees counter-clockwise on screen (cv::getRotationMatrix2D(c, a, 1)) changes
//     the angles by -a. With upright = true the angle is 0, meaning "image axes" (OpenCV's SURF
//     reports 270 there, an artefact of its internal convention; -1, "not applicable", would
//     break code that rotates by the angle).
//   - response: determinant of the approximated Hessian (Dxx*Dyy - (0.9*Dxy)^2) at the maximum.
//   - octave: octave index (0-based). class_id: sign of the Laplacian (trace), +1 or -1, which a
//     matcher may use to skip pairs of opposite sign (dark vs bright blobs).
// Keypoints returned by detect are sorted by decreasing response.
//
// Orientation: Haar responses (side 4s) at the pixel corners nearest to a grid of step s within
// radius 6s, Gaussian weight sigma = 2s, summed over a 60-degree window sliding in 1-degree steps;
// the angle of the longest sum wins. Descriptor: the Haar responses (side 2s) are evaluated at
// the exact rotated sample positions by bilinear interpolation of the four neighbouring integer
// placements (on the integral image), then expressed in the keypoint frame.
//
// compute() on given keypoints recomputes the orientation (unless upright) from the image and
// overwrites kp.angle; keypoints with size <= 0, a non-finite position, no Haar response inside
// the image or an all-zero descriptor window (flat or outside the image) are removed. The mask
// only applies to detection.
//
// Speed: the responses of every layer and the descriptors are computed with cv::parallel_for_.
// The response layers live in a per-thread buffer reused across calls (about 16 bytes per pixel
// for the default options), so repeated calls do not allocate.
class Surf : public StrictFeature2D {  // detect()/compute() throw on empty images
 public:
  explicit Surf(const SurfOptions& options = SurfOptions());
  static cv::Ptr<Surf> Create(const SurfOptions& options = SurfOptions());

  const SurfOptions& options() const { return options_; }

  void detectAndCompute(cv::InputArray image, cv::InputArray mask,
                        std::vector<cv::KeyPoint>& keypoints, cv::OutputArray descriptors,
                        bool useProvidedKeypoints = false) override;

  int descriptorSize() const override { return 64; }
  int descriptorType() const override { return CV_32F; }
  int defaultNorm() const override { return cv::NORM_L2; }
  cv::String getDefaultName() const override { return "imumatch.SURF"; }

 private:
  SurfOptions options_;
};

}  // namespace imumatch
