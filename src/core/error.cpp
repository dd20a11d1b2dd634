#include <uvr/error.h>

namespace uvr {

namespace {
std::string describe(const std::string &file, const std::string &position, const std::string &what) {
  std::string text = file;
  if (!position.empty())
    text += (text.empty() ? "" : ", ") + position;
  return text.empty() ? what : text + ": " + what;
}
} // namespace

Error::Error(const std::string &file, const std::string &position, const std::string &what)
    : std::runtime_error(describe(file, position, what)) {}

Error::Error(const std::string &what) : std::runtime_error(what) {}

} // namespace uvr
