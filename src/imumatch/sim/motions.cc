#include "imumatch/sim/motions.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <sstream>

#include "imumatch/core/error.h"
#include "imumatch/core/so3.h"

namespace imumatch {
namespace {

// Integral of the minimum-jerk step from 0 to tau (tau in [0, 1]).
double MinimumJerkIntegral(double tau) {
  if (tau <= 0.0) return 0.0;
  if (tau >= 1.0) return 0.5 + (tau - 1.0);
  const double t4 = tau * tau * tau * tau;
  return 2.5 * t4 - 3.0 * t4 * tau + t4 * tau * tau;
}

// A scalar function of time with analytic first and second derivatives.
struct Profile {
  enum class Kind { kStep, kRamp, kSine };
  Kind kind = Kind::kStep;
  double amplitude = 0.0;  // step height, ramp rate (per second) or sine amplitude
  double t0 = 0.0;         // step/ramp start; sine fade-in start
  double ramp = 1.0;       // step/ramp duration; sine fade duration
  double t1 = 0.0;         // sine: end of the fade-out
  double freq_hz = 0.0;
  double phase = 0.0;

  static Profile Step(double t0, double duration, double height) {
    Profile p;
    p.kind = Kind::kStep;
    p.t0 = t0;
    p.ramp = duration;
    p.amplitude = height;
    return p;
  }
  // The rate rises from 0 to `rate` along a minimum-jerk step starting at t0 (and stays there).
  static Profile Ramp(double t0, double duration, double rate) {
    Profile p = Step(t0, duration, rate);
    p.kind = Kind::kRamp;
    return p;
  }
  // amplitude * e(t) * sin(2 pi f (t - t0) + phase), e fading in over [t0, t0+fade] and out over
  // [t1-fade, t1] with minimum-jerk steps.
  static Profile Sine(double t0, double t1, double fade, double amplitude, double freq_hz,
                      double phase) {
    Profile p;
    p.kind = Kind::kSine;
    p.t0 = t0;
    p.t1 = t1;
    p.ramp = fade;
    p.amplitude = amplitude;
    p.freq_hz = freq_hz;
    p.phase = phase;
    return p;
  }

  // Value and derivatives {f, f', f''} at t.
  Eigen::Vector3d Eval(double t) const {
    const double tau = (t - t0) / ramp;
    switch (kind) {
      case Kind::kStep:
        return amplitude * Eigen::Vector3d(MinimumJerk(tau, 0), MinimumJerk(tau, 1) / ramp,
                                           MinimumJerk(tau, 2) / (ramp * ramp));
      case Kind::kRamp:
        return amplitude * Eigen::Vector3d(ramp * MinimumJerkIntegral(tau), MinimumJerk(tau, 0),
                                           MinimumJerk(tau, 1) / ramp);
      case Kind::kSine: {
        const double tau_out = (t - (t1 - ramp)) / ramp;
        const double e = MinimumJerk(tau, 0) - MinimumJerk(tau_out, 0);
        const double de = (MinimumJerk(tau, 1) - MinimumJerk(tau_out, 1)) / ramp;
        const double dde = (MinimumJerk(tau, 2) - MinimumJerk(tau_out, 2)) / (ramp * ramp);
        const double w = 2.0 * kPi * freq_hz;
        const double arg = w * (t - t0) + phase;
        const double g = std::sin(arg), dg = w * std::cos(arg), ddg = -w * w * g;
        return amplitude *
               Eigen::Vector3d(e * g, de * g + e * dg, dde * g + 2.0 * de * dg + e * ddg);
      }
    }
    return Eigen::Vector3d::Zero();
  }
};

Eigen::Vector3d EvalSum(const std::vector<Profile>& profiles, double t) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (const Profile& p : profiles) sum += p.Eval(t);
  return sum;
}

// p(t) = p0 + R0 q(t) (q: offset in the start body frame);
// R(t) = Rz(yaw(t)) * R0 * Exp(r(t)) (yaw about the world vertical, r a body rotation vector).
class ComposedTrajectory : public Trajectory {
 public:
  ComposedTrajectory(const Rigid3d& start, double end_time) : start_(start), end_time_(end_time) {}

  std::array<std::vector<Profile>, 3> offset;  // metres, in the start body frame
  std::vector<Profile> yaw;                    // radians, about world z
  std::array<std::vector<Profile>, 3> rotvec;  // radians, body rotation vector

