#include "scanlines/steps/assemble.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "scanlines/steps/events.hpp"
#include "scanlines/steps/noise.hpp"
#include "scanlines/steps/returns.hpp"

namespace scanlines {

ScanResult assemble(const Returns& returns, Index fit, const Moments& moments, const Ints& a,
                    const Ints& b, double angle_min, const Reals& sigma, Events events,
                    Index n_beams, bool wrap) {
    const Reals& x = returns.x;
    const Reals& y = returns.y;
    std::sort(events.breakpoints.begin(), events.breakpoints.end());
    std::sort(events.corners.begin(), events.corners.end());
    std::sort(events.outliers.begin(), events.outliers.end());
    Lines fitted = fit_many(fit, moments, a, b);
    Reals covariance = run_covariances(returns.r, returns.x, returns.y, fitted.rho, fitted.alpha, a, b, sigma,
                                       true);
    const std::size_t m = a.size();
    Reals lines(LINE_COLUMNS * m);
    const double cos_t = std::cos(angle_min), sin_t = std::sin(angle_min);
    for (std::size_t k = 0; k < m; ++k) {
        double* line = &lines[LINE_COLUMNS * k];
        const double rho = fitted.rho[k];
        const double c = std::cos(fitted.alpha[k]), s = std::sin(fitted.alpha[k]);
        double squares = 0.0;
        for (Index p = a[k]; p <= b[k]; ++p) {
            double off = x[p] * c + y[p] * s - rho;
            squares += off * off;
        }
        line[0] = rho;
        line[1] = wrap_angle(fitted.alpha[k] + angle_min);
        const Index ends[2] = {a[k], b[k]};
        for (int e = 0; e < 2; ++e) {
            Index p = ends[e];
            double off = x[p] * c + y[p] * s - rho;  // foot of the perpendicular onto the line
            double px = x[p] - off * c, py = y[p] - off * s;
            line[2 + 2 * e] = cos_t * px - sin_t * py;
            line[3 + 2 * e] = sin_t * px + cos_t * py;
        }
        line[6] = std::sqrt(squares / static_cast<double>(b[k] - a[k] + 1));
    }
    std::vector<std::int8_t> kinds =
        end_kinds(returns, a, b, n_beams, wrap, events.breakpoints, events.corners);
    std::vector<std::size_t> order(m);
    std::iota(order.begin(), order.end(), std::size_t{0});
    std::sort(order.begin(), order.end(), [&](std::size_t i, std::size_t j) {
        return returns.index[a[i]] < returns.index[a[j]];
    });
    ScanResult out;
    for (std::size_t k : order) {
        out.first.push_back(returns.index[a[k]]);
        out.last.push_back(returns.index[b[k]]);
        out.n_points.push_back(b[k] - a[k] + 1);
        out.lines.insert(out.lines.end(), &lines[LINE_COLUMNS * k], &lines[LINE_COLUMNS * (k + 1)]);
        out.covariances.insert(out.covariances.end(), &covariance[4 * k], &covariance[4 * k + 4]);
        out.end_kinds.push_back(kinds[2 * k]);
        out.end_kinds.push_back(kinds[2 * k + 1]);
    }
    out.breakpoints = std::move(events.breakpoints);
    out.corners = std::move(events.corners);
    out.outliers = std::move(events.outliers);
    return out;
}

void drop_small(const Reals& x, const Reals& y, Ints& a, Ints& b, Ints& group, Index min_points,
                double min_length) {
    std::size_t count = 0;
    const double fewest = std::max(static_cast<double>(min_points), 2.0);
    for (std::size_t k = 0; k < a.size(); ++k) {
        double length = std::hypot(x[b[k]] - x[a[k]], y[b[k]] - y[a[k]]);
        if (static_cast<double>(b[k] - a[k] + 1) >= fewest && length >= min_length) {
            a[count] = a[k];
            b[count] = b[k];
            group[count] = group[k];
            ++count;
        }
    }
    a.resize(count);
    b.resize(count);
    group.resize(count);
}

ScanResult finish(const Returns& returns, Index n_beams, bool full_circle, const Moments& moments,
                  Ints a, Ints b, Ints group, const Clustering& clusters, Ints outliers,
                  double angle_min, const Output& output, NoiseLine noise) {
    drop_small(returns.x, returns.y, a, b, group, output.min_points, output.min_length);
    bool wrap = clusters.clustered ? clusters.ring : full_circle;
    auto [corners, jumps] = segment_events(returns, n_beams, moments, a, b, group,
                                           clusters.clustered, wrap, output.corners);
    Ints breakpoints = clusters.clustered ? clusters.breakpoints : jumps;
    Ints gap = beam_gaps(returns.index, n_beams);
    Reals sigma = covariance_sigmas(output.range_sigma, noise, returns, gap);
    Events events{sorted_distinct(breakpoints), corners, sorted_distinct(outliers)};
    return assemble(returns, TLS, moments, a, b, angle_min, sigma, events, n_beams, full_circle);
}

ScanResult empty_result(Ints breakpoints, Ints outliers) {
    ScanResult out;
    std::sort(breakpoints.begin(), breakpoints.end());
    std::sort(outliers.begin(), outliers.end());
    out.breakpoints = std::move(breakpoints);
    out.outliers = std::move(outliers);
    return out;
}

}  // namespace scanlines
