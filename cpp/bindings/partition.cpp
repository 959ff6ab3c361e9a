#include <nanobind/stl/pair.h>

#include "arrays.hpp"
#include "scanlines/methods/partition.hpp"
#include "scanlines/methods/surfaces.hpp"

namespace scanlines::bind {

namespace {

// The objective's settings, shared by partition and surfaces (their segments group).
penalised::ObjectiveSettings objective_of(const nb::dict& segments) {
    return {setting<double>(segments, "penalty"), setting<double>(segments, "clutter_cost"),
            setting<double>(segments, "model_error")};
}

// The settings record of scanlines/methods/partition.py, group by group.
PartitionSettings partition_settings(const nb::dict& record) {
    nb::dict output = group(record, "output");
    return {setting<double>(group(record, "noise"), "noise_sigma"),
            objective_of(group(record, "segments")),
            {output_bounds_of(output), setting<double>(output, "max_rho_sigma")}};
}

// The settings record of scanlines/methods/surfaces.py, group by group.
SurfacesSettings surfaces_settings(const nb::dict& record) {
    nb::dict segments = group(record, "segments");
    return {setting<double>(group(record, "noise"), "noise_sigma"),
            {objective_of(segments), setting<double>(segments, "footprint"),
             setting<bool>(segments, "two_stage")},
            output_bounds_of(group(record, "output"))};
}

}  // namespace

void bind_partition(nb::module_& m) {
    m.def("partition_stack", &stack_kernel<partition_settings, partition_stack>,
          "The partition method on each row of a stack of scans: one flat table.");
    m.def("surfaces_stack", &stack_kernel<surfaces_settings, surfaces_stack>,
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
            expect_between("min_points", min_points, 0, MAX_SETTING_COUNT);
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
