#include "imumatch/core/time.h"

#include <gtest/gtest.h>

#include "imumatch/core/error.h"

namespace imumatch {
namespace {

TEST(Time, ParsesDecimalSecondsExactly) {
  EXPECT_EQ(ParseSecondsToNs("1305031102.175304"), 1305031102175304000LL);
  EXPECT_EQ(ParseSecondsToNs("1305031102.1753040001"), 1305031102175304000LL);
  EXPECT_EQ(ParseSecondsToNs("1305031102.1753040005"), 1305031102175304001LL);
  EXPECT_EQ(ParseSecondsToNs(" 12 "), 12000000000LL);
  EXPECT_EQ(ParseSecondsToNs("-0.5"), -500000000LL);
  EXPECT_EQ(ParseSecondsToNs(".25"), 250000000LL);
  EXPECT_EQ(ParseSecondsToNs("1.5e3"), 1500000000000LL);
}

TEST(Time, RejectsMalformedSeconds) {
  for (const char* bad : {"", "abc", "1.2.3", "1,5", "nan", "inf", "1e300", "-", "."}) {
    EXPECT_THROW(ParseSecondsToNs(bad), InvalidArgument) << bad;
  }
}

TEST(Time, ParsesIntegerNanoseconds) {
  EXPECT_EQ(ParseNs("1403715273262142976"), 1403715273262142976LL);
  EXPECT_THROW(ParseNs("1403715273262142976.5"), InvalidArgument);
  EXPECT_THROW(ParseNs("99999999999999999999"), InvalidArgument);
  EXPECT_THROW(ParseNs(""), InvalidArgument);
}

TEST(Time, FormatsRoundTrip) {
  EXPECT_EQ(FormatNsAsSeconds(1305031102175304000LL), "1305031102.175304000");
  EXPECT_EQ(FormatNsAsSeconds(-500000000LL), "-0.500000000");
  EXPECT_EQ(ParseSecondsToNs(FormatNsAsSeconds(1403715273262142976LL)), 1403715273262142976LL);
  EXPECT_EQ(SecondsToNs(0.05), 50000000LL);
  EXPECT_DOUBLE_EQ(NsToSeconds(2500000000LL), 2.5);
}

}  // namespace
}  // namespace imumatch
