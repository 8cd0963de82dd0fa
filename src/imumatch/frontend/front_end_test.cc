#include "imumatch/frontend/front_end.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <iostream>
#include <vector>

#include <gtest/gtest.h>

#include "imumatch/core/error.h"
#include "imumatch/core/rigid3.h"
#include "imumatch/core/time.h"
#include "imumatch/sim/synthetic_sequence.h"

namespace imumatch {
namespace {

// The walk motion (forward speed ramped to 0.8 m/s, bobbing, head rotation) at 20 Hz, 320 x 240,
// exact depth, simulated EuRoC-grade IMU: still for the first 0.5 s.
const SyntheticSequence& Walk() {
  static const SyntheticSequence seq = [] {
    SyntheticSequenceOptions so;
    so.motion = "walk";
    so.camera = PinholeCamera::KinectDefault().ScaledToWidth(320);
    so.frame_rate_hz = 20.0;
    return MakeSyntheticSequence(so);
  }();
  return seq;
}

FrontEndOptions Options() {
  FrontEndOptions o;
  o.features.max_keypoints = 400;
  o.still_s = 0.4;
  return o;
}

// Feeds the IMU up to (and one sample past) each frame, then the frame.
class Runner {
 public:
  Runner(const SyntheticSequence& seq, const FrontEndOptions& options)
      : seq_(seq), fe_(seq.camera, seq.imu_params, seq.cam_from_imu, options) {}
  FrontEndResult Next(size_t k, const cv::Mat* image = nullptr, const cv::Mat* depth = nullptr) {
    const SyntheticFrame& f = seq_.frames[k];
    while (next_imu_ < seq_.imu.size()) {
      const ImuSample& s = seq_.imu[next_imu_];
      if (skip_ && s.t_ns > skip_from_ && s.t_ns < skip_to_) {
        ++next_imu_;
        continue;
      }
      fe_.AddImu(s);
      ++next_imu_;
      if (s.t_ns >= f.t_ns) break;
    }
    FrontEndFrame in;
    in.t_ns = f.t_ns;
    in.image = image != nullptr ? *image : f.rgb;
    in.depth = depth != nullptr ? *depth : f.depth;
    return fe_.Process(in);
  }
  void DropImu(int64_t from, int64_t to) {
    skip_ = true;
    skip_from_ = from;
    skip_to_ = to;
  }
  FrontEnd& front_end() { return fe_; }

