#include "scanlines/steps/noise.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "scanlines/steps/returns.hpp"

namespace scanlines {

PowerSums offset_power_sums(const Index* index, Index a, Index b, Index i) {
    PowerSums s{0.0, 0.0, 0.0, 0.0, 0.0};
    for (Index p = a; p <= b; ++p) {
        double t = static_cast<double>(index[p] - index[i]);
        double t_2 = t * t;
        s.s0 += 1.0;
        s.s1 += t;
        s.s2 += t_2;
        s.s3 += t_2 * t;
        s.s4 += t_2 * t_2;
    }
    return s;
}

Parabola parabola_at_centre(const Index* index, const double* r, Index a, Index b, Index i,
                            const PowerSums& s) {
    double t0 = 0.0, t1 = 0.0, t2 = 0.0;
    for (Index p = a; p <= b; ++p) {
        double t = static_cast<double>(index[p] - index[i]);
        t0 += r[p];
        t1 += r[p] * t;
        t2 += r[p] * t * t;
    }
    double m00 = s.s0, m01 = s.s1, m02 = s.s2, m11 = s.s2, m12 = s.s3, m22 = s.s4;
    double c00 = m11 * m22 - m12 * m12;
    double c01 = m02 * m12 - m01 * m22;
    double c02 = m01 * m12 - m02 * m11;
    double det = m00 * c00 + m01 * c01 + m02 * c02;
    if (det == 0.0) return {0.0, 1.0, 0.0};
    double c11 = m00 * m22 - m02 * m02;
    double c12 = m01 * m02 - m00 * m12;
    double value = (c00 * t0 + c01 * t1 + c02 * t2) / det;
    double slope = (c01 * t0 + c11 * t1 + c12 * t2) / det;
    return {r[i] - value, c00 / det, slope};
}

std::pair<Reals, Reals> local_residuals(const Returns& returns, const Ints& gap) {
    const Index n = returns.size();
    const Index h = NOISE_HALF_WINDOW;
    Reals sample, at;
    if (n < 2 * h + 1) return {sample, at};
    const Index* index = returns.index.data();
    const double* r = returns.r.data();
    const Reals& x = returns.x;
    const Reals& y = returns.y;
    Ints stretch_start(n);
    stretch_start[0] = 0;
    for (Index i = 1; i < n; ++i)
        stretch_start[i] = gap[i - 1] <= MAX_BRIDGED_GAP ? stretch_start[i - 1] : i;
    Ints offsets(2 * h + 1);
    std::iota(offsets.begin(), offsets.end(), Index{0});
    const PowerSums contiguous = offset_power_sums(offsets.data(), 0, 2 * h, h);
    for (Index i = h; i < n - h; ++i) {
        if (stretch_start[i + h] > i - h || r[i] <= 0.0) continue;
        Index a = i - h, b = i + h;
        PowerSums sums = index[b] - index[a] == 2 * h ? contiguous
                                                      : offset_power_sums(index, a, b, i);
        Parabola fit = parabola_at_centre(index, r, a, b, i, sums);
        if (!(fit.leverage < 1.0)) continue;
        double bearing = std::fabs(std::atan2(x[a] * y[b] - y[a] * x[b], x[a] * x[b] + y[a] * y[b]));
        double per_beam = bearing / static_cast<double>(index[b] - index[a]);
        if (!(std::fabs(fit.slope) <= r[i] * per_beam)) continue;
        sample.push_back(std::fabs(fit.residual) / std::sqrt(1.0 - fit.leverage));
        at.push_back(r[i]);
    }
    return {sample, at};
}

double median(Reals values) {
    const std::size_t n = values.size();
    if (n == 0) return NAN;
    const std::size_t half = n / 2;
    std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(half),
                     values.end());
    double upper = values[half];
    if (n % 2 == 1) return upper;
    double lower = *std::max_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(half));
    return (lower + upper) / 2;
}

NoiseLine noise_line_of(const Reals& sample, const Reals& at) {
    const Index n = static_cast<Index>(sample.size());
    Index bins = std::min(MAX_BINS, n / MIN_SAMPLES_PER_BIN);
    if (bins == 0) {
        if (n < MIN_SAMPLES) return {NAN, NAN};
        bins = 1;
    }
    Ints order(n);
    std::iota(order.begin(), order.end(), Index{0});
    std::stable_sort(order.begin(), order.end(), [&](Index i, Index j) { return at[i] < at[j]; });
    Reals sigma(bins), where(bins), weight(bins);
    for (Index k = 0; k < bins; ++k) {
        Index lo = k * n / bins, hi = (k + 1) * n / bins;
        Reals part_sample, part_at;
        for (Index j = lo; j < hi; ++j) {
            part_sample.push_back(sample[order[j]]);
            part_at.push_back(at[order[j]]);
        }
        sigma[k] = median(part_sample) / 0.6745;
        where[k] = median(part_at);
        double spread = std::max(1.17 * sigma[k], MIN_NOISE_SIGMA);
        weight[k] = static_cast<double>(hi - lo) / (spread * spread);
    }
    double total = 0.0, sum_r = 0.0, sum_s = 0.0;
    for (Index k = 0; k < bins; ++k) total += weight[k];
    for (Index k = 0; k < bins; ++k) sum_r += weight[k] * where[k];
    for (Index k = 0; k < bins; ++k) sum_s += weight[k] * sigma[k];
    double mean_r = sum_r / total, mean_s = sum_s / total;
    double spread = 0.0;
    for (Index k = 0; k < bins; ++k) {
        double d = where[k] - mean_r;
        spread += weight[k] * (d * d);
    }
    double slope = 0.0;
    if (bins > 1 && spread > 0.0) {
        double cross = 0.0;
        for (Index k = 0; k < bins; ++k) cross += weight[k] * (where[k] - mean_r) * (sigma[k] - mean_s);
        slope = cross / spread;
        if (slope < SLOPE_SIGNIFICANCE / std::sqrt(spread)) slope = 0.0;
    }
    return {std::max(mean_s - slope * mean_r, 0.0), slope};
}

NoiseLine scan_noise(const Returns& returns, const Ints& gap) {
    auto [sample, at] = local_residuals(returns, gap);
    NoiseLine noise = noise_line_of(sample, at);
    if (!noise.known()) return {MIN_NOISE_SIGMA, 0.0};
    return noise;
}

NoiseLine resolve_noise(NoiseLine noise, const Returns& returns, const Ints& gap) {
    if (noise.known()) return noise;
    return scan_noise(returns, gap);
}

Reals return_sigmas(const Reals& r, NoiseLine noise) {
    Reals out(r.size());
    for (std::size_t i = 0; i < r.size(); ++i) out[i] = noise_at(noise, r[i]);
    return out;
}

Reals covariance_sigmas(double range_sigma, NoiseLine noise, const Returns& returns,
                        const Ints& gap) {
    if (range_sigma == range_sigma) return Reals(returns.r.size(), range_sigma);
    return return_sigmas(returns.r, resolve_noise(noise, returns, gap));
}

}  // namespace scanlines
