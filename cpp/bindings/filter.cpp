// The localisation filter's kernel (scanlines/map/filter.hpp): one scan's step, called by
// scanlines.map.filter, which builds the grid and documents the settings.
#include <cmath>
#include <string>

#include "arrays.hpp"
#include "scanlines/map/filter.hpp"
#include "scanlines/map/point_to_line.hpp"

namespace scanlines::bind {

namespace {

using InTable = In<double, nb::ndim<2>>;

// The filter's settings record (scanlines.map.filter.FilterSettings.record), by group and
// name; max_points is given on its own.
FilterParams params_of(const nb::dict& record) {
    const nb::dict odometry = group(record, "odometry"), association = group(record, "association"),
                   noise = group(record, "noise"), solver = group(record, "solver");
    auto count = [](const nb::dict& settings, const char* name) {
        return setting_in(settings, name, 1, MAX_SETTING_COUNT);
    };
    FilterParams p{};
    p.odometry_floor = number_setting(odometry, "odometry_floor");
    p.odometry_per_metre = number_setting(odometry, "odometry_per_metre");
    p.turn_floor = number_setting(odometry, "turn_floor");
    p.turn_per_radian = number_setting(odometry, "turn_per_radian");
    p.turn_per_metre = number_setting(odometry, "turn_per_metre");
    p.drift_walk = number_setting(odometry, "drift_walk");
    p.scale_walk = number_setting(odometry, "scale_walk");
    p.normal_window = count(association, "normal_window");
    p.neighbour_gap = number_setting(association, "neighbour_gap");
    p.flatness = number_setting(association, "flatness");
    p.normal_cosine = number_setting(association, "normal_cosine");
    p.gate_base = number_setting(association, "gate_base");
    p.gate_sigmas = number_setting(association, "gate_sigmas");
    p.gate_min = number_setting(association, "gate_min");
    p.gate_max = number_setting(association, "gate_max");
    p.line_returns = count(association, "line_returns");
    p.return_sigma = number_setting(noise, "return_sigma");
    p.line_sigma = number_setting(noise, "line_sigma");
    p.huber = number_setting(noise, "huber");
    p.iterations = count(solver, "iterations");
    p.tolerance = number_setting(solver, "tolerance");
    p.min_pairs = count(solver, "min_pairs");
    p.max_chi_square = number_setting(solver, "max_chi_square");
    p.max_points = 0;
    return p;
}

// A grid of shape (x0, y0, cell, nx, ny) and its cells, checked as far as the kernel reads it.
// `name`: the grid's name in the errors.
CellGrid cells_of(const char* name, const InReals& shape, const InInts& cell_start,
                  const InInts& cell_lines) {
    const std::string grid = std::string("the ") + name + " grid";
    if (shape.shape(0) != 5) value_error(grid + "'s shape is x0, y0, cell, nx, ny");
    // The cells nx, ny: whole numbers, the grid no larger than its cell starts.
    const double* v = shape.data();
    const double cells_x = v[3], cells_y = v[4];
    if (!(cells_x >= 1.0 && cells_y >= 1.0) || cells_x != std::floor(cells_x) ||
        cells_y != std::floor(cells_y) ||
        cells_x * cells_y + 1.0 != static_cast<double>(cell_start.shape(0)))
        value_error(grid + " has nx * ny + 1 cell starts");
    if (!std::isfinite(v[0]) || !std::isfinite(v[1]) || !(v[2] > 0.0) || !std::isfinite(v[2]))
        value_error(grid + "'s x0, y0 must be finite and its cell above 0");
    const Index nx = static_cast<Index>(cells_x), ny = static_cast<Index>(cells_y);
    if (static_cast<Index>(cell_start.shape(0)) != nx * ny + 1)
        value_error(grid + " has nx * ny + 1 cell starts");
    // The grid is built once by scanlines.map.filter.LineGrid, which checks it; here only
    // its ends (the kernel skips a cell or line id out of range rather than read past).
    const Index total = static_cast<Index>(cell_lines.shape(0));
    if (cell_start.data()[0] != 0 || cell_start.data()[nx * ny] != total)
        value_error(grid + "'s cell starts must run from 0 to its number of ids");
    return {v[0], v[1], v[2], nx, ny, view(cell_start), view(cell_lines)};
}

nb::tuple filter_scan_binding(const InReals& state, const InTable& covariance,
                              const InReals& increment, bool first, const InReals& x,
                              const InReals& y, const InReals& rho, const InTable& normal,
                              const InTable& start, const InTable& end, const InInts& sides,
                              const InReals& shape, const InInts& cell_start,
                              const InInts& cell_lines, const InReals& near_shape,
                              const InInts& near_cell_start, const InInts& near_cell_lines,
                              double near_reach, const nb::dict& settings, Index max_points) {
    constexpr std::size_t n = FILTER_STATE;
    if (state.shape(0) != n || covariance.shape(0) != n || covariance.shape(1) != n)
        throw nb::value_error("the state has 7 values and its covariance 7 x 7");
    if (increment.shape(0) != 3) throw nb::value_error("an increment is x, y, theta");
    if (x.shape(0) != y.shape(0)) throw nb::value_error("x and y must have one length");
    const std::size_t lines = rho.shape(0);
    if (normal.shape(0) != lines || start.shape(0) != lines || end.shape(0) != lines ||
        normal.shape(1) != 2 || start.shape(1) != 2 || end.shape(1) != 2 ||
        sides.shape(0) != lines)
        throw nb::value_error("rho, normal, start, end and sides must describe the same lines");
    const CellGrid wide = cells_of("wide", shape, cell_start, cell_lines);
    const CellGrid near = cells_of("near", near_shape, near_cell_start, near_cell_lines);
    if (!(near_reach >= 0.0) || !std::isfinite(near_reach))
        value_error("near_reach must be a finite distance >= 0, got " + std::to_string(near_reach));
    expect_at_least("max_points", max_points, 0);
    FilterParams params = params_of(settings);
    params.max_points = max_points;
    FilterVector s{};
    FilterMatrix c{};
    for (std::size_t i = 0; i < n; ++i) s[i] = state.data()[i];
    for (std::size_t i = 0; i < n * n; ++i) c[i] = covariance.data()[i];
    LineGrid grid{view(rho),
                  View<double>(normal.data(), static_cast<Index>(2 * lines)),
                  View<double>(start.data(), static_cast<Index>(2 * lines)),
                  View<double>(end.data(), static_cast<Index>(2 * lines)),
                  view(sides),
                  wide,
                  near,
                  near_reach};
    FilterStep step;
    {
        nb::gil_scoped_release unlocked;
        const double* move = first ? nullptr : increment.data();
        step = filter_scan(s, c, move, view(x), view(y), grid, params);
    }
    Reals out_state(step.state.begin(), step.state.end());
    Reals out_cov(step.covariance.begin(), step.covariance.end());
    return nb::make_tuple(to_numpy(std::move(out_state)), to_numpy(std::move(out_cov), {n, n}),
                          nb::make_tuple(step.predicted[0], step.predicted[1], step.predicted[2]),
                          step.pairs, step.lines, step.chi_square, static_cast<int>(step.status));
}

// The normal equations of K points on their lines (point_to_line.hpp) with unit variance:
// lever and normals K x 2, residuals K; huber in metres.
nb::tuple point_to_line_system_binding(const InTable& lever, const InTable& normals,
                                       const InReals& residuals, double huber) {
    const std::size_t k = residuals.shape(0);
    if (lever.shape(0) != k || normals.shape(0) != k || lever.shape(1) != 2 ||
        normals.shape(1) != 2)
        throw nb::value_error("lever and normals must be K x 2 for K residuals");
    if (!(huber >= 0.0)) throw nb::value_error("huber must be >= 0");
    LineSystem system{};
    {
        nb::gil_scoped_release unlocked;
        const double *l = lever.data(), *n = normals.data(), *e = residuals.data();
        for (std::size_t i = 0; i < k; ++i)
            add_point_to_line(system, n[2 * i], n[2 * i + 1], l[2 * i], l[2 * i + 1], e[i], 1.0,
                              huber);
    }
    Reals h(system.h, system.h + 9), g(system.g, system.g + 3);
    return nb::make_tuple(to_numpy(std::move(h), {3, 3}), to_numpy(std::move(g)), system.cost);
}

nb::object line_normals_binding(const InReals& alpha) {
    Reals normal;
    {
        nb::gil_scoped_release unlocked;
        normal = line_normals(view(alpha));
    }
    return to_numpy(std::move(normal), {alpha.shape(0), 2});
}

}  // namespace

void bind_filter(nb::module_& m) {
    m.def("filter_scan", &filter_scan_binding,
          "One step of the line-map filter (scanlines.map.filter): predict with the odometry "
          "increment, align the scan's returns to the map's lines.");
    m.def("point_to_line_system", &point_to_line_system_binding,
          "The normal equations of a pose update that brings points onto their lines "
          "(scanlines.geometry.registration.point_to_line_system).");
    m.def("line_normals", &line_normals_binding,
          "The unit normals (cos, sin) of lines at angles alpha (L x 2), as filter_scan takes "
          "them.");
}

}  // namespace scanlines::bind
