#include "core/error.h"
#include "io/mesh_io.h"

#include <algorithm>
#include <cctype>

namespace uvr {

Mesh loadMesh(const std::string &path, const LoadOptions &options) {
  std::string extension = path.substr(std::min(path.size(), path.find_last_of('.')));
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return char(std::tolower(c)); });
  if (extension == ".vtu")
    return buildMesh(readVtu(path), path);
  if (extension == ".vtk")
    return buildMesh(readVtkLegacy(path), path);
  if (extension == ".e" || extension == ".ex2" || extension == ".exo" || extension == ".g")
    return buildMesh(readExodus(path, options.timeStep), path);
  throw Error(path, "", "unknown mesh format '" + extension + "': expected .vtu, .vtk, .e, .ex2, .exo or .g");
}

} // namespace uvr
