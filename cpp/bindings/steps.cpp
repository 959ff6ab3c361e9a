// The steps the Python side calls on its own: the fits and covariances of the methods
// whose search is numpy, the clustering and finishing stages around it, the noise
// estimate of sensor profiles, assembly for ground truth, and the threshold sweep and
// denoising for the tests of the steps.
#include <nanobind/stl/pair.h>
#include <nanobind/stl/tuple.h>

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

void check_runs(const InInts& a, const InInts& b, Index n) {
    if (a.shape(0) != b.shape(0)) throw nb::value_error("a and b must have one length");
    for (std::size_t k = 0; k < a.shape(0); ++k)
        if (a.data()[k] < 0 || b.data()[k] >= n || b.data()[k] < a.data()[k] - 1)
            throw nb::index_error("a run lies outside the points");
}

nb::tuple fit_many_binding(Index fit, const InTable& table, double ox, double oy, const InInts& a,
                           const InInts& b) {
    Moments moments = moments_of(table, ox, oy);
    check_runs(a, b, moments.stride - 1);
    Lines lines = fit_many(fit, moments, vector_of(a), vector_of(b));
    return nb::make_tuple(to_numpy(std::move(lines.rho)), to_numpy(std::move(lines.alpha)),
                          to_numpy(std::move(lines.sse)));
}

nb::tuple tls_run_binding(const InTable& table, double ox, double oy, Index a, Index b) {
    Moments moments = moments_of(table, ox, oy);
    if (a < 0 || b >= moments.stride - 1) throw nb::index_error("the run lies outside the points");
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
    check_runs(a, b, n);
    Reals out = run_covariances(view(r), view(x), view(y), vector_of(rho), vector_of(alpha),
                                vector_of(a), vector_of(b), view(sigma), inflate);
    return to_numpy(std::move(out), {a.shape(0), 2, 2});
}

nb::object pair_chi_squares_binding(const InReals& rho, const InReals& alpha,
                                    const In<double, nb::ndim<3>>& covariance,
                                    const InInts& first, const InInts& second) {
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
    return to_numpy(covariance_sigmas(range_sigma, {noise.first, noise.second},
                                      returns_of(index, r, x, y), vector_of(gap)));
}

nb::tuple local_residuals_binding(const InInts& index, const InReals& r, const InReals& x,
                                  const InReals& y, const InInts& gap) {
    auto [sample, at] = local_residuals(returns_of(index, r, x, y), vector_of(gap));
    return nb::make_tuple(to_numpy(std::move(sample)), to_numpy(std::move(at)));
}

NoisePair scan_noise_binding(const InInts& index, const InReals& r, const InReals& x,
                             const InReals& y, const InInts& gap) {
    NoiseLine noise = scan_noise(returns_of(index, r, x, y), vector_of(gap));
    return {noise.sigma0, noise.per_metre};
}

nb::tuple cluster_scan_binding(const InInts& index, const InReals& r, const InReals& x,
                               const InReals& y, Index n_beams, double step, bool full_circle,
                               const nb::dict& rule, NoisePair noise) {
    Returns returns = returns_of(index, r, x, y);
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
    check_runs(a, b, returns.size());
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
    check_runs(a, b, returns.size());
    Moments moments = prefix_moments(returns.x, returns.y);
    ScanResult result = assemble(returns, fit, moments, vector_of(a), vector_of(b), angle_min,
                                 vector_of(sigma),
                                 {vector_of(breakpoints), vector_of(corners), vector_of(outliers)},
                                 n_beams, wrap);
    return result_to_numpy(std::move(result));
}

