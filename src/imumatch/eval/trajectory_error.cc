#include "imumatch/eval/trajectory_error.h"

#include <cmath>

#include "imumatch/core/error.h"

namespace imumatch {

RelativePoseError ComputeRelativePoseError(const std::vector<std::optional<Rigid3d>>& estimated,
                                           const std::vector<std::optional<Rigid3d>>& truth,
                                           size_t delta) {
  IMUMATCH_CHECK(estimated.size() == truth.size(),
                 estimated.size() << " estimated poses for " << truth.size() << " true ones");
  IMUMATCH_CHECK(delta >= 1, "delta must be at least 1");
  RelativePoseError out;
  double sum_t2 = 0.0, sum_t = 0.0, sum_r2 = 0.0, sum_r = 0.0;
  for (size_t i = 0; i + delta < estimated.size(); ++i) {
    const size_t j = i + delta;
    if (!estimated[i] || !estimated[j] || !truth[i] || !truth[j]) continue;
    const Rigid3d q = truth[i]->Inverse() * *truth[j];
    const Rigid3d p = estimated[i]->Inverse() * *estimated[j];
    const Rigid3d e = q.Inverse() * p;
    const double t = e.translation.norm();
    const double r = RotationDistance(e.rotation, Eigen::Quaterniond::Identity()) * 180.0 / M_PI;
    out.translation_m.push_back(t);
    out.rotation_deg.push_back(r);
    sum_t2 += t * t;
    sum_t += t;
    sum_r2 += r * r;
    sum_r += r;
  }
  const double n = static_cast<double>(out.pairs());
  if (n > 0) {
    out.rmse_translation_m = std::sqrt(sum_t2 / n);
    out.mean_translation_m = sum_t / n;
    out.rmse_rotation_deg = std::sqrt(sum_r2 / n);
    out.mean_rotation_deg = sum_r / n;
  }
  return out;
}

}  // namespace imumatch
