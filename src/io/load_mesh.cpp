#include "core/error.h"
#include "io/mesh_io.h"

#include <algorithm>
#include <cctype>

namespace uvr {

namespace {

std::string lowerCaseExtension(const std::string &path) {
  const size_t slash = path.find_last_of('/');
  const size_t dot = path.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash))
    return "";
  std::string extension = path.substr(dot);
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return char(std::tolower(c)); });
  return extension;
}

} // namespace

Mesh loadMesh(const std::string &path) {
  const std::string extension = lowerCaseExtension(path);
  if (extension == ".vtu")
    return buildMesh(readVtu(path), path);
  if (extension == ".vtk")
    return buildMesh(readVtkLegacy(path), path);
  if (extension == ".umesh")
    return readUmesh(path);
  throw Error(path, "", "unknown mesh format '" + extension + "': expected .vtu, .vtk or .umesh");
}

void saveMesh(const std::string &path, const Mesh &mesh) {
  const std::string extension = lowerCaseExtension(path);
  if (extension == ".umesh")
    return writeUmesh(path, mesh);
  if (extension == ".vtu")
    return writeVtu(path, mesh);
  throw Error(path, "", "cannot write mesh format '" + extension + "': expected .umesh or .vtu");
}

} // namespace uvr
