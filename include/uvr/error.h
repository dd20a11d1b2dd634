// The one error type the library throws: it names the file, the position in it and what was expected.
#pragma once

#include <stdexcept>
#include <string>

namespace uvr {

class Error : public std::runtime_error {
public:
  /// `position` is e.g. "byte 1234" or "line 17"; empty when the error concerns no particular place.
  Error(const std::string &file, const std::string &position, const std::string &what);
  explicit Error(const std::string &what);
};

} // namespace uvr
