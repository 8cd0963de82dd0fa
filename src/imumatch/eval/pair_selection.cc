#include "imumatch/eval/pair_selection.h"

#include <cmath>
#include <cstdlib>
#include <sstream>

#include "imumatch/core/error.h"
#include "imumatch/core/time.h"

namespace imumatch {

void PairSelection::Check() const {
  IMUMATCH_CHECK(std::isfinite(interval_s) && interval_s >= 0.0, "interval_s = " << interval_s);
  IMUMATCH_CHECK(step >= 1, "step = " << step);
}

std::vector<FramePair> SelectFramePairs(const std::vector<FrameRecord>& frames,
                                        const PairSelection& selection) {
  selection.Check();
  std::vector<FramePair> pairs;
  const size_t n = frames.size();
  auto full = [&] { return selection.max_pairs > 0 && pairs.size() >= selection.max_pairs; };
  if (!selection.explicit_pairs.empty()) {
    for (const FramePair& p : selection.explicit_pairs) {
      IMUMATCH_CHECK(p.a < n && p.b < n,
                     "frame pair (" << p.a << ", " << p.b << ") outside the " << n << " frames");
      IMUMATCH_CHECK(p.a != p.b, "frame pair (" << p.a << ", " << p.b << ") uses one frame twice");
      if (full()) break;
      pairs.push_back(p);
    }
    return pairs;
  }
  if (selection.interval_s > 0.0) {
    const int64_t interval_ns = SecondsToNs(selection.interval_s);
    size_t a = 0;
    while (a + 1 < n && !full()) {
      const int64_t target = frames[a].t_ns + interval_ns;
      size_t b = a + 1;
      while (b + 1 < n &&
             std::llabs(frames[b + 1].t_ns - target) <= std::llabs(frames[b].t_ns - target))
        ++b;
      // Stop when the sequence ends before the interval is (nearly) covered.
      if (frames[b].t_ns - frames[a].t_ns < interval_ns / 2) break;
      pairs.push_back({a, b});
      a = b;
    }
    return pairs;
  }
  const size_t step = static_cast<size_t>(selection.step);
  for (size_t a = 0; a + step < n && !full(); a += step) pairs.push_back({a, a + step});
  return pairs;
}

std::string WhyNoFramePairs(const std::vector<FrameRecord>& frames,
                            const PairSelection& selection) {
  std::string why = std::to_string(frames.size()) + (frames.size() == 1 ? " frame" : " frames");
  if (frames.size() < 2) return why;
  why += " over " + FormatNsAsSeconds(frames.back().t_ns - frames.front().t_ns) + " s";
  if (!selection.explicit_pairs.empty()) return why;
  if (selection.interval_s > 0.0) {
    std::ostringstream s;
    s << selection.interval_s;
    return why + ", none with a partner " + s.str() + " s later (--interval)";
  }
  if (static_cast<size_t>(selection.step) >= frames.size()) {
    why += ", fewer than --step " + std::to_string(selection.step) + " + 1";
  }
  return why;
}

}  // namespace imumatch
