// Small order statistics shared by the motion checks and the metrics.
//
//   double m = median({3.0, 1.0, 2.0, 10.0});   // 2.5
#pragma once

#include <vector>

namespace nec {

// The median (the mean of the two middle values for an even count); 0 for no values.
double median(std::vector<double> values);
// The upper of the two middle values for an even count (a value of the set); 0 for no values.
double upper_median(std::vector<double> values);
// The value at index floor(q × (n − 1)) of the sorted values, q in [0, 1]; 0 for no values.
double lower_quantile(std::vector<double> values, double q);

}  // namespace nec
