#include "neraf/util/number_text.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <limits>
#include <string>
#include <thread>

namespace neraf {
namespace {

TEST(CheckInteger, AcceptsDecimalAndWholeScientific) {
  std::string out;
  EXPECT_EQ(check_integer("42", 1, 100, &out), "");
  EXPECT_EQ(out, "42");
  EXPECT_EQ(check_integer("+7", 1, 100, &out), "");
  EXPECT_EQ(out, "7");
  EXPECT_EQ(check_integer("-1", -1, 10, &out), "");
  EXPECT_EQ(out, "-1");
  EXPECT_EQ(check_integer("1e3", 1, 100000, &out), "");
  EXPECT_EQ(out, "1000");
  EXPECT_EQ(check_integer("2.5e1", 1, 100, &out), "");
  EXPECT_EQ(out, "25");
  EXPECT_EQ(check_integer("100", 1, 100), "");  // bounds are inclusive
  EXPECT_EQ(check_integer("1", 1, 100), "");
}

TEST(CheckInteger, RefusesOverflowInsteadOfWrapping) {
  // strtoll saturates at 2^63 - 1 and CLI11 passed that on: a huge --steps became 9.2e18.
  const std::string why = check_integer("99999999999999999999", 1, 100000000);
  EXPECT_NE(why.find("must be a whole number in [1, 100000000]"), std::string::npos) << why;
  EXPECT_NE(why.find("got 99999999999999999999"), std::string::npos) << why;
  EXPECT_NE(check_integer("-99999999999999999999", -1, 10), "");
  EXPECT_NE(check_integer("1e23", 1, 100000000), "");
  EXPECT_NE(check_integer("9223372036854775808", std::numeric_limits<int64_t>::min(),
                          std::numeric_limits<int64_t>::max()),
            "");
}

TEST(CheckInteger, RefusesOutOfRangeFractionsAndText) {
  EXPECT_NE(check_integer("0", 1, 100), "");
  EXPECT_NE(check_integer("101", 1, 100), "");
  EXPECT_NE(check_integer("-2", -1, 100), "");
  for (const char* bad : {"1.5", "1e-1", "abc", "", " 5", "5 ", "5x", "0x10", "nan", "inf", "-",
                          "1e", "e3", "--5", "1,000"})
    EXPECT_NE(check_integer(bad, -100, 100), "") << bad;
}

TEST(CheckUnsigned, RefusesNegativeAndOverflow) {
  const uint64_t max = std::numeric_limits<uint64_t>::max();
  std::string out;
  EXPECT_EQ(check_unsigned("0", max, &out), "");
  EXPECT_EQ(out, "0");
  EXPECT_EQ(check_unsigned("18446744073709551615", max, &out), "");
  EXPECT_EQ(out, "18446744073709551615");
  EXPECT_EQ(check_unsigned("1e6", max, &out), "");
  EXPECT_EQ(out, "1000000");
  // strtoull turns "-1" into 2^64 - 1; that is what --seed -1 used to become.
  EXPECT_NE(check_unsigned("-1", max), "");
  EXPECT_NE(check_unsigned("-0", max), "");
  EXPECT_NE(check_unsigned("18446744073709551616", max), "");
  EXPECT_NE(check_unsigned("1e23", max), "");
  EXPECT_NE(check_unsigned("1.5", max), "");
  EXPECT_NE(check_unsigned("seven", max), "");
  EXPECT_NE(check_unsigned("11", 10), "");
  EXPECT_NE(check_unsigned("11", 10).find("[0, 10]"), std::string::npos);
}

TEST(CheckReal, FiniteAndInRange) {
  EXPECT_EQ(check_real("0.5", 0, 1), "");
  EXPECT_EQ(check_real("1", 0, 1), "");
  EXPECT_EQ(check_real("0", 0, 1), "");
  EXPECT_EQ(check_real("1e-3", 0, 1), "");
  EXPECT_EQ(check_real(".5", 0, 1), "");
  EXPECT_EQ(check_real("-90", -360, 360), "");
  EXPECT_NE(check_real("0", 0, 1, /*lo_open=*/true), "");
  EXPECT_NE(check_real("0", 0, 1, true).find("(0, 1]"), std::string::npos);
  EXPECT_NE(check_real("1.0001", 0, 1), "");
  EXPECT_NE(check_real("-1e-9", 0, 1), "");
  // CLI::Range lets NaN through (every comparison with it is false).
  for (const char* bad : {"nan", "NaN", "-nan", "inf", "-inf", "Infinity", "1e999", "abc", "",
                          "1.2.3", "0x1p3", "1e", " 1"})
    EXPECT_NE(check_real(bad, -1e300, 1e300), "") << bad;
}

TEST(RangeText, AsTheHelpShowsIt) {
  EXPECT_EQ(range_text(int64_t{1}, int64_t{1024}), "[1, 1024]");
  EXPECT_EQ(range_text(0.0, 1.0, true), "(0, 1]");
  EXPECT_EQ(range_text(0.01, 120.0), "[0.01, 120]");
}

TEST(MaxThreadCount, FourTimesTheHardwareThreads) {
  const unsigned hw = std::thread::hardware_concurrency();
  EXPECT_EQ(max_thread_count(), 4 * static_cast<int>(hw > 0 ? hw : 1));
  EXPECT_GE(max_thread_count(), 4);
}

}  // namespace
}  // namespace neraf
