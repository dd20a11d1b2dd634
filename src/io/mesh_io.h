// Mesh readers, one per format; loadMesh picks one by the file's extension.
#pragma once

#include "mesh/mesh.h"

#include <string>

namespace uvr {

/// VTK XML unstructured grid: ascii, inline base64, appended raw or base64; zlib; UInt32/UInt64 headers;
/// several Pieces (merged).
UnstructuredGrid readVtu(const std::string &path);

/// Legacy VTK unstructured grid: ascii or big-endian binary; `CELLS n size` and the 5.1 OFFSETS/CONNECTIVITY
/// layout; POINT_DATA and CELL_DATA with SCALARS and FIELD arrays.
UnstructuredGrid readVtkLegacy(const std::string &path);

/// Reads any supported format and builds the mesh. Throws uvr::Error naming the file and position.
Mesh loadMesh(const std::string &path);

} // namespace uvr