  Rigid3d WorldFromBody(double t) const override {
    const Eigen::Quaterniond rz(Eigen::AngleAxisd(EvalSum(yaw, t)[0], Eigen::Vector3d::UnitZ()));
    return Rigid3d(rz * start_.rotation * ExpSO3(Column(rotvec, t, 0)),
                   start_.translation + start_.rotation * Column(offset, t, 0));
  }
  Eigen::Vector3d VelocityInWorld(double t) const override {
    return start_.rotation * Column(offset, t, 1);
  }
  Eigen::Vector3d AccelerationInWorld(double t) const override {
    return start_.rotation * Column(offset, t, 2);
  }
  Eigen::Vector3d AngularVelocityInBody(double t) const override {
    const Eigen::Vector3d r = Column(rotvec, t, 0);
    const Eigen::Vector3d dr = Column(rotvec, t, 1);
    const double dyaw = EvalSum(yaw, t)[1];
    return ExpSO3(r).conjugate() *
               (start_.rotation.conjugate() * (dyaw * Eigen::Vector3d::UnitZ())) +
           RightJacobianSO3(r) * dr;
  }
  double EndTime() const override { return end_time_; }

 private:
  static Eigen::Vector3d Column(const std::array<std::vector<Profile>, 3>& p, double t, int d) {
    return Eigen::Vector3d(EvalSum(p[0], t)[d], EvalSum(p[1], t)[d], EvalSum(p[2], t)[d]);
  }
  Rigid3d start_;
  double end_time_;
};

bool Finite(const Rigid3d& pose) {
  return pose.rotation.coeffs().allFinite() && pose.translation.allFinite();
}

}  // namespace

double MinimumJerk(double tau, int derivative) {
  if (tau <= 0.0) return 0.0;
  if (tau >= 1.0) return derivative == 0 ? 1.0 : 0.0;
  const double t2 = tau * tau;
  switch (derivative) {
    case 0:
      return t2 * tau * (10.0 - 15.0 * tau + 6.0 * t2);
    case 1:
      return 30.0 * t2 * (1.0 - 2.0 * tau + t2);
    case 2:
      return 60.0 * tau * (1.0 - 3.0 * tau + 2.0 * t2);
    default:
      throw InvalidArgument("MinimumJerk: derivative must be 0, 1 or 2");
  }
}

Rigid3d SyntheticCamFromImu() {
  Eigen::Matrix3d cam_r_imu;
  // Columns: images of the IMU axes in the camera frame.
  cam_r_imu << 0, -1, 0,  //
      0, 0, -1,           //
      1, 0, 0;
  return Rigid3d(cam_r_imu, Eigen::Vector3d(0.02, 0.005, -0.01));
}

Rigid3d SyntheticStartWorldFromBody() {
  return Rigid3d(Eigen::Quaterniond::Identity(), Eigen::Vector3d(-1.0, 0.0, 1.4));
}

void MotionOptions::Check() const {
  IMUMATCH_CHECK(std::isfinite(duration_s) && duration_s > 0.0,
                 "MotionOptions.duration_s must be > 0, got " << duration_s);
  IMUMATCH_CHECK(std::isfinite(still_before_s) && still_before_s >= 0.0,
                 "MotionOptions.still_before_s must be >= 0, got " << still_before_s);
  IMUMATCH_CHECK(std::isfinite(still_after_s) && still_after_s >= 0.0,
                 "MotionOptions.still_after_s must be >= 0, got " << still_after_s);
  IMUMATCH_CHECK(std::isfinite(distance_m), "MotionOptions.distance_m must be finite");
  IMUMATCH_CHECK(std::isfinite(angle_deg), "MotionOptions.angle_deg must be finite");
  IMUMATCH_CHECK(std::isfinite(shake_scale) && shake_scale >= 0.0,
                 "MotionOptions.shake_scale must be >= 0, got " << shake_scale);
  IMUMATCH_CHECK(std::isfinite(yaw_rate_deg_s), "MotionOptions.yaw_rate_deg_s must be finite");
  IMUMATCH_CHECK(std::isfinite(roll_rate_deg_s), "MotionOptions.roll_rate_deg_s must be finite");
  IMUMATCH_CHECK(std::isfinite(roll_amplitude_deg),
                 "MotionOptions.roll_amplitude_deg must be finite");
  IMUMATCH_CHECK(std::isfinite(walk_speed_m_s), "MotionOptions.walk_speed_m_s must be finite");
  IMUMATCH_CHECK(Finite(world_from_body_start),
                 "MotionOptions.world_from_body_start must be finite");
}

