#include "imumatch/features/surf.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>

#include <opencv2/core/utility.hpp>

#include "imumatch/core/error.h"
#include "imumatch/core/so3.h"
#include "imumatch/features/image_util.h"

namespace imumatch {
namespace {

// Integral image in wrap-around uint32 arithmetic: the difference of four entries is the exact box
// sum whenever the box sum itself fits in 31 bits (any box below 8.4 million pixels), whatever the
// image size.
class IntegralImage {
 public:
  explicit IntegralImage(const cv::Mat& gray)
      : width_(gray.cols),
        height_(gray.rows),
        stride_(static_cast<size_t>(gray.cols) + 1),
        data_(stride_ * (static_cast<size_t>(gray.rows) + 1), 0u) {
    for (int y = 0; y < height_; ++y) {
      const uint8_t* row = gray.ptr<uint8_t>(y);
      const uint32_t* prev = &data_[static_cast<size_t>(y) * stride_];
      uint32_t* cur = &data_[static_cast<size_t>(y + 1) * stride_];
      uint32_t run = 0;
      for (int x = 0; x < width_; ++x) {
        run += row[x];
        cur[x + 1] = prev[x + 1] + run;
      }
    }
  }

  int width() const { return width_; }
  int height() const { return height_; }
  const uint32_t* Row(int y) const { return &data_[static_cast<size_t>(y) * stride_]; }

  // Sum of the pixels x in [x0, x1), y in [y0, y1). The caller keeps the box inside the image.
  float Box(int x0, int y0, int x1, int y1) const {
    const uint32_t* r0 = Row(y0);
    const uint32_t* r1 = Row(y1);
    return static_cast<float>(static_cast<int32_t>(r1[x1] - r1[x0] - r0[x1] + r0[x0]));
  }

  // Haar wavelet responses (right minus left half, bottom minus top half) of side 2*half centred
  // on the pixel corner nearest to (px, py), integer coordinates being pixel centres. False when
  // the wavelet leaves the image.
  bool HaarNearest(float px, float py, int half, float* hx, float* hy) const {
    const float fx = px + 0.5f;
    const float fy = py + 0.5f;
    const float lo = static_cast<float>(half);
    if (!(fx >= lo && fy >= lo && fx < static_cast<float>(width_ - half) &&
          fy < static_cast<float>(height_ - half))) {
      return false;  // also rejects NaN
    }
    const int x = static_cast<int>(fx + 0.5f);
    const int y = static_cast<int>(fy + 0.5f);
    if (x + half > width_ || y + half > height_) return false;
    const uint32_t* t = Row(y - half);
    const uint32_t* c = Row(y);
    const uint32_t* d = Row(y + half);
    *hx = static_cast<float>(static_cast<int32_t>((d[x + half] - 2u * d[x] + d[x - half]) -
                                                  (t[x + half] - 2u * t[x] + t[x - half])));
    *hy = static_cast<float>(static_cast<int32_t>((d[x + half] - 2u * c[x + half] + t[x + half]) -
                                                  (d[x - half] - 2u * c[x - half] + t[x - half])));
    return true;
  }

