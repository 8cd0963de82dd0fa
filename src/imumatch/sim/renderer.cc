#include "imumatch/sim/renderer.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <random>
#include <thread>
#include <vector>

#include "imumatch/camera/pixel_undistorter.h"
#include "imumatch/core/error.h"
#include "imumatch/sim/seed_mix.h"

namespace imumatch {
namespace {

// Bilinear sample of one mip level at level-0 texel coordinates (s, t); accumulates weight * BGR.
inline void SampleLevel(const cv::Mat& level, double scale, double s, double t, float weight,
                        float* out) {
  double x = s * scale, y = t * scale;
  const int w = level.cols, h = level.rows;
  x = std::min(std::max(x, 0.0), w - 1.0);
  y = std::min(std::max(y, 0.0), h - 1.0);
  const int x0 = std::min(static_cast<int>(x), w - 2 < 0 ? 0 : w - 2);
  const int y0 = std::min(static_cast<int>(y), h - 2 < 0 ? 0 : h - 2);
  const int x1 = std::min(x0 + 1, w - 1), y1 = std::min(y0 + 1, h - 1);
  const float fx = static_cast<float>(x - x0), fy = static_cast<float>(y - y0);
  const uint8_t* r0 = level.ptr<uint8_t>(y0);
  const uint8_t* r1 = level.ptr<uint8_t>(y1);
  const float w00 = (1 - fx) * (1 - fy) * weight, w01 = fx * (1 - fy) * weight;
  const float w10 = (1 - fx) * fy * weight, w11 = fx * fy * weight;
  for (int c = 0; c < 3; ++c) {
    out[c] +=
        w00 * r0[3 * x0 + c] + w01 * r0[3 * x1 + c] + w10 * r1[3 * x0 + c] + w11 * r1[3 * x1 + c];
  }
}

// Everything about the camera pose precomputed once per frame.
class FrameCaster {
 public:
  FrameCaster(const Scene& scene, const PinholeCamera& camera, const Rigid3d& world_from_cam,
              const RenderOptions& options)
      : scene_(scene), camera_(camera), options_(options) {
    const Eigen::Matrix3d world_r_cam = world_from_cam.RotationMatrix();
    for (const SceneBox& box : scene.boxes()) {
      const Eigen::Matrix3d box_r_world = box.world_from_box.RotationMatrix().transpose();
      origin_in_box_.push_back(box_r_world *
                               (world_from_cam.translation - box.world_from_box.translation));
      box_r_cam_.push_back(box_r_world * world_r_cam);
      // Image-space bounds of the box (culling): all 8 corners in front of the camera -> their
      // bounding rectangle plus a margin; otherwise the box is tested for every pixel.
      Bounds bounds;
      if (!box.is_room) {
        const Rigid3d cam_from_box = world_from_cam.Inverse() * box.world_from_box;
        bounds.all_pixels = false;
        bounds.u_min = bounds.v_min = std::numeric_limits<double>::infinity();
        bounds.u_max = bounds.v_max = -std::numeric_limits<double>::infinity();
        for (int c = 0; c < 8 && !bounds.all_pixels; ++c) {
          const Eigen::Vector3d corner((c & 1 ? 1 : -1) * box.half_size.x(),
                                       (c & 2 ? 1 : -1) * box.half_size.y(),
                                       (c & 4 ? 1 : -1) * box.half_size.z());
          const Eigen::Vector3d p = cam_from_box * corner;
          if (p.z() < 1e-6) {
            bounds.all_pixels = true;
            break;
          }
          const double u = camera.fx * p.x() / p.z() + camera.cx,
                       v = camera.fy * p.y() / p.z() + camera.cy;
          bounds.u_min = std::min(bounds.u_min, u - 2.0);
          bounds.u_max = std::max(bounds.u_max, u + 2.0);
          bounds.v_min = std::min(bounds.v_min, v - 2.0);
          bounds.v_max = std::max(bounds.v_max, v + 2.0);
        }
      }
      bounds_.push_back(bounds);
    }
    inv_texel_ = 1.0 / scene.options().texel_size_m;
  }

