// Numbers printed for people to read and to paste back into commands.
#pragma once

#include <string>

namespace cellbake {

// `v` rounded to a multiple of `step` (a power of ten), in plain decimals
// without trailing zeros or "-0": every integer digit is kept, so coordinates
// far from the origin keep their fractions (1e7 + 0.25 at step 0.01 is
// "10000000.25", never "1e+07").
std::string decimal_text(double v, double step);

// The step that shows a length-`scale` model to six significant digits: a
// power of ten (1e-4 for 18 m, 0.01 for 1.8 km).
double six_digit_step(double scale);

}  // namespace cellbake
