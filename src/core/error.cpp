#include <uvr/error.h>

namespace uvr {

namespace {

// Messages quote input (names, attributes, paths); a hostile file's 16 MB attribute must not become a 16 MB
// message. Longer parts keep their head and tail.
constexpr size_t kMaxPart = 1024;

std::string bounded(const std::string &text) {
  if (text.size() <= kMaxPart)
    return text;
  return text.substr(0, kMaxPart / 2) + " [... " + std::to_string(text.size() - kMaxPart) +
         " characters cut ...] " + text.substr(text.size() - kMaxPart / 2);
}

std::string describe(const std::string &file, const std::string &position, const std::string &what) {
  std::string text = bounded(file);
  if (!position.empty())
    text += (text.empty() ? "" : ", ") + bounded(position);
  return text.empty() ? bounded(what) : text + ": " + bounded(what);
}

} // namespace

Error::Error(const std::string &file, const std::string &position, const std::string &what)
    : std::runtime_error(describe(file, position, what)) {}

Error::Error(const std::string &what) : std::runtime_error(bounded(what)) {}

} // namespace uvr
