#pragma once

#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "imumatch/eval/end_to_end.h"
#include "imumatch/eval/evaluation.h"
#include "imumatch/eval/summary.h"

namespace imumatch {

// Minimal line plots drawn with OpenCV primitives (no plotting library): axes with "nice" ticks,
// grid, axis labels, title, legend, one polyline with point markers per series.
struct PlotSeries {
  std::string label;
  std::vector<double> x, y;                // same length; non-finite points are skipped
  cv::Scalar color = cv::Scalar(0, 0, 0);  // BGR
};

struct PlotOptions {
  std::string title;
  std::string x_label;
  std::string y_label;
  int width = 960;
  int height = 540;
  bool y_from_zero = true;  // include 0 in the y range
  double y_max = 0.0;       // > 0: fixed upper end of the y axis (e.g. 1 for precision)
  void Check() const;
};

// Tick values covering [lo, hi] with a 1/2/5 x 10^k step, about `target` of them.
std::vector<double> NiceTicks(double lo, double hi, int target = 6);

// Draws the plot on a white CV_8UC3 image. Throws InvalidArgument for bad options or series whose
// x and y lengths differ.
cv::Mat DrawLinePlot(const std::vector<PlotSeries>& series, const PlotOptions& options);

// The colour used for a method in every plot and match image legend.
cv::Scalar MethodColor(MatchMethod method);

// For every detector: time_<detector>.png (prediction + matching time per pair and method) and
// precision_<detector>.png (precision per pair at threshold_px). x = pair ordinal over all cases
// in record order. Returns the paths written (dir is created when missing).
std::vector<std::string> WritePerPairPlots(const std::string& dir,
                                           const std::vector<DetectorPairRecord>& records,
                                           double threshold_px);

}  // namespace imumatch
