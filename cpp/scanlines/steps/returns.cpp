#include "scanlines/steps/returns.hpp"

#include <algorithm>
#include <cmath>

namespace scanlines {

Returns valid_returns(View<double> ranges, View<bool> valid, View<double> cos, View<double> sin) {
    Returns out;
    for (Index i = 0; i < valid.size; ++i) {
        if (!valid[i]) continue;
        out.index.push_back(i);
        out.r.push_back(ranges[i]);
        out.x.push_back(ranges[i] * cos[i]);
        out.y.push_back(ranges[i] * sin[i]);
    }
    return out;
}

Returns turned(Returns returns, double angle) {
    const double c = std::cos(angle), si = std::sin(angle);
    for (Index p = 0; p < returns.size(); ++p) {
        double x = returns.x[p], y = returns.y[p];
        returns.x[p] = c * x - si * y;
        returns.y[p] = si * x + c * y;
    }
    return returns;
}

Ints beam_gaps(const Ints& index, Index n_beams) {
    Index n = std::max<Index>(static_cast<Index>(index.size()) - 1, 0);
    Ints gap(n);
    for (Index p = 0; p < n; ++p) gap[p] = py_mod(index[p + 1] - index[p], n_beams);
    return gap;
}

template <typename T>
static std::vector<T> rotated_values(const std::vector<T>& values, Index shift) {
    std::vector<T> out(values.begin() + shift, values.end());
    out.insert(out.end(), values.begin(), values.begin() + shift);
    return out;
}

Returns rotated(const Returns& returns, Index shift) {
    return {rotated_values(returns.index, shift), rotated_values(returns.r, shift),
            rotated_values(returns.x, shift), rotated_values(returns.y, shift)};
}

Returns kept(const Returns& returns, const Flags& keep) {
    Returns out;
    for (Index p = 0; p < returns.size(); ++p) {
        if (!keep[p]) continue;
        out.index.push_back(returns.index[p]);
        out.r.push_back(returns.r[p]);
        out.x.push_back(returns.x[p]);
        out.y.push_back(returns.y[p]);
    }
    return out;
}

}  // namespace scanlines
