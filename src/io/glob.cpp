#include "io/glob.h"

#include <algorithm>
#include <cctype>

namespace uvr {

namespace {
bool isDigit(char c) { return std::isdigit(static_cast<unsigned char>(c)) != 0; }
} // namespace

NamePattern::NamePattern(std::string_view pattern) {
  for (size_t i = 0; i < pattern.size(); ++i) {
    const char c = pattern[i];
    if (c == '%') {
      size_t j = i + 1;
      while (j < pattern.size() && isDigit(pattern[j]))
        ++j;
      if (j < pattern.size() && pattern[j] == 'd') {
        tokens_.push_back({Kind::Digit, 0});
        tokens_.push_back({Kind::DigitRun, 0});
        i = j;
        continue;
      }
    }
    if (c == '*') {
      if (tokens_.empty() || tokens_.back().kind != Kind::AnyRun) // ** is *
        tokens_.push_back({Kind::AnyRun, 0});
    } else {
      tokens_.push_back({c == '?' ? Kind::AnyChar : Kind::Char, c});
    }
  }
}

bool NamePattern::matches(std::string_view name) const {
  const size_t n = tokens_.size();
  // live[i]: the name read so far can be matched by tokens [0, i).
  std::vector<char> live(n + 1, 0), next(n + 1, 0);
  auto close = [&](std::vector<char> &states) { // runs may match nothing
    for (size_t i = 0; i < n; ++i)
      if (states[i] && (tokens_[i].kind == Kind::AnyRun || tokens_[i].kind == Kind::DigitRun))
        states[i + 1] = 1;
  };
  live[0] = 1;
  close(live);
  for (const char c : name) {
    std::fill(next.begin(), next.end(), 0);
    bool any = false;
    for (size_t i = 0; i < n; ++i) {
      if (!live[i])
        continue;
      const Token &t = tokens_[i];
      switch (t.kind) {
      case Kind::Char:
        next[i + 1] |= char(c == t.c);
        break;
      case Kind::AnyChar:
        next[i + 1] = 1;
        break;
      case Kind::AnyRun:
        next[i] = 1;
        break;
      case Kind::Digit:
        next[i + 1] |= char(isDigit(c));
        break;
      case Kind::DigitRun:
        next[i] |= char(isDigit(c));
        break;
      }
    }
    close(next);
    live.swap(next);
    for (char state : live)
      any |= state != 0;
    if (!any)
      return false;
  }
  return live[n] != 0;
}

} // namespace uvr
