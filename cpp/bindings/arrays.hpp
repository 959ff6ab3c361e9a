// numpy arrays to kernel views and kernel results to numpy arrays, for the bindings.
#pragma once

#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>

#include <array>
#include <cmath>
#include <limits>
#include <tuple>
#include <cstring>
#include <type_traits>
#include <utility>
#include <vector>

#include "checks.hpp"
#include "scanlines/core.hpp"
#include "scanlines/steps/assemble.hpp"
#include "scanlines/steps/breakpoints.hpp"
#include "scanlines/steps/split.hpp"
#include "scanlines/steps/stack.hpp"

namespace scanlines::bind {

namespace nb = nanobind;

template <typename T, typename... Extra>
using In = nb::ndarray<const T, nb::numpy, nb::c_contig, nb::device::cpu, Extra...>;

template <typename T>
View<T> view(const In<T, nb::ndim<1>>& array) {
    return {array.data(), static_cast<Index>(array.shape(0))};
}

// A vector moved into a numpy array that owns it.
template <typename T>
nb::object to_numpy(std::vector<T>&& values, std::initializer_list<std::size_t> shape) {
    auto* owned = new std::vector<T>(std::move(values));
    nb::capsule owner(owned, [](void* p) noexcept { delete static_cast<std::vector<T>*>(p); });
    return nb::cast(nb::ndarray<nb::numpy, T>(owned->data(), shape.size(), shape.begin(), owner));
}

template <typename T>
nb::object to_numpy(std::vector<T>&& values) {
    std::size_t n = values.size();
    return to_numpy(std::move(values), {n});
}

// bool flags as a numpy bool array.
inline nb::object flags_to_numpy(const Flags& flags) {
    auto* owned = new std::vector<std::uint8_t>(flags);
    nb::capsule owner(owned, [](void* p) noexcept { delete static_cast<std::vector<std::uint8_t>*>(p); });
    std::size_t shape[1] = {owned->size()};
    return nb::cast(nb::ndarray<nb::numpy, bool>(reinterpret_cast<bool*>(owned->data()), 1, shape, owner));
}

// One scan's result as Extraction takes it: first, last, n_points, lines (m, 7),
// covariances (m, 2, 2), breakpoints, corners, outliers, end_kinds (m, 2).
inline nb::tuple result_to_numpy(ScanResult&& c) {
    std::size_t m = c.first.size();
    return nb::make_tuple(
        to_numpy(std::move(c.first)), to_numpy(std::move(c.last)), to_numpy(std::move(c.n_points)),
        to_numpy(std::move(c.lines), {m, static_cast<std::size_t>(LINE_COLUMNS)}),
        to_numpy(std::move(c.covariances), {m, 2, 2}), to_numpy(std::move(c.breakpoints)),
        to_numpy(std::move(c.corners)), to_numpy(std::move(c.outliers)),
        to_numpy(std::move(c.end_kinds), {m, 2}));
}

template <typename T>
std::vector<T> vector_of(const In<T, nb::ndim<1>>& array) {
    return std::vector<T>(array.data(), array.data() + array.shape(0));
}

inline Flags flags_of(const In<bool, nb::ndim<1>>& array) {
    return Flags(array.data(), array.data() + array.shape(0));
}

using InReals = In<double, nb::ndim<1>>;
using InInts = In<Index, nb::ndim<1>>;
using InFlags = In<bool, nb::ndim<1>>;

// The Returns of the Python side's (index, r, x, y).
inline Returns returns_of(const InInts& index, const InReals& r, const InReals& x,
                          const InReals& y) {
    std::size_t n = index.shape(0);
    if (r.shape(0) != n || x.shape(0) != n || y.shape(0) != n)
        throw nb::value_error("index, r, x and y must have one length");
    return {vector_of(index), vector_of(r), vector_of(x), vector_of(y)};
}

inline nb::tuple returns_to_numpy(Returns&& returns) {
    return nb::make_tuple(to_numpy(std::move(returns.index)), to_numpy(std::move(returns.r)),
                          to_numpy(std::move(returns.x)), to_numpy(std::move(returns.y)));
}

// Moments viewing the Python side's table (5, n + 1): no copy.
inline Moments moments_of(const In<double, nb::ndim<2>>& table, double ox, double oy) {
    if (table.shape(0) != 5) throw nb::value_error("a moments table has 5 rows");
    if (table.shape(1) < 1) throw nb::value_error("a moments table has n + 1 columns, got none");
    return Moments(table.data(), static_cast<Index>(table.shape(1)), ox, oy);
}

// The same, for the n points whose moments the table must hold.
inline Moments moments_of(const In<double, nb::ndim<2>>& table, double ox, double oy,
                          std::size_t points) {
    Moments moments = moments_of(table, ox, oy);
    expect_length("the moments table's columns", table.shape(1), points + 1,
                  "n + 1 for the n points");
    return moments;
}

// A BreakpointRule as the Python side's named tuple (kind, k, margin_sigmas,
// tolerance_sigmas, noise, abd_lambda, pdbs_c0, jump_distance) holds it.
inline BreakpointRule breakpoint_rule_of(const nb::handle& rule) {
    if (nb::len(rule) != 8)
        throw nb::value_error("a breakpoint rule has 8 fields (kind, k, margin_sigmas, "
                              "tolerance_sigmas, noise, abd_lambda, pdbs_c0, jump_distance)");
    auto real = [&](std::size_t i) { return nb::cast<double>(nb::float_(rule[i])); };
    nb::handle noise = rule[4];
    if (nb::len(noise) != 2) throw nb::value_error("a rule's noise is (sigma0, per_metre)");
    const Index kind = nb::cast<Index>(nb::int_(rule[0]));
    expect_between("the rule's kind", kind, NO_RULE, FIXED);
    return {kind,
            real(1),
            real(2),
            real(3),
            {nb::cast<double>(nb::float_(noise[0])), nb::cast<double>(nb::float_(noise[1]))},
            real(5),
            real(6),
            real(7)};
}

// A RunCost from the moments' table and the noise sums (both empty: the plain error).
inline RunCost run_cost_of(Index fit, const In<double, nb::ndim<2>>& table, double ox, double oy,
                           const InReals& inv_r2, const InReals& variances) {
    expect_between("fit", fit, TLS, PAPER);
    Moments moments = moments_of(table, ox, oy);
    const std::size_t columns = table.shape(1);
    if (inv_r2.shape(0) != 0 || variances.shape(0) != 0) {
        expect_length("inv_r2", inv_r2.shape(0), columns, "running sums: n + 1 for n points");
        expect_length("variances", variances.shape(0), columns,
                      "running sums: n + 1 for n points");
    }
    return {fit, std::move(moments), vector_of(inv_r2), vector_of(variances)};
}

// The tuples the steps' Python side builds (scanlines.steps: Returns, RunCost with its
// Moments), taken as they are.
using ReturnsTuple = std::tuple<InInts, InReals, InReals, InReals>;
using CostTuple =
    std::tuple<Index, std::tuple<In<double, nb::ndim<2>>, double, double>, InReals, InReals>;

inline Returns returns_tuple_of(const ReturnsTuple& t) {
    return returns_of(std::get<0>(t), std::get<1>(t), std::get<2>(t), std::get<3>(t));
}

// A view of the caller's moments: valid while the call's arguments are.
inline RunCost cost_of(const CostTuple& t) {
    const auto& [table, ox, oy] = std::get<1>(t);
    return run_cost_of(std::get<0>(t), table, ox, oy, std::get<2>(t), std::get<3>(t));
}

template <typename T>
nb::object copy_to_numpy(const std::vector<T>& values) {
    return to_numpy(std::vector<T>(values));
}

inline nb::tuple runs_to_numpy(GroupedRuns&& runs) {
    return nb::make_tuple(to_numpy(std::move(runs.a)), to_numpy(std::move(runs.b)),
                          to_numpy(std::move(runs.group)));
}

// A stack kernel's table as ExtractionTable.of_flat_table reads it: the nine columns
// flat, each scan's counts (rows x 4) and their sums.
inline nb::tuple table_to_numpy(Table&& table) {
    ScanResult& c = table.columns;
    std::vector<Index> counts, used(4, 0);
    for (const auto& row : table.counts)
        for (int k = 0; k < 4; ++k) {
            counts.push_back(row[k]);
            used[k] += row[k];
        }
    std::size_t rows = table.counts.size();
    return nb::make_tuple(
        to_numpy(std::move(c.first)), to_numpy(std::move(c.last)), to_numpy(std::move(c.n_points)),
        to_numpy(std::move(c.lines)), to_numpy(std::move(c.covariances)),
        to_numpy(std::move(c.breakpoints)), to_numpy(std::move(c.corners)),
        to_numpy(std::move(c.outliers)), to_numpy(std::move(c.end_kinds)),
        to_numpy(std::move(counts), {rows, 4}), to_numpy(std::move(used)));
}

// The sensor of a stack kernel's call, as the Python side passes it.
inline Stack stack_of(const In<double, nb::ndim<2>>& ranges, const In<bool, nb::ndim<2>>& valid,
                      const In<double, nb::ndim<1>>& cos, const In<double, nb::ndim<1>>& sin,
                      double step, bool full_circle, double angle_min,
                      std::pair<double, double> noise) {
    Index rows = static_cast<Index>(ranges.shape(0)), beams = static_cast<Index>(ranges.shape(1));
    if (valid.shape(0) != ranges.shape(0) || valid.shape(1) != ranges.shape(1) ||
        static_cast<Index>(cos.shape(0)) != beams || static_cast<Index>(sin.shape(0)) != beams)
        throw nb::value_error("ranges, valid and the bearing tables disagree in shape");
    expect_step(step);
    if (!std::isfinite(angle_min)) throw nb::value_error("angle_min must be finite");
    return {ranges.data(), valid.data(), rows, beams, view(cos), view(sin),
            step, full_circle, angle_min, {noise.first, noise.second}};
}

// A setting read by name from the settings the method's module passes: plain Python numbers
// (bool for a flag, int for a count or code, float or int for a number), nothing else.
template <typename T>
T setting(const nb::dict& settings, const char* name) {
    if (!settings.contains(name)) throw nb::key_error(name);
    PyObject* value = nb::object(settings[name]).ptr();
    auto wrong = [&](const char* kind) {
        throw nb::type_error((std::string("setting ") + name + " must be " + kind + ", got " +
                              Py_TYPE(value)->tp_name)
                                 .c_str());
    };
    if constexpr (std::is_same_v<T, bool>) {
        if (!PyBool_Check(value)) wrong("a bool");
        return value == Py_True;
    } else if constexpr (std::is_integral_v<T>) {
        if (!PyLong_CheckExact(value)) wrong("an int");
        int overflow = 0;
        long long out = PyLong_AsLongLongAndOverflow(value, &overflow);
        if (overflow != 0) value_error(std::string("setting ") + name + " is out of range");
        return static_cast<T>(out);
    } else {
        if (PyFloat_CheckExact(value)) return PyFloat_AS_DOUBLE(value);
        if (!PyLong_CheckExact(value)) wrong("a float");
        double out = PyLong_AsDouble(value);
        if (out == -1.0 && PyErr_Occurred()) throw nb::python_error();
        return out;
    }
}

// An integer setting in low .. high (a count, window or code).
inline Index setting_in(const nb::dict& settings, const char* name, Index low, Index high) {
    Index value = setting<Index>(settings, name);
    expect_between(name, value, low, high);
    return value;
}

// A number setting that must not be NaN (NaN stands for "not given" only where it is read
// with setting<double>).
inline double number_setting(const nb::dict& settings, const char* name) {
    double value = setting<double>(settings, name);
    if (value != value) value_error(std::string("setting ") + name + " must be a number, got NaN");
    return value;
}

// The largest count a setting may give (the most beams a reader accepts, MAX_COUNT in
// scanlines/params.py, with room).
constexpr Index MAX_SETTING_COUNT = 1'000'000'000;

// One group of a method's settings record (scanlines.params.Settings.record).
inline nb::dict group(const nb::dict& record, const char* name) {
    if (!record.contains(name)) throw nb::key_error(name);
    return nb::cast<nb::dict>(record[name]);
}

// The clustering rule's fields (the shared clustering settings, RuleSpec in
// scanlines/steps/breakpoints.py), by name.
inline RuleSpec rule_spec_of(const nb::dict& clustering) {
    return {setting_in(clustering, "breakpoints", NO_RULE, FIXED),
            number_setting(clustering, "k"),
            number_setting(clustering, "noise_k"),
            number_setting(clustering, "line_k"),
            setting<double>(clustering, "abd_lambda"),  // NaN: "auto" (the adaptive method's)
            number_setting(clustering, "pdbs_c0"),
            number_setting(clustering, "jump_distance")};
}

// The output settings every method has (output_settings in scanlines/steps/assemble.py).
inline OutputBounds output_bounds_of(const nb::dict& output) {
    return {setting_in(output, "min_points", 0, MAX_SETTING_COUNT),
            setting<double>(output, "min_length"),
            setting<double>(output, "range_sigma")};
}

// The shared corner rule's bounds (EVENTS in scanlines/steps/events.py).
inline CornerBounds corner_bounds_of(const nb::dict& events) {
    return {setting_in(events, "corner_beams", 0, MAX_SETTING_COUNT),
            setting<double>(events, "corner_distance"),
            setting<double>(events, "corner_angle")};
}

// A comparison method's output (Output in scanlines/steps/assemble.py): its output and
// events settings (one flat dict may hold both).
inline Output output_of(const nb::dict& output, const nb::dict& events) {
    return {output_bounds_of(output), corner_bounds_of(events)};
}

// A method's stack kernel as the Python side calls it: the sensor's arrays and the method's
// settings record (read into its typed settings by read), one flat table out, the kernel run
// without the GIL.
template <auto read, auto kernel>
nb::tuple stack_kernel(const In<double, nb::ndim<2>>& ranges, const In<bool, nb::ndim<2>>& valid,
                       const In<double, nb::ndim<1>>& cos, const In<double, nb::ndim<1>>& sin,
                       double step, bool full_circle, double angle_min,
                       std::pair<double, double> noise, const nb::dict& record) {
    Stack stack = stack_of(ranges, valid, cos, sin, step, full_circle, angle_min, noise);
    auto settings = read(record);
    Table table;
    {
        nb::gil_scoped_release unlocked;
        table = kernel(stack, settings);
    }
    return table_to_numpy(std::move(table));
}

// The same for a kernel that also takes the thresholds it tries (grid).
template <auto read, auto kernel>
nb::tuple grid_stack_kernel(const In<double, nb::ndim<2>>& ranges,
                            const In<bool, nb::ndim<2>>& valid,
                            const In<double, nb::ndim<1>>& cos,
                            const In<double, nb::ndim<1>>& sin, double step, bool full_circle,
                            double angle_min, std::pair<double, double> noise,
                            const nb::dict& record, const InReals& grid) {
    Stack stack = stack_of(ranges, valid, cos, sin, step, full_circle, angle_min, noise);
    auto settings = read(record);
    Reals thresholds = vector_of(grid);
    Table table;
    {
        nb::gil_scoped_release unlocked;
        table = kernel(stack, settings, thresholds);
    }
    return table_to_numpy(std::move(table));
}

}  // namespace scanlines::bind
