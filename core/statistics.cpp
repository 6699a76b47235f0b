#include "core/statistics.h"

#include <algorithm>

#include "core/error.h"

namespace dvso {

double Median(std::vector<double> values) {
  Require(!values.empty(), "Median: no values");
  const size_t middle = values.size() / 2;
  std::nth_element(values.begin(), values.begin() + middle, values.end());
  const double upper = values[middle];
  if (values.size() % 2 == 1) return upper;
  // nth_element leaves the lower half before `middle`: its largest is the other middle value.
  return 0.5 * (upper + *std::max_element(values.begin(), values.begin() + middle));
}

}  // namespace dvso
