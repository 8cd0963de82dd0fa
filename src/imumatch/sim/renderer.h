#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "imumatch/camera/pinhole_camera.h"
#include "imumatch/core/rigid3.h"
#include "imumatch/sim/scene.h"

namespace imumatch {

// Kinect-like depth corruption, off by default (exact ground-truth depth).
struct DepthNoiseOptions {
  // Gaussian noise on z with sigma = noise_coefficient * z^2 (metres), then quantised.
  bool add_noise = false;
  double noise_coefficient = 1.425e-3;
  // Holes (raw 0): random dropouts, beyond max_range_m, below min_range_m, and where the ray meets
  // the surface at a grazing angle (|cos incidence| < min_incidence_cos).
  bool add_holes = false;
  double dropout_probability = 0.02;
  double min_range_m = 0.4;
  double max_range_m = 4.5;
  double min_incidence_cos = 0.2;
  uint64_t seed = 1;  // the noise is a deterministic function of the seed (not of the thread count)
  void Check() const;
};

struct RenderOptions {
  int num_threads = 2;
  // Prefilter the textures by the pixel footprint (mip-mapped, up to 4 taps along the major axis
  // of an anisotropic footprint). false = bilinear on the full-resolution texture (aliased).
  bool filter_textures = true;
  double lod_bias = 0.0;  // added to the mip level (negative = sharper)
  // Pixels whose neighbours see another surface (silhouettes, box edges) are averaged over
  // n x n sub-pixel samples; 1 = off. Depth is always that of the pixel centre ray.
  int edge_supersampling = 3;
  DepthNoiseOptions depth_noise;
  void Check() const;
};

struct RenderedView {
  cv::Mat rgb;    // CV_8UC3, OpenCV BGR channel order (as cv::imread returns)
  cv::Mat depth;  // CV_16U, raw = round(z * camera.depth_scale), z along the optical axis; 0 = none
};

// The ideal pixel (K times the normalised ray, PinholeCamera::PixelToNormalized to float rounding,
// by PixelUndistorter) of every pixel centre of a camera with a lens: the same for every frame
// the camera renders, so a sequence computes it once (about 3 ms for 640 x 480). Empty for a
// camera without distortion (its ideal pixels are its pixels).
class LensRayMap {
 public:
  explicit LensRayMap(const PinholeCamera& camera);
  const PinholeCamera& camera() const { return camera_; }
  bool empty() const { return ideal_.empty(); }
  // Pixel (u, v)'s ideal pixel as (x, y).
  const float* At(int u, int v) const {
    return ideal_.data() + (static_cast<size_t>(v) * camera_.width + u) * 2;
  }

 private:
  PinholeCamera camera_;
  std::vector<float> ideal_;
};

// Ray-casts the scene for the camera at world_from_cam. Pixel (u, v) is rendered along the ray
// through its centre (OpenCV convention), through the camera's lens when it has one (either
// distortion model: the ray of PinholeCamera::PixelToNormalized, to float rounding of the ideal
// pixel), so the depth image and the poses stay exact ground truth for a distorted image.
// lens_rays: the camera's LensRayMap when the caller renders many frames with it (InvalidArgument
// when it was made for another camera); null: computed here.
RenderedView RenderView(const Scene& scene, const PinholeCamera& camera,
                        const Rigid3d& world_from_cam,
                        const RenderOptions& options = RenderOptions(),
                        const LensRayMap* lens_rays = nullptr);

// The exact scene point seen through pixel uv (continuous coordinates), in the camera frame
// (its z is the depth), or nullopt when the ray hits nothing. Independent of the raster code.
std::optional<Eigen::Vector3d> AnalyticPointInCam(const Scene& scene, const PinholeCamera& camera,
                                                  const Rigid3d& world_from_cam,
                                                  const Eigen::Vector2d& uv);
// Its z in metres, NaN when nothing is hit.
double AnalyticDepth(const Scene& scene, const PinholeCamera& camera, const Rigid3d& world_from_cam,
                     const Eigen::Vector2d& uv);

}  // namespace imumatch
