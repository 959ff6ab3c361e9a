// The steps the Python side calls on its own: the fits and covariances of the methods
// whose search is numpy, the clustering and finishing stages around it, the noise
// estimate of sensor profiles, assembly for ground truth, and the threshold sweep and
// denoising for the tests of the steps.
#include <nanobind/stl/pair.h>
#include <nanobind/stl/tuple.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "arrays.hpp"
#include "scanlines/methods/clustered.hpp"
#include "scanlines/steps/assemble.hpp"
#include "scanlines/steps/denoise.hpp"
#include "scanlines/steps/fit.hpp"
#include "scanlines/steps/merge.hpp"
#include "scanlines/steps/noise.hpp"
#include "scanlines/steps/select.hpp"

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

// What a sweep of the clusters [start, end] indexes: clusters of the cost's points, in order,
// a score per candidate, each candidate inside a cluster, a count of evaluations.
void check_sweep(const RunCost& cost, const Ints& start, const Ints& end, const Ints& candidates,
                 const Reals& scores, Index max_evaluations) {
    const Index n = cost.moments.stride - 1;
    expect_clusters(start, end, n);
    expect_length("scores", scores.size(), candidates.size(), "one score per candidate");
    for (std::size_t j = 0; j < candidates.size(); ++j) {
        Index c = candidates[j];
        auto after = std::upper_bound(start.begin(), start.end(), c);
        if (after == start.begin() || c > end[static_cast<std::size_t>(after - start.begin()) - 1])
            index_error("candidates[" + std::to_string(j) + "] = " + text(c) +
                        " lies in no cluster");
    }
    expect_between("max_evaluations", max_evaluations, 0, MAX_SETTING_COUNT);
}

// A sweep continued with the cost it was started with (its points), candidates done .. upto.
void check_sweep_step(const Sweep& sweep, const RunCost& cost, Index done, Index upto) {
    const Index n = cost.moments.stride - 1;
    if (static_cast<Index>(sweep.run_end.size()) != n)
        value_error("the sweep was started on " + text(static_cast<Index>(sweep.run_end.size())) +
                    " points, the cost has " + text(n));
    expect_between("done", done, 0, sweep.useful);
    expect_between("upto", upto, done, sweep.useful);
}

// The sweep and criterion (scanlines/steps/select.py), for the tests of the steps.
// The Sweep type, once per process: a process may import the module twice (two copies of
// the package side by side, tools/benchmarks/compare_versions.py).
static void bind_sweep_type(nb::module_& m) {
    if (nb::type<Sweep>().is_valid()) {
        m.attr("Sweep") = nb::type<Sweep>();
        return;
    }
    nb::class_<Sweep>(m, "Sweep", "A threshold sweep in progress (scanlines.steps.select).")
        .def_prop_ro("ranked", [](const Sweep& s) { return copy_to_numpy(s.ranked); })
        .def_prop_ro("ranked_score", [](const Sweep& s) { return copy_to_numpy(s.ranked_score); })
        .def_ro("useful", &Sweep::useful)
        .def_prop_ro("accepted", [](const Sweep& s) { return flags_to_numpy(s.accepted); })
        .def_prop_ro("parent_a", [](const Sweep& s) { return copy_to_numpy(s.parent_a); })
        .def_prop_ro("parent_b", [](const Sweep& s) { return copy_to_numpy(s.parent_b); })
        .def_prop_ro("sse", [](const Sweep& s) { return copy_to_numpy(s.sse); })
        .def_prop_ro("segments", [](const Sweep& s) { return copy_to_numpy(s.segments); });
}

