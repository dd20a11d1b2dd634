// Scanning the text formats: whitespace, tokens, numbers and keywords, the same way in every reader. All
// inline, for their per-value loops.
#pragma once

#include <charconv>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

namespace uvr {

/// The whitespace that separates values and tokens: space, tab and line breaks.
constexpr bool isSpace(char c) { return c == ' ' || c == '\n' || c == '\r' || c == '\t'; }

/// The first character at or after `p` that is not whitespace, or `end`.
inline const char *skipSpace(const char *p, const char *end) {
  while (p != end && isSpace(*p))
    ++p;
  return p;
}

/// The end of the token that starts at `p`: the first whitespace at or after it, or `end`.
inline const char *tokenEnd(const char *p, const char *end) {
  while (p != end && !isSpace(*p))
    ++p;
  return p;
}

/// `s` without its leading and trailing whitespace.
inline std::string_view trim(std::string_view s) {
  while (!s.empty() && isSpace(s.front()))
    s.remove_prefix(1);
  while (!s.empty() && isSpace(s.back()))
    s.remove_suffix(1);
  return s;
}

/// The whitespace-separated tokens of `text`.
inline std::vector<std::string_view> splitTokens(std::string_view text) {
  std::vector<std::string_view> tokens;
  const char *p = text.data(), *end = p + text.size();
  while ((p = skipSpace(p, end)) != end) {
    const char *stop = tokenEnd(p, end);
    tokens.emplace_back(p, size_t(stop - p));
    p = stop;
  }
  return tokens;
}

/// Parses all of [first, last) as a T (std::from_chars: no sign '+', no leading whitespace); false unless the
/// whole text is one T in range. `value` is what from_chars leaves there.
template <typename T> inline bool parseNumber(const char *first, const char *last, T &value) {
  const auto [stop, ec] = std::from_chars(first, last, value);
  return ec == std::errc() && stop == last;
}
template <typename T> inline bool parseNumber(std::string_view text, T &value) {
  return parseNumber(text.data(), text.data() + text.size(), value);
}

/// `s` in ASCII upper case: keywords that the formats accept in any case.
inline std::string toUpper(std::string_view s) {
  std::string result(s);
  for (char &c : result)
    if (c >= 'a' && c <= 'z')
      c = char(c - 'a' + 'A');
  return result;
}

/// `s` in ASCII lower case.
inline std::string toLower(std::string_view s) {
  std::string result(s);
  for (char &c : result)
    if (c >= 'A' && c <= 'Z')
      c = char(c - 'A' + 'a');
  return result;
}

} // namespace uvr
