// CLI11 validators for numeric options: they see the text before conversion, so NaN, infinities and values
// out of range are refused with a message that CLI11 prefixes with the option's name.
#pragma once

#include <CLI/CLI.hpp>

#include <cmath>
#include <cstdlib>
#include <string>

namespace uvr {

/// A number, finite, with `accept(value)` true; `what` says what is expected ("a number > 0").
template <class Accept> CLI::Validator numberCheck(const std::string &what, Accept accept) {
  return CLI::Validator(
      [what, accept](std::string &text) -> std::string {
        char *end = nullptr;
        const double value = std::strtod(text.c_str(), &end);
        if (text.empty() || end != text.c_str() + text.size() || !std::isfinite(value) || !accept(value))
          return "expected " + what + ", got '" + text + "'";
        return {};
      },
      what);
}

inline CLI::Validator finiteNumber() {
  return numberCheck("a finite number", [](double) { return true; });
}
inline CLI::Validator positiveNumber() {
  return numberCheck("a finite number > 0", [](double v) { return v > 0.0; });
}
inline CLI::Validator atLeast(double low, const std::string &lowText) {
  return numberCheck("a finite number >= " + lowText, [low](double v) { return v >= low; });
}
/// An integer of at least `low`.
inline CLI::Validator integerAtLeast(long long low) {
  return numberCheck("an integer >= " + std::to_string(low),
                     [low](double v) { return v >= double(low) && v == std::floor(v); });
}

} // namespace uvr
