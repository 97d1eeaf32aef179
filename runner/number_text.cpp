#include "runner/number_text.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace cellbake {

std::string decimal_text(double v, double step) {
  const int decimals = std::clamp(int(std::lround(-std::log10(step))), 0, 300);
  const double rounded = std::round(v / step) * step;
  std::string text(std::size_t(std::snprintf(nullptr, 0, "%.*f", decimals, rounded)), '\0');
  std::snprintf(text.data(), text.size() + 1, "%.*f", decimals, rounded);
  if (text.find('.') != std::string::npos) {
    text.erase(text.find_last_not_of('0') + 1);
    if (text.back() == '.') text.pop_back();
  }
  return text == "-0" ? "0" : text;
}

double six_digit_step(double scale) {
  if (!(scale > 0) || !std::isfinite(scale)) return 1e-6;
  return std::pow(10.0, std::floor(std::log10(scale)) - 5);
}

}  // namespace cellbake