  struct Hit {
    double depth = 0.0;  // z in the camera
    int surface = -1;
    double cos_incidence = 0.0;
  };

  // Casts the ray through the ideal pixel (u, v) (K times the ray's normalised coordinates: the
  // image pixel itself for a camera without distortion); writes BGR into colour when non-null.
  // step_u / step_v: the ideal-pixel offsets of one step of the footprint along the image's u and
  // v (one pixel, or 1/n for sub-samples; through a lens, its Jacobian's columns).
  Hit Cast(double u, double v, const Eigen::Vector2d& step_u, const Eigen::Vector2d& step_v,
           float* colour) const {
    const Eigen::Vector3d d_cam((u - camera_.cx) / camera_.fx, (v - camera_.cy) / camera_.fy, 1.0);
    double best = std::numeric_limits<double>::infinity();
    int best_surface = -1, best_box = -1;
    Eigen::Vector3d best_d;
    for (int b = 0; b < static_cast<int>(box_r_cam_.size()); ++b) {
      const Bounds& bounds = bounds_[b];
      if (!bounds.all_pixels &&
          (u < bounds.u_min || u > bounds.u_max || v < bounds.v_min || v > bounds.v_max)) {
        continue;
      }
      const Eigen::Vector3d d = box_r_cam_[b] * d_cam;
      int surface = -1;
      const double t = scene_.IntersectBoxLocal(b, origin_in_box_[b], d, &surface);
      if (t < best) {
        best = t;
        best_surface = surface;
        best_box = b;
        best_d = d;
      }
    }
    Hit hit;
    if (best_surface < 0) {
      if (colour) colour[0] = colour[1] = colour[2] = 0.0f;
      return hit;
    }
    hit.depth = best;
    hit.surface = best_surface;
    const SceneSurface& s = scene_.surfaces()[best_surface];
    const int axis = s.axis, ia = (axis + 1) % 3, ib = (axis + 2) % 3;
    hit.cos_incidence = std::abs(best_d[axis]) / best_d.norm();
    if (!colour) return hit;
    const Eigen::Vector3d& half = scene_.boxes()[best_box].half_size;
    const Eigen::Vector3d p = origin_in_box_[best_box] + best * best_d;
    const double a = (p[ia] + half[ia]) * inv_texel_, bb = (p[ib] + half[ib]) * inv_texel_;
    colour[0] = colour[1] = colour[2] = 0.0f;
    if (!options_.filter_textures) {
      SampleLevel(s.mip_levels[0], 1.0, a, bb, s.shade, colour);
      return hit;
    }
    // Derivatives of the surface point with respect to the pixel coordinates (exact for the plane):
    // dP/du = t (e_u - d (n.e_u)/(n.d)), in texels.
    const Eigen::Matrix3d& m = box_r_cam_[best_box];
    const Eigen::Vector3d e_u =
        m.col(0) * (step_u.x() / camera_.fx) + m.col(1) * (step_u.y() / camera_.fy);
    const Eigen::Vector3d e_v =
        m.col(0) * (step_v.x() / camera_.fx) + m.col(1) * (step_v.y() / camera_.fy);
    const Eigen::Vector3d dp_du = best * (e_u - best_d * (e_u[axis] / best_d[axis])) * inv_texel_;
    const Eigen::Vector3d dp_dv = best * (e_v - best_d * (e_v[axis] / best_d[axis])) * inv_texel_;
    const Eigen::Vector2d gu(dp_du[ia], dp_du[ib]), gv(dp_dv[ia], dp_dv[ib]);
    const double lu = gu.norm(), lv = gv.norm();
    const Eigen::Vector2d major = lu >= lv ? gu : gv;
    const double major_len = std::max(lu, lv), minor_len = std::max(std::min(lu, lv), 1e-9);
    const int taps =
        std::min(4, std::max(1, static_cast<int>(std::ceil(major_len / minor_len - 1e-3))));
    double lod = std::log2(std::max(major_len / taps, 1e-9)) + options_.lod_bias;
    const int last = static_cast<int>(s.mip_levels.size()) - 1;
    lod = std::min(std::max(lod, 0.0), static_cast<double>(last));
    const int l0 = std::min(static_cast<int>(lod), last);
    const int l1 = std::min(l0 + 1, last);
    const float frac = static_cast<float>(lod - l0);
    const float w = s.shade / taps;
    for (int k = 0; k < taps; ++k) {
      const double off = (k + 0.5) / taps - 0.5;
      const double sa = a + off * major.x(), sb = bb + off * major.y();
      SampleLevel(s.mip_levels[l0], std::ldexp(1.0, -l0), sa, sb, w * (1.0f - frac), colour);
      if (frac > 0.0f)
        SampleLevel(s.mip_levels[l1], std::ldexp(1.0, -l1), sa, sb, w * frac, colour);
    }
    return hit;
  }

