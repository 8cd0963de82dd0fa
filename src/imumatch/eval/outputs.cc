#include "imumatch/eval/outputs.h"

#include "imumatch/eval/match_image.h"
#include "imumatch/eval/plots.h"

namespace imumatch {

std::vector<std::string> WriteEvaluationOutputs(const std::string& dir,
                                                const EvaluationResult& result,
                                                const ReportContext& context) {
  std::vector<std::string> written = WriteReportFiles(dir, result, context);
  for (auto& p : WritePerPairPlots(dir, result.records, context.threshold.threshold_px)) {
    written.push_back(std::move(p));
  }
  MatchImageOptions mo;
  mo.threshold_px = context.threshold.threshold_px;
  for (auto& p : WriteMatchImages(dir, result.visuals, mo)) written.push_back(std::move(p));
  return written;
}

}  // namespace imumatch
