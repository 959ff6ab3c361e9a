// Range noise: a line sigma(r) = sigma0 + per_metre r measured from the data
// (scanlines/steps/noise.py).
#pragma once

#include <utility>

#include "scanlines/core.hpp"
#include "scanlines/steps/fit.hpp"

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

struct PowerSums {
    double s0, s1, s2, s3, s4;
};
// Sums of t^0 .. t^4 over the beam offsets t = index[p] - index[i] of positions a..b.
PowerSums offset_power_sums(const Index* index, Index a, Index b, Index i);

struct Parabola {
    double residual, leverage, slope;
};
// Least-squares parabola of r over the beam offsets of positions a..b (their power sums
// s): (r[i] - fit at i, leverage of i, slope at i per beam).
Parabola parabola_at_centre(const Index* index, const double* r, Index a, Index b, Index i,
                            const PowerSums& s);

// Range-noise samples of a scan and the range of each.
std::pair<Reals, Reals> local_residuals(const Returns& returns, const Ints& gap);

// The noise line of samples taken at ranges; NaN fields with fewer than MIN_SAMPLES.
NoiseLine noise_line_of(const Reals& sample, const Reals& at);

// The noise line of one scan; a constant MIN_NOISE_SIGMA without enough samples.
NoiseLine scan_noise(const Returns& returns, const Ints& gap);

// noise if known, else the scan's own.
NoiseLine resolve_noise(NoiseLine noise, const Returns& returns, const Ints& gap);

// The noise sigma at each range.
Reals return_sigmas(const Reals& r, NoiseLine noise);

// Per-return sigma of the segment covariances: range_sigma where it is a number (NaN: not
// given), else noise as resolve_noise resolves it.
Reals covariance_sigmas(double range_sigma, NoiseLine noise, const Returns& returns,
                        const Ints& gap);

// The median of values, as numpy's (the mean of the middle two of an even count).
double median(Reals values);

}  // namespace scanlines
