#include <nanobind/stl/pair.h>

#include "arrays.hpp"
#include "scanlines/methods/adaptive.hpp"
#include "scanlines/steps/select.hpp"

namespace scanlines::bind {

namespace {

Reals reals(const In<double, nb::ndim<1>>& array) {
    return Reals(array.data(), array.data() + array.shape(0));
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
}

}  // namespace scanlines::bind