 private:
  const Scene& scene_;
  const PinholeCamera& camera_;
  const RenderOptions& options_;
  std::vector<Eigen::Vector3d> origin_in_box_;
  std::vector<Eigen::Matrix3d> box_r_cam_;
  struct Bounds {
    bool all_pixels = true;
    double u_min = 0.0, u_max = 0.0, v_min = 0.0, v_max = 0.0;
  };
  std::vector<Bounds> bounds_;
  double inv_texel_ = 1.0;
};

inline cv::Vec3b ToPixel(const float* c) {
  return cv::Vec3b(cv::saturate_cast<uint8_t>(c[0]), cv::saturate_cast<uint8_t>(c[1]),
                   cv::saturate_cast<uint8_t>(c[2]));
}

template <typename Fn>
void ParallelRows(int rows, int num_threads, Fn fn) {
  if (num_threads <= 1) {
    for (int r = 0; r < rows; ++r) fn(r);
    return;
  }
  std::vector<std::thread> threads;
  for (int i = 0; i < num_threads; ++i) {
    threads.emplace_back([&, i] {
      for (int r = i; r < rows; r += num_threads) fn(r);
    });
  }
  for (std::thread& t : threads) t.join();
}

}  // namespace

void DepthNoiseOptions::Check() const {
  IMUMATCH_CHECK(std::isfinite(noise_coefficient) && noise_coefficient >= 0.0,
                 "DepthNoiseOptions.noise_coefficient must be >= 0, got " << noise_coefficient);
  IMUMATCH_CHECK(
      dropout_probability >= 0.0 && dropout_probability <= 1.0,
      "DepthNoiseOptions.dropout_probability must be in [0,1], got " << dropout_probability);
  IMUMATCH_CHECK(min_range_m >= 0.0 && max_range_m > min_range_m,
                 "DepthNoiseOptions needs 0 <= min_range_m < max_range_m, got "
                     << min_range_m << ", " << max_range_m);
  IMUMATCH_CHECK(min_incidence_cos >= 0.0 && min_incidence_cos < 1.0,
                 "DepthNoiseOptions.min_incidence_cos must be in [0,1), got " << min_incidence_cos);
}

void RenderOptions::Check() const {
  IMUMATCH_CHECK(num_threads >= 1 && num_threads <= 64,
                 "RenderOptions.num_threads must be in [1,64], got " << num_threads);
  IMUMATCH_CHECK(std::isfinite(lod_bias) && std::abs(lod_bias) <= 4.0,
                 "RenderOptions.lod_bias must be in [-4,4], got " << lod_bias);
  IMUMATCH_CHECK(edge_supersampling >= 1 && edge_supersampling <= 8,
                 "RenderOptions.edge_supersampling must be in [1,8], got " << edge_supersampling);
  depth_noise.Check();
}

LensRayMap::LensRayMap(const PinholeCamera& camera) : camera_(camera) {
  camera.Check();
  if (!camera.HasDistortion()) return;
  const int width = camera.width, height = camera.height;
  ideal_.resize(static_cast<size_t>(width) * height * 2);
  for (int v = 0; v < height; ++v) {
    for (int u = 0; u < width; ++u) {
      const size_t i = (static_cast<size_t>(v) * width + u) * 2;
      ideal_[i] = static_cast<float>(u);
      ideal_[i + 1] = static_cast<float>(v);
    }
  }
  PixelUndistorter(camera).ToIdealInPlace(ideal_.data(), width * height, 2);
  if (!camera.WiderThanField()) return;
  // Beyond the field of view (PinholeCamera::InField) no ray: those pixels render black, without
  // depth, like a fisheye's vignetted corners.
  for (int v = 0; v < height; ++v) {
    for (int u = 0; u < width; ++u) {
      if (camera.InField(Eigen::Vector2d(u, v))) continue;
      const size_t i = (static_cast<size_t>(v) * width + u) * 2;
      ideal_[i] = ideal_[i + 1] = std::numeric_limits<float>::quiet_NaN();
    }
  }
}

RenderedView RenderView(const Scene& scene, const PinholeCamera& camera,
                        const Rigid3d& world_from_cam, const RenderOptions& options,
                        const LensRayMap* lens_rays) {
  camera.Check();
  options.Check();
  IMUMATCH_CHECK(
      world_from_cam.rotation.coeffs().allFinite() && world_from_cam.translation.allFinite(),
      "RenderView: world_from_cam must be finite");
  const FrameCaster caster(scene, camera, world_from_cam, options);
  const int width = camera.width, height = camera.height;
  RenderedView view;
  view.rgb.create(height, width, CV_8UC3);
  view.depth.create(height, width, CV_16U);
  cv::Mat surface_ids(height, width, CV_32S);
  const DepthNoiseOptions& noise = options.depth_noise;

  // Through a lens, every pixel centre's ideal pixel (the caller's map, or one made here) and the
  // ideal-pixel steps to its right and lower neighbours (the lens's Jacobian, for the texture
  // filter's footprint and the edge sub-samples).
  const bool distorted = camera.HasDistortion();
  std::optional<LensRayMap> own_rays;
  if (lens_rays != nullptr) {
    IMUMATCH_CHECK(lens_rays->camera().SameImageGeometry(camera),
                   "RenderView: the LensRayMap was made for another camera");
  } else if (distorted) {
    own_rays.emplace(camera);
    lens_rays = &*own_rays;
  }
  struct PixelRay {
    double u, v;
    Eigen::Vector2d step_u, step_v;
  };
  const auto ray_of = [&](int u, int v) {
    if (!distorted) return PixelRay{double(u), double(v), {1.0, 0.0}, {0.0, 1.0}};
    const auto at = [&](int uu, int vv) {
      const float* p = lens_rays->At(uu, vv);
      return Eigen::Vector2d(p[0], p[1]);
    };
    const Eigen::Vector2d p = at(u, v);
    // The step to the next pixel, else from the previous one (image border, field's edge); a
    // one-pixel image (or a pixel alone in the field) has none: the lens's stretch is then taken
    // as none.
    const auto step = [&](int du, int dv, const Eigen::Vector2d& none) -> Eigen::Vector2d {
      const int un = u + du, vn = v + dv, up = u - du, vp = v - dv;
      if (un < width && vn < height) {
        const Eigen::Vector2d d = at(un, vn) - p;
        if (d.allFinite()) return d;
      }
      if (up >= 0 && vp >= 0) {
        const Eigen::Vector2d d = p - at(up, vp);
        if (d.allFinite()) return d;
      }
      return none;
    };
    return PixelRay{p.x(), p.y(), step(1, 0, {1.0, 0.0}), step(0, 1, {0.0, 1.0})};
  };

  ParallelRows(height, options.num_threads, [&](int v) {
    cv::Vec3b* rgb = view.rgb.ptr<cv::Vec3b>(v);
    uint16_t* depth = view.depth.ptr<uint16_t>(v);
    int* ids = surface_ids.ptr<int>(v);
    std::mt19937_64 rng(SplitMix64(noise.seed ^ SplitMix64(static_cast<uint64_t>(v) + 1)));
    std::normal_distribution<double> gauss(0.0, 1.0);
    std::uniform_real_distribution<double> uniform(0.0, 1.0);
    for (int u = 0; u < width; ++u) {
      float colour[3];
      const PixelRay ray = ray_of(u, v);
      if (!std::isfinite(ray.u)) {  // beyond the field of view (LensRayMap)
        rgb[u] = cv::Vec3b(0, 0, 0);
        depth[u] = 0;
        ids[u] = -2;
        if (noise.add_noise) gauss(rng);  // the same draws as every other pixel's
        if (noise.add_holes) uniform(rng);
        continue;
      }
      const FrameCaster::Hit hit = caster.Cast(ray.u, ray.v, ray.step_u, ray.step_v, colour);
      rgb[u] = ToPixel(colour);
      ids[u] = hit.surface;
      double z = hit.surface >= 0 ? hit.depth : 0.0;
      // Draw the random numbers for every pixel so the noise pattern does not depend on the scene.
      const double n = noise.add_noise ? gauss(rng) : 0.0;
      const double drop = noise.add_holes ? uniform(rng) : 1.0;
      if (z > 0.0 && noise.add_holes &&
          (drop < noise.dropout_probability || z < noise.min_range_m || z > noise.max_range_m ||
           hit.cos_incidence < noise.min_incidence_cos)) {
        z = 0.0;
      }
      if (z > 0.0 && noise.add_noise) z += noise.noise_coefficient * z * z * n;
      const double raw = std::round(z * camera.depth_scale);
      depth[u] = (z > 0.0 && raw >= 1.0 && raw <= 65535.0) ? static_cast<uint16_t>(raw) : 0;
    }
  });

  const int n = options.edge_supersampling;
  if (n > 1) {
    // Sub-sample pixels at surface boundaries (reads only surface_ids, writes only its own pixel).
    ParallelRows(height, options.num_threads, [&](int v) {
      const int* ids = surface_ids.ptr<int>(v);
      const int* up = surface_ids.ptr<int>(std::max(v - 1, 0));
      const int* down = surface_ids.ptr<int>(std::min(v + 1, height - 1));
      cv::Vec3b* rgb = view.rgb.ptr<cv::Vec3b>(v);
      for (int u = 0; u < width; ++u) {
        const int id = ids[u];
        const bool edge = up[u] != id || down[u] != id || (u > 0 && ids[u - 1] != id) ||
                          (u + 1 < width && ids[u + 1] != id);
        if (!edge || id == -2) continue;
        float sum[3] = {0.0f, 0.0f, 0.0f};
        const PixelRay ray = ray_of(u, v);
        const Eigen::Vector2d sub_u = ray.step_u / n, sub_v = ray.step_v / n;
        for (int j = 0; j < n; ++j) {
          for (int i = 0; i < n; ++i) {
            float c[3];
            const double a = (i + 0.5) / n - 0.5, b = (j + 0.5) / n - 0.5;
            caster.Cast(ray.u + a * ray.step_u.x() + b * ray.step_v.x(),
                        ray.v + a * ray.step_u.y() + b * ray.step_v.y(), sub_u, sub_v, c);
            for (int k = 0; k < 3; ++k) sum[k] += c[k];
          }
        }
        for (float& s : sum) s /= static_cast<float>(n * n);
        rgb[u] = ToPixel(sum);
      }
    });
  }
  return view;
}

std::optional<Eigen::Vector3d> AnalyticPointInCam(const Scene& scene, const PinholeCamera& camera,
                                                  const Rigid3d& world_from_cam,
                                                  const Eigen::Vector2d& uv) {
  const Eigen::Vector2d xy = camera.PixelToNormalized(uv);
  const Eigen::Vector3d d_cam(xy.x(), xy.y(), 1.0);
  const std::optional<RayHit> hit =
      scene.CastRay(world_from_cam.translation, world_from_cam.rotation * d_cam);
  if (!hit) return std::nullopt;
  return Eigen::Vector3d(hit->distance * d_cam);
}

double AnalyticDepth(const Scene& scene, const PinholeCamera& camera, const Rigid3d& world_from_cam,
                     const Eigen::Vector2d& uv) {
  const std::optional<Eigen::Vector3d> p = AnalyticPointInCam(scene, camera, world_from_cam, uv);
  return p ? p->z() : std::numeric_limits<double>::quiet_NaN();
}

}  // namespace imumatch