 private:
  const SyntheticSequence& seq_;
  FrontEnd fe_;
  size_t next_imu_ = 0;
  bool skip_ = false;
  int64_t skip_from_ = 0, skip_to_ = 0;
};

TEST(FrontEnd, RunFromRestRecoversTheVelocity) {
  const SyntheticSequence& seq = Walk();
  Runner run(seq, Options());
  const int64_t t_check = SecondsToNs(0.5 + 1.0);  // 1 s into the motion
  bool checked = false;
  for (size_t k = 0; k < seq.frames.size(); ++k) {
    const FrontEndResult r = run.Next(k);
    if (seq.frames[k].t_ns < SecondsToNs(0.4)) {  // waiting for 0.4 s of still IMU
      EXPECT_EQ(r.status, FrameStatus::kFirst);
      EXPECT_NE(r.event.find("waiting"), std::string::npos) << r.event;
      continue;
    }
    if (r.status == FrameStatus::kFirst) {
      EXPECT_NE(r.event.find("still start"), std::string::npos) << r.event;
      continue;
    }
    EXPECT_EQ(r.status, FrameStatus::kGuided) << "frame " << k << ": " << r.event;
    EXPECT_TRUE(r.pose_from_depth) << "frame " << k << ": " << r.pose.reason;
    if (!checked && seq.frames[k].t_ns >= t_check) {
      const Eigen::Vector3d truth = seq.frames[k].imu_velocity_in_world;
      // The front end's world is gravity-aligned with yaw zero at the start; compare speeds and
      // the vertical component (yaw-free).
      EXPECT_GT(truth.norm(), 0.3);
      EXPECT_NEAR(r.velocity_in_world.norm(), truth.norm(), 0.05 * truth.norm());
      EXPECT_NEAR(r.velocity_in_world.z(), truth.z(), 0.05 * truth.norm());
      checked = true;
    }
  }
  EXPECT_TRUE(checked);
}

// A live front end keeps no fitted rotations by default (nothing reads them); estimating the
// camera's clock offset online, it keeps the last time_offset_window of them only, estimates every
// time_offset_every, and on a synthetic walk (one clock for camera and IMU) finds no offset.
TEST(FrontEnd, OnlineTimeOffsetKeepsItsWindowAndFindsNoOffsetOnOneClock) {
  const SyntheticSequence& seq = Walk();
  {
    Runner run(seq, Options());
    for (size_t k = 0; k < seq.frames.size(); ++k) run.Next(k);
    EXPECT_TRUE(run.front_end().fitted_rotations().empty());
    EXPECT_FALSE(run.front_end().online_time_offset().has_value());
  }
  FrontEndOptions o = Options();
  o.estimate_time_offset = true;
  o.time_offset_window = 10;
  o.time_offset_every = 3;
  Runner run(seq, o);
  size_t most = 0;
  int guided = 0;
  for (size_t k = 0; k < seq.frames.size(); ++k) {
    guided += run.Next(k).status == FrameStatus::kGuided ? 1 : 0;
    most = std::max(most, run.front_end().fitted_rotations().size());
  }
  EXPECT_GE(guided, 14);  // more fits than the window holds
  EXPECT_EQ(most, 10u);
  const std::optional<TimeOffsetEstimate>& online = run.front_end().online_time_offset();
  ASSERT_TRUE(online.has_value());
  EXPECT_GE(online->observations, 1);
  EXPECT_LE(online->observations, 10);
  if (online->measured) {
    EXPECT_NEAR(online->offset_s, 0.0, std::max(3.0 * online->sigma_s, 1e-3)) << online->Summary();
  }
  EXPECT_LE(std::llabs(run.front_end().imu_time_offset_ns()), 1'000'000);
  o.time_offset_every = 11;  // more than the window
  EXPECT_THROW(o.Check(), InvalidArgument);
}

// Without depth nothing corrects the velocity: an accelerometer bias error, constant, makes its
// error grow linearly with the time since the last fit with depth, and the stated sigma must
// grow so too (it grew as a random walk, sqrt(dt / t) of that: 6x too small after 2 s at 20 Hz).
// The simulated IMU has an accelerometer bias the still start cannot reveal; depth stops at 1.5 s.
TEST(FrontEnd, WithoutDepthTheVelocitySigmaGrowsLinearly) {
  static const SyntheticSequence seq = [] {
    SyntheticSequenceOptions so;
    so.motion = "walk";
    so.camera = PinholeCamera::KinectDefault().ScaledToWidth(320);
    so.frame_rate_hz = 20.0;
    so.imu_initial_bias.accel = Eigen::Vector3d(0.06, -0.05, 0.04);
    return MakeSyntheticSequence(so);
  }();
  const FrontEndOptions o = Options();
  Runner run(seq, o);
  const int64_t no_depth_from = SecondsToNs(1.5);
  int64_t last_fix = 0;
  double worst = 0.0;
  int checked = 0;
  for (size_t k = 0; k < seq.frames.size(); ++k) {
    const bool depth = seq.frames[k].t_ns < no_depth_from;
    cv::Mat none;
    const FrontEndResult r = depth ? run.Next(k) : run.Next(k, nullptr, &none);
    if (r.status != FrameStatus::kGuided) continue;
    if (r.pose_from_depth) {
      last_fix = r.t_ns;
      continue;
    }
    if (last_fix == 0) continue;
    const double since = NsToSeconds(r.t_ns - last_fix);
    // The hand-computed floor: the bias sigma integrated over the time since the last fix.
    EXPECT_GE(r.velocity_sigma, o.motion.accel_bias_sigma * since * 0.999) << "frame " << k;
    // And it covers the actual error (speed and vertical: the front end's yaw is its own).
    const Eigen::Vector3d truth = seq.frames[k].imu_velocity_in_world;
    const double e = std::max(std::fabs(r.velocity_in_world.norm() - truth.norm()),
                              std::fabs(r.velocity_in_world.z() - truth.z()));
    worst = std::max(worst, e / r.velocity_sigma);
    ++checked;
  }
  std::cout << "velocity error / sigma without depth, worst: " << worst << "\n";
  EXPECT_GE(checked, 25);
  EXPECT_LT(worst, 3.0);
}

// A log that does not start still (a turn from its first sample) with a gyro bias: the front end
// starts from a zero bias and learns it from the rotations its fits measure (GyroBiasFilter), so
// the IMU's predicted rotation comes to the truth; with learning off the bias stays in it (0.16 deg
// per frame here, as MH_05's 0.23 deg).
TEST(FrontEnd, WithoutAStillStartTheGyroBiasIsLearntFromTheFits) {
  static const SyntheticSequence seq = [] {
    SyntheticSequenceOptions so;
    so.motion = "left30";
    so.motion_options.still_before_s = 0.0;
    so.camera = PinholeCamera::KinectDefault().ScaledToWidth(320);
    so.frame_rate_hz = 20.0;
    so.imu_initial_bias.gyro = Eigen::Vector3d(0.02, -0.03, 0.04);
    return MakeSyntheticSequence(so);
  }();
  // The median over the last half of the guided frames of the IMU rotation's error (deg), and the
  // front end's bias at the end.
  const auto run = [&](bool learn, Eigen::Vector3d* bias, int* updates) {
    FrontEndOptions o = Options();
    o.learn_gyro_bias = learn;
    Runner runner(seq, o);
    std::vector<double> errors;
    std::string first_event;
    for (size_t k = 0; k < seq.frames.size(); ++k) {
      const FrontEndResult r = runner.Next(k);
      if (r.status == FrameStatus::kFirst && r.has_state) {
        first_event = r.event;
        // The state starts at the frame with the velocity unknown, not "at rest" at the log's
        // start and propagated.
        EXPECT_EQ(r.velocity_sigma, o.unknown_velocity_sigma);
        EXPECT_NE(r.event.find("velocity unknown"), std::string::npos) << r.event;
      }
      if (r.status != FrameStatus::kGuided || k == 0) continue;
      const Rigid3d truth =
          seq.frames[k].world_from_cam.Inverse() * seq.frames[k - 1].world_from_cam;
      errors.push_back(RotationDistance(r.imu_motion.cam_b_from_cam_a.rotation, truth.rotation) *
                       180.0 / M_PI);
    }
    EXPECT_NE(first_event.find("not still"), std::string::npos) << first_event;
    EXPECT_GE(errors.size(), 20u);
    *bias = runner.front_end().gyro_bias();
    const GyroBiasFilter* filter = runner.front_end().gyro_bias_filter();
    *updates = filter != nullptr ? filter->updates() : 0;
    std::vector<double> late(errors.begin() + static_cast<std::ptrdiff_t>(errors.size() / 2),
                             errors.end());
    std::nth_element(late.begin(), late.begin() + static_cast<std::ptrdiff_t>(late.size() / 2),
                     late.end());
    return late[late.size() / 2];
  };
  Eigen::Vector3d learnt, fixed;
  int updates = 0, no_updates = 0;
  const double error_learnt = run(true, &learnt, &updates);
  const double error_fixed = run(false, &fixed, &no_updates);
  std::cout << "learnt bias " << learnt.transpose() << " (" << updates
            << " updates); IMU rotation error, median of the last half: " << error_learnt
            << " deg learnt, " << error_fixed << " deg fixed\n";
  EXPECT_EQ(fixed, Eigen::Vector3d::Zero());
  EXPECT_EQ(no_updates, 0);
  EXPECT_GE(updates, 10);
  // The simulated bias (its random walk moves it by about 1e-4 rad/s over these 2.5 s).
  EXPECT_LT((learnt - seq.imu_initial_bias.gyro).cwiseAbs().maxCoeff(), 0.003)
      << learnt.transpose();
  EXPECT_GT(error_fixed, 0.1);
  EXPECT_LT(error_learnt, 0.2 * error_fixed);
}

TEST(FrontEnd, ImuGapAndBlackFrameAreReportedAndTheRunGoesOn) {
  const SyntheticSequence& seq = Walk();
  Runner run(seq, Options());
  const size_t gap_frame = 30, black_frame = 40;
  // 0.2 s without IMU before frame 30.
  run.DropImu(seq.frames[gap_frame].t_ns - SecondsToNs(0.2), seq.frames[gap_frame].t_ns - 1);
  const cv::Mat black = cv::Mat::zeros(seq.frames[0].rgb.size(), seq.frames[0].rgb.type());
  const int64_t gap_from = seq.frames[gap_frame].t_ns - SecondsToNs(0.2);
  for (size_t k = 0; k < seq.frames.size(); ++k) {
    const FrontEndResult r = run.Next(k, k == black_frame ? &black : nullptr);
    if (r.status == FrameStatus::kFirst) continue;
    // The intervals that overlap the gap, the black frame and the one after it (nothing to
    // match against) fall back to brute force with the reason; every other frame is guided.
    const bool over_gap = seq.frames[k].t_ns > gap_from && k <= gap_frame;
    if (over_gap) {
      EXPECT_EQ(r.status, FrameStatus::kBruteForce) << "frame " << k;
      EXPECT_NE(r.event.find("IMU gap"), std::string::npos) << r.event;
    } else if (k == black_frame || k == black_frame + 1) {
      EXPECT_EQ(r.status, FrameStatus::kBruteForce) << "frame " << k;
      EXPECT_NE(r.event.find("too few features"), std::string::npos) << r.event;
      EXPECT_TRUE(r.matches.empty());
    } else {
      EXPECT_EQ(r.status, FrameStatus::kGuided) << "frame " << k << ": " << r.event;
    }
    EXPECT_TRUE(r.world_from_cam.translation.allFinite());
  }
}

TEST(FrontEnd, AnImuGapInTheStillStartShortensItAndTheRunGoesOn) {
  const SyntheticSequence& seq = Walk();
  Runner run(seq, Options());
  run.DropImu(SecondsToNs(0.2), SecondsToNs(0.3));  // 0.1 s without IMU while still
  bool initialised = false;
  int guided = 0, later = 0;
  for (size_t k = 0; k < 30; ++k) {
    const FrontEndResult r = run.Next(k);
    if (!initialised && r.status == FrameStatus::kFirst &&
        r.event.find("waiting") == std::string::npos) {
      // The gyro bias from the still start up to the gap (0.2 s, 40 samples), not refused.
      EXPECT_NE(r.event.find("gyro bias from the still start"), std::string::npos) << r.event;
      EXPECT_NE(r.event.find("ends at an IMU gap"), std::string::npos) << r.event;
      initialised = true;
      continue;
    }
    if (!initialised) continue;
    ++later;
    if (r.status == FrameStatus::kGuided) ++guided;
  }
  EXPECT_TRUE(initialised);
  EXPECT_GT(later, 20);
  EXPECT_EQ(guided, later);
}

TEST(FrontEnd, BadFramesAreRefused) {
  const SyntheticSequence& seq = Walk();
  FrontEnd fe(seq.camera, seq.imu_params, seq.cam_from_imu, Options());
  FrontEndFrame empty;
  EXPECT_THROW(fe.Process(empty), InvalidArgument);
  FrontEndFrame wrong;
  wrong.image = cv::Mat::zeros(10, 10, CV_8UC1);
  EXPECT_THROW(fe.Process(wrong), InvalidArgument);
  FrontEndOptions bad = Options();
  bad.min_matches = -1;
  EXPECT_THROW(FrontEnd(seq.camera, seq.imu_params, seq.cam_from_imu, bad), InvalidArgument);
}

}  // namespace
}  // namespace imumatch