std::vector<std::string> MotionNames() {
  return {"front1m", "back1m", "left30", "right30", "shake", "fast_rotation", "walk", "roll45"};
}

std::unique_ptr<Trajectory> MakeMotion(std::string_view name, const MotionOptions& options) {
  options.Check();
  const double t0 = options.MotionStartTime();
  const double t1 = options.MotionEndTime();
  const double duration = options.duration_s;
  auto traj = std::make_unique<ComposedTrajectory>(options.world_from_body_start,
                                                   t1 + options.still_after_s);
  using P = Profile;
  if (name == "front1m" || name == "back1m") {
    const double sign = name == "front1m" ? 1.0 : -1.0;
    traj->offset[0].push_back(P::Step(t0, duration, sign * options.distance_m));
  } else if (name == "left30" || name == "right30") {
    const double sign = name == "left30" ? 1.0 : -1.0;
    traj->yaw.push_back(P::Step(t0, duration, sign * options.angle_deg * kDegToRad));
  } else if (name == "shake") {
    const double fade = std::min(0.4, 0.5 * duration);
    const double s = options.shake_scale;
    auto sine = [&](double amplitude, double f, double phase) {
      return P::Sine(t0, t1, fade, s * amplitude, f, phase);
    };
    traj->offset[0] = {sine(0.015, 1.1, 0.3), sine(0.008, 2.7, 1.0)};
    traj->offset[1] = {sine(0.025, 0.7, 2.1), sine(0.010, 1.9, 0.4)};
    traj->offset[2] = {sine(0.015, 1.3, 4.0), sine(0.006, 3.1, 2.5)};
    traj->rotvec[0] = {sine(2.0 * kDegToRad, 0.9, 0.7), sine(1.0 * kDegToRad, 2.3, 5.0)};
    traj->rotvec[1] = {sine(3.0 * kDegToRad, 1.2, 1.6), sine(1.0 * kDegToRad, 2.9, 0.2)};
    traj->rotvec[2] = {sine(3.0 * kDegToRad, 0.6, 3.3), sine(1.5 * kDegToRad, 1.7, 1.2)};
  } else if (name == "fast_rotation") {
    const double ramp = std::min(0.4, 0.5 * duration);
    const double rate = options.yaw_rate_deg_s * kDegToRad;
    traj->yaw = {P::Ramp(t0, ramp, rate), P::Ramp(t1 - ramp, ramp, -rate)};
    traj->rotvec[0] = {P::Sine(t0, t1, ramp, options.roll_amplitude_deg * kDegToRad, 1.5, 0.0)};
    traj->rotvec[1] = {P::Sine(t0, t1, ramp, 3.0 * kDegToRad, 0.8, 1.0)};
    traj->offset[1] = {P::Sine(t0, t1, ramp, 0.01, 0.9, 0.5)};
  } else if (name == "roll45") {
    // About the body x axis, which is the camera's optical axis: an in-plane image rotation.
    const double ramp = std::min(0.2, 0.5 * duration);
    const double rate = options.roll_rate_deg_s * kDegToRad;
    traj->rotvec[0] = {P::Ramp(t0, ramp, rate), P::Ramp(t1 - ramp, ramp, -rate)};
  } else if (name == "walk") {
    const double ramp = std::min(0.6, 0.5 * duration);
    const double fade = std::min(0.4, 0.5 * duration);
    const double v = options.walk_speed_m_s;
    traj->offset[0] = {P::Ramp(t0, ramp, v), P::Ramp(t1 - ramp, ramp, -v)};
    traj->offset[1] = {P::Sine(t0, t1, fade, 0.02, 1.0, 0.0)};
    traj->offset[2] = {P::Sine(t0, t1, fade, 0.02, 2.0, 0.0)};
    traj->rotvec[0] = {P::Sine(t0, t1, fade, 1.5 * kDegToRad, 1.0, 0.5)};
    traj->rotvec[1] = {P::Sine(t0, t1, fade, 2.0 * kDegToRad, 2.0, 0.3)};
    traj->rotvec[2] = {P::Sine(t0, t1, fade, 4.0 * kDegToRad, 0.5, 0.0)};
  } else {
    std::ostringstream names;
    for (const std::string& n : MotionNames()) names << " " << n;
    throw InvalidArgument("unknown motion '" + std::string(name) + "'; valid names:" + names.str());
  }
  return traj;
}

}  // namespace imumatch
