#include "imumatch/sim/renderer.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "imumatch/camera/camera_test_util.h"
#include "imumatch/core/error.h"
#include "imumatch/core/so3.h"
#include "imumatch/sim/motions.h"
#include "imumatch/sim/scene.h"

namespace imumatch {
namespace {

// 320 x 240 with the Kinect field of view.
PinholeCamera HalfCamera() { return PinholeCamera::KinectDefault().ScaledToWidth(320); }

const Scene& FurnishedScene() {
  static const Scene scene;
  return scene;
}

Rigid3d WorldFromCam(const Eigen::Vector3d& position, double yaw_deg, double pitch_deg) {
  // Level body facing world +x, then yaw about world z and pitch about the body y (left) axis.
  const Eigen::Quaterniond world_r_body =
      Eigen::Quaterniond(Eigen::AngleAxisd(yaw_deg * kPi / 180.0, Eigen::Vector3d::UnitZ())) *
      Eigen::Quaterniond(Eigen::AngleAxisd(pitch_deg * kPi / 180.0, Eigen::Vector3d::UnitY()));
  const Rigid3d world_from_body(world_r_body, position);
  const Rigid3d cam_from_body(SyntheticCamFromImu().rotation, Eigen::Vector3d::Zero());
  return world_from_body * cam_from_body.Inverse();
}

// A camera 2 m in front of the empty room's front wall (x = 3), turned 12 deg and pitched 5 deg:
// the wall fills the image and the depth of pixel (u, v) is D / (n . R d(u, v)) with
// d = ((u-cx)/fx, (v-cy)/fy, 1): independent of the ray caster.
TEST(RendererTest, DepthOfAWallMatchesThePlaneFormulaExactly) {
  SceneOptions scene_options;
  scene_options.furniture = false;
  scene_options.texel_size_m = 0.02;  // coarse textures: only depth matters here
  const Scene scene(scene_options);
  const PinholeCamera camera = PinholeCamera::KinectDefault();
  const Rigid3d world_from_cam = WorldFromCam(Eigen::Vector3d(1.0, 0.2, 1.4), 12.0, -5.0);
  const RenderedView view = RenderView(scene, camera, world_from_cam);
  ASSERT_EQ(view.depth.type(), CV_16U);
  ASSERT_EQ(view.rgb.type(), CV_8UC3);
  ASSERT_EQ(view.depth.size(), cv::Size(640, 480));
  const Eigen::Matrix3d r = world_from_cam.RotationMatrix();
  int exact = 0, off_by_one = 0, wrong = 0;
  double min_z = 1e9, max_z = 0.0;
  for (int v = 0; v < camera.height; ++v) {
    for (int u = 0; u < camera.width; ++u) {
      const Eigen::Vector3d d((u - camera.cx) / camera.fx, (v - camera.cy) / camera.fy, 1.0);
      const double z = 2.0 / (r * d).x();
      min_z = std::min(min_z, z);
      max_z = std::max(max_z, z);
      const int expected = static_cast<int>(std::lround(z * 5000.0));
      const int raw = view.depth.at<uint16_t>(v, u);
      if (raw == expected) {
        ++exact;
      } else if (std::abs(raw - expected) == 1) {
        ++off_by_one;  // rounding ties only
      } else {
        ++wrong;
      }
    }
  }
  EXPECT_EQ(wrong, 0);
  EXPECT_LE(off_by_one, 20);
  EXPECT_GT(exact, 640 * 480 - 20);
  // The geometry is really slanted: the depth spans a range.
  EXPECT_LT(min_z, 2.05);
  EXPECT_GT(max_z, 2.2);
  // Where the raster samples a pixel centre, the analytic ray cast agrees.
  for (const Eigen::Vector2d& uv :
       {Eigen::Vector2d(0, 0), Eigen::Vector2d(639, 479), Eigen::Vector2d(320, 17)}) {
    const Eigen::Vector3d d((uv.x() - camera.cx) / camera.fx, (uv.y() - camera.cy) / camera.fy,
                            1.0);
    EXPECT_NEAR(AnalyticDepth(scene, camera, world_from_cam, uv), 2.0 / (r * d).x(), 1e-12);
  }
}

TEST(RendererTest, RenderedDepthMatchesAnalyticRayCastAtRandomPixels) {
  const Scene& scene = FurnishedScene();
  const PinholeCamera camera = PinholeCamera::KinectDefault();
  const auto motion = MakeMotion("walk", MotionOptions());
  const Rigid3d world_from_cam = motion->WorldFromBody(1.7) * SyntheticCamFromImu().Inverse();
  const RenderedView view = RenderView(scene, camera, world_from_cam);
  std::mt19937 rng(5);
  int checked = 0, furniture_hits = 0;
  for (int i = 0; i < 400; ++i) {
    const int u = static_cast<int>(rng() % 640), v = static_cast<int>(rng() % 480);
    const std::optional<Eigen::Vector3d> p =
        AnalyticPointInCam(scene, camera, world_from_cam, Eigen::Vector2d(u, v));
    ASSERT_TRUE(p.has_value());  // inside a closed room every ray hits something
    // The analytic point projects back onto the pixel and lies on a box face.
    const Eigen::Vector2d uv = *camera.Project(*p);
    EXPECT_LT((uv - Eigen::Vector2d(u, v)).norm(), 1e-9);
    const std::optional<RayHit> hit =
        scene.CastRay(world_from_cam.translation, world_from_cam * *p - world_from_cam.translation);
    ASSERT_TRUE(hit.has_value());
    EXPECT_NEAR(hit->distance, 1.0, 1e-9);
    const SceneBox& box = scene.boxes()[scene.surfaces()[hit->surface].box];
    const Eigen::Vector3d local = box.world_from_box.Inverse() * (world_from_cam * *p);
    const Eigen::Vector3d slack = (local.cwiseAbs() - box.half_size).cwiseAbs();
    EXPECT_LT(slack.minCoeff(), 1e-9);
    EXPECT_LT((local.cwiseAbs() - box.half_size).maxCoeff(), 1e-9);
    if (!box.is_room) ++furniture_hits;
    EXPECT_NEAR(view.depth.at<uint16_t>(v, u), p->z() * 5000.0, 0.5 + 1e-6) << u << "," << v;
    ++checked;
  }
  EXPECT_EQ(checked, 400);
  EXPECT_GT(furniture_hits, 20);
}

// Corners detected independently in two frames of a moving camera: the exact motion maps the
// corners of frame A onto corners of frame B to sub-pixel accuracy (this also checks the
// anti-aliasing: aliased textures make corners jump between frames).
void ExpectFeaturesMoveWithTheTruePose(const PinholeCamera& camera) {
  const Scene& scene = FurnishedScene();
  const auto motion = MakeMotion("walk", MotionOptions());
  const Rigid3d body_from_cam = SyntheticCamFromImu().Inverse();
  const Rigid3d world_from_a = motion->WorldFromBody(1.2) * body_from_cam;
  const Rigid3d world_from_b = motion->WorldFromBody(1.2 + 1.0 / 30.0) * body_from_cam;
  const Rigid3d b_from_a = world_from_b.Inverse() * world_from_a;
  ASSERT_GT(b_from_a.translation.norm(), 0.015);  // a real motion
  auto corners = [&](const Rigid3d& world_from_cam, int max_corners, double quality,
                     double min_distance) {
    const RenderedView view = RenderView(scene, camera, world_from_cam);
    cv::Mat gray;
    cv::cvtColor(view.rgb, gray, cv::COLOR_BGR2GRAY);
    // A fisheye's field of view (shrunk by 8 px): its black corners' edge is no scene corner.
    cv::Mat field(camera.height, camera.width, CV_8U);
    for (int v = 0; v < camera.height; ++v) {
      for (int u = 0; u < camera.width; ++u) {
        field.at<uint8_t>(v, u) = camera.InField(Eigen::Vector2d(u, v)) ? 255 : 0;
      }
    }
    cv::erode(field, field, cv::Mat::ones(17, 17, CV_8U));
    std::vector<cv::Point2f> pts;
    cv::goodFeaturesToTrack(gray, pts, max_corners, quality, min_distance, field);
    cv::cornerSubPix(gray, pts, cv::Size(3, 3), cv::Size(-1, -1),
                     cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 30, 0.01));
    return pts;
  };
  const std::vector<cv::Point2f> pts_a = corners(world_from_a, 600, 0.01, 7.0);
  const std::vector<cv::Point2f> pts_b = corners(world_from_b, 2000, 0.005, 3.0);
  ASSERT_GT(pts_a.size(), 300u);  // the textures are rich in corners
  int tested = 0, within_half = 0, within_one = 0;
  for (const cv::Point2f& pa : pts_a) {
    const Eigen::Vector2d uv_a(pa.x, pa.y);
    const std::optional<Eigen::Vector3d> p_a =
        AnalyticPointInCam(scene, camera, world_from_a, uv_a);
    if (!p_a) continue;
    // Skip corners made by occlusion boundaries (not attached to one 3D point): the depth 4 px to
    // either side continues the centre's (second difference within 1 %), as on one smooth
    // surface, even where it changes fast (a fisheye sees the floor at grazing angles).
    bool boundary = false;
    for (const Eigen::Vector2d& off : {Eigen::Vector2d(4, 0), Eigen::Vector2d(0, 4)}) {
      if (!camera.InField(uv_a + off) || !camera.InField(uv_a - off)) boundary = true;
      const double z_plus = AnalyticDepth(scene, camera, world_from_a, uv_a + off);
      const double z_minus = AnalyticDepth(scene, camera, world_from_a, uv_a - off);
      if (!(std::abs(z_plus + z_minus - 2.0 * p_a->z()) < 0.01 * p_a->z())) boundary = true;
    }
    if (boundary) continue;
    const Eigen::Vector3d p_b = b_from_a * *p_a;
    const std::optional<Eigen::Vector2d> uv_b = camera.Project(p_b);
    if (!uv_b || !camera.IsInside(*uv_b, 10.0) || !camera.InField(*uv_b)) continue;
    // Visible in B (not occluded).
    if (std::abs(AnalyticDepth(scene, camera, world_from_b, *uv_b) - p_b.z()) > 1e-3) continue;
    double best = 1e9;
    for (const cv::Point2f& pb : pts_b)
      best = std::min(best, (Eigen::Vector2d(pb.x, pb.y) - *uv_b).norm());
    ++tested;
    if (best < 0.5) ++within_half;
    if (best < 1.0) ++within_one;
  }
  ASSERT_GT(tested, 200);
  const double frac_half = static_cast<double>(within_half) / tested;
  const double frac_one = static_cast<double>(within_one) / tested;
  ::testing::Test::RecordProperty("fraction_within_0_5px", std::to_string(frac_half));
  ::testing::Test::RecordProperty("fraction_within_1px", std::to_string(frac_one));
  std::printf("corners tested %d: within 0.5 px %.3f, within 1 px %.3f\n", tested, frac_half,
              frac_one);
  EXPECT_GT(frac_one, 0.85);
  EXPECT_GT(frac_half, 0.75);
}

TEST(RendererTest, FeaturesMoveWithTheTruePose) {
  ExpectFeaturesMoveWithTheTruePose(PinholeCamera::KinectDefault());
}

// Through a lens the image is distorted and the ground truth stays exact: corners found in the
// rendered (distorted) images still move as the camera model projects the true motion.
TEST(RendererTest, FeaturesMoveWithTheTruePoseThroughEurocsLens) {
  ExpectFeaturesMoveWithTheTruePose(PinholeCamera::EurocCam0());
}

TEST(RendererTest, FeaturesMoveWithTheTruePoseThroughAnEquidistantLens) {
  ExpectFeaturesMoveWithTheTruePose(testing::EquidistantTestCamera());
}

// A fisheye wider than the field of view (TUM-VI's: 108 deg at the corners), rendered up to 80 deg.
TEST(RendererTest, FeaturesMoveWithTheTruePoseThroughAFisheye) {
  ExpectFeaturesMoveWithTheTruePose(PinholeCamera::TumViCam0());
}

// Through a lens, pixel (u, v) shows the scene along the ray the camera model gives it: its depth
// equals the analytic ray cast along PixelToNormalized(u, v) (the model's own inverse, in double,
// and the scene's exact ray-box intersection, not the raster code) at every other pixel of the
// image, and the lens matters: along the straight pinhole ray the depth differs in much of it.
TEST(RendererTest, DepthThroughALensFollowsTheLensRay) {
  SceneOptions scene_options;
  scene_options.texel_size_m = 0.02;  // coarse textures: only depth matters here
  const Scene scene(scene_options);
  for (const PinholeCamera& camera :
       {PinholeCamera::EurocCam0(), testing::EquidistantTestCamera(), PinholeCamera::TumViCam0()}) {
    PinholeCamera straight = camera;
    straight.model = DistortionModel::kRadialTangential;
    straight.distortion = {0, 0, 0, 0, 0};
    const Rigid3d world_from_cam = WorldFromCam(Eigen::Vector3d(-1.0, 0.3, 1.3), 20.0, 3.0);
    RenderOptions options;
    options.num_threads = 1;
    const RenderedView view = RenderView(scene, camera, world_from_cam, options);
    ASSERT_EQ(view.depth.size(), cv::Size(camera.width, camera.height));
    int exact = 0, off_by_one = 0, wrong = 0, bent = 0, checked = 0, beyond_field = 0;
    for (int v = 0; v < camera.height; v += 2) {
      for (int u = 0; u < camera.width; u += 2) {
        const Eigen::Vector2d uv(u, v);
        if (!camera.InField(uv)) {  // a fisheye's corners beyond 80 deg: black, no depth
          ASSERT_EQ(view.depth.at<uint16_t>(v, u), 0) << uv.transpose();
          ASSERT_EQ(view.rgb.at<cv::Vec3b>(v, u), cv::Vec3b(0, 0, 0)) << uv.transpose();
          ++beyond_field;
          continue;
        }
        const double z = AnalyticDepth(scene, camera, world_from_cam, uv);
        ASSERT_TRUE(std::isfinite(z));  // inside a closed room every ray hits something
        const int expected = static_cast<int>(std::lround(z * camera.depth_scale));
        const int raw = view.depth.at<uint16_t>(v, u);
        const double z_straight = AnalyticDepth(scene, straight, world_from_cam, uv);
        if (std::abs(z_straight - z) * camera.depth_scale > 10.0) ++bent;
        ++checked;
        if (raw == expected) {
          ++exact;
        } else if (std::abs(raw - expected) == 1) {
          ++off_by_one;  // rounding ties (and the ideal pixel's float rounding) only
        } else {
          ++wrong;
        }
      }
    }
    // A pixel whose ray grazes an edge between two surfaces may land on either side of it with
    // the ideal pixel's float rounding: a handful at most.
    EXPECT_LE(wrong, checked / 5000) << camera.ToString();
    EXPECT_LE(off_by_one, checked / 1000) << camera.ToString();
    EXPECT_GT(bent, checked / 4) << camera.ToString();  // the lens matters in much of the image
    // Only the fisheye has pixels beyond the field: its corners, 17 % of the image.
    EXPECT_EQ(beyond_field > 0, camera.WiderThanField()) << beyond_field;
    std::printf(
        "%s: %d pixels, %d exact, %d off by one, %d other; %d differ along the straight ray\n",
        ToString(camera.model), checked, exact, off_by_one, wrong, bent);
  }
}

TEST(RendererTest, DeterministicForAFixedSeed) {
  const PinholeCamera camera = [] {
    PinholeCamera c = PinholeCamera::KinectDefault();
    c.width = 160;
    c.height = 120;
    c.fx = c.fy = 131.25;
    c.cx = 79.5;
    c.cy = 59.5;
    return c;
  }();
  const Rigid3d pose = WorldFromCam(Eigen::Vector3d(-1.0, 0.3, 1.3), 20.0, 3.0);
  RenderOptions options;
  options.depth_noise.add_noise = true;
  options.depth_noise.add_holes = true;
  const RenderedView a = RenderView(FurnishedScene(), camera, pose, options);
  options.num_threads = 1;  // the result does not depend on the threading
  const RenderedView b = RenderView(FurnishedScene(), camera, pose, options);
  EXPECT_EQ(cv::norm(a.rgb, b.rgb, cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(a.depth, b.depth, cv::NORM_INF), 0.0);
  // A scene built again from the same seed renders the same image; another seed does not.
  SceneOptions other;
  other.texel_size_m = 0.02;
  other.seed = 11;
  const RenderedView c = RenderView(Scene(other), camera, pose);
  const RenderedView d = RenderView(Scene(other), camera, pose);
  EXPECT_EQ(cv::norm(c.rgb, d.rgb, cv::NORM_INF), 0.0);
  other.seed = 12;
  const RenderedView e = RenderView(Scene(other), camera, pose);
  EXPECT_GT(cv::norm(c.rgb, e.rgb, cv::NORM_L1) / (160 * 120 * 3), 10.0);
  options.depth_noise.seed = 2;
  const RenderedView f = RenderView(FurnishedScene(), camera, pose, options);
  EXPECT_GT(cv::norm(a.depth, f.depth, cv::NORM_INF), 0.0);
}

TEST(RendererTest, KinectDepthNoiseAndHoles) {
  SceneOptions scene_options;
  scene_options.furniture = false;
  scene_options.texel_size_m = 0.02;
  const Scene scene(scene_options);
  const PinholeCamera camera = HalfCamera();
  // Facing the front wall (x = 3) at 2 m: every pixel has z in [2, 2.3].
  const Rigid3d pose = WorldFromCam(Eigen::Vector3d(1.0, 0.0, 1.4), 0.0, 0.0);
  const RenderedView exact = RenderView(scene, camera, pose);
  RenderOptions options;
  options.depth_noise.add_noise = true;
  const RenderedView noisy = RenderView(scene, camera, pose, options);
  double sum = 0.0, sum_sq_normalised = 0.0;
  int n = 0;
  for (int v = 0; v < camera.height; ++v) {
    for (int u = 0; u < camera.width; ++u) {
      const double z = exact.depth.at<uint16_t>(v, u) / 5000.0;
      const double e = noisy.depth.at<uint16_t>(v, u) / 5000.0 - z;
      const double sigma = 1.425e-3 * z * z;
      sum += e / sigma;
      sum_sq_normalised += (e / sigma) * (e / sigma);
      ++n;
    }
  }
  EXPECT_NEAR(sum / n, 0.0, 0.02);
  EXPECT_NEAR(std::sqrt(sum_sq_normalised / n), 1.0, 0.03);

  options = RenderOptions();
  options.depth_noise.add_holes = true;
  options.depth_noise.dropout_probability = 0.1;
  const RenderedView holes = RenderView(scene, camera, pose, options);
  EXPECT_NEAR(cv::countNonZero(holes.depth == 0) / (320.0 * 240.0), 0.1, 0.01);
  options.depth_noise.dropout_probability = 0.0;
  options.depth_noise.max_range_m = 2.1;
  const Rigid3d slanted = WorldFromCam(Eigen::Vector3d(1.0, 0.2, 1.4), 12.0, -5.0);
  const RenderedView slanted_exact = RenderView(scene, camera, slanted);
  const RenderedView far = RenderView(scene, camera, slanted, options);
  int near_kept = 0, far_removed = 0;
  for (int v = 0; v < camera.height; ++v) {
    for (int u = 0; u < camera.width; ++u) {
      const int raw = slanted_exact.depth.at<uint16_t>(v, u);
      if (raw == 10500) continue;  // z within half a unit of the limit
      if (raw < 10500) {
        ASSERT_EQ(far.depth.at<uint16_t>(v, u), raw);
        ++near_kept;
      } else {
        ASSERT_EQ(far.depth.at<uint16_t>(v, u), 0);
        ++far_removed;
      }
    }
  }
  EXPECT_GT(near_kept, 5000);
  EXPECT_GT(far_removed, 5000);
  // Grazing angles: 5 cm from the side wall y = -2.5, looking along it. Pixel u = 200 sees the
  // wall at |cos incidence| = 0.15 (a hole), pixel u = 300 at 0.47 (kept).
  options.depth_noise.max_range_m = 10.0;
  options.depth_noise.min_range_m = 0.0;
  const Rigid3d along = WorldFromCam(Eigen::Vector3d(0.0, -2.45, 1.4), 0.0, 0.0);
  for (const int u : {200, 300}) {
    const std::optional<RayHit> hit = scene.CastRay(
        along.translation, along.rotation * Eigen::Vector3d((u - camera.cx) / camera.fx, 0.0, 1.0));
    ASSERT_TRUE(hit.has_value());
    EXPECT_NEAR(hit->normal_in_world.y(), 1.0, 1e-12);  // the side wall, facing into the room
  }
  const RenderedView graze = RenderView(scene, camera, along, options);
  const RenderedView clean = RenderView(scene, camera, along);
  EXPECT_EQ(graze.depth.at<uint16_t>(120, 200), 0);
  EXPECT_GT(clean.depth.at<uint16_t>(120, 200), 0);
  EXPECT_EQ(graze.depth.at<uint16_t>(120, 300), clean.depth.at<uint16_t>(120, 300));
}

// A one-pixel-wide (and one-pixel-high) camera with a lens renders without reading beyond the
// image (ASan checks the neighbour lookups).
TEST(RendererTest, OnePixelCameraWithALens) {
  PinholeCamera tiny = PinholeCamera::EurocCam0();
  tiny.width = 1;
  tiny.height = 1;
  tiny.cx = tiny.cy = 0.0;
  SceneOptions small;
  small.texel_size_m = 0.05;
  small.furniture = false;
  const Scene scene(small);
  const Rigid3d world_from_cam = WorldFromCam(Eigen::Vector3d(1.0, 0.2, 1.4), 12.0, -5.0);
  const RenderedView view = RenderView(scene, tiny, world_from_cam);
  ASSERT_EQ(view.depth.size(), cv::Size(1, 1));
  EXPECT_NEAR(view.depth.at<uint16_t>(0, 0),
              AnalyticDepth(scene, tiny, world_from_cam, Eigen::Vector2d(0, 0)) * tiny.depth_scale,
              0.5 + 1e-3);
}

// A sequence computes its lens's ray map once and passes it to every frame: the same images as a
// map made per frame; a map of another camera is refused.
TEST(RendererTest, ASharedLensRayMapRendersTheSameFrame) {
  SceneOptions small;
  small.texel_size_m = 0.05;
  small.furniture = false;
  const Scene scene(small);
  const PinholeCamera camera = PinholeCamera::EurocCam0().ScaledToWidth(188);
  const Rigid3d world_from_cam = WorldFromCam(Eigen::Vector3d(1.0, 0.2, 1.4), 12.0, -5.0);
  const LensRayMap rays(camera);
  ASSERT_FALSE(rays.empty());
  const RenderedView shared = RenderView(scene, camera, world_from_cam, RenderOptions(), &rays);
  const RenderedView own = RenderView(scene, camera, world_from_cam);
  EXPECT_EQ(cv::norm(shared.rgb, own.rgb, cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(shared.depth, own.depth, cv::NORM_INF), 0.0);
  PinholeCamera other = camera;
  other.distortion[0] = -0.2;
  EXPECT_THROW(RenderView(scene, other, world_from_cam, RenderOptions(), &rays), InvalidArgument);
  EXPECT_TRUE(LensRayMap(PinholeCamera::KinectDefault()).empty());  // no lens: no map
}

TEST(RendererTest, RejectsBadInput) {
  PinholeCamera bad_camera = PinholeCamera::KinectDefault();
  bad_camera.fx = 0.0;
  SceneOptions small;
  small.texel_size_m = 0.05;
  small.furniture = false;
  const Scene scene(small);
  EXPECT_THROW(RenderView(scene, bad_camera, Rigid3d()), InvalidArgument);
  RenderOptions bad;
  bad.num_threads = 0;
  EXPECT_THROW(RenderView(scene, PinholeCamera::KinectDefault(), Rigid3d(), bad), InvalidArgument);
  SceneOptions bad_scene;
  bad_scene.texel_size_m = 0.0;
  EXPECT_THROW(Scene{bad_scene}, InvalidArgument);
  EXPECT_THROW(scene.CastRay(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()), InvalidArgument);
}

}  // namespace
}  // namespace imumatch
