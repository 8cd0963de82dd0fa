#include "imumatch/eval/match_image.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <sstream>

#include <Eigen/Eigenvalues>
#include <opencv2/imgproc.hpp>

#include "imumatch/core/error.h"
#include "imumatch/eval/plots.h"
#include "imumatch/io/image_io.h"

namespace imumatch {
namespace {

const cv::Scalar kGreen(40, 200, 40);
const cv::Scalar kRed(40, 40, 230);
const cv::Scalar kWindow(230, 160, 0);
const cv::Scalar kEllipse(220, 60, 200);

void DashedLine(cv::Mat& img, cv::Point2f a, cv::Point2f b, const cv::Scalar& color, int thickness,
                float dash = 8.0f, float gap = 6.0f) {
  const cv::Point2f d = b - a;
  const float len = std::sqrt(d.dot(d));
  if (len < 1e-3f) return;
  const cv::Point2f u = d / len;
  for (float s = 0.0f; s < len; s += dash + gap) {
    const float e = std::min(len, s + dash);
    cv::line(img, a + u * s, a + u * e, color, thickness, cv::LINE_AA);
  }
}

cv::Mat ToBgr(const cv::Mat& image) {
  cv::Mat out;
  if (image.channels() == 1) {
    cv::cvtColor(image, out, cv::COLOR_GRAY2BGR);
  } else if (image.channels() == 4) {
    cv::cvtColor(image, out, cv::COLOR_BGRA2BGR);
  } else {
    out = image.clone();
  }
  return out;
}

std::string Safe(std::string s) {
  for (char& c : s) {
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '-' && c != '_') c = '_';
  }
  return s;
}

}  // namespace

void MatchImageOptions::Check() const {
  IMUMATCH_CHECK(std::isfinite(threshold_px) && threshold_px > 0.0,
                 "threshold_px = " << threshold_px);
  IMUMATCH_CHECK(max_windows >= 0, "max_windows = " << max_windows);
}

