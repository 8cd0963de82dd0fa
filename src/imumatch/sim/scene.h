#pragma once

#include <cstdint>
#include <limits>
#include <optional>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "imumatch/core/rigid3.h"

namespace imumatch {

// An oriented box: centre and orientation world_from_box, half side lengths along the box axes.
// A room box is seen from the inside (rays exit through its walls), furniture from the outside.
struct SceneBox {
  Rigid3d world_from_box;
  Eigen::Vector3d half_size = Eigen::Vector3d::Ones();
  bool is_room = false;
};

// One textured planar face of a box. Surface index = 6 * box + 2 * axis + (side > 0 ? 1 : 0).
// Texture coordinates (metres): a along box axis (axis+1)%3, b along (axis+2)%3, both measured from
// the face's minimum corner, so (a, b) in [0, 2*half_size].
struct SceneSurface {
  int box = 0;
  int axis = 0;        // 0, 1, 2: the box axis the face is normal to
  int side = 1;        // -1 or +1: the face at -half_size or +half_size
  float shade = 1.0f;  // constant Lambertian factor of the face (fixed light direction)
  // Mip-map pyramid of the procedural texture, CV_8UC3 (OpenCV BGR order). Level k texel j has
  // its centre at level-0 coordinate j * 2^k (cv::pyrDown), level-0 texel i at a = i * texel_size.
  std::vector<cv::Mat> mip_levels;
};

struct SceneOptions {
  uint64_t seed = 7;            // textures are a deterministic function of the seed
  double texel_size_m = 0.005;  // level-0 texel size on every surface
  // The room spans [room_min, room_max] (world z up, floor at z = room_min.z()).
  Eigen::Vector3d room_min = Eigen::Vector3d(-3.0, -2.5, 0.0);
  Eigen::Vector3d room_max = Eigen::Vector3d(3.0, 2.5, 2.8);
  bool furniture = true;  // the fixed layout of furniture-like boxes (table, cabinet, sofa, ...)
  void Check() const;
};

struct RayHit {
  double distance = 0.0;  // ray parameter: point = origin + distance * direction
  Eigen::Vector3d point_in_world = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal_in_world = Eigen::Vector3d::Zero();  // unit, facing the ray origin
  int surface = -1;
  Eigen::Vector2d surface_ab = Eigen::Vector2d::Zero();  // texture coordinates, metres
};

// The synthetic textured room: walls, floor and ceiling plus furniture boxes, each face with its
// own procedural texture (multi-scale value noise, blobs, rectangles, lines, random glyphs and
// binary-code patches: rich in corners and blobs for SIFT/ORB, and not repetitive).
class Scene {
 public:
  explicit Scene(const SceneOptions& options = SceneOptions());

  // Exact analytic ray cast: the nearest surface hit at distance > 1e-9 along the ray, or nullopt.
  // direction need not be unit length.
  std::optional<RayHit> CastRay(const Eigen::Vector3d& origin_in_world,
                                const Eigen::Vector3d& direction_in_world) const;

  const SceneOptions& options() const { return options_; }
  const std::vector<SceneBox>& boxes() const { return boxes_; }
  const std::vector<SceneSurface>& surfaces() const { return surfaces_; }

  // Intersects a ray given in box coordinates with box `b`. Returns the distance and sets the
  // surface index and hit side; infinity when missed.
  double IntersectBoxLocal(int b, const Eigen::Vector3d& origin_in_box,
                           const Eigen::Vector3d& direction_in_box, int* surface) const;

 private:
  SceneOptions options_;
  std::vector<SceneBox> boxes_;
  std::vector<SceneSurface> surfaces_;
};

// Slab test; inline because the renderer calls it for every pixel and box.
inline double Scene::IntersectBoxLocal(int b, const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                                       int* surface) const {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  const Eigen::Vector3d& h = boxes_[b].half_size;
  double t_near = -kInf, t_far = kInf;
  int axis_near = -1, axis_far = -1;
  for (int k = 0; k < 3; ++k) {
    if (d[k] == 0.0) {
      if (o[k] < -h[k] || o[k] > h[k]) return kInf;
      continue;
    }
    const double inv = 1.0 / d[k];
    double t1 = (-h[k] - o[k]) * inv, t2 = (h[k] - o[k]) * inv;
    if (t1 > t2) std::swap(t1, t2);
    if (t1 > t_near) {
      t_near = t1;
      axis_near = k;
    }
    if (t2 < t_far) {
      t_far = t2;
      axis_far = k;
    }
  }
  if (t_near > t_far) return kInf;
  if (boxes_[b].is_room) {
    if (t_far <= 1e-9 || axis_far < 0) return kInf;
    *surface = 6 * b + 2 * axis_far + (d[axis_far] > 0.0 ? 1 : 0);
    return t_far;
  }
  if (t_near <= 1e-9 || axis_near < 0) return kInf;
  *surface = 6 * b + 2 * axis_near + (d[axis_near] > 0.0 ? 0 : 1);
  return t_near;
}

}  // namespace imumatch
