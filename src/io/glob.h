// File-name patterns of numbered series (data_%d.vtu, data_%04d.vtu, data_*.vtu, data_?.vtu), matched by
// simulating all pattern positions at once: time linear in the name for a given pattern, never the
// exponential backtracking a regular expression engine may take on a*a*a*...b.
#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace uvr {

class NamePattern {
public:
  /// `*` any run of characters, `?` one character, `%d` or `%0Nd` one or more digits; anything else itself.
  explicit NamePattern(std::string_view pattern);
  bool matches(std::string_view name) const;

private:
  enum class Kind { Char, AnyChar, AnyRun, Digit, DigitRun };
  struct Token {
    Kind kind;
    char c;
  };
  std::vector<Token> tokens_;
};

} // namespace uvr
