// File-name patterns of numbered series: the input is a pattern, a newline and a name. The matcher must
// answer in time linear in the name (libFuzzer's -timeout catches a blow-up) and, where both are short,
// agree with a plain backtracking matcher.
#include "io/glob.h"

#include <cctype>
#include <cstdint>
#include <cstdlib>
#include <string_view>

namespace {

/// The reference: patterns as the documentation states them, by backtracking (exponential, so short only).
bool reference(std::string_view p, std::string_view s) {
  if (p.empty())
    return s.empty();
  if (p[0] == '%') {
    size_t j = 1;
    while (j < p.size() && std::isdigit(static_cast<unsigned char>(p[j])))
      ++j;
    if (j < p.size() && p[j] == 'd') {
      for (size_t n = 1; n <= s.size() && std::isdigit(static_cast<unsigned char>(s[n - 1])); ++n)
        if (reference(p.substr(j + 1), s.substr(n)))
          return true;
      return false;
    }
  }
  if (p[0] == '*') {
    for (size_t n = 0; n <= s.size(); ++n)
      if (reference(p.substr(1), s.substr(n)))
        return true;
    return false;
  }
  if (s.empty() || (p[0] != '?' && p[0] != s[0]))
    return false;
  return reference(p.substr(1), s.substr(1));
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  const std::string_view input(reinterpret_cast<const char *>(data), size);
  const size_t newline = input.find('\n');
  const std::string_view pattern = input.substr(0, newline);
  const std::string_view name =
      newline == std::string_view::npos ? std::string_view() : input.substr(newline + 1);
  const bool matches = uvr::NamePattern(pattern).matches(name);
  if (pattern.size() <= 12 && name.size() <= 16 && matches != reference(pattern, name))
    std::abort();
  return 0;
}
