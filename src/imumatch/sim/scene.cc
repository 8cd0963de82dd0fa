#include "imumatch/sim/scene.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include <opencv2/imgproc.hpp>

#include "imumatch/core/error.h"
#include "imumatch/core/so3.h"
#include "imumatch/sim/seed_mix.h"

namespace imumatch {
namespace {

SceneBox MakeBox(double x, double y, double z, double sx, double sy, double sz, double yaw_deg) {
  SceneBox box;
  box.world_from_box = Rigid3d(
      Eigen::Quaterniond(Eigen::AngleAxisd(yaw_deg * kPi / 180.0, Eigen::Vector3d::UnitZ())),
      Eigen::Vector3d(x, y, z));
  box.half_size = 0.5 * Eigen::Vector3d(sx, sy, sz);
  return box;
}

cv::Scalar RandomColor(cv::RNG& rng) {
  return cv::Scalar(rng.uniform(0, 256), rng.uniform(0, 256), rng.uniform(0, 256));
}

// A high-contrast colour: each channel either dark or bright.
cv::Scalar ContrastColor(cv::RNG& rng, bool dark) {
  cv::Scalar c;
  for (int i = 0; i < 3; ++i) c[i] = dark ? rng.uniform(0, 70) : rng.uniform(170, 256);
  if (rng.uniform(0, 3) == 0)
    c[rng.uniform(0, 3)] = dark ? rng.uniform(150, 256) : rng.uniform(0, 80);
  return c;
}

// Procedural texture of width x height texels (texel_m metres each), deterministic in seed.
cv::Mat MakeTexture(int width, int height, double texel_m, uint64_t seed) {
  cv::RNG rng(seed);
  const double w_m = width * texel_m, h_m = height * texel_m;
  // Multi-scale value noise: random lattices upsampled with bicubic interpolation; mostly
  // luminance with some colour. Computed at half resolution (the finest octave spans 4 texels)
  // and upsampled once; the shapes drawn below add the full-resolution detail.
  const cv::Size half((width + 1) / 2, (height + 1) / 2);
  cv::Mat acc(
      half, CV_32FC3,
      cv::Scalar(rng.uniform(70.0, 190.0), rng.uniform(70.0, 190.0), rng.uniform(70.0, 190.0)));
  const double wavelengths[] = {0.8, 0.3, 0.12, 0.05, 0.02};
  const double amplitudes[] = {40.0, 32.0, 26.0, 20.0, 14.0};
  for (int o = 0; o < 5; ++o) {
    const int gw = std::max(2, static_cast<int>(std::ceil(w_m / wavelengths[o])) + 1);
    const int gh = std::max(2, static_cast<int>(std::ceil(h_m / wavelengths[o])) + 1);
    cv::Mat lum(gh, gw, CV_32F), chroma(gh, gw, CV_32FC3);
    rng.fill(lum, cv::RNG::UNIFORM, -1.0, 1.0);
    rng.fill(chroma, cv::RNG::UNIFORM, -1.0, 1.0);
    cv::Mat lum3;
    cv::merge(std::vector<cv::Mat>{lum, lum, lum}, lum3);
    cv::Mat lattice = 0.75 * lum3 + 0.35 * chroma;
    cv::Mat up;
    cv::resize(lattice, up, half, 0, 0, cv::INTER_CUBIC);
    cv::scaleAdd(up, amplitudes[o], acc, acc);
  }
  cv::Mat half_tex, tex;
  acc.convertTo(half_tex, CV_8UC3);
  cv::resize(half_tex, tex, cv::Size(width, height), 0, 0, cv::INTER_LINEAR);

  const double area = w_m * h_m;
  const double px = 1.0 / texel_m;  // texels per metre
  auto count = [&](double per_m2) { return static_cast<int>(std::round(area * per_m2)); };
  auto point = [&]() {
    return cv::Point2d(rng.uniform(0.0, width * 1.0), rng.uniform(0.0, height * 1.0));
  };
  auto log_uniform = [&](double lo, double hi) {
    return std::exp(rng.uniform(std::log(lo), std::log(hi)));
  };
  constexpr int kShift = 4;
  constexpr double kScale = 1 << kShift;
  auto fixed = [&](cv::Point2d p) {
    return cv::Point(static_cast<int>(std::lround(p.x * kScale)),
                     static_cast<int>(std::lround(p.y * kScale)));
  };
  // Blobs.
  for (int i = count(10.0); i > 0; --i) {
    const double r = log_uniform(0.012, 0.12) * px;
    const cv::Size axes(static_cast<int>(r * kScale),
                        static_cast<int>(r * rng.uniform(0.4, 1.0) * kScale));
    cv::ellipse(tex, fixed(point()), axes, rng.uniform(0.0, 180.0), 0, 360, RandomColor(rng),
                cv::FILLED, cv::LINE_AA, kShift);
  }
  // Rotated rectangles and triangles with high contrast.
  for (int i = count(8.0); i > 0; --i) {
    const cv::Point2d c = point();
    const bool dark = rng.uniform(0, 2) == 0;
    if (rng.uniform(0, 3) == 0) {
      std::vector<cv::Point> tri;
      const double r = log_uniform(0.02, 0.12) * px;
      for (int k = 0; k < 3; ++k) {
        const double ang = rng.uniform(0.0, 2.0 * kPi);
        tri.push_back(fixed(c + cv::Point2d(r * std::cos(ang), r * std::sin(ang))));
      }
      cv::fillConvexPoly(tex, tri, ContrastColor(rng, dark), cv::LINE_AA, kShift);
    } else {
      const cv::RotatedRect rect(
          cv::Point2f(c), cv::Size2f(log_uniform(0.02, 0.2) * px, log_uniform(0.02, 0.2) * px),
          static_cast<float>(rng.uniform(0.0, 180.0)));
      cv::Point2f corners[4];
      rect.points(corners);
      std::vector<cv::Point> poly;
      for (const cv::Point2f& p : corners) poly.push_back(fixed(cv::Point2d(p)));
      cv::fillConvexPoly(tex, poly, ContrastColor(rng, dark), cv::LINE_AA, kShift);
    }
  }
  // Binary code patches (random bits: corners that are not repeated).
  for (int i = count(3.0); i > 0; --i) {
    const int n = rng.uniform(4, 7);
    const double cell = rng.uniform(0.01, 0.025) * px;
    const cv::Point2d origin = point();
    const bool invert = rng.uniform(0, 2) == 0;
    const cv::Scalar fg = invert ? cv::Scalar(240, 240, 240) : cv::Scalar(15, 15, 15);
    const cv::Scalar bg = invert ? cv::Scalar(15, 15, 15) : cv::Scalar(240, 240, 240);
    cv::rectangle(tex, fixed(origin - cv::Point2d(cell, cell)),
                  fixed(origin + cv::Point2d(cell * (n + 1), cell * (n + 1))), bg, cv::FILLED,
                  cv::LINE_AA, kShift);
    for (int r = 0; r < n; ++r) {
      for (int c = 0; c < n; ++c) {
        if (rng.uniform(0, 2) == 0) continue;
        const cv::Point2d p0 = origin + cv::Point2d(c * cell, r * cell);
        cv::rectangle(tex, fixed(p0), fixed(p0 + cv::Point2d(cell, cell)), fg, cv::FILLED,
                      cv::LINE_AA, kShift);
      }
    }
  }
  // Line segments.
  for (int i = count(5.0); i > 0; --i) {
    const cv::Point2d a = point();
    const double len = log_uniform(0.04, 0.3) * px, ang = rng.uniform(0.0, 2.0 * kPi);
    const cv::Point2d b = a + cv::Point2d(len * std::cos(ang), len * std::sin(ang));
    cv::line(tex, fixed(a), fixed(b), ContrastColor(rng, rng.uniform(0, 2) == 0), rng.uniform(1, 4),
             cv::LINE_AA, kShift);
  }
  // Random glyphs.
  static const char kAlphabet[] = "ABCDEFGHJKLMNPQRSTUVWXYZ0123456789#%&@";
  const int fonts[] = {cv::FONT_HERSHEY_SIMPLEX, cv::FONT_HERSHEY_DUPLEX, cv::FONT_HERSHEY_COMPLEX,
                       cv::FONT_HERSHEY_TRIPLEX};
  for (int i = count(4.0); i > 0; --i) {
    std::string text;
    for (int k = rng.uniform(2, 7); k > 0; --k)
      text += kAlphabet[rng.uniform(0, static_cast<int>(sizeof(kAlphabet)) - 1)];
    const double height_px = log_uniform(0.025, 0.09) * px;
    const double font_scale = height_px / 22.0;
    const int thickness =
        std::max(1, static_cast<int>(std::lround(font_scale * rng.uniform(1.0, 2.5))));
    cv::putText(tex, text, cv::Point(point()), fonts[rng.uniform(0, 4)], font_scale,
                ContrastColor(rng, rng.uniform(0, 2) == 0), thickness, cv::LINE_AA);
  }
  return tex;
}

}  // namespace

void SceneOptions::Check() const {
  IMUMATCH_CHECK(std::isfinite(texel_size_m) && texel_size_m >= 0.001 && texel_size_m <= 0.1,
                 "SceneOptions.texel_size_m must be in [0.001, 0.1], got " << texel_size_m);
  IMUMATCH_CHECK(
      room_min.allFinite() && room_max.allFinite() && (room_max - room_min).minCoeff() > 0.5,
      "SceneOptions room must be finite and at least 0.5 m on each side");
  IMUMATCH_CHECK((room_max - room_min).maxCoeff() <= 50.0, "SceneOptions room larger than 50 m");
}

Scene::Scene(const SceneOptions& options) : options_(options) {
  options_.Check();
  SceneBox room;
  room.world_from_box =
      Rigid3d(Eigen::Quaterniond::Identity(), 0.5 * (options_.room_min + options_.room_max));
  room.half_size = 0.5 * (options_.room_max - options_.room_min);
  room.is_room = true;
  boxes_.push_back(room);
  if (options_.furniture) {
    // Fixed layout for the default room (furniture placed relative to the room's floor).
    const double f = options_.room_min.z();
    const std::vector<SceneBox> furniture = {
        MakeBox(1.2, 0.3, f + 0.375, 1.2, 0.8, 0.75, 10.0),   // table
        MakeBox(1.1, 0.2, f + 0.90, 0.35, 0.30, 0.30, 25.0),  // box on the table
        MakeBox(2.6, -1.6, f + 0.90, 0.6, 1.0, 1.8, 0.0),     // cabinet
        MakeBox(0.5, 2.0, f + 0.40, 1.8, 0.8, 0.8, -5.0),     // sofa
        MakeBox(-2.2, -1.8, f + 1.0, 0.5, 0.5, 2.0, 30.0),    // pillar
        MakeBox(2.2, 1.5, f + 0.30, 0.6, 0.6, 0.6, 40.0),     // crate
        MakeBox(-2.9, 0.5, f + 1.5, 0.1, 1.2, 0.8, 0.0),      // board on the back wall
        MakeBox(-0.3, -1.5, f + 0.45, 0.5, 0.5, 0.9, 15.0),   // stool
    };
    for (const SceneBox& box : furniture) {
      const Eigen::Vector3d c = box.world_from_box.translation;
      if (((c.array() > options_.room_min.array()) && (c.array() < options_.room_max.array()))
              .all()) {
        boxes_.push_back(box);
      }
    }
  }
  const Eigen::Vector3d light = Eigen::Vector3d(0.3, 0.5, 1.0).normalized();
  const double texel = options_.texel_size_m;
  for (int b = 0; b < static_cast<int>(boxes_.size()); ++b) {
    for (int axis = 0; axis < 3; ++axis) {
      for (int side : {-1, 1}) {
        SceneSurface s;
        s.box = b;
        s.axis = axis;
        s.side = side;
        Eigen::Vector3d normal_local = Eigen::Vector3d::Zero();
        normal_local[axis] = boxes_[b].is_room ? -side : side;  // facing the viewer
        const Eigen::Vector3d normal = boxes_[b].world_from_box.rotation * normal_local;
        s.shade = static_cast<float>(0.62 + 0.38 * std::max(0.0, normal.dot(light)));
        const int ia = (axis + 1) % 3, ib = (axis + 2) % 3;
        const int width = static_cast<int>(std::ceil(2.0 * boxes_[b].half_size[ia] / texel)) + 1;
        const int height = static_cast<int>(std::ceil(2.0 * boxes_[b].half_size[ib] / texel)) + 1;
        const uint64_t seed =
            SplitMix64(options_.seed * 1000003ULL + static_cast<uint64_t>(surfaces_.size()));
        s.mip_levels.push_back(MakeTexture(width, height, texel, seed));
        while (s.mip_levels.back().cols >= 4 && s.mip_levels.back().rows >= 4) {
          cv::Mat down;
          cv::pyrDown(s.mip_levels.back(), down);
          s.mip_levels.push_back(down);
        }
        surfaces_.push_back(std::move(s));
      }
    }
  }
}

std::optional<RayHit> Scene::CastRay(const Eigen::Vector3d& origin,
                                     const Eigen::Vector3d& direction) const {
  IMUMATCH_CHECK(origin.allFinite() && direction.allFinite() && direction.norm() > 0.0,
                 "CastRay needs a finite origin and a non-zero direction");
  double best = std::numeric_limits<double>::infinity();
  int best_surface = -1;
  for (int b = 0; b < static_cast<int>(boxes_.size()); ++b) {
    const Rigid3d& wb = boxes_[b].world_from_box;
    const Eigen::Quaterniond box_from_world = wb.rotation.conjugate();
    int surface = -1;
    const double t = IntersectBoxLocal(b, box_from_world * (origin - wb.translation),
                                       box_from_world * direction, &surface);
    if (t < best) {
      best = t;
      best_surface = surface;
    }
  }
  if (best_surface < 0) return std::nullopt;
  const SceneSurface& s = surfaces_[best_surface];
  const SceneBox& box = boxes_[s.box];
  RayHit hit;
  hit.distance = best;
  hit.surface = best_surface;
  hit.point_in_world = origin + best * direction;
  Eigen::Vector3d normal_local = Eigen::Vector3d::Zero();
  normal_local[s.axis] = box.is_room ? -s.side : s.side;
  hit.normal_in_world = box.world_from_box.rotation * normal_local;
  const Eigen::Vector3d p_in_box = box.world_from_box.Inverse() * hit.point_in_world;
  const int ia = (s.axis + 1) % 3, ib = (s.axis + 2) % 3;
  hit.surface_ab =
      Eigen::Vector2d(p_in_box[ia] + box.half_size[ia], p_in_box[ib] + box.half_size[ib]);
  return hit;
}

}  // namespace imumatch
