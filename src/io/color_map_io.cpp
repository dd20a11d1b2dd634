// ParaView's colour-map preset files, read and written (declared in <uvr/color_map.h>).
#include "core/color_map.h"

#include "io/file_buffer.h"
#include "io/text_scan.h"
#include <uvr/error.h>

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>

namespace uvr {

namespace {

using Json = nlohmann::json;

// The whole of ParaView's own preset collection is under 1 MB; anything far larger is not a preset file (and
// a parsed JSON value takes many times its text).
constexpr uint64_t kMaxPresetBytes = 16u << 20;
// ParaView's presets nest 3 levels deep; a parser recursing once per level must not meet 10^7 of them.
constexpr int kMaxJsonDepth = 64;

std::string readSmallFile(const std::string &path) {
  const InputFile input(path); // refuses what is not a regular file before opening it
  if (input.size() > kMaxPresetBytes)
    throw Error(path, "",
                "is " + std::to_string(input.size()) +
                    " bytes, too large for a colour-map preset file (at most " +
                    std::to_string(kMaxPresetBytes) + ")");
  std::string text(size_t(input.size()), '\0');
  input.read(0, text.data(), input.size());
  return text;
}

/// Fails at the first bracket nested deeper than kMaxJsonDepth, outside strings: before parsing.
void checkJsonDepth(const std::string &text, const std::string &path) {
  int depth = 0;
  bool inString = false;
  for (size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (inString) {
      if (c == '\\')
        ++i;
      else if (c == '"')
        inString = false;
    } else if (c == '"') {
      inString = true;
    } else if (c == '[' || c == '{') {
      if (++depth > kMaxJsonDepth)
        throw Error(path, "byte " + std::to_string(i),
                    "invalid JSON: nested more than " + std::to_string(kMaxJsonDepth) + " levels deep");
    } else if (c == ']' || c == '}') {
      --depth;
    }
  }
}

// nlohmann's message without its "[json.exception.parse_error.101] " tag.
std::string jsonMessage(const Json::exception &e) {
  std::string what = e.what();
  if (const size_t tag = what.find("] "); !what.empty() && what.front() == '[' && tag != std::string::npos)
    what.erase(0, tag + 2);
  return what;
}

Json parseJsonFile(const std::string &path) {
  const std::string text = readSmallFile(path);
  checkJsonDepth(text, path);
  try {
    return Json::parse(text);
  } catch (const Json::parse_error &e) {
    // nlohmann counts the bytes read, so the offending byte is at offset e.byte - 1.
    throw Error(path, "byte " + std::to_string(e.byte > 0 ? e.byte - 1 : 0),
                "invalid JSON: " + jsonMessage(e));
  } catch (const Json::exception &e) {
    // E.g. a number too large for a double; nlohmann gives no position for those.
    throw Error(path, "", "invalid JSON: " + jsonMessage(e));
  }
}

std::string presetName(const Json &preset) {
  const auto name = preset.find("Name");
  return name != preset.end() && name->is_string() ? name->get<std::string>() : std::string();
}

// Where in the file a preset is, for error messages: its name, or its index when it has none.
std::string presetPosition(const Json &preset, size_t index) {
  const std::string name = presetName(preset);
  return name.empty() ? "preset " + std::to_string(index + 1) : "preset \"" + name + "\"";
}

std::vector<float> readNumbers(const Json &preset, const char *key, const std::string &file,
                               const std::string &position) {
  const Json &array = preset.at(key);
  if (!array.is_array())
    throw Error(file, position, std::string(key) + " is not an array");
  std::vector<float> numbers;
  numbers.reserve(array.size());
  for (size_t i = 0; i < array.size(); ++i) {
    if (!array[i].is_number())
      throw Error(file, position, std::string(key) + "[" + std::to_string(i) + "] is not a number");
    const float value = array[i].get<float>();
    if (!std::isfinite(value))
      throw Error(file, position, std::string(key) + "[" + std::to_string(i) + "] is out of range");
    numbers.push_back(value);
  }
  return numbers;
}

ColorMap parsePreset(const Json &preset, size_t index, const std::string &file) {
  const std::string position = presetPosition(preset, index);
  ColorMap map;
  map.name = presetName(preset);
  if (!preset.contains("RGBPoints"))
    throw Error(file, position, "the preset has no RGBPoints (only continuous colour maps are supported)");
  map.rgbPoints = readNumbers(preset, "RGBPoints", file, position);
  if (preset.contains("Points"))
    map.opacityPoints = readNumbers(preset, "Points", file, position);
  // Without a ColorSpace ParaView keeps the one the map had; RGB is the neutral choice here.
  if (const auto space = preset.find("ColorSpace"); space != preset.end()) {
    if (!space->is_string())
      throw Error(file, position, "ColorSpace is not a string");
    map.colorSpace = space->get<std::string>();
  }
  if (preset.contains("NanColor")) {
    const std::vector<float> nan = readNumbers(preset, "NanColor", file, position);
    if (nan.size() < 3)
      throw Error(file, position, "NanColor needs 3 values (r, g, b)");
    map.nanColor = {nan[0], nan[1], nan[2]};
  }
  checkColorMap(map, file, position);
  return map;
}

// "A", "B", ... for error messages, cut short for large collections.
std::string listNames(const std::vector<const Json *> &presets) {
  constexpr size_t shown = 20;
  std::string list;
  for (size_t i = 0; i < presets.size() && i < shown; ++i) {
    const std::string name = presetName(*presets[i]);
    list += (i ? ", " : "") + (name.empty() ? "(unnamed)" : "\"" + name + "\"");
  }
  if (presets.size() > shown)
    list += " and " + std::to_string(presets.size() - shown) + " more";
  return list.empty() ? "none" : list;
}

/// The presets of a file: an array of them or a single preset object.
std::vector<const Json *> presetList(const Json &root, const std::string &path) {
  std::vector<const Json *> presets;
  if (root.is_array()) {
    for (const Json &element : root)
      presets.push_back(&element);
  } else if (root.is_object()) {
    presets.push_back(&root);
  } else {
    throw Error(path, "", "expected an array of colour-map presets or a single preset object");
  }
  for (size_t i = 0; i < presets.size(); ++i)
    if (!presets[i]->is_object())
      throw Error(path, "preset " + std::to_string(i + 1), "a preset must be a JSON object");
  return presets;
}

} // namespace

std::vector<ColorMap> readColorMapPresets(const std::string &path) {
  const Json root = parseJsonFile(path);
  const std::vector<const Json *> presets = presetList(root, path);
  std::vector<ColorMap> maps;
  for (size_t i = 0; i < presets.size(); ++i)
    if (presets[i]->contains("RGBPoints"))
      maps.push_back(parsePreset(*presets[i], i, path));
  if (maps.empty())
    throw Error(path, "", "no preset has RGBPoints (presets found: " + listNames(presets) + ")");
  return maps;
}

void writeColorMapFile(const std::string &path, const ColorMap &map) {
  Json preset = {{"Name", map.name},
                 {"ColorSpace", map.colorSpace},
                 {"RGBPoints", map.rgbPoints},
                 {"NanColor", {map.nanColor.x, map.nanColor.y, map.nanColor.z}}};
  if (!map.opacityPoints.empty())
    preset["Points"] = map.opacityPoints;
  std::ofstream out(path);
  out << Json::array({preset}).dump(2) << '\n';
  if (!out)
    throw Error(path, "", "cannot write the preset");
}

ColorMap readColorMapFile(const std::string &path, const std::string &name) {
  const Json root = parseJsonFile(path);
  const std::vector<const Json *> presets = presetList(root, path);
  if (name.empty()) {
    for (size_t i = 0; i < presets.size(); ++i)
      if (presets[i]->contains("RGBPoints"))
        return parsePreset(*presets[i], i, path);
    throw Error(path, "", "no preset has RGBPoints (presets found: " + listNames(presets) + ")");
  }
  // An exact match first; names differing only in case are accepted as a fallback.
  for (size_t i = 0; i < presets.size(); ++i)
    if (presetName(*presets[i]) == name)
      return parsePreset(*presets[i], i, path);
  const std::string key = toLower(name);
  for (size_t i = 0; i < presets.size(); ++i)
    if (toLower(presetName(*presets[i])) == key)
      return parsePreset(*presets[i], i, path);
  throw Error(path, "", "no preset named \"" + name + "\" (presets found: " + listNames(presets) + ")");
}

} // namespace uvr
