#include "imumatch/camera/pixel_undistorter.h"

#include <algorithm>
#include <cmath>

#include <Eigen/LU>

#include "imumatch/core/error.h"
#include "imumatch/core/so3.h"

namespace imumatch {

PixelUndistorter::PixelUndistorter(const PinholeCamera& camera, double cell_px) : camera_(camera) {
  camera.Check();
  IMUMATCH_CHECK(std::isfinite(cell_px) && cell_px >= 1.0, "cell_px=" << cell_px);
  identity_ = !camera.HasDistortion();
  min_x_ = min_y_ = -0.5;
  max_x_ = camera.width - 0.5;
  max_y_ = camera.height - 0.5;
  if (identity_) return;
  cell_ = cell_px;
  inv_cell_ = 1.0 / cell_px;
  cols_ = static_cast<int>(std::ceil(camera.width / cell_px)) + 1;
  rows_ = static_cast<int>(std::ceil(camera.height / cell_px)) + 1;
  table_.resize(static_cast<size_t>(cols_) * rows_);
  for (int r = 0; r < rows_; ++r) {
    for (int c = 0; c < cols_; ++c) {
      table_[static_cast<size_t>(r) * cols_ + c] =
          camera.PixelToNormalized(Eigen::Vector2d(origin_ + c * cell_, origin_ + r * cell_));
    }
  }
  if (camera.model == DistortionModel::kEquidistant) {
    // g(rho) = tan(theta) / rho and g'(rho) = (rho sec^2(theta) / radius'(theta) - tan(theta)) /
    // rho^2 up to the table's farthest node (the image corners plus a cell), 4096 steps: the
    // cubic Hermite interpolation's error (h^4 / 384 times g's fourth derivative) is far below a
    // float's rounding. A lens wider than the field of view: up to the field's edge (the image
    // beyond it is not matched; points there take ToIdeal).
    double max_rho = 0.0;
    for (const double u : {origin_, origin_ + (cols_ - 1) * cell_}) {
      for (const double v : {origin_, origin_ + (rows_ - 1) * cell_}) {
        max_rho =
            std::max(max_rho, std::hypot((u - camera.cx) / camera.fx, (v - camera.cy) / camera.fy));
      }
    }
    if (camera.WiderThanField()) {
      max_rho =
          std::min(max_rho, camera.EquidistantRadius(PinholeCamera::kMaxFieldAngleDeg * kDegToRad));
    }
    constexpr int kSteps = 4096;
    radial_step_ = max_rho / kSteps;
    inv_radial_step_ = 1.0 / radial_step_;
    radial_g_.assign(kSteps + 2, 1.0);  // node 0, on the axis: g = 1, g' = 0 (g is even)
    radial_dg_.assign(kSteps + 2, 0.0);
    for (int k = 1; k < kSteps + 2; ++k) {
      const double rho = k * radial_step_;
      const double theta = camera.EquidistantAngle(rho);
      double slope = 0.0;
      camera.EquidistantRadius(theta, &slope);
      const double t = std::tan(theta), sec2 = 1.0 + t * t;
      radial_g_[k] = t / rho;
      radial_dg_[k] = (rho * sec2 / slope - t) / (rho * rho);
    }
  }
  // The image border mapped to ideal pixels, sampled every pixel: its bounding box.
  Eigen::Vector2d lo, hi;
  camera.IdealImageBounds(1.0, &lo, &hi);
  min_x_ = lo.x();
  min_y_ = lo.y();
  max_x_ = hi.x();
  max_y_ = hi.y();
  const double jac_cell = 16.0;
  inv_jac_cell_ = 1.0 / jac_cell;
  jac_cols_ = static_cast<int>(std::ceil((max_x_ - min_x_) / jac_cell)) + 1;
  jac_rows_ = static_cast<int>(std::ceil((max_y_ - min_y_) / jac_cell)) + 1;
  jac_table_.resize(static_cast<size_t>(jac_cols_) * jac_rows_);
  for (int r = 0; r < jac_rows_; ++r) {
    for (int c = 0; c < jac_cols_; ++c) {
      const Eigen::Matrix2d m = camera.IdealFromPixelJacobian(
          Eigen::Vector2d(min_x_ + c * jac_cell, min_y_ + r * jac_cell));
      jac_table_[static_cast<size_t>(r) * jac_cols_ + c] = (m * m.transpose()).cast<float>();
    }
  }
}

namespace {

// The table's bilinear interpolation at grid coordinates (gx, gy) inside it: the Newton step's
// start. table: node (c, r) at table[2 * (r * cols + c)], x then y.
[[gnu::always_inline]] inline void TableStart(const double* table, int cols, double gx, double gy,
                                              double* x, double* y) {
  const int c = static_cast<int>(gx), r = static_cast<int>(gy);
  const double ax = gx - c, ay = gy - r;
  const int k = 2 * (r * cols + c), kn = k + 2 * cols;
  *x = (1.0 - ay) * ((1.0 - ax) * table[k] + ax * table[k + 2]) +
       ay * ((1.0 - ax) * table[kn] + ax * table[kn + 2]);
  *y = (1.0 - ay) * ((1.0 - ax) * table[k + 1] + ax * table[k + 3]) +
       ay * ((1.0 - ax) * table[kn + 1] + ax * table[kn + 3]);
}

}  // namespace

Eigen::Vector2d PixelUndistorter::ToIdeal(const Eigen::Vector2d& uv,
                                          Eigen::Matrix2d* ideal_from_pixel) const {
  if (identity_) {
    if (ideal_from_pixel != nullptr) ideal_from_pixel->setIdentity();
    return uv;
  }
  const double gx = (uv.x() - origin_) * inv_cell_, gy = (uv.y() - origin_) * inv_cell_;
  Eigen::Vector2d xy;
  if (gx >= 0.0 && gy >= 0.0 && gx < cols_ - 1 && gy < rows_ - 1) {
    static_assert(sizeof(Eigen::Vector2d) == 2 * sizeof(double));
    TableStart(reinterpret_cast<const double*>(table_.data()), cols_, gx, gy, &xy.x(), &xy.y());
    // A lens wider than the field: nodes at 90 deg and beyond have no bearing.
    if (!xy.allFinite()) xy = camera_.PixelToNormalized(uv);
  } else {
    xy = camera_.PixelToNormalized(uv);  // outside the table (or NaN): the iterative inverse
  }
  // One Newton step on distort(xy) = target (two for an equidistant lens, whose ideal pixels
  // curve more at the corners: the table's start is 1e-4 px off after one step there).
  const Eigen::Vector2d target = camera_.IdealToNormalized(uv);
  Eigen::Matrix2d j, j_inv;
  const int steps = camera_.model == DistortionModel::kEquidistant ? 2 : 1;
  for (int step = 0; step < steps; ++step) {
    const Eigen::Vector2d residual = camera_.DistortNormalized(xy, &j) - target;
    j_inv = j.inverse();
    xy -= j_inv * residual;
  }
  if (ideal_from_pixel != nullptr) {
    // K J^-1 K^-1 (J at the previous iterate: the difference is far below what noise needs).
    *ideal_from_pixel << j_inv(0, 0), j_inv(0, 1) * camera_.fx / camera_.fy,
        j_inv(1, 0) * camera_.fy / camera_.fx, j_inv(1, 1);
  }
  return camera_.NormalizedToIdeal(xy);
}

namespace {

// The table's start and one Newton step (ToIdeal's arithmetic) for a run of points that all lie
// inside the table, over arrays so that the compiler vectorises it for the instruction set of
// the caller (below).
struct NewtonArgs {
  double k1, k2, p1, p2, k3, fx, fy, cx, cy, origin, inv_cell;
  int cols;
  const double* table;  // as TableStart takes it
};
[[gnu::always_inline]] inline void NewtonRun(const NewtonArgs& args, int n,
                                             const double* __restrict us,
                                             const double* __restrict vs, double* __restrict out_x,
                                             double* __restrict out_y) {
  // Parameters as locals: the compiler then knows the stores do not change them.
  const double k1 = args.k1, k2 = args.k2, p1 = args.p1, p2 = args.p2, k3 = args.k3;
  const double fx = args.fx, fy = args.fy, cx = args.cx, cy = args.cy;
  const double origin = args.origin, inv_cell = args.inv_cell;
  const int cols = args.cols;
  const double* __restrict table = args.table;
  for (int i = 0; i < n; ++i) {
    const double u = us[i], v = vs[i];
    double x, y;
    TableStart(table, cols, (u - origin) * inv_cell, (v - origin) * inv_cell, &x, &y);
    const double tx = (u - cx) / fx, ty = (v - cy) / fy;
    const RadTan e = EvalRadTan(k1, k2, p1, p2, k3, x, y);
    const double ex = e.dx - tx, ey = e.dy - ty;
    const double inv_det = 1.0 / (e.j00 * e.j11 - e.j01 * e.j01);
    x -= inv_det * (e.j11 * ex - e.j01 * ey);
    y -= inv_det * (e.j00 * ey - e.j01 * ex);
    out_x[i] = fx * x + cx;
    out_y[i] = fy * y + cy;
  }
}
// The equidistant lens's radial table for a run of points inside it: x_ideal = g(rho) x_d on the
// normalised plane, g by cubic Hermite interpolation (ToIdealInPlace's arithmetic), over arrays
// so that the compiler vectorises it (the table reads become gathers).
struct RadialArgs {
  double fx, fy, cx, cy, step, inv_step;
  const double* g;   // g at rho = k step
  const double* dg;  // its derivative
};
[[gnu::always_inline]] inline void RadialRun(const RadialArgs& args, int n,
                                             const double* __restrict us,
                                             const double* __restrict vs, double* __restrict out_x,
                                             double* __restrict out_y) {
  const double fx = args.fx, fy = args.fy, cx = args.cx, cy = args.cy;
  const double step = args.step, inv_step = args.inv_step;
  const double* __restrict g = args.g;
  const double* __restrict dg = args.dg;
  for (int i = 0; i < n; ++i) {
    const double xd = (us[i] - cx) / fx, yd = (vs[i] - cy) / fy;
    const double s = std::sqrt(xd * xd + yd * yd) * inv_step;
    const int k = static_cast<int>(s);
    const double t = s - k, t2 = t * t, t3 = t2 * t;
    const double gi = (2 * t3 - 3 * t2 + 1) * g[k] + (t3 - 2 * t2 + t) * step * dg[k] +
                      (-2 * t3 + 3 * t2) * g[k + 1] + (t3 - t2) * step * dg[k + 1];
    out_x[i] = fx * gi * xd + cx;
    out_y[i] = fy * gi * yd + cy;
  }
}
bool CpuHas(PixelUndistorter::Path path) {
  switch (path) {
    case PixelUndistorter::Path::kAuto:
    case PixelUndistorter::Path::kPortable:
      return true;
#if defined(__x86_64__) || defined(__i386__)
    case PixelUndistorter::Path::kAvx2:
      return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
    case PixelUndistorter::Path::kAvx512:
      return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512dq") &&
             __builtin_cpu_supports("avx512vl");
#else
    default:
      return false;
#endif
  }
  return false;
}
// A run kernel (NewtonRun, RadialRun) compiled once for each instruction-set path, chosen at
// run time: the kernel is inlined into each, and the compiler vectorises it for that path.
template <typename Args,
          void (*Kernel)(const Args&, int, const double*, const double*, double*, double*)>
struct RunDispatch {
  using Fn = void (*)(const Args&, int, const double*, const double*, double*, double*);
  static void Portable(const Args& a, int n, const double* us, const double* vs, double* out_x,
                       double* out_y) {
    Kernel(a, n, us, vs, out_x, out_y);
  }
#if defined(__x86_64__) || defined(__i386__)
  [[gnu::target("avx2,fma")]] static void Avx2(const Args& a, int n, const double* us,
                                               const double* vs, double* out_x, double* out_y) {
    Kernel(a, n, us, vs, out_x, out_y);
  }
  [[gnu::target("avx512f,avx512dq,avx512vl")]] static void Avx512(const Args& a, int n,
                                                                  const double* us,
                                                                  const double* vs, double* out_x,
                                                                  double* out_y) {
    Kernel(a, n, us, vs, out_x, out_y);
  }
#endif
  static Fn Select(PixelUndistorter::Path path) {
    using Path = PixelUndistorter::Path;
    if (path == Path::kAuto) {
      path = CpuHas(Path::kAvx512) ? Path::kAvx512
                                   : (CpuHas(Path::kAvx2) ? Path::kAvx2 : Path::kPortable);
    }
#if defined(__x86_64__) || defined(__i386__)
    if (path == Path::kAvx512) return &Avx512;
    if (path == Path::kAvx2) return &Avx2;
#endif
    return &Portable;
  }
};
using NewtonDispatch = RunDispatch<NewtonArgs, &NewtonRun>;
using RadialDispatch = RunDispatch<RadialArgs, &RadialRun>;

// ToIdealInPlace's frame: runs of up to 64 points loaded as doubles into us / vs; kernel(us, vs,
// len, out_x, out_y, outside, &num_outside) marks the points it cannot take (replacing them in
// us / vs meanwhile) and maps the run; the results are stored back as floats, the marked points
// through fallback(u, v) from their original values.
template <typename Kernel, typename Fallback>
void ForEachRun(float* xy, int n, int stride, Kernel&& kernel, Fallback&& fallback) {
  constexpr int kRun = 64;
  double us[kRun], vs[kRun], original_u[kRun], original_v[kRun], out_x[kRun], out_y[kRun];
  int outside[kRun];
  for (int begin = 0; begin < n; begin += kRun) {
    const int len = std::min(kRun, n - begin);
    for (int i = 0; i < len; ++i) {
      const float* p = xy + static_cast<size_t>(begin + i) * stride;
      original_u[i] = us[i] = p[0];
      original_v[i] = vs[i] = p[1];
    }
    int num_outside = 0;
    kernel(us, vs, len, out_x, out_y, outside, &num_outside);
    for (int i = 0; i < len; ++i) {
      float* p = xy + static_cast<size_t>(begin + i) * stride;
      p[0] = static_cast<float>(out_x[i]);
      p[1] = static_cast<float>(out_y[i]);
    }
    for (int o = 0; o < num_outside; ++o) {
      float* p = xy + static_cast<size_t>(begin + outside[o]) * stride;
      const Eigen::Vector2d ideal = fallback(original_u[outside[o]], original_v[outside[o]]);
      p[0] = static_cast<float>(ideal.x());
      p[1] = static_cast<float>(ideal.y());
    }
  }
}

}  // namespace

bool PixelUndistorter::Supported(Path path) { return CpuHas(path); }

void PixelUndistorter::ToIdealInPlace(float* xy, int n, int stride, Path path) const {
  IMUMATCH_CHECK(n >= 0 && stride >= 2, "n=" << n << " stride=" << stride);
  IMUMATCH_CHECK(CpuHas(path), "this CPU lacks the instruction set of the requested path");
  if (identity_ || n == 0) return;
  const auto to_ideal = [this](double u, double v) { return ToIdeal(Eigen::Vector2d(u, v)); };
  if (camera_.model == DistortionModel::kEquidistant) {
    // Radial: the ideal point is g(rho) times the distorted one on the normalised plane, g from
    // the table by cubic Hermite interpolation (no Newton step, no transcendental function), in
    // runs of 64 like the radial-tangential loop below. Beyond the table (and NaN): ToIdeal.
    static const RadialDispatch::Fn best_radial = RadialDispatch::Select(Path::kAuto);
    const RadialDispatch::Fn radial_run =
        path == Path::kAuto ? best_radial : RadialDispatch::Select(path);
    const RadialArgs args{camera_.fx,   camera_.fy,       camera_.cx,       camera_.cy,
                          radial_step_, inv_radial_step_, radial_g_.data(), radial_dg_.data()};
    // Inside the table: rho below its last interval's start (squared: no root here; a point
    // that rounds onto that start still has both its nodes, the table holds one more).
    const double last_rho = (static_cast<double>(radial_g_.size()) - 2.0) * radial_step_;
    const double max_rho2 = last_rho * last_rho;
    const double inv_fx = 1.0 / camera_.fx, inv_fy = 1.0 / camera_.fy;
    ForEachRun(
        xy, n, stride,
        [&](double* us, double* vs, int len, double* out_x, double* out_y, int* outside,
            int* num_outside) {
          for (int i = 0; i < len; ++i) {
            const double xd = (us[i] - camera_.cx) * inv_fx, yd = (vs[i] - camera_.cy) * inv_fy;
            if (!(xd * xd + yd * yd < max_rho2)) {  // (and NaN)
              outside[(*num_outside)++] = i;
              us[i] = camera_.cx;  // the axis meanwhile
              vs[i] = camera_.cy;
            }
          }
          radial_run(args, len, us, vs, out_x, out_y);
        },
        to_ideal);
    return;
  }
  static const NewtonDispatch::Fn best = NewtonDispatch::Select(Path::kAuto);
  const NewtonDispatch::Fn newton_run = path == Path::kAuto ? best : NewtonDispatch::Select(path);
  const auto& [k1, k2, p1, p2, k3] = camera_.distortion;
  const NewtonArgs args{k1,
                        k2,
                        p1,
                        p2,
                        k3,
                        camera_.fx,
                        camera_.fy,
                        camera_.cx,
                        camera_.cy,
                        origin_,
                        inv_cell_,
                        cols_,
                        reinterpret_cast<const double*>(table_.data())};
  const double last_col = cols_ - 1, last_row = rows_ - 1;
  ForEachRun(
      xy, n, stride,
      [&](double* us, double* vs, int len, double* out_x, double* out_y, int* outside,
          int* num_outside) {
        for (int i = 0; i < len; ++i) {
          const double gx = (us[i] - origin_) * inv_cell_, gy = (vs[i] - origin_) * inv_cell_;
          if (!(gx >= 0.0 && gy >= 0.0 && gx < last_col && gy < last_row)) {
            // (And NaN.) ToIdeal's path afterwards; a node of the table meanwhile.
            outside[(*num_outside)++] = i;
            us[i] = vs[i] = origin_;
          }
        }
        newton_run(args, len, us, vs, out_x, out_y);
      },
      to_ideal);
}

}  // namespace imumatch
