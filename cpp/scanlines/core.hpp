// The types every kernel shares, and Python's arithmetic where C++'s differs.
//
// Kernels take views of caller-owned arrays and return owned std::vectors. Nothing here
// knows Python: the binding layer (bindings/) converts numpy arrays to and from these.
#pragma once

#include <cmath>
#include <cstdint>
#include <vector>

namespace scanlines {

using Index = std::int64_t;
using Ints = std::vector<Index>;
using Reals = std::vector<double>;
using Flags = std::vector<std::uint8_t>;  // bytes, as numpy bools: no bit packing in hot loops

// A read-only view of a contiguous array.
template <typename T>
struct View {
    const T* data = nullptr;
    Index size = 0;
    View() = default;
    View(const T* d, Index n) : data(d), size(n) {}
    View(const std::vector<T>& v) : data(v.data()), size(static_cast<Index>(v.size())) {}
    const T& operator[](Index i) const { return data[i]; }
};

// The valid returns of one scan in beam order (steps/returns.hpp).
struct Returns {
    Ints index;  // beam of each position
    Reals r, x, y;
    Index size() const { return static_cast<Index>(index.size()); }
};

// Range noise sigma(r) = max(sigma0 + per_metre r, MIN_NOISE_SIGMA); NaN: not known.
struct NoiseLine {
    double sigma0;
    double per_metre;
    bool known() const { return sigma0 == sigma0; }
};

// Number of columns of a segment's line: rho, alpha, start x, y, end x, y, rms.
constexpr Index LINE_COLUMNS = 7;

// What a method gives for one scan: the columns of an Extraction, flat and row-major.
struct ScanResult {
    Ints first, last, n_points;
    Reals lines;        // LINE_COLUMNS per segment
    Reals covariances;  // 2 x 2 per segment
    Ints breakpoints, corners, outliers;
    std::vector<std::int8_t> end_kinds;  // 2 per segment
    Index segments() const { return static_cast<Index>(first.size()); }
};

// Python's float modulo: the result takes the sign of the divisor.
inline double py_mod(double a, double b) {
    double mod = std::fmod(a, b);
    if (mod != 0.0) {
        if ((b < 0.0) != (mod < 0.0)) mod += b;
    } else {
        mod = std::copysign(0.0, b);
    }
    return mod;
}

// Python's integer modulo (floor division's remainder).
inline Index py_mod(Index a, Index b) {
    Index mod = a % b;
    if (mod != 0 && ((mod < 0) != (b < 0))) mod += b;
    return mod;
}

}  // namespace scanlines
