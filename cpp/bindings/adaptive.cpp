#include <nanobind/stl/pair.h>
#include <nanobind/stl/tuple.h>

#include <cmath>
#include <tuple>

#include "arrays.hpp"
#include "scanlines/methods/adaptive.hpp"
#include "scanlines/steps/corners.hpp"
#include "scanlines/steps/denoise.hpp"
#include "scanlines/steps/fit.hpp"
#include "scanlines/steps/select.hpp"

namespace scanlines::bind {

namespace {

// The settings record of scanlines/methods/adaptive.py, group by group.
AdaptiveSettings adaptive_settings(const nb::dict& record) {
    AdaptiveSettings s;
    nb::dict noise = group(record, "noise");
    s.noise = {setting<double>(noise, "noise_sigma"), setting<bool>(noise, "estimate_noise"),
               setting<bool>(noise, "constant_noise")};
    nb::dict clustering = group(record, "clustering");
    s.clustering = {rule_spec_of(clustering), setting<bool>(clustering, "auto_abd_lambda"),
                    setting_in(clustering, "denoise", ISOLATED, NO_DENOISE),
                    setting_in(clustering, "window", 1, MAX_SETTING_COUNT),
                    setting_in(clustering, "min_cluster_points", 0, MAX_SETTING_COUNT)};
    nb::dict segments = group(record, "segments");
    auto& g = s.segments;
    g.corner_score = setting_in(segments, "corner_score", TURN, DK_SIGNED);
    g.slope_window = setting_in(segments, "slope_window", 0, MAX_SETTING_COUNT);
    g.auto_slope_window = setting<bool>(segments, "auto_slope_window");
    g.use_grid = setting<bool>(segments, "use_grid");
    g.max_evaluations = setting_in(segments, "max_evaluations", 0, MAX_SETTING_COUNT);
    g.criterion = setting_in(segments, "criterion", BIC, SSE);
    g.penalty = setting<double>(segments, "penalty");
    g.fit = setting_in(segments, "fit", TLS, PAPER);
    g.shared_corner = setting<bool>(segments, "shared_corner");
    g.merge = setting<bool>(segments, "merge");
    g.merge_chi2 = setting<double>(segments, "merge_chi2");
    g.max_residual = setting<double>(segments, "max_residual");
    s.events = {setting<bool>(group(record, "events"), "corner_check")};
    s.output = output_bounds_of(group(record, "output"));
    return s;
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
            RunCost run_cost = cost_of(cost);
            if (static_cast<Index>(sweep.run_end.size()) != run_cost.moments.stride - 1)
                value_error("the sweep was started on other points than the cost's");
            expect_between("done", done, 0, sweep.useful);
            return sweep_decided(sweep, run_cost, shared, done, n_points, sigma, penalty);
        },
        "Extend the sweep until the bic choice is certain: (best level, inserted).");
}

#ifdef SCANLINES_STAGE_TIMES
// The time of each stage of the method (a build with -DSCANLINES_STAGE_TIMES=ON, for
// tools/benchmarks/stage_times.py).
void bind_stage_times(nb::module_& m) {
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
            Table table;
            {
                nb::gil_scoped_release unlocked;
                table = adaptive_stack_timed(stack, s, thresholds, seconds);
            }
            nb::dict out;
            for (int k = 0; k < N_ADAPTIVE_STAGES; ++k) out[ADAPTIVE_STAGE_NAMES[k]] = seconds[k];
            return nb::make_tuple(out, table_to_numpy(std::move(table)));
        },
        "adaptive_stack's arguments: the seconds each stage of the method took over the stack, "
        "by name, in order, and adaptive_stack's table.");
}
#endif

}  // namespace

void bind_adaptive(nb::module_& m) {
    m.def("adaptive_stack", &grid_stack_kernel<adaptive_settings, adaptive_stack>,
          "The adaptive method on each row of a stack of scans: one flat table.");
#ifdef SCANLINES_STAGE_TIMES
    bind_stage_times(m);
#endif
    bind_own_steps(m);
}

}  // namespace scanlines::bind
