#include "imumatch/eval/plots.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <map>
#include <sstream>

#include <opencv2/imgproc.hpp>

#include "imumatch/core/error.h"
#include "imumatch/io/image_io.h"

namespace imumatch {
namespace {

std::string TickLabel(double v, double step) {
  std::ostringstream out;
  const int digits = step >= 1.0 ? 0 : static_cast<int>(std::ceil(-std::log10(step) - 1e-9));
  out << std::fixed << std::setprecision(std::clamp(digits, 0, 6)) << v;
  return out.str();
}

void PutText(cv::Mat& img, const std::string& text, cv::Point org, double scale,
             const cv::Scalar& color = cv::Scalar(0, 0, 0), int thickness = 1) {
  cv::putText(img, text, org, cv::FONT_HERSHEY_SIMPLEX, scale, color, thickness, cv::LINE_AA);
}

cv::Size TextSize(const std::string& text, double scale, int thickness = 1) {
  int baseline = 0;
  return cv::getTextSize(text, cv::FONT_HERSHEY_SIMPLEX, scale, thickness, &baseline);
}

}  // namespace

void PlotOptions::Check() const {
  IMUMATCH_CHECK(width >= 200 && height >= 150, "plot size " << width << "x" << height);
  IMUMATCH_CHECK(std::isfinite(y_max) && y_max >= 0.0, "y_max = " << y_max);
}

std::vector<double> NiceTicks(double lo, double hi, int target) {
  std::vector<double> ticks;
  if (!(std::isfinite(lo) && std::isfinite(hi)) || target < 1) return ticks;
  if (hi <= lo) hi = lo + 1.0;
  const double raw = (hi - lo) / target;
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  double step = mag;
  for (double m : {1.0, 2.0, 5.0, 10.0}) {
    step = m * mag;
    if (step >= raw) break;
  }
  const double first = std::ceil(lo / step - 1e-9) * step;
  for (double v = first; v <= hi + 1e-9 * step; v += step)
    ticks.push_back(std::abs(v) < 1e-12 * step ? 0.0 : v);
  return ticks;
}

cv::Scalar MethodColor(MatchMethod method) {
  switch (method) {
    case MatchMethod::kBruteForce:
      return cv::Scalar(40, 40, 220);  // red
    case MatchMethod::kGuided:
      return cv::Scalar(60, 160, 40);  // green
    case MatchMethod::kFixedWindow:
      return cv::Scalar(200, 120, 30);  // blue
    case MatchMethod::kOwnBruteForce:
      return cv::Scalar(20, 140, 230);  // orange
    case MatchMethod::kKltUnseeded:
      return cv::Scalar(140, 140, 140);  // grey
    case MatchMethod::kKlt:
      return cv::Scalar(180, 60, 160);  // purple
    case MatchMethod::kHybrid:
      return cv::Scalar(30, 30, 30);  // black
  }
  return cv::Scalar(0, 0, 0);
}

cv::Mat DrawLinePlot(const std::vector<PlotSeries>& series, const PlotOptions& options) {
  options.Check();
  double x0 = INFINITY, x1 = -INFINITY, y0 = INFINITY, y1 = -INFINITY;
  for (const auto& s : series) {
    IMUMATCH_CHECK(s.x.size() == s.y.size(), "series '" << s.label << "': x and y lengths differ");
    for (size_t i = 0; i < s.x.size(); ++i) {
      if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i])) continue;
      x0 = std::min(x0, s.x[i]);
      x1 = std::max(x1, s.x[i]);
      y0 = std::min(y0, s.y[i]);
      y1 = std::max(y1, s.y[i]);
    }
  }
  if (!std::isfinite(x0)) x0 = 0, x1 = 1, y0 = 0, y1 = 1;
  if (options.y_from_zero) y0 = std::min(y0, 0.0);
  if (options.y_max > 0.0) y1 = options.y_max;
  if (x1 <= x0) x0 -= 0.5, x1 += 0.5;
  if (y1 <= y0) y1 = y0 + 1.0;
  const std::vector<double> yt = NiceTicks(y0, y1, 6);
  if (!yt.empty() && options.y_max <= 0.0) y1 = std::max(y1, yt.back());
  const std::vector<double> xt = NiceTicks(x0, x1, 8);

  cv::Mat img(options.height, options.width, CV_8UC3, cv::Scalar(255, 255, 255));
  const int left = 80, right = 20, top = 50, bottom = 60;
  const cv::Rect area(left, top, options.width - left - right, options.height - top - bottom);
  auto px = [&](double x) {
    return area.x + static_cast<int>(std::lround((x - x0) / (x1 - x0) * area.width));
  };
  auto py = [&](double y) {
    return area.y + area.height - static_cast<int>(std::lround((y - y0) / (y1 - y0) * area.height));
  };
  const double ystep = yt.size() > 1 ? yt[1] - yt[0] : 1.0;
  const double xstep = xt.size() > 1 ? xt[1] - xt[0] : 1.0;
  for (double v : yt) {
    if (v < y0 - 1e-12 || v > y1 + 1e-12) continue;
    const int y = py(v);
    cv::line(img, {area.x, y}, {area.x + area.width, y}, cv::Scalar(225, 225, 225), 1);
    cv::line(img, {area.x - 5, y}, {area.x, y}, cv::Scalar(0, 0, 0), 1);
    const std::string label = TickLabel(v, ystep);
    const cv::Size ts = TextSize(label, 0.45);
    PutText(img, label, {area.x - 8 - ts.width, y + ts.height / 2}, 0.45);
  }
  for (double v : xt) {
    const int x = px(v);
    cv::line(img, {x, area.y}, {x, area.y + area.height}, cv::Scalar(235, 235, 235), 1);
    cv::line(img, {x, area.y + area.height}, {x, area.y + area.height + 5}, cv::Scalar(0, 0, 0), 1);
    const std::string label = TickLabel(v, xstep);
    const cv::Size ts = TextSize(label, 0.45);
    PutText(img, label, {x - ts.width / 2, area.y + area.height + 8 + ts.height}, 0.45);
  }
  cv::rectangle(img, area, cv::Scalar(0, 0, 0), 1);
  // Title and axis labels.
  {
    const cv::Size ts = TextSize(options.title, 0.65, 2);
    PutText(img, options.title, {(options.width - ts.width) / 2, 30}, 0.65, cv::Scalar(0, 0, 0), 2);
    const cv::Size xs = TextSize(options.x_label, 0.5);
    PutText(img, options.x_label, {area.x + (area.width - xs.width) / 2, options.height - 12}, 0.5);
    // y label: drawn horizontally and rotated by 90 degrees.
    const cv::Size ys = TextSize(options.y_label, 0.5);
    cv::Mat label(ys.height + 10, ys.width + 6, CV_8UC3, cv::Scalar(255, 255, 255));
    PutText(label, options.y_label, {3, ys.height + 3}, 0.5);
    cv::Mat rotated;
    cv::rotate(label, rotated, cv::ROTATE_90_COUNTERCLOCKWISE);
    const int yy = std::max(0, area.y + (area.height - rotated.rows) / 2);
    if (yy + rotated.rows <= img.rows && rotated.cols + 8 <= left) {
      rotated.copyTo(img(cv::Rect(8, yy, rotated.cols, rotated.rows)));
    }
  }
  // Series.
  for (const auto& s : series) {
    std::vector<cv::Point> pts;
    for (size_t i = 0; i < s.x.size(); ++i) {
      if (std::isfinite(s.x[i]) && std::isfinite(s.y[i])) pts.emplace_back(px(s.x[i]), py(s.y[i]));
    }
    if (pts.size() > 1) cv::polylines(img, pts, false, s.color, 2, cv::LINE_AA);
    if (pts.size() <= 60) {
      for (const auto& p : pts) cv::circle(img, p, 4, s.color, cv::FILLED, cv::LINE_AA);
    }
  }
  // Legend (top right, inside the plot area).
  int legend_w = 0;
  for (const auto& s : series) legend_w = std::max(legend_w, TextSize(s.label, 0.5).width);
  const int lx = area.x + area.width - legend_w - 50, ly = area.y + 10;
  if (!series.empty()) {
    const cv::Rect box(lx - 8, ly - 4, legend_w + 56, static_cast<int>(series.size()) * 22 + 6);
    cv::rectangle(img, box, cv::Scalar(255, 255, 255), cv::FILLED);
    cv::rectangle(img, box, cv::Scalar(120, 120, 120), 1);
  }
  for (size_t i = 0; i < series.size(); ++i) {
    const int y = ly + 12 + static_cast<int>(i) * 22;
    cv::line(img, {lx, y}, {lx + 30, y}, series[i].color, 3, cv::LINE_AA);
    PutText(img, series[i].label, {lx + 38, y + 5}, 0.5);
  }
  return img;
}