void bind_select(nb::module_& m) {
    bind_sweep_type(m);
    m.def(
        "threshold_grid",
        [](double low, double high, double step, Index max_evaluations) {
            if (!std::isfinite(low) || !std::isfinite(high))
                value_error("low and high must be finite");
            if (!(step > 0.0) || !std::isfinite(step))
                value_error("step must be finite and above 0");
            expect_between("max_evaluations", max_evaluations, 0, MAX_SETTING_COUNT);
            return to_numpy(threshold_grid(low, high, step, max_evaluations));
        },
        "low, low + step, ... up to high, at most max_evaluations values.");
    m.def(
        "start_sweep",
        [](const CostTuple& cost, const InInts& start, const InInts& end, const InInts& candidates,
           const InReals& scores, const InReals& grid, bool use_grid, Index max_evaluations) {
            RunCost run_cost = cost_of(cost);
            Ints starts = vector_of(start), ends = vector_of(end), at = vector_of(candidates);
            Reals score = vector_of(scores);
            check_sweep(run_cost, starts, ends, at, score, max_evaluations);
            return start_sweep(run_cost, starts, ends, at, score, vector_of(grid), use_grid,
                               max_evaluations);
        },
        "A sweep of the clusters [start, end] with no candidate inserted yet.");
    m.def(
        "extend_sweep",
        [](Sweep& sweep, const CostTuple& cost, bool shared, Index done, Index upto) {
            RunCost run_cost = cost_of(cost);
            check_sweep_step(sweep, run_cost, done, upto);
            return extend_sweep(sweep, run_cost, shared, done, upto);
        },
        "Insert candidates done .. upto - 1 of the sweep (in place); returns upto.");
    m.def(
        "sweep_levels",
        [](const CostTuple& cost, const InInts& start, const InInts& end, const InInts& candidates,
           const InReals& scores, const InReals& grid, bool use_grid, Index max_evaluations,
           bool shared) {
            RunCost run_cost = cost_of(cost);
            Ints starts = vector_of(start), ends = vector_of(end), at = vector_of(candidates);
            Reals score = vector_of(scores);
            check_sweep(run_cost, starts, ends, at, score, max_evaluations);
            Levels out = sweep_levels(run_cost, starts, ends, at, score, vector_of(grid), use_grid,
                                      max_evaluations, shared);
            return nb::make_tuple(to_numpy(std::move(out.ranked)), flags_to_numpy(out.accepted),
                                  to_numpy(std::move(out.sse)), to_numpy(std::move(out.segments)),
                                  to_numpy(std::move(out.thresholds)),
                                  to_numpy(std::move(out.levels)));
        },
        "Every cut a threshold makes: (ranked, accepted, sse, segments, thresholds, levels).");
    m.def(
        "best_level",
        [](Index criterion, const InReals& sse, const InInts& segments, const InInts& levels,
           Index n_points, double sigma, double penalty) {
            expect_between("criterion", criterion, BIC, SSE);
            expect_length("segments", segments.shape(0), sse.shape(0), "one per cut, as sse");
            expect_positions("levels", levels.data(), levels.shape(0),
                             static_cast<Index>(sse.shape(0)));
            auto [best, values] = best_level(criterion, vector_of(sse), vector_of(segments),
                                             vector_of(levels), n_points, sigma, penalty);
            return nb::make_tuple(best, to_numpy(std::move(values)));
        },
        "Index of the best tried threshold (the first on a tie) and every criterion value.");
    m.def(
        "level_corners",
        [](const InInts& ranked, const InFlags& accepted, Index level) {
            expect_length("accepted", accepted.shape(0), ranked.shape(0), "one per candidate");
            expect_between("level", level, 0, static_cast<Index>(ranked.shape(0)));
            return to_numpy(level_corners(vector_of(ranked), flags_of(accepted), level));
        },
        "Sorted positions of the accepted candidates among the level best.");
}

// Denoising (scanlines/steps/denoise.py), for the tests of the steps.
void bind_denoise(nb::module_& m) {
    m.def(
        "literal_noise",
        [](const InReals& d) { return flags_to_numpy(literal_noise(vector_of(d))); },
        "Step 2 as written, on neighbour distances d (length n - 1): a mask of n points.");
    m.def(
        "isolated_noise",
        [](const ReturnsTuple& returns, const InInts& gap, double step, nb::handle rule,
           const InFlags& breaks) {
            Returns points = returns_tuple_of(returns);
            expect_pairs("gap", gap.shape(0), points.index.size());
            expect_pairs("breaks", breaks.shape(0), points.index.size());
            return flags_to_numpy(isolated_noise(points, vector_of(gap), step,
                                                 breakpoint_rule_of(rule), flags_of(breaks)));
        },
        "Points cut off from both neighbours that are themselves continuous (a spike).");
    m.def(
        "window_means",
        [](const InReals& x, const InReals& y, const InFlags& noise, Index window,
           const InFlags& breaks) {
            const std::size_t n = x.shape(0);
            expect_length("y", y.shape(0), n, "one per point, as x");
            expect_length("noise", noise.shape(0), n, "one flag per point");
            expect_pairs("breaks", breaks.shape(0), n);
            expect_at_least("window", window, 1);
            auto [mx, my] =
                window_means(vector_of(x), vector_of(y), flags_of(noise), window, flags_of(breaks));
            return nb::make_tuple(to_numpy(std::move(mx)), to_numpy(std::move(my)));
        },
        "Step 3: noise point i and its neighbours become the mean of window points.");
    m.def(
        "in_between_clusters",
        [](const InReals& r, const InInts& gap, const InFlags& breaks, const InFlags& small,
           double margin) {
            const std::size_t n = r.shape(0);
            expect_pairs("gap", gap.shape(0), n);
            expect_pairs("breaks", breaks.shape(0), n);
            expect_length("small", small.shape(0), n, "one flag per point");
            return flags_to_numpy(in_between_clusters(vector_of(r), vector_of(gap),
                                                      flags_of(breaks), flags_of(small), margin));
        },
        "Mask of the returns of two-return clusters that lie in depth between their neighbours.");
    m.def(
        "denoise",
        [](const ReturnsTuple& returns, Index n_beams, double step, bool full_circle,
           nb::handle rule, Index kind, Index window, Index min_cluster_points, double margin) {
            Returns points = returns_tuple_of(returns);
            expect_beams(points.index, n_beams);
            expect_step(step);
            expect_between("kind", kind, ISOLATED, NO_DENOISE);
            expect_between("window", window, 1, MAX_SETTING_COUNT);
            expect_between("min_cluster_points", min_cluster_points, 0, MAX_SETTING_COUNT);
            Denoised out = denoise(std::move(points), n_beams, step, full_circle,
                                   breakpoint_rule_of(rule), kind, window, min_cluster_points,
                                   margin);
            return nb::make_tuple(returns_to_numpy(std::move(out.returns)),
                                  to_numpy(std::move(out.outliers)), flags_to_numpy(out.breaks));
        },
        "Steps 2-3 by kind: (returns, beams dropped as noise, break flags or empty).");
}

}  // namespace

void bind_steps(nb::module_& m) {
    bind_select(m);
    bind_denoise(m);
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
