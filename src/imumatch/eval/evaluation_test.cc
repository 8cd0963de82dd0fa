#include "imumatch/eval/evaluation.h"

#include <gtest/gtest.h>

#include "imumatch/core/error.h"

namespace imumatch {
namespace {

std::vector<FrameRecord> Frames(std::initializer_list<double> t_s) {
  std::vector<FrameRecord> out;
  for (double t : t_s) {
    FrameRecord f;
    f.t_ns = SecondsToNs(t);
    out.push_back(f);
  }
  return out;
}

TEST(EvaluationTest, ConsecutiveAndStepPairs) {
  const auto frames = Frames({0.0, 0.1, 0.2, 0.3, 0.4});
  PairSelection s;
  auto p = SelectFramePairs(frames, s);
  ASSERT_EQ(p.size(), 4u);
  EXPECT_EQ(p[3].a, 3u);
  EXPECT_EQ(p[3].b, 4u);
  s.step = 2;
  p = SelectFramePairs(frames, s);
  ASSERT_EQ(p.size(), 2u);  // (0,2), (2,4)
  EXPECT_EQ(p[1].a, 2u);
  EXPECT_EQ(p[1].b, 4u);
  s.step = 1;
  s.max_pairs = 3;
  EXPECT_EQ(SelectFramePairs(frames, s).size(), 3u);
}

TEST(EvaluationTest, IntervalPairsTakeTheNearestFrame) {
  // 30 Hz-ish timestamps; a 2 s interval from t=0 lands on the frame nearest to 2.0 s.
  std::vector<FrameRecord> frames;
  for (int i = 0; i <= 130; ++i) {
    FrameRecord f;
    f.t_ns = SecondsToNs(i * 0.0333);
    frames.push_back(f);
  }
  PairSelection s;
  s.interval_s = 2.0;
  const auto p = SelectFramePairs(frames, s);
  ASSERT_EQ(p.size(), 2u);  // 0 -> 60 (1.998 s), 60 -> 120; 120 -> 130 is too short
  EXPECT_EQ(p[0].a, 0u);
  EXPECT_EQ(p[0].b, 60u);
  EXPECT_EQ(p[1].b, 120u);
}

TEST(EvaluationTest, ExplicitPairsAreChecked) {
  const auto frames = Frames({0.0, 0.1, 0.2});
  PairSelection s;
  s.explicit_pairs = {{0, 2}};
  EXPECT_EQ(SelectFramePairs(frames, s).size(), 1u);
  s.explicit_pairs = {{0, 3}};
  EXPECT_THROW(SelectFramePairs(frames, s), InvalidArgument);
  s.explicit_pairs = {{1, 1}};
  EXPECT_THROW(SelectFramePairs(frames, s), InvalidArgument);
  s.explicit_pairs.clear();
  s.step = 0;
  EXPECT_THROW(SelectFramePairs(frames, s), InvalidArgument);
}

TEST(EvaluationTest, PadBinaryDescriptorsKeepsHammingDistances) {
  cv::Mat a(2, 61, CV_8U), b(2, 61, CV_8U);
  cv::randu(a, 0, 256);
  cv::randu(b, 0, 256);
  const cv::Mat pa = PadBinaryDescriptors(a), pb = PadBinaryDescriptors(b);
  EXPECT_EQ(pa.cols, 64);
  EXPECT_EQ(cv::norm(a.row(0), b.row(1), cv::NORM_HAMMING),
            cv::norm(pa.row(0), pb.row(1), cv::NORM_HAMMING));
  cv::Mat f(2, 64, CV_32F, cv::Scalar(1.0f));
  EXPECT_EQ(PadBinaryDescriptors(f).data, f.data);  // float: untouched
}

TEST(EvaluationTest, MethodAndMotionSourceNames) {
  for (MatchMethod m : {MatchMethod::kBruteForce, MatchMethod::kGuided, MatchMethod::kFixedWindow,
                        MatchMethod::kOwnBruteForce}) {
    EXPECT_EQ(ParseMatchMethod(ToString(m)), m);
  }
  EXPECT_THROW(ParseMatchMethod("flann"), InvalidArgument);
  EXPECT_EQ(ParseMotionSource("gt"), MotionSource::kGroundTruth);
  EXPECT_THROW(ParseMotionSource("vio"), InvalidArgument);
  EvaluationOptions o;
  o.detectors.clear();
  EXPECT_THROW(o.Check(), InvalidArgument);
}

}  // namespace
}  // namespace imumatch
