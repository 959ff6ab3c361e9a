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

}  // namespace

void bind_segmentation(nb::module_& m) {
    m.def("threshold", [](nb::handle rule, double r_from, double r_to, Index gap, double step) {
        return threshold(breakpoint_rule_of(rule), r_from, r_to, gap, step);
    });
    m.def("break_flags", [](const InInts& index, const InReals& r, const InReals& x,
                            const InReals& y, const InInts& gap, double step, nb::handle rule) {
        return flags_array(
            break_flags(returns_of(index, r, x, y), vector_of(gap), step, breakpoint_rule_of(rule)));
    });
    m.def("cluster_returns", [](const InInts& index, const InReals& r, const InReals& x,
                                const InReals& y, Index n_beams, double step, bool full_circle,
                                nb::handle rule, Index ring_window,
                                const In<bool, nb::ndim<1>>& known_breaks) {
        Clusters c = cluster_returns(returns_of(index, r, x, y), n_beams, step, full_circle,
                                     breakpoint_rule_of(rule), ring_window, flags_of(known_breaks));
        return nb::make_tuple(returns_to_numpy(std::move(c.returns)), to_numpy(std::move(c.start)),
                              to_numpy(std::move(c.end)), to_numpy(std::move(c.breakpoints)),
                              c.ring);
    });
    m.def("slope_scores", [](const InReals& r, const InInts& gap, double step, const InInts& start,
                             const InInts& end, bool is_signed) {
        return to_numpy(slope_scores(vector_of(r), vector_of(gap), step, vector_of(start),
                                     vector_of(end), is_signed));
    });
    m.def("turn_scores", [](const InReals& x, const InReals& y, const InTable& table, double ox,
                            double oy, const InInts& start, const InInts& end, Index window) {
        return to_numpy(turn_scores(vector_of(x), vector_of(y), moments_of(table, ox, oy),
                                    vector_of(start), vector_of(end), window));
    });
    m.def("peak_positions", [](const InReals& score, const InInts& start, const InInts& end) {
        return to_numpy(peak_positions(vector_of(score), vector_of(start), vector_of(end)));
    });
    m.def("chord_distance", [](const InReals& x, const InReals& y, Index a, Index b, Index p) {
        return chord_distance(vector_of(x), vector_of(y), a, b, p);
    });
    m.def("split_at_farthest", [](const InReals& x, const InReals& y, const InTable& table,
                                  double ox, double oy, const InInts& a, const InInts& b,
                                  const InInts& group, double threshold, Index reference) {
        GroupedRuns runs{vector_of(a), vector_of(b), vector_of(group)};
        return runs_to_numpy(split_at_farthest(vector_of(x), vector_of(y),
                                               moments_of(table, ox, oy), runs, threshold,
                                               reference));
    });
    m.def("merge_by_chi_square", [](const InInts& index, const InReals& r, const InReals& x,
                                    const InReals& y, const InTable& table, double ox, double oy,
                                    const InInts& a, const InInts& b, const InInts& group,
                                    const InReals& sigma, double threshold, bool inflate) {
        return runs_to_numpy(merge_by_chi_square(returns_of(index, r, x, y),
                                                 moments_of(table, ox, oy), vector_of(a),
                                                 vector_of(b), vector_of(group), vector_of(sigma),
                                                 threshold, inflate));
    });
    m.def("segment_events", [](const InInts& index, const InReals& r, const InReals& x,
                               const InReals& y, Index n_beams, const InTable& table, double ox,
                               double oy, const InInts& a, const InInts& b, const InInts& group,
                               bool clustered, bool wrap, Index corner_beams,
                               double corner_distance, double corner_angle) {
        auto [corners, jumps] = segment_events(
            returns_of(index, r, x, y), n_beams, moments_of(table, ox, oy), vector_of(a),
            vector_of(b), vector_of(group), clustered, wrap,
            {corner_beams, corner_distance, corner_angle});
        return nb::make_tuple(to_numpy(std::move(corners)), to_numpy(std::move(jumps)));
    });
    m.def("junction_events", [](const InInts& index, const InReals& r, const InReals& x,
                                const InReals& y, Index fit, const InTable& table, double ox,
                                double oy, const InInts& a, const InInts& b, const InInts& owner,
                                bool shared, bool ring, double sigma, const InReals& turn_sigma) {
        auto [corners, jumps] = junction_events(
            returns_of(index, r, x, y), fit, moments_of(table, ox, oy), vector_of(a),
            vector_of(b), vector_of(owner), shared, ring, sigma, vector_of(turn_sigma));
        return nb::make_tuple(to_numpy(std::move(corners)), to_numpy(std::move(jumps)));
    });
}

}  // namespace scanlines::bind
