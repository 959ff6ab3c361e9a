// Merging neighbouring runs (scanlines/steps/merge.py).
#pragma once

#include "scanlines/core.hpp"
#include "scanlines/steps/fit.hpp"
#include "scanlines/steps/split.hpp"

namespace scanlines {

// dL^T (P_1 + P_2)^-1 dL of two lines (covariances row-major 2 x 2); NaN where singular.
double chi_square(double rho_1, double alpha_1, double rho_2, double alpha_2,
                  const double* covariance_1, const double* covariance_2);

// Merge neighbouring runs of one group while their lines pass the chi-square test.
GroupedRuns merge_by_chi_square(const Returns& returns, const Moments& moments, const Ints& a,
                         const Ints& b, const Ints& group, const Reals& sigma, double threshold,
                         bool inflate);

}  // namespace scanlines
