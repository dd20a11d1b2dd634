#include "view_script.h"

#include <uvr/error.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

namespace uvr {

namespace {

/// Each command's argument count (-1: one or more words, -2: pairs of numbers) and whether they are numbers.
struct Signature {
  int count;
  bool numeric;
};

const std::map<std::string, Signature> kCommands = {
    {"orbit", {2, true}},       {"pan", {2, true}},   {"zoom", {1, true}},     {"reset-camera", {0, false}},
    {"mode", {1, false}},       {"s1", {1, true}},    {"s2", {1, true}},       {"p", {1, true}},
    {"preset", {-1, false}},    {"range", {2, true}}, {"opacity", {-2, true}}, {"heatmap", {1, false}},
    {"screenshot", {1, false}}, {"view", {1, false}},
};

} // namespace

std::vector<ScriptCommand> readViewScript(const std::string &path) {
  std::ifstream in(path);
  if (!in)
    throw Error(path, "", std::string("cannot open file: ") + std::strerror(errno));
  std::error_code error;
  if (!std::filesystem::is_regular_file(path, error))
    throw Error(path, "", "cannot open file: not a regular file");
  std::vector<ScriptCommand> commands;
  std::string text;
  for (int lineNumber = 1; std::getline(in, text); ++lineNumber) {
    if (const size_t hash = text.find('#'); hash != std::string::npos)
      text.resize(hash);
    std::istringstream words(text);
    ScriptCommand command;
    command.line = lineNumber;
    if (!(words >> command.name))
      continue;
    const std::string position = "line " + std::to_string(lineNumber);
    const auto found = kCommands.find(command.name);
    if (found == kCommands.end())
      throw Error(path, position, "unknown command '" + command.name + "'");
    for (std::string word; words >> word;)
      command.words.push_back(word);
    const Signature signature = found->second;
    const size_t n = command.words.size();
    const bool countOk = signature.count == -1   ? n >= 1
                         : signature.count == -2 ? n >= 2 && n % 2 == 0
                                                 : n == size_t(signature.count);
    if (!countOk)
      throw Error(path, position, "wrong number of arguments for '" + command.name + "'");
    if (signature.numeric) {
      for (const std::string &word : command.words) {
        size_t used = 0;
        float value = 0.f;
        try {
          value = std::stof(word, &used);
        } catch (const std::exception &) {
        }
        if (used != word.size())
          throw Error(path, position, "'" + command.name + "' expects numbers, got '" + word + "'");
        command.numbers.push_back(value);
      }
    }
    if (command.name == "heatmap" && command.words[0] != "on" && command.words[0] != "off")
      throw Error(path, position, "heatmap expects on or off");
    commands.push_back(std::move(command));
  }
  return commands;
}

} // namespace uvr