cv::Mat DrawMatchImage(const PairVisual& visual, size_t run_index,
                       const MatchImageOptions& options) {
  options.Check();
  IMUMATCH_CHECK(run_index < visual.runs.size(), "run_index " << run_index);
  IMUMATCH_CHECK(!visual.image_a.empty() && !visual.image_b.empty(), "empty images");
  const PairVisual::Run& run = visual.runs[run_index];
  const cv::Mat a = ToBgr(visual.image_a), b = ToBgr(visual.image_b);
  const int header = 34;
  cv::Mat canvas(std::max(a.rows, b.rows) + header, a.cols + b.cols, CV_8UC3,
                 cv::Scalar(255, 255, 255));
  a.copyTo(canvas(cv::Rect(0, header, a.cols, a.rows)));
  b.copyTo(canvas(cv::Rect(a.cols, header, b.cols, b.rows)));
  const cv::Point2f off_a(0.0f, header), off_b(static_cast<float>(a.cols), header);

  if (options.draw_unmatched_keypoints) {
    for (const auto& kp : visual.keypoints_a)
      cv::circle(canvas, kp.pt + off_a, 2, cv::Scalar(0, 200, 255), 1);
    for (const auto& kp : visual.keypoints_b)
      cv::circle(canvas, kp.pt + off_b, 2, cv::Scalar(0, 200, 255), 1);
  }
  // Search windows on frame B.
  cv::Mat right = canvas(cv::Rect(a.cols, header, b.cols, b.rows));
  const bool distorted = visual.camera.HasDistortion();
  int windows = 0;
  const size_t stride = options.max_windows > 0
                            ? std::max<size_t>(1, (run.matches.size() + options.max_windows - 1) /
                                                      options.max_windows)
                            : run.matches.size() + 1;
  for (size_t k = 0; k < run.matches.size(); k += stride) {
    const Match& m = run.matches[k];
    if (windows >= options.max_windows) break;
    if (m.query_idx < 0 || static_cast<size_t>(m.query_idx) >= run.predictions.size()) continue;
    const KeypointPrediction& p = run.predictions[m.query_idx];
    if (!p.HasWindow()) continue;
    ++windows;
    // Predictions are in ideal pixels: every outline is sampled there and mapped into the image,
    // so a straight epipolar segment shows as the curve it is under a distorted lens.
    auto polyline = [&](const std::vector<Eigen::Vector2f>& ideal, const cv::Scalar& colour,
                        bool closed) {
      std::vector<cv::Point> pts;
      for (const Eigen::Vector2f& q : ideal) {
        const Eigen::Vector2d px = distorted ? visual.camera.IdealToPixel(q.cast<double>())
                                             : Eigen::Vector2d(q.cast<double>());
        pts.emplace_back(cvRound(px.x() * 16.0), cvRound(px.y() * 16.0));
      }
      cv::polylines(right, pts, closed, colour, 1, cv::LINE_AA, 4);
    };
    auto edge = [](const Eigen::Vector2f& from, const Eigen::Vector2f& to,
                   std::vector<Eigen::Vector2f>& out) {
      constexpr int kSteps = 8;
      for (int i = 0; i < kSteps; ++i) {
        out.push_back(from + (to - from) * (static_cast<float>(i) / kSteps));
      }
    };
    std::vector<Eigen::Vector2f> box;
    const Eigen::Vector2f c00(p.min_x, p.min_y), c10(p.max_x, p.min_y), c11(p.max_x, p.max_y),
        c01(p.min_x, p.max_y);
    edge(c00, c10, box);
    edge(c10, c11, box);
    edge(c11, c01, box);
    edge(c01, c00, box);
    polyline(box, kWindow, true);
    if (p.status == PredictionStatus::kWithoutDepth) {
      std::vector<Eigen::Vector2f> segment;
      edge(p.segment_start, p.segment_end, segment);
      segment.push_back(p.segment_end);
      polyline(segment, kWindow, false);
    } else if (p.covariance.squaredNorm() > 0.0f) {
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix2f> es(p.covariance);
      const Eigen::Vector2f ev = es.eigenvalues().cwiseMax(0.0f);
      const float gate = std::sqrt(9.21f);  // 99% gate, 2 dof
      std::vector<Eigen::Vector2f> ellipse;
      for (int i = 0; i < 32; ++i) {
        const float t = static_cast<float>(i) * 2.0f * static_cast<float>(M_PI) / 32.0f;
        ellipse.push_back(p.uv +
                          gate * (std::cos(t) * std::sqrt(ev(1)) * es.eigenvectors().col(1) +
                                  std::sin(t) * std::sqrt(ev(0)) * es.eigenvectors().col(0)));
      }
      polyline(ellipse, kEllipse, true);
    }
  }
  int correct = 0;
  for (size_t i = 0; i < run.matches.size(); ++i) {
    const Match& m = run.matches[i];
    const cv::Point2f pa = visual.keypoints_a[m.query_idx].pt + off_a;
    // A track (train_idx -1) and a refined match end at the refined position.
    const cv::Point2f pb = (m.refined_uv_b.allFinite() || m.train_idx < 0
                                ? cv::Point2f(m.refined_uv_b.x(), m.refined_uv_b.y())
                                : visual.keypoints_b[static_cast<size_t>(m.train_idx)].pt) +
                           off_b;
    const MatchResidual& r = run.residuals[i];
    const bool ok = r.CorrectAt(options.threshold_px);
    if (ok) {
      ++correct;
      cv::line(canvas, pa, pb, kGreen, 1, cv::LINE_AA);
    } else {
      DashedLine(canvas, pa, pb, kRed, 1);
    }
    cv::circle(canvas, pa, 3, ok ? kGreen : kRed, 1, cv::LINE_AA);
    cv::circle(canvas, pb, 3, ok ? kGreen : kRed, 1, cv::LINE_AA);
  }
  std::ostringstream text;
  text << visual.case_name << " pair " << visual.pair_index << "  " << ToString(visual.detector)
       << "  " << DisplayName(run.method) << ": " << run.matches.size() << " matches, " << correct
       << " correct (green), " << run.matches.size() - static_cast<size_t>(correct)
       << " false (red dashed) @ " << std::fixed << std::setprecision(1) << options.threshold_px
       << " px";
  if (!run.predictions.empty()) text << "; windows on B";
  cv::putText(canvas, text.str(), {8, 23}, cv::FONT_HERSHEY_SIMPLEX, 0.55, cv::Scalar(0, 0, 0), 1,
              cv::LINE_AA);
  cv::line(canvas, {a.cols, header}, {a.cols, canvas.rows}, cv::Scalar(255, 255, 255), 2);
  return canvas;
}

std::vector<std::string> WriteMatchImages(const std::string& dir,
                                          const std::vector<PairVisual>& visuals,
                                          const MatchImageOptions& options) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw Error("cannot create output folder " + dir + ": " + ec.message());
  std::vector<std::string> written;
  for (const PairVisual& v : visuals) {
    for (size_t i = 0; i < v.runs.size(); ++i) {
      const std::string name = "match_" + Safe(v.case_name) + "_" + std::to_string(v.pair_index) +
                               "_" + ToString(v.detector) + "_" + ToString(v.runs[i].method) +
                               ".png";
      const std::string path = (std::filesystem::path(dir) / name).string();
      WriteImage(path, DrawMatchImage(v, i, options));
      written.push_back(path);
    }
  }
  return written;
}

}  // namespace imumatch