nb::tuple fit_run_binding(Index fit, const InTable& table, double ox, double oy, Index a, Index b) {
    Moments moments = moments_of(table, ox, oy);
    if (a < 0 || b >= moments.stride - 1) throw nb::index_error("the run lies outside the points");
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

// The sweep and criterion (scanlines/steps/select.py), for the tests of the steps.
void bind_select(nb::module_& m) {
    m.def(
        "threshold_grid",
        [](double low, double high, double step, Index max_evaluations) {
            return to_numpy(threshold_grid(low, high, step, max_evaluations));
        },
        "low, low + step, ... up to high, at most max_evaluations values.");
    // A process may import the module twice (two copies of the package side by side,
    // tools/benchmarks/compare_versions.py): the type is registered once.
    if (nb::type<Sweep>().is_valid()) {
        m.attr("Sweep") = nb::type<Sweep>();
    } else {
        nb::class_<Sweep>(m, "Sweep", "A threshold sweep in progress (scanlines.steps.select).")
            .def_prop_ro("ranked", [](const Sweep& s) { return copy_to_numpy(s.ranked); })
            .def_prop_ro("ranked_score",
                         [](const Sweep& s) { return copy_to_numpy(s.ranked_score); })
            .def_ro("useful", &Sweep::useful)
            .def_prop_ro("accepted", [](const Sweep& s) { return flags_to_numpy(s.accepted); })
            .def_prop_ro("parent_a", [](const Sweep& s) { return copy_to_numpy(s.parent_a); })
            .def_prop_ro("parent_b", [](const Sweep& s) { return copy_to_numpy(s.parent_b); })
            .def_prop_ro("sse", [](const Sweep& s) { return copy_to_numpy(s.sse); })
            .def_prop_ro("segments", [](const Sweep& s) { return copy_to_numpy(s.segments); });
    }
    m.def(
        "start_sweep",
        [](const CostTuple& cost, const InInts& start, const InInts& end, const InInts& candidates,
           const InReals& scores, const InReals& grid, bool use_grid, Index max_evaluations) {
            return start_sweep(cost_of(cost), vector_of(start), vector_of(end),
                               vector_of(candidates), vector_of(scores), vector_of(grid), use_grid,
                               max_evaluations);
        },
        "A sweep of the clusters [start, end] with no candidate inserted yet.");
    m.def(
        "extend_sweep",
        [](Sweep& sweep, const CostTuple& cost, bool shared, Index done, Index upto) {
            return extend_sweep(sweep, cost_of(cost), shared, done, upto);
        },
        "Insert candidates done .. upto - 1 of the sweep (in place); returns upto.");
    m.def(
        "sweep_levels",
        [](const CostTuple& cost, const InInts& start, const InInts& end, const InInts& candidates,
           const InReals& scores, const InReals& grid, bool use_grid, Index max_evaluations,
           bool shared) {
            Levels out = sweep_levels(cost_of(cost), vector_of(start), vector_of(end),
                                      vector_of(candidates), vector_of(scores), vector_of(grid),
                                      use_grid, max_evaluations, shared);
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
            auto [best, values] = best_level(criterion, vector_of(sse), vector_of(segments),
                                             vector_of(levels), n_points, sigma, penalty);
            return nb::make_tuple(best, to_numpy(std::move(values)));
        },
        "Index of the best tried threshold (the first on a tie) and every criterion value.");
    m.def(
        "level_corners",
        [](const InInts& ranked, const InFlags& accepted, Index level) {
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
            return flags_to_numpy(isolated_noise(returns_tuple_of(returns), vector_of(gap), step,
                                                 breakpoint_rule_of(rule), flags_of(breaks)));
        },
        "Points cut off from both neighbours that are themselves continuous (a spike).");
    m.def(
        "window_means",
        [](const InReals& x, const InReals& y, const InFlags& noise, Index window,
           const InFlags& breaks) {
            auto [mx, my] =
                window_means(vector_of(x), vector_of(y), flags_of(noise), window, flags_of(breaks));
            return nb::make_tuple(to_numpy(std::move(mx)), to_numpy(std::move(my)));
        },
        "Step 3: noise point i and its neighbours become the mean of window points.");
    m.def(
        "small_clusters",
        [](const InFlags& breaks, Index min_points, bool seam_joined) {
            return flags_to_numpy(small_clusters(flags_of(breaks), min_points, seam_joined));
        },
        "Mask of the points of clusters with fewer than min_points returns.");
    m.def(
        "in_between_clusters",
        [](const InReals& r, const InInts& gap, const InFlags& breaks, const InFlags& small,
           double margin) {
            return flags_to_numpy(in_between_clusters(vector_of(r), vector_of(gap),
                                                      flags_of(breaks), flags_of(small), margin));
        },
        "Mask of the returns of two-return clusters that lie in depth between their neighbours.");
    m.def(
        "denoise",
        [](const ReturnsTuple& returns, Index n_beams, double step, bool full_circle,
           nb::handle rule, Index kind, Index window, Index min_cluster_points, double margin) {
            Denoised out = denoise(returns_tuple_of(returns), n_beams, step, full_circle,
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