std::vector<std::string> WritePerPairPlots(const std::string& dir,
                                           const std::vector<DetectorPairRecord>& records,
                                           double threshold_px) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw Error("cannot create output folder " + dir + ": " + ec.message());
  std::vector<std::string> written;
  std::map<int, std::map<int, std::pair<PlotSeries, PlotSeries>>> by_detector;  // time, precision
  std::map<int, int> ordinal;
  for (const auto& r : records) {
    const int d = static_cast<int>(r.detector);
    const int x = ordinal[d]++;
    for (const auto& run : r.runs) {
      auto& [time, precision] = by_detector[d][static_cast<int>(run.method)];
      time.label = precision.label = DisplayName(run.method);
      time.color = precision.color = MethodColor(run.method);
      const double motion = UsesPrediction(run.method) ? r.motion_ms : 0.0;
      time.x.push_back(x);
      time.y.push_back(motion + run.predict_ms + run.match_ms);
      const RunCounts c = CountRun(r, run, threshold_px);
      precision.x.push_back(x);
      precision.y.push_back(c.counts.matches > 0 ? c.precision : NAN);
    }
  }
  for (const auto& [d, methods] : by_detector) {
    const std::string name = ToString(static_cast<DetectorKind>(d));
    std::vector<PlotSeries> time, precision;
    for (const auto& [m, s] : methods) {
      time.push_back(s.first);
      precision.push_back(s.second);
    }
    PlotOptions o;
    o.title = name + ": IMU motion + prediction + matching time per frame pair";
    o.x_label = "frame pair";
    o.y_label = "time [ms]";
    std::string path = (std::filesystem::path(dir) / ("time_" + name + ".png")).string();
    WriteImage(path, DrawLinePlot(time, o));
    written.push_back(path);
    std::ostringstream t;
    t << std::fixed << std::setprecision(2) << threshold_px;
    o.title = name + ": precision per frame pair (threshold " + t.str() + " px)";
    o.y_label = "precision";
    o.y_max = 1.0;
    path = (std::filesystem::path(dir) / ("precision_" + name + ".png")).string();
    WriteImage(path, DrawLinePlot(precision, o));
    written.push_back(path);
  }
  return written;
}

}  // namespace imumatch
