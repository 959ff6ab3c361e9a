#include "scanlines/io/numbers.hpp"

#include <cmath>

namespace scanlines {

namespace {

constexpr std::int64_t LARGEST_EXACT = std::int64_t{1} << 53;

// 10^0 .. 10^22: exact doubles (5^22 < 2^53).
constexpr double POWERS_OF_TEN[23] = {1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,
                                      1e8,  1e9,  1e10, 1e11, 1e12, 1e13, 1e14, 1e15,
                                      1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};

// str.split() separators among ASCII: \t \n \v \f \r, \x1c-\x1f and the space.
bool is_space(std::uint8_t byte) {
    return byte == 32 || (9 <= byte && byte <= 13) || (28 <= byte && byte <= 31);
}

bool is_digit(std::uint8_t byte) { return 48 <= byte && byte <= 57; }

// (value, kind) of the token data[start:end].
std::pair<double, std::int8_t> read_number(const std::uint8_t* data, Index start, Index end) {
    const std::pair<double, std::int8_t> failed{NAN, NOT_A_NUMBER};
    Index i = start;
    bool negative = data[i] == '-';
    if (data[i] == '-' || data[i] == '+') ++i;
    std::int64_t significand = 0;
    Index digits = 0, after_point = 0;
    bool point = false, exact = true;
    for (; i < end; ++i) {
        std::uint8_t byte = data[i];
        if (is_digit(byte)) {
            ++digits;
            if (significand > LARGEST_EXACT)
                exact = false;
            else
                significand = significand * 10 + (byte - 48);
            if (point) ++after_point;
        } else if (byte == '.' && !point) {
            point = true;
        } else {
            break;
        }
    }
    if (digits == 0) return failed;
    Index exponent = 0;
    bool has_exponent = false;
    if (i < end && (data[i] == 'e' || data[i] == 'E')) {
        has_exponent = true;
        ++i;
        bool exponent_negative = i < end && data[i] == '-';
        if (i < end && (data[i] == '-' || data[i] == '+')) ++i;
        int exponent_digits = 0;
        while (i < end && is_digit(data[i]) && exponent_digits < 6) {
            exponent = exponent * 10 + (data[i] - 48);
            ++exponent_digits;
            ++i;
        }
        if (exponent_digits == 0) return failed;
        if (exponent_negative) exponent = -exponent;
    }
    if (i != end || !exact || significand > LARGEST_EXACT) return failed;
    Index power = exponent - after_point;
    if (power > 22 || power < -22) return failed;
    double value = static_cast<double>(significand);
    if (power > 0)
        value = value * POWERS_OF_TEN[power];
    else if (power < 0)
        value = value / POWERS_OF_TEN[-power];
    if (negative) value = -value;
    return {value, !point && !has_exponent ? INTEGER : DECIMAL};
}

}  // namespace

NumberFields read_fields(const std::uint8_t* data, Index n) {
    NumberFields out;
    Index i = 0;
    while (i < n) {
        if (is_space(data[i])) {
            ++i;
            continue;
        }
        Index end = i;
        while (end < n && !is_space(data[end])) ++end;
        auto [value, kind] = read_number(data, i, end);
        if (kind == NOT_A_NUMBER) out.texts.push_back(static_cast<Index>(out.values.size()));
        out.values.push_back(value);
        out.kinds.push_back(kind);
        i = end;
    }
    return out;
}

}  // namespace scanlines
