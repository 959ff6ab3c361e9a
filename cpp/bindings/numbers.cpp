#include "arrays.hpp"
#include "scanlines/io/numbers.hpp"

namespace scanlines::bind {

void bind_numbers(nb::module_& m) {
    m.def(
        "read_fields",
        [](const nb::bytes& line) {
            NumberFields fields = read_fields(reinterpret_cast<const std::uint8_t*>(line.c_str()),
                                              static_cast<Index>(line.size()));
            nb::list texts;
            for (Index position : fields.texts) texts.append(position);
            return nb::make_tuple(to_numpy(std::move(fields.values)),
                                  to_numpy(std::move(fields.kinds)), texts);
        },
        "The tokens of an ASCII line: values (NaN where not a number), kinds, and the "
        "positions of the tokens not read as numbers.");
}

}  // namespace scanlines::bind
