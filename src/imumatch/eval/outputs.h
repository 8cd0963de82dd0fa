#pragma once

#include <string>
#include <vector>

#include "imumatch/eval/end_to_end.h"
#include "imumatch/eval/evaluation.h"
#include "imumatch/eval/report.h"
#include "imumatch/eval/summary.h"

namespace imumatch {

// Everything the CLI writes into its output folder: report.md/.json, summary/pairs/skipped CSV,
// per-pair time and precision plots, and match images of the kept visuals (at the context's
// threshold). Returns the paths written.
std::vector<std::string> WriteEvaluationOutputs(const std::string& dir,
                                                const EvaluationResult& result,
                                                const ReportContext& context);

}  // namespace imumatch
