// The segmentation steps the Python side calls on their own (the methods whose search is
// numpy, and the tests of each step): where a scan is cut. Noise points, breakpoint rules,
// clusters, corner scores, the threshold sweep, splits, merges and the events between
// segments.
#include <nanobind/stl/pair.h>
#include <nanobind/stl/tuple.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "arrays.hpp"
#include "scanlines/steps/breakpoints.hpp"
#include "scanlines/steps/clusters.hpp"
#include "scanlines/steps/corners.hpp"
#include "scanlines/steps/denoise.hpp"
#include "scanlines/steps/events.hpp"
#include "scanlines/steps/merge.hpp"
#include "scanlines/steps/select.hpp"
#include "scanlines/steps/split.hpp"

namespace scanlines::bind {

namespace {

using InTable = In<double, nb::ndim<2>>;

nb::object flags_array(const Flags& flags) { return flags_to_numpy(flags); }

// Clusters [start, end] of n points: in order, disjoint, inside the points.
void check_clusters(const InInts& start, const InInts& end, std::size_t n) {
    expect_clusters(Ints(start.data(), start.data() + start.shape(0)),
                    Ints(end.data(), end.data() + end.shape(0)), static_cast<Index>(n));
}

// Runs [a, b] of n points with their group (cluster or owner) each.
void check_grouped_runs(const InInts& a, const InInts& b, const InInts& group, Index n,
                        const char* group_name) {
    expect_runs("a", "b", a.data(), a.shape(0), b.data(), b.shape(0), n);
    expect_length(group_name, group.shape(0), a.shape(0), "one per run");
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

// Clustering and corner scores (scanlines/steps/breakpoints.py, clusters.py, corners.py).
static void bind_clustering(nb::module_& m) {
    m.def("threshold", [](nb::handle rule, double r_from, double r_to, Index gap, double step) {
        expect_at_least("gap", gap, 0);
        return threshold(breakpoint_rule_of(rule), r_from, r_to, gap, step);
    });
    m.def("break_flags", [](const InInts& index, const InReals& r, const InReals& x,
                            const InReals& y, const InInts& gap, double step, nb::handle rule) {
        Returns returns = returns_of(index, r, x, y);
        expect_pairs("gap", gap.shape(0), index.shape(0));
        return flags_array(break_flags(returns, vector_of(gap), step, breakpoint_rule_of(rule)));
    });
    m.def("cluster_returns", [](const InInts& index, const InReals& r, const InReals& x,
                                const InReals& y, Index n_beams, double step, bool full_circle,
                                nb::handle rule, Index ring_window,
                                const In<bool, nb::ndim<1>>& known_breaks) {
        Returns returns = returns_of(index, r, x, y);
        expect_beams(returns.index, n_beams);
        expect_step(step);
        expect_between("ring_window", ring_window, 1, MAX_SETTING_COUNT);
        if (known_breaks.shape(0) != 0) expect_pairs("known_breaks", known_breaks.shape(0), index.shape(0));
        Clusters c = cluster_returns(std::move(returns), n_beams, step, full_circle,
                                     breakpoint_rule_of(rule), ring_window, flags_of(known_breaks));
        return nb::make_tuple(returns_to_numpy(std::move(c.returns)), to_numpy(std::move(c.start)),
                              to_numpy(std::move(c.end)), to_numpy(std::move(c.breakpoints)),
                              c.ring);
    });
    m.def("slope_scores", [](const InReals& r, const InInts& gap, double step, const InInts& start,
                             const InInts& end, bool is_signed) {
        expect_pairs("gap", gap.shape(0), r.shape(0));
        check_clusters(start, end, r.shape(0));
        return to_numpy(slope_scores(vector_of(r), vector_of(gap), step, vector_of(start),
                                     vector_of(end), is_signed));
    });
    m.def("turn_scores", [](const InReals& x, const InReals& y, const InTable& table, double ox,
                            double oy, const InInts& start, const InInts& end, Index window) {
        expect_length("y", y.shape(0), x.shape(0), "one per point, as x");
        Moments moments = moments_of(table, ox, oy, x.shape(0));
        check_clusters(start, end, x.shape(0));
        expect_between("window", window, 1, MAX_SETTING_COUNT);
        return to_numpy(turn_scores(vector_of(x), vector_of(y), moments,
                                    vector_of(start), vector_of(end), window));
    });
    m.def("peak_positions", [](const InReals& score, const InInts& start, const InInts& end) {
        check_clusters(start, end, score.shape(0));
        return to_numpy(peak_positions(vector_of(score), vector_of(start), vector_of(end)));
    });
}

// Splitting, merging and the events between segments (steps/split.py, merge.py, events.py).
static void bind_segments(nb::module_& m) {
    m.def("chord_distance", [](const InReals& x, const InReals& y, Index a, Index b, Index p) {
        const Index n = static_cast<Index>(x.shape(0));
        expect_length("y", y.shape(0), x.shape(0), "one per point, as x");
        expect_position("a", a, n);
        expect_position("b", b, n);
        expect_position("p", p, n);
        return chord_distance(vector_of(x), vector_of(y), a, b, p);
    });
    m.def("split_at_farthest", [](const InReals& x, const InReals& y, const InTable& table,
                                  double ox, double oy, const InInts& a, const InInts& b,
                                  const InInts& group, double threshold, Index reference) {
        expect_length("y", y.shape(0), x.shape(0), "one per point, as x");
        Moments moments = moments_of(table, ox, oy, x.shape(0));
        check_grouped_runs(a, b, group, static_cast<Index>(x.shape(0)), "group");
        expect_between("reference", reference, CHORD, LINE);
        GroupedRuns runs{vector_of(a), vector_of(b), vector_of(group)};
        return runs_to_numpy(
            split_at_farthest(vector_of(x), vector_of(y), moments, runs, threshold, reference));
    });
    m.def("merge_by_chi_square", [](const InInts& index, const InReals& r, const InReals& x,
                                    const InReals& y, const InTable& table, double ox, double oy,
                                    const InInts& a, const InInts& b, const InInts& group,
                                    const InReals& sigma, double threshold, bool inflate) {
        Returns returns = returns_of(index, r, x, y);
        Moments moments = moments_of(table, ox, oy, index.shape(0));
        check_grouped_runs(a, b, group, returns.size(), "group");
        expect_length("sigma", sigma.shape(0), index.shape(0), "one noise sigma per return");
        return runs_to_numpy(merge_by_chi_square(returns, moments, vector_of(a),
                                                 vector_of(b), vector_of(group), vector_of(sigma),
                                                 threshold, inflate));
    });
    m.def("segment_events", [](const InInts& index, const InReals& r, const InReals& x,
                               const InReals& y, Index n_beams, const InTable& table, double ox,
                               double oy, const InInts& a, const InInts& b, const InInts& group,
                               bool clustered, bool wrap, Index corner_beams,
                               double corner_distance, double corner_angle) {
        Returns returns = returns_of(index, r, x, y);
        expect_beams(returns.index, n_beams);
        Moments moments = moments_of(table, ox, oy, index.shape(0));
        check_grouped_runs(a, b, group, returns.size(), "group");
        expect_at_least("corner_beams", corner_beams, 0);
        auto [corners, jumps] = segment_events(
            returns, n_beams, moments, vector_of(a),
            vector_of(b), vector_of(group), clustered, wrap,
            {corner_beams, corner_distance, corner_angle});
        return nb::make_tuple(to_numpy(std::move(corners)), to_numpy(std::move(jumps)));
    });
    m.def("junction_events", [](const InInts& index, const InReals& r, const InReals& x,
                                const InReals& y, Index fit, const InTable& table, double ox,
                                double oy, const InInts& a, const InInts& b, const InInts& owner,
                                bool shared, bool ring, double sigma, const InReals& turn_sigma) {
        Returns returns = returns_of(index, r, x, y);
        expect_between("fit", fit, TLS, PAPER);
        Moments moments = moments_of(table, ox, oy, index.shape(0));
        check_grouped_runs(a, b, owner, returns.size(), "owner");
        if (turn_sigma.shape(0) != 0)
            expect_length("turn_sigma", turn_sigma.shape(0), a.shape(0), "one per run, or none");
        auto [corners, jumps] = junction_events(
            returns, fit, moments, vector_of(a),
            vector_of(b), vector_of(owner), shared, ring, sigma, vector_of(turn_sigma));
        return nb::make_tuple(to_numpy(std::move(corners)), to_numpy(std::move(jumps)));
    });
}

void bind_segmentation(nb::module_& m) {
    bind_clustering(m);
    bind_segments(m);
    bind_select(m);
    bind_denoise(m);
}

}  // namespace scanlines::bind
