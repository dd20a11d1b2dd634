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

/// Exodus II (netCDF-3 or netCDF-4): element blocks of volume types merged, nodal variables and element
/// variables (per block, merged) at time step `timeStep` (0-based). Throws uvr::Error when uvr was built
/// without netCDF.
UnstructuredGrid readExodus(const std::string &path, int timeStep);

/// What a load may choose beyond the file: formats with time steps read step `timeStep` (0-based).
struct LoadOptions {
  int timeStep = 0;
};

/// Reads any supported format and builds the mesh. Throws uvr::Error naming the file and position.
Mesh loadMesh(const std::string &path, const LoadOptions &options = {});

} // namespace uvr
