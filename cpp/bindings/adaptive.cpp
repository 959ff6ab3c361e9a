#include <nanobind/stl/pair.h>

#include "arrays.hpp"
#include "scanlines/methods/adaptive.hpp"
#include "scanlines/steps/denoise.hpp"
#include "scanlines/steps/select.hpp"

namespace scanlines::bind {

namespace {

Reals reals(const In<double, nb::ndim<1>>& array) {
    return Reals(array.data(), array.data() + array.shape(0));
}

// A one-dimensional array of any sequence numpy takes, copied.
template <typename T>
std::vector<T> values_of(nb::handle sequence) {
    auto array = nb::cast<In<T, nb::ndim<1>>>(sequence);
    return std::vector<T>(array.data(), array.data() + array.shape(0));
}

// The tuples the steps' tests build in Python (scanlines.steps: Returns, BreakpointRule,
// RunCost), read by position.
Returns returns_of(nb::handle t) {
    return {values_of<Index>(t[0]), values_of<double>(t[1]), values_of<double>(t[2]),
            values_of<double>(t[3])};
}

BreakpointRule rule_of(nb::handle t) {
    nb::handle noise = t[4];
    return {nb::cast<Index>(t[0]),          nb::cast<double>(t[1]),
            nb::cast<double>(t[2]),         nb::cast<double>(t[3]),
            {nb::cast<double>(noise[0]), nb::cast<double>(noise[1])},
            nb::cast<double>(t[5]),         nb::cast<double>(t[6]),
            nb::cast<double>(t[7])};
}

RunCost cost_of(nb::handle t) {
    nb::handle moments = t[1];
    auto table = nb::cast<In<double, nb::ndim<2>>>(moments[0]);
    Moments m{Reals(table.data(), table.data() + table.shape(0) * table.shape(1)),
              static_cast<Index>(table.shape(1)), nb::cast<double>(moments[1]),
              nb::cast<double>(moments[2])};
    return {nb::cast<Index>(t[0]), std::move(m), values_of<double>(t[2]), values_of<double>(t[3])};
}

template <typename T>
nb::object copy_to_numpy(const std::vector<T>& values) {
    return to_numpy(std::vector<T>(values));
}

AdaptiveSettings adaptive_settings(const nb::dict& d) {
    AdaptiveSettings s;
    s.min_points = setting<Index>(d, "min_points");
    s.min_length = setting<double>(d, "min_length");
    s.range_sigma = setting<double>(d, "range_sigma");
    s.breakpoints = setting<Index>(d, "breakpoints");
    s.k = setting<double>(d, "k");
    s.noise_k = setting<double>(d, "noise_k");
    s.line_k = setting<double>(d, "line_k");
    s.abd_lambda = setting<double>(d, "abd_lambda");
    s.auto_abd_lambda = setting<bool>(d, "auto_abd_lambda");
    s.pdbs_c0 = setting<double>(d, "pdbs_c0");
    s.jump_distance = setting<double>(d, "jump_distance");
    s.denoise = setting<Index>(d, "denoise");
    s.window = setting<Index>(d, "window");
    s.corner_score = setting<Index>(d, "corner_score");
    s.slope_window = setting<Index>(d, "slope_window");
    s.auto_slope_window = setting<bool>(d, "auto_slope_window");
    s.use_grid = setting<bool>(d, "use_grid");
    s.max_evaluations = setting<Index>(d, "max_evaluations");
    s.criterion = setting<Index>(d, "criterion");
    s.penalty = setting<double>(d, "penalty");
    s.noise_sigma = setting<double>(d, "noise_sigma");
    s.estimate_noise = setting<bool>(d, "estimate_noise");
    s.fit = setting<Index>(d, "fit");
    s.shared_corner = setting<bool>(d, "shared_corner");
    s.merge = setting<bool>(d, "merge");
    s.merge_chi2 = setting<double>(d, "merge_chi2");
    s.max_residual = setting<double>(d, "max_residual");
    s.corner_check = setting<bool>(d, "corner_check");
    s.min_cluster_points = setting<Index>(d, "min_cluster_points");
    s.constant_noise = setting<bool>(d, "constant_noise");
    return s;
}

// The sweep and criterion (scanlines/steps/select.py), for the tests of the steps.
void bind_select(nb::module_& m) {
    nb::class_<Sweep>(m, "Sweep", "A threshold sweep in progress (scanlines.steps.select).")
        .def_prop_ro("ranked", [](const Sweep& s) { return copy_to_numpy(s.ranked); })
        .def_prop_ro("ranked_score", [](const Sweep& s) { return copy_to_numpy(s.ranked_score); })
        .def_ro("useful", &Sweep::useful)
        .def_prop_ro("accepted", [](const Sweep& s) { return flags_to_numpy(s.accepted); })
        .def_prop_ro("parent_a", [](const Sweep& s) { return copy_to_numpy(s.parent_a); })
        .def_prop_ro("parent_b", [](const Sweep& s) { return copy_to_numpy(s.parent_b); })
        .def_prop_ro("sse", [](const Sweep& s) { return copy_to_numpy(s.sse); })
        .def_prop_ro("segments", [](const Sweep& s) { return copy_to_numpy(s.segments); });
    m.def(
        "start_sweep",
        [](nb::handle cost, nb::handle start, nb::handle end, nb::handle candidates,
           nb::handle scores, nb::handle grid, bool use_grid, Index max_evaluations) {
            return start_sweep(cost_of(cost), values_of<Index>(start), values_of<Index>(end),
                               values_of<Index>(candidates), values_of<double>(scores),
                               values_of<double>(grid), use_grid, max_evaluations);
        },
        "A sweep of the clusters [start, end] with no candidate inserted yet.");
    m.def(
        "extend_sweep",
        [](Sweep& sweep, nb::handle cost, bool shared, Index done, Index upto) {
            return extend_sweep(sweep, cost_of(cost), shared, done, upto);
        },
        "Insert candidates done .. upto - 1 of the sweep (in place); returns upto.");
    m.def(
        "sweep_decided",
        [](Sweep& sweep, nb::handle cost, bool shared, Index done, Index n_points, double sigma,
           double penalty) {
            return sweep_decided(sweep, cost_of(cost), shared, done, n_points, sigma, penalty);
        },
        "Extend the sweep until the bic choice is certain: (best level, inserted).");
    m.def(
        "sweep_levels",
        [](nb::handle cost, nb::handle start, nb::handle end, nb::handle candidates,
           nb::handle scores, nb::handle grid, bool use_grid, Index max_evaluations,
           bool shared) {
            Levels out = sweep_levels(cost_of(cost), values_of<Index>(start),
                                      values_of<Index>(end), values_of<Index>(candidates),
                                      values_of<double>(scores), values_of<double>(grid),
                                      use_grid, max_evaluations, shared);
            return nb::make_tuple(to_numpy(std::move(out.ranked)), flags_to_numpy(out.accepted),
                                  to_numpy(std::move(out.sse)), to_numpy(std::move(out.segments)),
                                  to_numpy(std::move(out.thresholds)),
                                  to_numpy(std::move(out.levels)));
        },
        "Every cut a threshold makes: (ranked, accepted, sse, segments, thresholds, levels).");
    m.def(
        "best_level",
        [](Index criterion, nb::handle sse, nb::handle segments, nb::handle levels,
           Index n_points, double sigma, double penalty) {
            auto [best, values] =
                best_level(criterion, values_of<double>(sse), values_of<Index>(segments),
                           values_of<Index>(levels), n_points, sigma, penalty);
            return nb::make_tuple(best, to_numpy(std::move(values)));
        },
        "Index of the best tried threshold (the first on a tie) and every criterion value.");
    m.def(
        "level_corners",
        [](nb::handle ranked, nb::handle accepted, Index level) {
            Flags flags;
            for (bool f : values_of<bool>(accepted)) flags.push_back(f);
            return to_numpy(level_corners(values_of<Index>(ranked), flags, level));
        },
        "Sorted positions of the accepted candidates among the level best.");
}

// Denoising (scanlines/steps/denoise.py), for the tests of the steps.
void bind_denoise(nb::module_& m) {
    auto flags = [](nb::handle h) {
        Flags out;
        for (bool f : values_of<bool>(h)) out.push_back(f);
        return out;
    };
    m.def(
        "literal_noise",
        [](nb::handle d) { return flags_to_numpy(literal_noise(values_of<double>(d))); },
        "Step 2 as written, on neighbour distances d (length n - 1): a mask of n points.");
    m.def(
        "isolated_noise",
        [flags](nb::handle returns, nb::handle gap, double step, nb::handle rule,
                nb::handle breaks) {
            return flags_to_numpy(isolated_noise(returns_of(returns), values_of<Index>(gap), step,
                                                 rule_of(rule), flags(breaks)));
        },
        "Points cut off from both neighbours that are themselves continuous (a spike).");
    m.def(
        "window_means",
        [flags](nb::handle x, nb::handle y, nb::handle noise, Index window, nb::handle breaks) {
            auto [mx, my] = window_means(values_of<double>(x), values_of<double>(y), flags(noise),
                                         window, flags(breaks));
            return nb::make_tuple(to_numpy(std::move(mx)), to_numpy(std::move(my)));
        },
        "Step 3: noise point i and its neighbours become the mean of window points.");
    m.def(
        "small_clusters",
        [flags](nb::handle breaks, Index min_points, bool seam_joined) {
            return flags_to_numpy(small_clusters(flags(breaks), min_points, seam_joined));
        },
        "Mask of the points of clusters with fewer than min_points returns.");
    m.def(
        "in_between_clusters",
        [flags](nb::handle r, nb::handle gap, nb::handle breaks, nb::handle small,
                double margin) {
            return flags_to_numpy(in_between_clusters(values_of<double>(r), values_of<Index>(gap),
                                                      flags(breaks), flags(small), margin));
        },
        "Mask of the returns of two-return clusters that lie in depth between their neighbours.");
}

}  // namespace

void bind_adaptive(nb::module_& m) {
    m.def(
        "adaptive_stack",
        [](const In<double, nb::ndim<2>>& ranges, const In<bool, nb::ndim<2>>& valid,
           const In<double, nb::ndim<1>>& cos, const In<double, nb::ndim<1>>& sin, double step,
           bool full_circle, double angle_min, std::pair<double, double> noise,
           const nb::dict& settings, const In<double, nb::ndim<1>>& grid) {
            Stack stack = stack_of(ranges, valid, cos, sin, step, full_circle, angle_min, noise);
            AdaptiveSettings s = adaptive_settings(settings);
            Reals thresholds = reals(grid);
            Table table;
            {
                nb::gil_scoped_release unlocked;
                table = adaptive_stack(stack, s, thresholds);
            }
            return table_to_numpy(std::move(table));
        },
        "The adaptive method on each row of a stack of scans: one flat table.");
    m.def(
        "threshold_grid",
        [](double low, double high, double step, Index max_evaluations) {
            return to_numpy(threshold_grid(low, high, step, max_evaluations));
        },
        "low, low + step, ... up to high, at most max_evaluations values.");
    bind_select(m);
    bind_denoise(m);
}

}  // namespace scanlines::bind