  // Haar wavelet responses (right minus left half, bottom minus top half) of side 2*half centred
  // on the sub-pixel point (px, py), integer coordinates being pixel centres. The box sums are
  // taken on the bilinearly interpolated integral image, i.e. over boxes shifted by fractions of a
  // pixel, so responses vary smoothly with the position. False when the wavelet leaves the image.
  bool Haar(float px, float py, int half, float* hx, float* hy) const {
    // Integral-image index k is the pixel boundary at coordinate k - 0.5.
    const float fx = px + 0.5f;
    const float fy = py + 0.5f;
    const float lo = static_cast<float>(half);
    if (!(fx >= lo && fy >= lo && fx < static_cast<float>(width_ - half) &&
          fy < static_cast<float>(height_ - half))) {
      return false;  // also rejects NaN
    }
    const int x = static_cast<int>(fx);
    const int y = static_cast<int>(fy);
    const float ax = fx - static_cast<float>(x);
    const float ay = fy - static_cast<float>(y);
    // 6 x 6 integral values at rows/cols {-half, -half+1, 0, 1, half, half+1} around (x, y).
    const int offs[6] = {-half, -half + 1, 0, 1, half, half + 1};
    uint32_t m[6][6];
    for (int i = 0; i < 6; ++i) {
      const uint32_t* row = Row(y + offs[i]);
      for (int k = 0; k < 6; ++k) m[i][k] = row[x + offs[k]];
    }
    // Exact integer responses of the wavelets centred on the four integral corners around the
    // point (wrap-around arithmetic, see above), blended bilinearly.
    float rx[2][2];
    float ry[2][2];
    for (int a = 0; a < 2; ++a) {
      for (int b = 0; b < 2; ++b) {
        const uint32_t* t = m[a];
        const uint32_t* c = m[a + 2];
        const uint32_t* d = m[a + 4];
        rx[a][b] = static_cast<float>(static_cast<int32_t>((d[b + 4] - 2u * d[b + 2] + d[b]) -
                                                           (t[b + 4] - 2u * t[b + 2] + t[b])));
        ry[a][b] = static_cast<float>(static_cast<int32_t>((d[b + 4] - 2u * c[b + 4] + t[b + 4]) -
                                                           (d[b] - 2u * c[b] + t[b])));
      }
    }
    const float w00 = (1.f - ax) * (1.f - ay);
    const float w01 = ax * (1.f - ay);
    const float w10 = (1.f - ax) * ay;
    const float w11 = ax * ay;
    *hx = w00 * rx[0][0] + w01 * rx[0][1] + w10 * rx[1][0] + w11 * rx[1][1];
    *hy = w00 * ry[0][0] + w01 * ry[0][1] + w10 * ry[1][0] + w11 * ry[1][1];
    return true;
  }

 private:
  int width_;
  int height_;
  size_t stride_;
  std::vector<uint32_t> data_;
};

// Filter side of interval i (0-based) in octave o: 9,15,21,27; 15,27,39,51; 27,51,75,99; ...
int FilterSize(int octave, int interval) { return 3 * ((2 << octave) * (interval + 1) + 1); }

struct HessianValues {
  float dxx, dyy, dxy;
};

// Box-filter approximations of the Gaussian second derivatives for an odd filter side L centred on
// pixel (x, y), each lobe normalised by its area (scale-normalised responses). The caller keeps
// the filter inside the image: x - (L-1)/2 >= 0 and x + (L-1)/2 < width, same for y.
struct HessianFilter {
  explicit HessianFilter(int filter_size)
      : size(filter_size),
        half((filter_size - 1) / 2),
        lobe(filter_size / 3),
        inv_lobe_area(1.f / static_cast<float>(lobe * (2 * lobe - 1))),
        inv_square_area(1.f / static_cast<float>(lobe * lobe)) {}

  HessianValues At(const IntegralImage& ii, int x, int y) const {
    const int h = half;
    const int l = lobe;
    // Dxx: three lobes l wide and 2l-1 high, weights +1 -2 +1 = whole strip minus 3x middle.
    const float dxx = ii.Box(x - h, y - l + 1, x + h + 1, y + l) -
                      3.f * ii.Box(x - h + l, y - l + 1, x - h + 2 * l, y + l);
    const float dyy = ii.Box(x - l + 1, y - h, x + l, y + h + 1) -
                      3.f * ii.Box(x - l + 1, y - h + l, x + l, y - h + 2 * l);
    // Dxy: four l x l squares around the centre pixel (which is left out), + - / - +.
    const float dxy = ii.Box(x - l, y - l, x, y) + ii.Box(x + 1, y + 1, x + 1 + l, y + 1 + l) -
                      ii.Box(x + 1, y - l, x + 1 + l, y) - ii.Box(x - l, y + 1, x, y + 1 + l);
    return {dxx * inv_lobe_area, dyy * inv_lobe_area, dxy * inv_square_area};
  }

