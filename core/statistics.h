// Small statistics shared by the evaluation, the stereo brightness transfer and the benchmarks. (The label
// writer's float median and the mono initialiser's upper median are their own: changing them would change
// labels and initialisations.)
#pragma once

#include <vector>

namespace dvso {

// Median with numpy.median's semantics: the mean of the two middle values for an even count.
// Throws dvso::Error for no values (callers decide what an empty set means).
double Median(std::vector<double> values);

}  // namespace dvso
