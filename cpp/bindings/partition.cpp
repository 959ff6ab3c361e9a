#include <nanobind/stl/pair.h>

#include "arrays.hpp"
#include "scanlines/methods/partition.hpp"
#include "scanlines/methods/surfaces.hpp"

namespace scanlines::bind {

void bind_partition(nb::module_& m) {
    m.def(
        "partition_stack",
        [](const In<double, nb::ndim<2>>& ranges, const In<bool, nb::ndim<2>>& valid,
           const In<double, nb::ndim<1>>& cos, const In<double, nb::ndim<1>>& sin, double step,
           bool full_circle, double angle_min, std::pair<double, double> noise,
           const nb::dict& settings) {
            Stack stack = stack_of(ranges, valid, cos, sin, step, full_circle, angle_min, noise);
            PartitionSettings s{setting<double>(settings, "penalty"),
                                setting<double>(settings, "clutter_cost"),
                                setting<double>(settings, "model_error"),
                                setting<Index>(settings, "min_points"),
                                setting<double>(settings, "min_length"),
                                setting<double>(settings, "max_rho_sigma"),
                                setting<double>(settings, "noise_sigma"),
                                setting<double>(settings, "range_sigma")};
            Table table;
            {
                nb::gil_scoped_release unlocked;
                table = partition_stack(stack, s);
            }
            return table_to_numpy(std::move(table));
        },
        "The partition method on each row of a stack of scans: one flat table.");
    m.def(
        "surfaces_stack",
        [](const In<double, nb::ndim<2>>& ranges, const In<bool, nb::ndim<2>>& valid,
           const In<double, nb::ndim<1>>& cos, const In<double, nb::ndim<1>>& sin, double step,
           bool full_circle, double angle_min, std::pair<double, double> noise,
           const nb::dict& settings) {
            Stack stack = stack_of(ranges, valid, cos, sin, step, full_circle, angle_min, noise);
            SurfacesSettings s{setting<double>(settings, "penalty"),
                               setting<double>(settings, "clutter_cost"),
                               setting<double>(settings, "model_error"),
                               setting<double>(settings, "footprint"),
                               setting<Index>(settings, "min_points"),
                               setting<double>(settings, "min_length"),
                               setting<double>(settings, "noise_sigma"),
                               setting<double>(settings, "range_sigma")};
            Table table;
            {
                nb::gil_scoped_release unlocked;
                table = surfaces_stack(stack, s);
            }
            return table_to_numpy(std::move(table));
        },
        "The surfaces method on each row of a stack of scans: one flat table.");
    m.def(
        "partition_optimal_runs",
        [](const In<double, nb::ndim<1>>& x, const In<double, nb::ndim<1>>& y,
           const In<double, nb::ndim<1>>& sigma, double model_error,
           const In<bool, nb::ndim<1>>& opens, double penalty, double clutter_cost,
           Index min_points) {
            std::size_t n = x.shape(0);
            if (y.shape(0) != n || sigma.shape(0) != n || opens.shape(0) != n)
                throw nb::value_error("x, y, sigma and opens must have one length");
            Reals xs(x.data(), x.data() + n), ys(y.data(), y.data() + n);
            Reals sigmas(sigma.data(), sigma.data() + n);
            Flags open_flags(opens.data(), opens.data() + n);
            auto [a, b] = partition_optimal_runs(xs, ys, sigmas, model_error, open_flags, penalty,
                                                 clutter_cost, min_points);
            return nb::make_tuple(to_numpy(std::move(a)), to_numpy(std::move(b)));
        },
        "The partition's dynamic programme alone (every return held): runs (a, b).");
}

}  // namespace scanlines::bind
