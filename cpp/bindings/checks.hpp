// The checks of what a kernel indexes, made at the binding before the kernel runs: a
// ValueError (lengths, counts, windows, codes) or IndexError (positions) naming the argument.
// Kernels trust their arguments; every call from Python passes through one of these.
#pragma once

#include <nanobind/nanobind.h>

#include <cmath>
#include <cstddef>
#include <string>
#include <vector>

#include "scanlines/core.hpp"

namespace scanlines::bind {

namespace nb = nanobind;

[[noreturn]] inline void value_error(const std::string& message) {
    throw nb::value_error(message.c_str());
}

[[noreturn]] inline void index_error(const std::string& message) {
    throw nb::index_error(message.c_str());
}

inline std::string text(Index value) { return std::to_string(value); }

// name has want values (why: what fixes the length).
inline void expect_length(const char* name, std::size_t got, std::size_t want, const char* why) {
    if (got != want)
        value_error(std::string(name) + " has " + std::to_string(got) + " values, expected " +
                    std::to_string(want) + " (" + why + ")");
}

// name has n - 1 values for n points (one per pair of consecutive points; none for none).
inline void expect_pairs(const char* name, std::size_t got, std::size_t points) {
    expect_length(name, got, points > 0 ? points - 1 : 0, "one per pair of consecutive points");
}

inline void expect_at_least(const char* name, Index value, Index least) {
    if (value < least)
        value_error(std::string(name) + " must be at least " + text(least) + ", got " +
                    text(value));
}

// A code or count in low .. high.
inline void expect_between(const char* name, Index value, Index low, Index high) {
    if (value < low || value > high)
        value_error(std::string(name) + " must be in " + text(low) + " .. " + text(high) +
                    ", got " + text(value));
}

// The angular step between beams (radians, its sign dropped by the caller): finite, above 0.
inline void expect_step(double step) {
    if (!(step > 0.0) || !std::isfinite(step))
        value_error("step must be a finite angle above 0, got " + std::to_string(step));
}

// A position of n points.
inline void expect_position(const char* name, Index value, Index n) {
    if (value < 0 || value >= n)
        index_error(std::string(name) + " = " + text(value) + " lies outside the positions 0 .. " +
                    text(n - 1));
}

// Positions of n points, each.
inline void expect_positions(const char* name, const Index* values, std::size_t count, Index n) {
    for (std::size_t k = 0; k < count; ++k)
        if (values[k] < 0 || values[k] >= n)
            index_error(std::string(name) + "[" + std::to_string(k) + "] = " + text(values[k]) +
                        " lies outside the positions 0 .. " + text(n - 1));
}

inline void expect_positions(const char* name, const Ints& values, Index n) {
    expect_positions(name, values.data(), values.size(), n);
}

// Runs [a[k], b[k]] of n points: one length, inside the points, none reversed (an empty run
// b = a - 1 only when allowed).
inline void expect_runs(const char* a_name, const char* b_name, const Index* a, std::size_t a_count,
                        const Index* b, std::size_t b_count, Index n, bool allow_empty = false) {
    if (a_count != b_count)
        value_error(std::string(a_name) + " and " + b_name + " must have one length, got " +
                    std::to_string(a_count) + " and " + std::to_string(b_count));
    for (std::size_t k = 0; k < a_count; ++k) {
        const std::string at = "[" + std::to_string(k) + "]";
        if (a[k] < 0 || a[k] >= n || b[k] >= n || b[k] < a[k] - (allow_empty ? 1 : 0))
            index_error("run " + std::string(a_name) + at + " = " + text(a[k]) + " .. " + b_name +
                        at + " = " + text(b[k]) + " lies outside the positions 0 .. " +
                        text(n - 1));
    }
}

inline void expect_runs(const char* a_name, const char* b_name, const Ints& a, const Ints& b,
                        Index n, bool allow_empty = false) {
    expect_runs(a_name, b_name, a.data(), a.size(), b.data(), b.size(), n, allow_empty);
}

// Clusters [start[c], end[c]] of n points: non-empty runs, in order and disjoint.
inline void expect_clusters(const Ints& start, const Ints& end, Index n) {
    expect_runs("start", "end", start, end, n);
    for (std::size_t c = 1; c < start.size(); ++c)
        if (start[c] <= end[c - 1])
            index_error("cluster start[" + std::to_string(c) + "] = " + text(start[c]) +
                        " does not follow end[" + std::to_string(c - 1) + "] = " +
                        text(end[c - 1]));
}

// Beam numbers of a scan of n_beams beams, strictly increasing (a full circle's returns may
// be rotated once: then the sequence wraps at most once).
inline void expect_beams(const Ints& index, Index n_beams) {
    expect_at_least("n_beams", n_beams, 1);
    Index wraps = 0;
    for (std::size_t p = 0; p < index.size(); ++p) {
        if (index[p] < 0 || index[p] >= n_beams)
            index_error("index[" + std::to_string(p) + "] = " + text(index[p]) +
                        " lies outside the beams 0 .. " + text(n_beams - 1));
        if (p > 0 && index[p] <= index[p - 1] && ++wraps > 1)
            value_error("index must increase (a full circle's may wrap once), index[" +
                        std::to_string(p) + "] = " + text(index[p]));
    }
}

}  // namespace scanlines::bind
