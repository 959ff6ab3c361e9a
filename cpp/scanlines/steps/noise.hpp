// Range noise: a line sigma(r) = sigma0 + per_metre r measured from the data
// (scanlines/steps/noise.py).
#pragma once

#include <utility>

#include "scanlines/core.hpp"

namespace scanlines {

constexpr double MIN_NOISE_SIGMA = 1e-3;
constexpr Index NOISE_HALF_WINDOW = 3;
constexpr Index MIN_SAMPLES_PER_BIN = 40;
constexpr Index MAX_BINS = 4;
constexpr double SLOPE_SIGNIFICANCE = 2.0;
constexpr Index MIN_SAMPLES = 5;

inline double noise_at(NoiseLine noise, double r) {
    double sigma = noise.sigma0 + noise.per_metre * r;
    return MIN_NOISE_SIGMA > sigma ? MIN_NOISE_SIGMA : sigma;  // Python's max(sigma, floor)
}

// Range-noise samples of a scan and the range of each.
std::pair<Reals, Reals> local_residuals(const Returns& returns, const Ints& gap);

// The noise line of samples taken at ranges; NaN fields with fewer than MIN_SAMPLES.
NoiseLine noise_line_of(const Reals& sample, const Reals& at);

// The noise line of one scan; a constant MIN_NOISE_SIGMA without enough samples.
NoiseLine scan_noise(const Returns& returns, const Ints& gap);

// noise if known, else the scan's own.
NoiseLine resolve_noise(NoiseLine noise, const Returns& returns, const Ints& gap);

// The median of values, as numpy's (the mean of the middle two of an even count).
double median(Reals values);

}  // namespace scanlines
