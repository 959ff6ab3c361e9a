// The numbers of a text record in one pass: the fast path of the text readers
// (scanlines/io/numbers.py documents which tokens it reads exactly).
#pragma once

#include <cstdint>
#include <vector>

#include "scanlines/core.hpp"

namespace scanlines {

enum NumberKind : std::int8_t { NOT_A_NUMBER = 0, INTEGER = 1, DECIMAL = 2 };

struct NumberFields {
    Reals values;                    // NaN where not a number
    std::vector<std::int8_t> kinds;  // NumberKind of each token
    Ints texts;                      // positions of the tokens not read as numbers
};

// The whitespace-separated tokens of an ASCII line, split as Python's str.split() does.
NumberFields read_fields(const std::uint8_t* data, Index n);

}  // namespace scanlines
