// The segmentation steps the Python side calls on their own (the methods whose search is
// numpy, and the tests of each step): breakpoint rules, clusters, corner scores, splits,
// merges and the events between segments.
#include <nanobind/stl/pair.h>

#include "arrays.hpp"
#include "scanlines/steps/breakpoints.hpp"
#include "scanlines/steps/clusters.hpp"
#include "scanlines/steps/corners.hpp"
#include "scanlines/steps/events.hpp"
#include "scanlines/steps/merge.hpp"
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
}

}  // namespace scanlines::bind