  int size;
  int half;
  int lobe;
  float inv_lobe_area;
  float inv_square_area;
};

inline float Determinant(const HessianValues& h) {
  return h.dxx * h.dyy - 0.81f * h.dxy * h.dxy;  // (0.9 * Dxy)^2
}

// Determinant-of-Hessian responses of one filter size, sampled every `step` pixels. Samples whose
// filter does not fit in the image hold 0.
struct ResponseLayer {
  int filter = 0;
  int step = 1;
  int rows = 0;
  int cols = 0;
  std::vector<float> det;

  float At(int r, int c) const { return det[static_cast<size_t>(r) * cols + c]; }
};

inline int32_t BoxSum(const uint32_t* r0, const uint32_t* r1, int x0, int x1) {
  return static_cast<int32_t>(r1[x1] - r1[x0] - r0[x1] + r0[x0]);
}

// Fills `layer` (filter and step set by the caller). Reuses the layer's buffer.
void ComputeLayer(const IntegralImage& ii, ResponseLayer* layer) {
  const HessianFilter filter(layer->filter);
  const int step = layer->step;
  const int h = filter.half;
  const int l = filter.lobe;
  const float inv_lobe_area = filter.inv_lobe_area;
  const float inv_square_area = filter.inv_square_area;
  const int width = ii.width();
  const int height = ii.height();
  layer->rows = (height - 1) / step + 1;
  layer->cols = (width - 1) / step + 1;
  layer->det.resize(static_cast<size_t>(layer->rows) * layer->cols);
  // Samples whose filter fits in the image: [r_begin, r_end) x [c_begin, c_end); others hold 0.
  const int r_begin = std::min(layer->rows, (h + step - 1) / step);
  const int r_end = std::max(r_begin, std::min(layer->rows, (height - 1 - h) / step + 1));
  const int c_begin = std::min(layer->cols, (h + step - 1) / step);
  const int c_end = std::max(c_begin, std::min(layer->cols, (width - 1 - h) / step + 1));
  const int cols = layer->cols;
  cv::parallel_for_(cv::Range(0, layer->rows), [&](const cv::Range& range) {
    for (int r = range.start; r < range.end; ++r) {
      float* out = &layer->det[static_cast<size_t>(r) * cols];
      if (r < r_begin || r >= r_end || c_begin == c_end) {
        std::fill(out, out + cols, 0.f);
        continue;
      }
      std::fill(out, out + c_begin, 0.f);
      std::fill(out + c_end, out + cols, 0.f);
      const int y = r * step;
      const uint32_t* xx0 = ii.Row(y - l + 1);  // Dxx: rows of the three side-by-side lobes
      const uint32_t* xx1 = ii.Row(y + l);
      const uint32_t* yy0 = ii.Row(y - h);  // Dyy: whole strip and middle lobe
      const uint32_t* yy1 = ii.Row(y - h + l);
      const uint32_t* yy2 = ii.Row(y - h + 2 * l);
      const uint32_t* yy3 = ii.Row(y + h + 1);
      const uint32_t* xy0 = ii.Row(y - l);  // Dxy: squares above and below the centre row
      const uint32_t* xy1 = ii.Row(y);
      const uint32_t* xy2 = ii.Row(y + 1);
      const uint32_t* xy3 = ii.Row(y + 1 + l);
      for (int c = c_begin; c < c_end; ++c) {
        const int x = c * step;
        const int32_t dxx =
            BoxSum(xx0, xx1, x - h, x + h + 1) - 3 * BoxSum(xx0, xx1, x - h + l, x - h + 2 * l);
        const int32_t dyy =
            BoxSum(yy0, yy3, x - l + 1, x + l) - 3 * BoxSum(yy1, yy2, x - l + 1, x + l);
        const int32_t dxy = BoxSum(xy0, xy1, x - l, x) + BoxSum(xy2, xy3, x + 1, x + 1 + l) -
                            BoxSum(xy0, xy1, x + 1, x + 1 + l) - BoxSum(xy2, xy3, x - l, x);
        const float fxx = static_cast<float>(dxx) * inv_lobe_area;
        const float fyy = static_cast<float>(dyy) * inv_lobe_area;
        const float fxy = static_cast<float>(dxy) * inv_square_area;
        out[c] = Determinant({fxx, fyy, fxy});
      }
    }
  });
}

bool KeypointGreater(const cv::KeyPoint& a, const cv::KeyPoint& b) {
  if (a.response != b.response) return a.response > b.response;
  if (a.size != b.size) return a.size > b.size;
  if (a.pt.y != b.pt.y) return a.pt.y < b.pt.y;
  return a.pt.x < b.pt.x;
}

// Fits a 3D quadratic to the 3x3x3 neighbourhood of (r, c) in `mid` and returns the offset of its
// extremum in sample units (x, y, layer). False when the system is singular or the offset leaves
// the neighbourhood (|offset| > 1 in some dimension, as in OpenCV).
bool InterpolateExtremum(const ResponseLayer& below, const ResponseLayer& mid,
                         const ResponseLayer& above, int r, int c, cv::Vec3d* offset) {
  const double v = mid.At(r, c);
  const double dx = 0.5 * (mid.At(r, c + 1) - mid.At(r, c - 1));
  const double dy = 0.5 * (mid.At(r + 1, c) - mid.At(r - 1, c));
  const double ds = 0.5 * (above.At(r, c) - below.At(r, c));
  const double dxx = mid.At(r, c + 1) + mid.At(r, c - 1) - 2 * v;
  const double dyy = mid.At(r + 1, c) + mid.At(r - 1, c) - 2 * v;
  const double dss = above.At(r, c) + below.At(r, c) - 2 * v;
  const double dxy = 0.25 * (mid.At(r + 1, c + 1) - mid.At(r + 1, c - 1) - mid.At(r - 1, c + 1) +
                             mid.At(r - 1, c - 1));
  const double dxs =
      0.25 * (above.At(r, c + 1) - above.At(r, c - 1) - below.At(r, c + 1) + below.At(r, c - 1));
  const double dys =
      0.25 * (above.At(r + 1, c) - above.At(r - 1, c) - below.At(r + 1, c) + below.At(r - 1, c));
  const cv::Matx33d hessian(dxx, dxy, dxs, dxy, dyy, dys, dxs, dys, dss);
  const cv::Vec3d gradient(dx, dy, ds);
  cv::Vec3d x;
  if (!cv::solve(hessian, -gradient, x, cv::DECOMP_LU)) return false;
  if (!(std::abs(x[0]) <= 1.0 && std::abs(x[1]) <= 1.0 && std::abs(x[2]) <= 1.0)) return false;
  *offset = x;
  return true;
}

std::vector<cv::KeyPoint> FastHessian(const IntegralImage& ii, const SurfOptions& options) {
  const int width = ii.width();
  const int height = ii.height();
  const int layers_per_octave = options.n_intervals + 2;
  std::vector<cv::KeyPoint> keypoints;
  const float threshold = static_cast<float>(options.hessian_threshold);
  for (int octave = 0; octave < options.n_octaves; ++octave) {
    const int step = 1 << octave;
    const int top_filter = FilterSize(octave, layers_per_octave - 1);
    const int top_half = (top_filter - 1) / 2;
    // Rows/cols whose 3x3 neighbourhood has the largest filter of the octave inside the image.
    const int r_begin = (top_half + step - 1) / step + 1;
    const int r_end = (height - 1 - top_half) / step;  // exclusive
    const int c_begin = (top_half + step - 1) / step + 1;
    const int c_end = (width - 1 - top_half) / step;
    if (r_end <= r_begin || c_end <= c_begin) break;  // larger octaves do not fit either

    // Per-thread buffers reused across calls and octaves (no page faults on repeated calls).
    thread_local std::vector<ResponseLayer> layers;
    layers.resize(layers_per_octave);
    for (int i = 0; i < layers_per_octave; ++i) {
      layers[i].filter = FilterSize(octave, i);
      layers[i].step = step;
      ComputeLayer(ii, &layers[i]);
    }
    const int filter_spacing = 6 << octave;
    for (int i = 1; i + 1 < layers_per_octave; ++i) {
      const ResponseLayer& below = layers[i - 1];
      const ResponseLayer& mid = layers[i];
      const ResponseLayer& above = layers[i + 1];
      const HessianFilter mid_filter(mid.filter);
      for (int r = r_begin; r < r_end; ++r) {
        const float* row = &mid.det[static_cast<size_t>(r) * mid.cols];
        for (int c = c_begin; c < c_end; ++c) {
          const float v = row[c];
          if (!(v > threshold)) continue;
          bool is_max = true;
          for (int dr = -1; dr <= 1 && is_max; ++dr) {
            for (int dc = -1; dc <= 1; ++dc) {
              if (below.At(r + dr, c + dc) >= v || above.At(r + dr, c + dc) >= v ||
                  ((dr != 0 || dc != 0) && mid.At(r + dr, c + dc) >= v)) {
                is_max = false;
                break;
              }
            }
          }
          if (!is_max) continue;
          cv::Vec3d offset;
          if (!InterpolateExtremum(below, mid, above, r, c, &offset)) continue;
          const HessianValues h = mid_filter.At(ii, c * step, r * step);
          const float trace = h.dxx + h.dyy;
          cv::KeyPoint kp;
          kp.pt.x = static_cast<float>((c + offset[0]) * step);
          kp.pt.y = static_cast<float>((r + offset[1]) * step);
          kp.size = static_cast<float>(mid.filter + offset[2] * filter_spacing);
          kp.angle = 0.f;
          kp.response = v;  // the sampled maximum, as OpenCV (always above the threshold)
          kp.octave = octave;
          kp.class_id = (trace > 0.f) - (trace < 0.f);
          keypoints.push_back(kp);
        }
      }
    }
  }
  std::sort(keypoints.begin(), keypoints.end(), KeypointGreater);
  return keypoints;
}

// Orientation samples: grid points (i, j) in units of s with i^2 + j^2 <= 36 (radius 6s),
// Gaussian weight with sigma = 2s.
struct OrientationSample {
  int i, j;
  float weight;
};

const std::vector<OrientationSample>& OrientationSamples() {
  static const std::vector<OrientationSample> samples = [] {
    std::vector<OrientationSample> out;
    for (int j = -6; j <= 6; ++j) {
      for (int i = -6; i <= 6; ++i) {
        if (i * i + j * j > 36) continue;
        out.push_back({i, j, std::exp(-static_cast<float>(i * i + j * j) / (2.f * 2.f * 2.f))});
      }
    }
    return out;
  }();
  return samples;
}

// Gaussian weights (sigma = 3.3s) of the 20 x 20 descriptor samples, centred on the keypoint.
const std::array<float, 400>& DescriptorWeights() {
  static const std::array<float, 400> weights = [] {
    std::array<float, 400> w{};
    for (int i = 0; i < 20; ++i) {
      for (int j = 0; j < 20; ++j) {
        const float u = static_cast<float>(j) - 9.5f;
        const float v = static_cast<float>(i) - 9.5f;
        w[i * 20 + j] = std::exp(-(u * u + v * v) / (2.f * 3.3f * 3.3f));
      }
    }
    return w;
  }();
  return weights;
}

// Dominant orientation in degrees (OpenCV convention) from Haar responses of side 4s in a circle
// of radius 6s, summed in a 60-degree window sliding in 1-degree steps. False when no response
// could be sampled.
bool DominantOrientation(const IntegralImage& ii, const cv::KeyPoint& kp, float* angle_deg) {
  const float s = 1.2f * kp.size / 9.f;
  const int half = std::max(1, static_cast<int>(std::lround(2.f * s)));
  std::array<float, 360> bin_x{};
  std::array<float, 360> bin_y{};
  int n = 0;
  for (const OrientationSample& sample : OrientationSamples()) {
    float hx = 0.f;
    float hy = 0.f;
    if (!ii.HaarNearest(kp.pt.x + static_cast<float>(sample.i) * s,
                        kp.pt.y + static_cast<float>(sample.j) * s, half, &hx, &hy)) {
      continue;
    }
    hx *= sample.weight;
    hy *= sample.weight;
    if (hx == 0.f && hy == 0.f) continue;
    const int bin = std::min(359, static_cast<int>(cv::fastAtan2(hy, hx)));  // +-0.3 degrees
    bin_x[bin] += hx;
    bin_y[bin] += hy;
    ++n;
  }
  if (n == 0) return false;
  constexpr int kWindow = 60;
  float sx = 0.f;
  float sy = 0.f;
  for (int b = 0; b < kWindow; ++b) {
    sx += bin_x[b];
    sy += bin_y[b];
  }
  float best_x = sx;
  float best_y = sy;
  float best = sx * sx + sy * sy;
  for (int start = 1; start < 360; ++start) {
    const int add = (start + kWindow - 1) % 360;
    sx += bin_x[add] - bin_x[start - 1];
    sy += bin_y[add] - bin_y[start - 1];
    const float mag = sx * sx + sy * sy;
    if (mag > best) {
      best = mag;
      best_x = sx;
      best_y = sy;
    }
  }
  float a = std::atan2(best_y, best_x) * static_cast<float>(kRadToDeg);
  if (a < 0.f) a += 360.f;
  if (a >= 360.f) a -= 360.f;
  *angle_deg = a;
  return true;
}

// 64-d SURF descriptor: 20s window rotated to kp.angle, 4 x 4 subregions of 5 x 5 samples spaced
// by s, Haar responses of side 2s weighted by a Gaussian (sigma 3.3s), per subregion
// (sum dx, sum dy, sum |dx|, sum |dy|) in the keypoint frame, L2-normalised. Responses whose
// wavelet leaves the image count as 0. False (descriptor unusable) when every response is 0.
bool ComputeDescriptor(const IntegralImage& ii, const cv::KeyPoint& kp, float* out) {
  const float s = 1.2f * kp.size / 9.f;
  const int half = std::max(1, static_cast<int>(std::lround(s)));
  const float angle = kp.angle * static_cast<float>(kDegToRad);
  const float co = std::cos(angle);
  const float si = std::sin(angle);
  const std::array<float, 400>& weights = DescriptorWeights();
  std::fill(out, out + 64, 0.f);
  for (int i = 0; i < 20; ++i) {
    const float v = (static_cast<float>(i) - 9.5f) * s;
    for (int j = 0; j < 20; ++j) {
      const float u = (static_cast<float>(j) - 9.5f) * s;
      float hx = 0.f;
      float hy = 0.f;
      if (!ii.Haar(kp.pt.x + u * co - v * si, kp.pt.y + u * si + v * co, half, &hx, &hy)) continue;
      const float w = weights[i * 20 + j];
      const float rx = w * (hx * co + hy * si);
      const float ry = w * (-hx * si + hy * co);
      float* bin = out + 4 * ((i / 5) * 4 + j / 5);
      bin[0] += rx;
      bin[1] += ry;
      bin[2] += std::abs(rx);
      bin[3] += std::abs(ry);
    }
  }
  double norm2 = 0.0;
  for (int k = 0; k < 64; ++k) norm2 += static_cast<double>(out[k]) * out[k];
  if (!(norm2 > 0.0)) return false;  // no response inside the image (or a flat window)
  const float scale = static_cast<float>(1.0 / std::sqrt(norm2));
  for (int k = 0; k < 64; ++k) out[k] *= scale;
  return true;
}

}  // namespace

void SurfOptions::Check() const {
  IMUMATCH_CHECK(
      std::isfinite(hessian_threshold) && hessian_threshold >= 0.0,
      "SurfOptions.hessian_threshold must be finite and >= 0, got " << hessian_threshold);
  IMUMATCH_CHECK(n_octaves >= 1 && n_octaves <= 8,
                 "SurfOptions.n_octaves must be in [1, 8], got " << n_octaves);
  IMUMATCH_CHECK(n_intervals >= 1 && n_intervals <= 8,
                 "SurfOptions.n_intervals must be in [1, 8], got " << n_intervals);
  IMUMATCH_CHECK(max_keypoints >= 0,
                 "SurfOptions.max_keypoints must be >= 0 (0 = all), got " << max_keypoints);
}

Surf::Surf(const SurfOptions& options) : options_(options) { options_.Check(); }

cv::Ptr<Surf> Surf::Create(const SurfOptions& options) { return cv::makePtr<Surf>(options); }

void Surf::detectAndCompute(cv::InputArray image, cv::InputArray mask,
                            std::vector<cv::KeyPoint>& keypoints, cv::OutputArray descriptors,
                            bool useProvidedKeypoints) {
  const cv::Mat gray = ToGray8(image.getMat(), "Surf");
  const IntegralImage ii(gray);

  if (!useProvidedKeypoints) {
    keypoints = FastHessian(ii, options_);
    const cv::Mat mask_mat = mask.getMat();
    if (!mask_mat.empty()) {
      if (mask_mat.type() != CV_8UC1 || mask_mat.size() != gray.size()) {
        throw InvalidArgument("Surf: the mask must be 8-bit single-channel of the image size");
      }
      cv::KeyPointsFilter::runByPixelsMask(keypoints, mask_mat);
    }
    if (options_.max_keypoints > 0 && static_cast<int>(keypoints.size()) > options_.max_keypoints) {
      keypoints.resize(options_.max_keypoints);  // already sorted by decreasing response
    }
  }

  // Orientation (and validity) for every keypoint, then descriptors, in parallel.
  const int n = static_cast<int>(keypoints.size());
  std::vector<uint8_t> valid(n, 1);
  const bool need_descriptors = descriptors.needed();
  cv::Mat desc;
  if (need_descriptors) desc.create(n, 64, CV_32F);
  const bool upright = options_.upright;
  const float max_size = 10.f * static_cast<float>(std::max(gray.cols, gray.rows));
  cv::parallel_for_(cv::Range(0, n), [&](const cv::Range& range) {
    for (int k = range.start; k < range.end; ++k) {
      cv::KeyPoint& kp = keypoints[k];
      // Sizes beyond 10x the image cannot be described (and would overflow integer wavelet sizes).
      if (!(kp.size > 0.f && kp.size < max_size) || !std::isfinite(kp.pt.x) ||
          !std::isfinite(kp.pt.y)) {
        valid[k] = 0;
        continue;
      }
      if (upright) {
        kp.angle = 0.f;
      } else if (!DominantOrientation(ii, kp, &kp.angle)) {
        valid[k] = 0;
        continue;
      }
      if (need_descriptors && !ComputeDescriptor(ii, kp, desc.ptr<float>(k))) valid[k] = 0;
    }
  });

  if (std::find(valid.begin(), valid.end(), 0) != valid.end()) {
    std::vector<cv::KeyPoint> kept;
    cv::Mat kept_desc;
    std::vector<int> rows;
    for (int k = 0; k < n; ++k) {
      if (!valid[k]) continue;
      kept.push_back(keypoints[k]);
      rows.push_back(k);
    }
    if (need_descriptors) {
      kept_desc.create(static_cast<int>(rows.size()), 64, CV_32F);
      for (size_t r = 0; r < rows.size(); ++r) desc.row(rows[r]).copyTo(kept_desc.row(r));
      desc = kept_desc;
    }
    keypoints.swap(kept);
  }
  if (need_descriptors) {
    if (desc.empty()) {
      descriptors.release();
    } else {
      desc.copyTo(descriptors);
    }
  }
}

}  // namespace imumatch
