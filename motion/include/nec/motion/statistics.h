// Small order statistics shared by the motion checks and the metrics.
//
//   double m = median({3.0, 1.0, 2.0, 10.0});   // 2.5
#pragma once

#include <vector>

namespace nec {

// The median (the mean of the two middle values for an even count); 0 for no values.
double median(std::vector<double> values);

}  // namespace nec
