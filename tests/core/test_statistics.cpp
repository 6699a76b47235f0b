// core/statistics.h by hand.
#include <gtest/gtest.h>

#include <vector>

#include "core/error.h"
#include "core/statistics.h"

namespace dvso {
namespace {

TEST(Statistics, MedianOfAnOddCountIsTheMiddleValue) {
  EXPECT_EQ(Median({3.0, -1.0, 7.0}), 3.0);
  EXPECT_EQ(Median({5.0}), 5.0);
}

TEST(Statistics, MedianOfAnEvenCountIsTheMeanOfTheTwoMiddleValues) {
  EXPECT_EQ(Median({4.0, 1.0, 3.0, 2.0}), 2.5);      // numpy.median([4, 1, 3, 2]) = 2.5
  EXPECT_EQ(Median({10.0, 0.0, 0.0, 10.0}), 5.0);
  EXPECT_EQ(Median({9.0, 8.0, 1.0, 2.0, 3.0, 7.0}), 5.0);  // middle two 3 and 7
}

TEST(Statistics, MedianOfNoValuesIsAnError) { EXPECT_THROW(Median({}), Error); }

}  // namespace
}  // namespace dvso
