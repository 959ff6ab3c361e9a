#include <nanobind/stl/pair.h>
#include <nanobind/stl/tuple.h>

#include <cmath>
#include <tuple>

#include "arrays.hpp"
#include "scanlines/methods/adaptive.hpp"
#include "scanlines/steps/denoise.hpp"
#include "scanlines/steps/select.hpp"

namespace scanlines::bind {

namespace {

using InFlags = In<bool, nb::ndim<1>>;

// The tuples the steps' Python side builds (scanlines.steps: Returns, RunCost with its
// Moments), taken as they are.
using ReturnsTuple = std::tuple<InInts, InReals, InReals, InReals>;
using CostTuple =
    std::tuple<Index, std::tuple<In<double, nb::ndim<2>>, double, double>, InReals, InReals>;

Returns returns_tuple_of(const ReturnsTuple& t) {
    return returns_of(std::get<0>(t), std::get<1>(t), std::get<2>(t), std::get<3>(t));
}

// A view of the caller's moments: valid while the call's arguments are.
RunCost cost_of(const CostTuple& t) {
    const auto& [table, ox, oy] = std::get<1>(t);
    return run_cost_of(std::get<0>(t), table, ox, oy, std::get<2>(t), std::get<3>(t));
}

template <typename T>
nb::object copy_to_numpy(const std::vector<T>& values) {
    return to_numpy(std::vector<T>(values));
}

// The settings record of scanlines/methods/adaptive.py, group by group.
AdaptiveSettings adaptive_settings(const nb::dict& record) {
    AdaptiveSettings s;
    nb::dict noise = group(record, "noise");
    s.noise = {setting<double>(noise, "noise_sigma"), setting<bool>(noise, "estimate_noise"),
               setting<bool>(noise, "constant_noise")};
    nb::dict clustering = group(record, "clustering");
    s.clustering = {rule_spec_of(clustering), setting<bool>(clustering, "auto_abd_lambda"),
                    setting<Index>(clustering, "denoise"), setting<Index>(clustering, "window"),
                    setting<Index>(clustering, "min_cluster_points")};
    nb::dict segments = group(record, "segments");
    auto& g = s.segments;
    g.corner_score = setting<Index>(segments, "corner_score");
    g.slope_window = setting<Index>(segments, "slope_window");
    g.auto_slope_window = setting<bool>(segments, "auto_slope_window");
    g.use_grid = setting<bool>(segments, "use_grid");
    g.max_evaluations = setting<Index>(segments, "max_evaluations");
    g.criterion = setting<Index>(segments, "criterion");
    g.penalty = setting<double>(segments, "penalty");
    g.fit = setting<Index>(segments, "fit");
    g.shared_corner = setting<bool>(segments, "shared_corner");
    g.merge = setting<bool>(segments, "merge");
    g.merge_chi2 = setting<double>(segments, "merge_chi2");
    g.max_residual = setting<double>(segments, "max_residual");
    s.events = {setting<bool>(group(record, "events"), "corner_check")};
    s.output = output_bounds_of(group(record, "output"));
    return s;
}

// The sweep and criterion (scanlines/steps/select.py), for the tests of the steps.
void bind_select(nb::module_& m) {
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

// The adaptive method's own steps (methods/adaptive.hpp), for the tests.
void bind_own_steps(nb::module_& m) {
    m.attr("MAX_BRIDGED_SHARE") = std::sin(1.0 * (3.141592653589793 / 180.0)) /
                                  std::sin(14.0 * (3.141592653589793 / 180.0));
    m.def("auto_abd_lambda", &auto_abd_lambda);
    m.def("residual_tolerances", [](const InReals& r, std::pair<double, double> noise, double floor) {
        return to_numpy(residual_tolerances(vector_of(r), {noise.first, noise.second}, floor));
    });
    m.def(
        "sweep_decided",
        [](Sweep& sweep, const CostTuple& cost, bool shared, Index done, Index n_points,
           double sigma, double penalty) {
            return sweep_decided(sweep, cost_of(cost), shared, done, n_points, sigma, penalty);
        },
        "Extend the sweep until the bic choice is certain: (best level, inserted).");
}

}  // namespace

void bind_adaptive(nb::module_& m) {
    m.def(
        "adaptive_stack",
        [](const In<double, nb::ndim<2>>& ranges, const In<bool, nb::ndim<2>>& valid,
           const In<double, nb::ndim<1>>& cos, const In<double, nb::ndim<1>>& sin, double step,
           bool full_circle, double angle_min, std::pair<double, double> noise,
           const nb::dict& settings, const InReals& grid) {
            Stack stack = stack_of(ranges, valid, cos, sin, step, full_circle, angle_min, noise);
            AdaptiveSettings s = adaptive_settings(settings);
            Reals thresholds = vector_of(grid);
            Table table;
            {
                nb::gil_scoped_release unlocked;
                table = adaptive_stack(stack, s, thresholds);
            }
            return table_to_numpy(std::move(table));
        },
        "The adaptive method on each row of a stack of scans: one flat table.");
    m.def(
        "adaptive_stage_seconds",
        [](const In<double, nb::ndim<2>>& ranges, const In<bool, nb::ndim<2>>& valid,
           const In<double, nb::ndim<1>>& cos, const In<double, nb::ndim<1>>& sin, double step,
           bool full_circle, double angle_min, std::pair<double, double> noise,
           const nb::dict& settings, const InReals& grid) {
            Stack stack = stack_of(ranges, valid, cos, sin, step, full_circle, angle_min, noise);
            AdaptiveSettings s = adaptive_settings(settings);
            Reals thresholds = vector_of(grid);
            StageSeconds seconds{};
            {
                nb::gil_scoped_release unlocked;
                adaptive_stack(stack, s, thresholds, &seconds);
            }
            nb::dict out;
            for (int k = 0; k < N_ADAPTIVE_STAGES; ++k) out[ADAPTIVE_STAGE_NAMES[k]] = seconds[k];
            return out;
        },
        "adaptive_stack's arguments: the seconds each stage of the method took over the stack, "
        "by name, in order.");
    m.def(
        "threshold_grid",
        [](double low, double high, double step, Index max_evaluations) {
            return to_numpy(threshold_grid(low, high, step, max_evaluations));
        },
        "low, low + step, ... up to high, at most max_evaluations values.");
    bind_select(m);
    bind_denoise(m);
    bind_own_steps(m);
}

}  // namespace scanlines::bind
