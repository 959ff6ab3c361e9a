// The fitting steps the Python side calls on their own: the fits and covariances of the
// methods whose search is numpy, the clustering and finishing stages around it, the noise
// estimate of sensor profiles and assembly for ground truth.
#include <nanobind/stl/pair.h>
#include <nanobind/stl/tuple.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "arrays.hpp"
#include "scanlines/methods/clustered.hpp"
#include "scanlines/steps/assemble.hpp"
#include "scanlines/steps/fit.hpp"
#include "scanlines/steps/merge.hpp"
#include "scanlines/steps/noise.hpp"

namespace scanlines::bind {

namespace {

using InTable = In<double, nb::ndim<2>>;
using NoisePair = std::pair<double, double>;

nb::tuple prefix_moments_binding(const InReals& x, const InReals& y) {
    if (x.shape(0) != y.shape(0)) throw nb::value_error("x and y must have one length");
    Moments m = prefix_moments(vector_of(x), vector_of(y));
    std::size_t columns = static_cast<std::size_t>(m.stride);
    double ox = m.ox, oy = m.oy;
    return nb::make_tuple(to_numpy(m.release(), {5, columns}), ox, oy);
}

// Runs [a, b] of n points (an empty run b = a - 1 allowed: its line is NaN).
void check_runs(const InInts& a, const InInts& b, Index n) {
    expect_runs("a", "b", a.data(), a.shape(0), b.data(), b.shape(0), n, true);
}

// The same, each run holding a point at least.
void check_filled_runs(const InInts& a, const InInts& b, Index n) {
    expect_runs("a", "b", a.data(), a.shape(0), b.data(), b.shape(0), n);
}

// One run [a, b] of the n points of a moments table.
void check_run(Index a, Index b, Index n) {
    expect_runs("a", "b", &a, 1, &b, 1, n, true);
}

nb::tuple fit_many_binding(Index fit, const InTable& table, double ox, double oy, const InInts& a,
                           const InInts& b) {
    expect_between("fit", fit, TLS, PAPER);
    Moments moments = moments_of(table, ox, oy);
    check_runs(a, b, moments.stride - 1);
    Lines lines = fit_many(fit, moments, vector_of(a), vector_of(b));
    return nb::make_tuple(to_numpy(std::move(lines.rho)), to_numpy(std::move(lines.alpha)),
                          to_numpy(std::move(lines.sse)));
}

nb::tuple tls_run_binding(const InTable& table, double ox, double oy, Index a, Index b) {
    Moments moments = moments_of(table, ox, oy);
    check_run(a, b, moments.stride - 1);
    Line line = tls_run(moments, a, b);
    return nb::make_tuple(line.rho, line.alpha, line.sse);
}

nb::object run_covariances_binding(const InReals& r, const InReals& x, const InReals& y,
                                   const InReals& rho, const InReals& alpha, const InInts& a,
                                   const InInts& b, const InReals& sigma, bool inflate) {
    const Index n = static_cast<Index>(x.shape(0));
    if (static_cast<Index>(r.shape(0)) != n || static_cast<Index>(y.shape(0)) != n ||
        static_cast<Index>(sigma.shape(0)) != n)
        throw nb::value_error("r, x, y and sigma must have one length");
    check_filled_runs(a, b, n);
    expect_length("rho", rho.shape(0), a.shape(0), "one line per run");
    expect_length("alpha", alpha.shape(0), a.shape(0), "one line per run");
    Reals out = run_covariances(view(r), view(x), view(y), vector_of(rho), vector_of(alpha),
                                vector_of(a), vector_of(b), view(sigma), inflate);
    return to_numpy(std::move(out), {a.shape(0), 2, 2});
}

nb::object pair_chi_squares_binding(const InReals& rho, const InReals& alpha,
                                    const In<double, nb::ndim<3>>& covariance,
                                    const InInts& first, const InInts& second) {
    const std::size_t m = rho.shape(0);
    expect_length("alpha", alpha.shape(0), m, "one angle per line");
    expect_length("covariance", covariance.shape(0), m, "one 2 x 2 covariance per line");
    if (covariance.shape(1) != 2 || covariance.shape(2) != 2)
        value_error("covariance must hold 2 x 2 matrices");
    expect_length("second", second.shape(0), first.shape(0), "one pair of lines each");
    expect_positions("first", first.data(), first.shape(0), static_cast<Index>(m));
    expect_positions("second", second.data(), second.shape(0), static_cast<Index>(m));
    Reals out(first.shape(0));
    const double* cov = covariance.data();
    for (std::size_t i = 0; i < out.size(); ++i) {
        Index j = first.data()[i], k = second.data()[i];
        out[i] = chi_square(rho.data()[j], alpha.data()[j], rho.data()[k], alpha.data()[k],
                            cov + 4 * j, cov + 4 * k);
    }
    return to_numpy(std::move(out));
}

nb::object covariance_sigmas_binding(double range_sigma, NoisePair noise, const InInts& index,
                                     const InReals& r, const InReals& x, const InReals& y,
                                     const InInts& gap) {
    Returns returns = returns_of(index, r, x, y);
    expect_pairs("gap", gap.shape(0), index.shape(0));
    return to_numpy(covariance_sigmas(range_sigma, {noise.first, noise.second}, returns,
                                      vector_of(gap)));
}

nb::tuple local_residuals_binding(const InInts& index, const InReals& r, const InReals& x,
                                  const InReals& y, const InInts& gap) {
    Returns returns = returns_of(index, r, x, y);
    expect_pairs("gap", gap.shape(0), index.shape(0));
    auto [sample, at] = local_residuals(returns, vector_of(gap));
    return nb::make_tuple(to_numpy(std::move(sample)), to_numpy(std::move(at)));
}

NoisePair scan_noise_binding(const InInts& index, const InReals& r, const InReals& x,
                             const InReals& y, const InInts& gap) {
    Returns returns = returns_of(index, r, x, y);
    expect_pairs("gap", gap.shape(0), index.shape(0));
    NoiseLine noise = scan_noise(returns, vector_of(gap));
    return {noise.sigma0, noise.per_metre};
}

nb::tuple cluster_scan_binding(const InInts& index, const InReals& r, const InReals& x,
                               const InReals& y, Index n_beams, double step, bool full_circle,
                               const nb::dict& rule, NoisePair noise) {
    Returns returns = returns_of(index, r, x, y);
    expect_at_least("the number of returns", returns.size(), 1);
    expect_beams(returns.index, n_beams);
    expect_step(step);
    RuleSpec spec = rule_spec_of(rule);
    Clusters c;
    {
        nb::gil_scoped_release unlocked;
        c = cluster_scan(std::move(returns), n_beams, step, full_circle, spec,
                         {noise.first, noise.second});
    }
    return nb::make_tuple(returns_to_numpy(std::move(c.returns)), to_numpy(std::move(c.start)),
                          to_numpy(std::move(c.end)), to_numpy(std::move(c.breakpoints)), c.ring);
}

nb::tuple finish_binding(const InInts& index, const InReals& r, const InReals& x,
                         const InReals& y, Index n_beams, bool full_circle, const InInts& a,
                         const InInts& b, const InInts& group,
                         std::pair<bool, bool> clustered_ring, const InInts& breakpoints,
                         const InInts& outliers, double angle_min, const nb::dict& out,
                         NoisePair noise) {
    Returns returns = returns_of(index, r, x, y);
    expect_beams(returns.index, n_beams);
    check_filled_runs(a, b, returns.size());
    expect_length("group", group.shape(0), a.shape(0), "one cluster per run");
    Output output = output_of(out, out);  // the step's Output tuple: both groups' fields
    Clustering clustering{clustered_ring.first, clustered_ring.second, vector_of(breakpoints)};
    ScanResult result;
    {
        nb::gil_scoped_release unlocked;
        Moments moments = prefix_moments(returns.x, returns.y);
        result = finish(returns, n_beams, full_circle, moments, vector_of(a), vector_of(b),
                        vector_of(group), clustering, vector_of(outliers), angle_min, output,
                        {noise.first, noise.second});
    }
    return result_to_numpy(std::move(result));
}

nb::tuple assemble_binding(const InInts& index, const InReals& r, const InReals& x,
                           const InReals& y, Index fit, const InInts& a, const InInts& b,
                           double angle_min, const InReals& sigma, const InInts& breakpoints,
                           const InInts& corners, const InInts& outliers, Index n_beams,
                           bool wrap) {
    Returns returns = returns_of(index, r, x, y);
    expect_between("fit", fit, TLS, PAPER);
    expect_beams(returns.index, n_beams);
    check_filled_runs(a, b, returns.size());
    expect_length("sigma", sigma.shape(0), index.shape(0), "one noise sigma per return");
    Moments moments = prefix_moments(returns.x, returns.y);
    ScanResult result = assemble(returns, fit, moments, vector_of(a), vector_of(b), angle_min,
                                 vector_of(sigma),
                                 {vector_of(breakpoints), vector_of(corners), vector_of(outliers)},
                                 n_beams, wrap);
    return result_to_numpy(std::move(result));
}

nb::tuple fit_run_binding(Index fit, const InTable& table, double ox, double oy, Index a, Index b) {
    expect_between("fit", fit, TLS, PAPER);
    Moments moments = moments_of(table, ox, oy);
    check_run(a, b, moments.stride - 1);
    Line line = fit_run(fit, moments, a, b);
    return nb::make_tuple(line.rho, line.alpha, line.sse);
}

nb::tuple offset_power_sums_binding(const InInts& index, Index a, Index b, Index i) {
    if (a < 0 || b >= static_cast<Index>(index.shape(0)) || i < a || i > b)
        throw nb::index_error("positions outside the index");
    PowerSums s = offset_power_sums(index.data(), a, b, i);
    return nb::make_tuple(s.s0, s.s1, s.s2, s.s3, s.s4);
}

nb::tuple parabola_at_centre_binding(const InInts& index, const InReals& r, Index a, Index b,
                                     Index i, std::tuple<double, double, double, double, double> s) {
    if (a < 0 || b >= static_cast<Index>(index.shape(0)) || r.shape(0) != index.shape(0) || i < a ||
        i > b)
        throw nb::index_error("positions outside the index");
    auto [s0, s1, s2, s3, s4] = s;
    Parabola p = parabola_at_centre(index.data(), r.data(), a, b, i, {s0, s1, s2, s3, s4});
    return nb::make_tuple(p.residual, p.leverage, p.slope);
}

}  // namespace

void bind_fits(nb::module_& m) {
    m.def("fit_run", &fit_run_binding);
    m.def("hesse_difference", &hesse_difference);
    m.def("offset_power_sums", &offset_power_sums_binding);
    m.def("parabola_at_centre", &parabola_at_centre_binding);
    m.def("prefix_moments", &prefix_moments_binding);
    m.def("fit_many", &fit_many_binding);
    m.def("tls_run", &tls_run_binding);
    m.def("run_covariances", &run_covariances_binding);
    m.def("pair_chi_squares", &pair_chi_squares_binding);
    m.def("covariance_sigmas", &covariance_sigmas_binding);
    m.def("local_residuals", &local_residuals_binding);
    m.def("scan_noise", &scan_noise_binding);
    m.def("cluster_scan", &cluster_scan_binding);
    m.def("finish", &finish_binding);
    m.def("assemble", &assemble_binding);
}

}  // namespace scanlines::bind
