#include "imumatch/imu/time_offset.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>

#include <Eigen/Cholesky>
#include <Eigen/LU>

#include "imumatch/core/error.h"
#include "imumatch/core/so3.h"
#include "imumatch/core/time.h"

namespace imumatch {

void TimeOffsetOptions::Check() const {
  IMUMATCH_CHECK(std::isfinite(max_offset_s) && max_offset_s > 0.0 && max_offset_s <= 1.0,
                 "TimeOffsetOptions.max_offset_s must be in (0, 1] s, got " << max_offset_s);
  IMUMATCH_CHECK(std::isfinite(step_s) && step_s > 0.0 && step_s * 4.0 <= max_offset_s,
                 "TimeOffsetOptions.step_s must be in (0, max_offset_s / 4], got " << step_s);
  // Every grid point integrates the gyro over every observation: bounded work.
  IMUMATCH_CHECK(max_offset_s / step_s <= kMaxTimeOffsetSteps,
                 "TimeOffsetOptions: max_offset_s / step_s must be at most "
                     << kMaxTimeOffsetSteps << " grid steps each side, got "
                     << max_offset_s / step_s);
  IMUMATCH_CHECK(std::isfinite(gate_chi2) && gate_chi2 > 0.0,
                 "TimeOffsetOptions.gate_chi2 must be > 0, got " << gate_chi2);
  IMUMATCH_CHECK(std::isfinite(scale_sigma) && scale_sigma >= 0.0,
                 "TimeOffsetOptions.scale_sigma must be >= 0, got " << scale_sigma);
  IMUMATCH_CHECK(min_observations >= 4,
                 "TimeOffsetOptions.min_observations must be >= 4 (the offset and a 3-axis bias "
                 "correction are solved), got "
                     << min_observations);
  IMUMATCH_CHECK(std::isfinite(max_sigma_s) && max_sigma_s > 0.0,
                 "TimeOffsetOptions.max_sigma_s must be > 0, got " << max_sigma_s);
  IMUMATCH_CHECK(std::isfinite(ambiguity_chi2) && ambiguity_chi2 >= 0.0,
                 "TimeOffsetOptions.ambiguity_chi2 must be >= 0, got " << ambiguity_chi2);
  IMUMATCH_CHECK(jackknife_blocks == 0 || (jackknife_blocks >= 2 && jackknife_blocks <= 1000),
                 "TimeOffsetOptions.jackknife_blocks must be 0 (off) or in [2, 1000], got "
                     << jackknife_blocks);
}

namespace {

// Milliseconds to one decimal with their sign, "+0.0" for what rounds to zero (not "-0.0").
double TenthsOfMs(double seconds) {
  const double tenths = std::round(seconds * 1e4);
  return tenths == 0.0 ? 0.0 : tenths / 10.0;
}

// A sigma in milliseconds: one decimal, "< 0.1" below what one decimal shows.
std::string SigmaMs(double seconds) {
  std::ostringstream out;
  if (seconds < 0.5e-4) {
    out << "< 0.1";
  } else {
    out << std::fixed << std::setprecision(1) << seconds * 1e3;
  }
  return out.str();
}

// Seconds to the 0.1 ms the estimate resolves, without a sign for zero: "0.0102", "-0.004".
std::string ShiftSeconds(double seconds) {
  double rounded = std::round(seconds * 1e4) / 1e4;
  if (rounded == 0.0) rounded = 0.0;  // not "-0"
  std::ostringstream out;
  out << std::fixed << std::setprecision(4) << rounded;
  std::string s = out.str();
  while (s.back() == '0') s.pop_back();
  if (s.back() == '.') s.push_back('0');
  return s;
}

}  // namespace

std::string FormatOffsetMs(double seconds) {
  std::ostringstream out;
  out << std::fixed << std::setprecision(1) << std::showpos << TenthsOfMs(seconds) << " ms";
  return out.str();
}

std::string TimeOffsetEstimate::Summary() const {
  if (!measured) return "not measured (" + reason + ")";
  std::ostringstream out;
  out << FormatOffsetMs(offset_s) << " (+- " << SigmaMs(sigma_s) << " ms, " << inliers << " of "
      << observations << " fitted rotations)";
  return out.str();
}

std::string TimeOffsetAdvice(const TimeOffsetEstimate& estimate, double applied_shift_s,
                             const TimeOffsetAdviceOptions& options) {
  if (!estimate.measured || std::fabs(estimate.offset_s) < options.min_offset_s ||
      std::fabs(estimate.offset_s) <= options.min_sigmas * estimate.sigma_s) {
    return {};
  }
  const std::string total = ShiftSeconds(applied_shift_s + estimate.offset_s);
  std::ostringstream out;
  out << "the camera's and the IMU's clocks look " << FormatOffsetMs(estimate.offset_s)
      << " apart (+- " << SigmaMs(estimate.sigma_s) << " ms) beyond the timeshift_cam_imu applied ("
      << ShiftSeconds(applied_shift_s)
      << " s): the IMU's rotation between frames is read that far off, which the search windows "
         "absorb at the cost of their size; set timeshift_cam_imu to "
      << total
      << " s (the key timeshift_cam_imu in cam0/sensor.yaml or Kalibr's camchain.yaml, or "
         "--timeshift-cam-imu "
      << total << ")";
  return out.str();
}

namespace {

// The gyro's rotation imu_a_from_imu_b over the samples (midpoint rule, as Preintegrate).
Eigen::Quaterniond GyroRotation(const std::vector<ImuSample>& samples,
                                const Eigen::Vector3d& bias) {
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
  for (size_t k = 0; k + 1 < samples.size(); ++k) {
    const double dt = NsToSeconds(samples[k + 1].t_ns - samples[k].t_ns);
    const Eigen::Vector3d w = 0.5 * (samples[k].gyro_rad_s + samples[k + 1].gyro_rad_s) - bias;
    q = (q * ExpSO3(w * dt)).normalized();
  }
  return q;
}

struct Usable {
  const RotationObservation* obs;
  double dt;
  Eigen::Matrix3d weight;  // inverse of the measurement's and the gyro's noise
};

struct GridCost {
  double cost = std::numeric_limits<double>::infinity();
  int inliers = 0;
  double median = 0.0;  // of the observations' normalised squared residuals
  Eigen::Vector3d db = Eigen::Vector3d::Zero();
};

// The gyro's rotation against each observation at one offset: r_i = Log(dR_gyro^T dR_i).
std::vector<Eigen::Vector3d> ResidualsAt(const ImuBuffer& imu, const Eigen::Vector3d& bias,
                                         const std::vector<Usable>& usable, int64_t offset_ns) {
  std::vector<Eigen::Vector3d> r(usable.size());
  for (size_t i = 0; i < usable.size(); ++i) {
    const RotationObservation& o = *usable[i].obs;
    const Eigen::Quaterniond gyro =
        GyroRotation(imu.Slice(o.t_a_ns + offset_ns, o.t_b_ns + offset_ns), bias);
    r[i] = LogSO3(gyro.conjugate() * o.imu_a_from_imu_b);
  }
  return r;
}

// The truncated cost of one offset's residuals, each normalised by its covariance times scale2,
// with the bias correction solved on the inliers; of the observations whose keep is 1.
GridCost CostOf(const std::vector<Eigen::Vector3d>& r, const std::vector<Usable>& usable,
                double scale2, double gate, const std::vector<char>& keep) {
  const size_t n = usable.size();
  // A bias error db turns the gyro's rotation by about -dt db: r_i + dt_i db is what is left.
  GridCost out;
  std::vector<char> inlier(keep);
  std::vector<double> c;
  c.reserve(n);
  for (int iteration = 0; iteration < 4; ++iteration) {
    Eigen::Matrix3d h = Eigen::Matrix3d::Zero();
    Eigen::Vector3d g = Eigen::Vector3d::Zero();
    for (size_t i = 0; i < n; ++i) {
      if (!inlier[i]) continue;
      h += usable[i].dt * usable[i].dt * usable[i].weight;
      g += usable[i].dt * usable[i].weight * r[i];
    }
    const Eigen::FullPivLU<Eigen::Matrix3d> lu(h);
    GridCost next;
    next.db = lu.isInvertible() ? Eigen::Vector3d(-lu.solve(g)) : out.db;
    next.cost = 0.0;
    c.clear();
    for (size_t i = 0; i < n; ++i) {
      if (!keep[i]) continue;
      const Eigen::Vector3d e = r[i] + usable[i].dt * next.db;
      const double ci = e.dot(usable[i].weight * e) / scale2;
      c.push_back(ci);
      inlier[i] = ci <= gate;
      next.inliers += inlier[i];
      next.cost += std::min(ci, gate);
    }
    const auto mid = c.begin() + static_cast<std::ptrdiff_t>(c.size() / 2);
    std::nth_element(c.begin(), mid, c.end());
    next.median = *mid;
    if (iteration > 0 && !(next.cost < out.cost)) break;
    out = next;
  }
  return out;
}

// The grid's costs for the observations kept, their lowest point, and how far the cost rises
// above it over the grid.
struct GridCosts {
  std::vector<GridCost> cost;
  size_t best = 0;
  double range = 0.0;
};
GridCosts CostsOverGrid(const std::vector<std::vector<Eigen::Vector3d>>& residuals,
                        const std::vector<Usable>& usable, double scale2, double gate,
                        const std::vector<char>& keep) {
  GridCosts out;
  out.cost.resize(residuals.size());
  out.best = residuals.size() / 2;  // offset 0 wins ties
  for (size_t k = 0; k < residuals.size(); ++k) {
    out.cost[k] = CostOf(residuals[k], usable, scale2, gate, keep);
    if (out.cost[k].cost < out.cost[out.best].cost) out.best = k;
  }
  double highest = out.cost[out.best].cost;
  for (const GridCost& c : out.cost) highest = std::max(highest, c.cost);
  out.range = highest - out.cost[out.best].cost;
  return out;
}

// The minimum's offset from the grid's lowest point by the parabola through it and its
// neighbours (in steps), and the cost's second derivative (per step^2); false at the grid's edge
// or where the cost is not convex there.
bool ParabolaAtMinimum(const GridCosts& g, double* shift_steps, double* second) {
  if (g.best == 0 || g.best + 1 == g.cost.size()) return false;
  const double cm = g.cost[g.best - 1].cost, c0 = g.cost[g.best].cost, cp = g.cost[g.best + 1].cost;
  *second = cm + cp - 2.0 * c0;
  if (!(*second > 0.0)) return false;
  *shift_steps = 0.5 * (cm - cp) / *second;
  return true;
}

}  // namespace

std::string RotationObservationProblem(const RotationObservation& o) {
  if (!(o.t_b_ns > o.t_a_ns)) {
    return "t_b " + std::to_string(o.t_b_ns) + " ns is not after t_a " + std::to_string(o.t_a_ns) +
           " ns";
  }
  if (!o.covariance.allFinite() || !o.covariance.isApprox(o.covariance.transpose(), 1e-9)) {
    return "covariance not finite and symmetric";
  }
  if (!std::isfinite(o.imu_a_from_imu_b.norm()) ||
      !(std::fabs(o.imu_a_from_imu_b.norm() - 1.0) < 1e-6)) {
    return "not a unit quaternion";
  }
  if (Eigen::LLT<Eigen::Matrix3d>(o.covariance).info() != Eigen::Success) {
    return "covariance not positive definite";
  }
  return {};
}

TimeOffsetEstimate EstimateTimeOffset(const ImuBuffer& imu, const ImuParams& params,
                                      const Eigen::Vector3d& gyro_bias,
                                      const std::vector<RotationObservation>& observations,
                                      const TimeOffsetOptions& options) {
  options.Check();
  IMUMATCH_CHECK(gyro_bias.allFinite(), "EstimateTimeOffset: the gyro bias is not finite");
  const int64_t max_ns = SecondsToNs(options.max_offset_s);
  const int64_t step_ns = std::max<int64_t>(1, SecondsToNs(options.step_s));
  std::vector<Usable> usable;
  for (size_t i = 0; i < observations.size(); ++i) {
    const RotationObservation& o = observations[i];
    const std::string problem = RotationObservationProblem(o);
    IMUMATCH_REQUIRE(problem.empty(), "rotation observation " << i << ": " << problem);
    std::vector<ImuSample> samples;
    try {
      // Covered, without a gap, at every offset of the grid.
      samples = imu.Slice(o.t_a_ns - max_ns, o.t_b_ns + max_ns);
    } catch (const Error&) {
      continue;
    }
    const double dt = NsToSeconds(o.t_b_ns - o.t_a_ns);
    const double angle = LogSO3(o.imu_a_from_imu_b).norm();
    const double scale = options.scale_sigma * angle;
    const Eigen::Matrix3d noise =
        o.covariance +
        Eigen::Matrix3d::Identity() *
            (params.gyro_noise_density * params.gyro_noise_density * dt + scale * scale);
    usable.push_back({&o, dt, noise.inverse()});
  }
  TimeOffsetEstimate est;
  est.observations = static_cast<int>(usable.size());
  if (est.observations < options.min_observations) {
    est.reason = std::to_string(est.observations) + " fitted rotations inside the IMU log, " +
                 std::to_string(options.min_observations) + " needed";
    return est;
  }
  const int steps = static_cast<int>(max_ns / step_ns);
  std::vector<std::vector<Eigen::Vector3d>> residuals;
  for (int k = -steps; k <= steps; ++k) {
    residuals.push_back(ResidualsAt(imu, gyro_bias, usable, k * step_ns));
  }
  // Real fits state their covariance optimistically: a first search finds the offset with the
  // stated covariances, the observations' scatter there (the median normalised squared residual
  // against a chi-square's with 3 dof, 2.366: robust to the fits that locked onto something else)
  // scales them, and the search runs again. The sigma then reflects the scatter.
  const std::vector<char> all(usable.size(), 1);
  GridCosts grid;
  double scale2 = 1.0;
  for (int round = 0; round < 2; ++round) {
    grid = CostsOverGrid(residuals, usable, scale2, options.gate_chi2, all);
    scale2 *= std::max(1.0, grid.cost[grid.best].median / 2.366);
  }
  const int best = static_cast<int>(grid.best);
  est.cost_at_zero = grid.cost[static_cast<size_t>(steps)].cost;
  const GridCost& at = grid.cost[grid.best];
  est.cost = at.cost;
  est.inliers = at.inliers;
  est.gyro_bias_correction = at.db;
  const double h = NsToSeconds(step_ns);
  // The offset of grid point k, or of a point between grid points.
  auto offset_at = [&](double k) { return (k - steps) * h; };
  est.offset_s = offset_at(best);
  const std::string searched =
      "+-" + std::to_string(static_cast<int>(std::lround(options.max_offset_s * 1e3))) +
      " ms searched";
  // The cost is a chi-square: an offset is told apart from another when the cost differs by 1 (one
  // sigma of one parameter). A cost that stays within 1 over the whole grid shows none, wherever
  // its minimum falls (on exact data the rounding decides it).
  if (!(grid.range >= 1.0)) {
    est.reason =
        "the fitted rotations do not vary enough to show an offset (the cost changes by "
        "less than 1 over the " +
        searched + ")";
    return est;
  }
  if (best == 0 || best == 2 * steps) {
    est.reason = "the cost falls towards the edge of the " + searched;
    return est;
  }
  double shift = 0.0, second = 0.0;
  if (!ParabolaAtMinimum(grid, &shift, &second)) {
    est.reason = "the fitted rotations do not vary enough to show an offset";
    return est;
  }
  est.offset_s += shift * h;
  // The cost is a chi-square: it rises by 1 at one sigma of one parameter.
  est.sigma_s = std::sqrt(2.0 / second) * h;
  // A second minimum nearly as low as the lowest, away from it (beyond 3 sigmas and a grid step;
  // the grid's ends count when the cost falls towards them): a periodic motion (a vibration, a
  // gait) repeats its rotations at a shift of its period, and the lowest point is then one of
  // several that the fits cannot tell apart.
  for (size_t k = 0; k < grid.cost.size(); ++k) {
    const double c = grid.cost[k].cost;
    const bool local_minimum = (k == 0 || c <= grid.cost[k - 1].cost) &&
                               (k + 1 == grid.cost.size() || c <= grid.cost[k + 1].cost);
    const double at_s = offset_at(static_cast<double>(k));
    if (!local_minimum || std::fabs(at_s - est.offset_s) <= 3.0 * est.sigma_s + h) continue;
    if (c - at.cost < options.ambiguity_chi2) {
      std::ostringstream why;
      why << std::fixed << std::setprecision(1) << "ambiguous: a second minimum of the cost at "
          << FormatOffsetMs(at_s) << ", within " << c - at.cost << " of the lowest's at "
          << FormatOffsetMs(est.offset_s)
          << " (a periodic motion repeats its rotations at a shift of its period)";
      est.reason = why.str();
      return est;
    }
  }
  // That sigma takes the observations as independent, and consecutive pairs' fits are not (they
  // share a frame, and a scene's errors last over many frames). The block jackknife does not
  // assume it: the estimate again without each of jackknife_blocks runs of consecutive
  // observations, whose spread (times (B - 1) / B) is the estimate's variance. The larger of the
  // two sigmas stands.
  const size_t n = usable.size();
  const size_t blocks = std::min<size_t>(static_cast<size_t>(options.jackknife_blocks), n / 2);
  if (blocks >= 2) {
    std::vector<double> leave_out;
    for (size_t b = 0; b < blocks; ++b) {
      std::vector<char> keep(all);
      for (size_t i = b * n / blocks; i < (b + 1) * n / blocks; ++i) keep[i] = 0;
      const GridCosts g = CostsOverGrid(residuals, usable, scale2, options.gate_chi2, keep);
      double s_b = 0.0, second_b = 0.0;
      // As for all of them: a cost that changes by less than 1 shows no offset.
      if (!(g.range >= 1.0) || !ParabolaAtMinimum(g, &s_b, &second_b)) {
        est.reason = "the offset is not shown without one of the " + std::to_string(blocks) +
                     " runs of consecutive fitted rotations (the cost is flat, or its minimum at "
                     "the edge of the " +
                     searched + ")";
        return est;
      }
      leave_out.push_back(offset_at(static_cast<double>(g.best) + s_b));
    }
    double mean = 0.0;
    for (const double o : leave_out) mean += o / static_cast<double>(blocks);
    double spread = 0.0;
    for (const double o : leave_out) spread += (o - mean) * (o - mean);
    est.jackknife_sigma_s =
        std::sqrt(spread * static_cast<double>(blocks - 1) / static_cast<double>(blocks));
    est.sigma_s = std::max(est.sigma_s, est.jackknife_sigma_s);
  }
  if (est.sigma_s > options.max_sigma_s) {
    std::ostringstream why;
    why << std::fixed << std::setprecision(1) << "sigma "
        << (est.sigma_s > options.max_offset_s ? "beyond the +-" : "")
        << std::min(est.sigma_s, options.max_offset_s) * 1e3
        << " ms: the fitted rotations do not vary enough to show an offset";
    est.reason = why.str();
    return est;
  }
  est.measured = true;
  return est;
}

TimeOffsetEstimate TryEstimateTimeOffset(const ImuBuffer& imu, const ImuParams& params,
                                         const Eigen::Vector3d& gyro_bias,
                                         const std::vector<RotationObservation>& observations,
                                         const TimeOffsetOptions& options) {
  try {
    return EstimateTimeOffset(imu, params, gyro_bias, observations, options);
  } catch (const Error& e) {
    TimeOffsetEstimate est;
    est.reason = e.what();
    return est;
  }
}

}  // namespace imumatch
