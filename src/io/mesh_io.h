// Mesh readers and writers, one per format; loadMesh and saveMesh pick one by the file's extension.
#pragma once

#include "mesh/mesh.h"

#include <uvr/io.h>

#include <string>

namespace uvr {

/// VTK XML unstructured grid: ascii, inline base64, appended raw or base64; zlib; UInt32/UInt64 headers;
/// several Pieces (merged).
UnstructuredGrid readVtu(const std::string &path);
/// A .vtu file as buildMesh makes it, from the decoded cell arrays in place: loadMesh's way, which copies
/// them into no UnstructuredGrid.
Mesh loadVtu(const std::string &path);

/// Legacy VTK unstructured grid: ascii or big-endian binary; `CELLS n size` and the 5.1 OFFSETS/CONNECTIVITY
/// layout; POINT_DATA and CELL_DATA with SCALARS and FIELD arrays.
UnstructuredGrid readVtkLegacy(const std::string &path);

/// Gmsh .msh, formats 2.2 and 4.1, ascii and binary. Volume elements of any order (by their corners; one
/// line on stderr says so), lower-dimensional ones for buildMesh to skip; $NodeData and $ElementData at
/// `options.timeStep` (the n-th distinct time-step index of each field). Sets `*timeStepCount` if given.
UnstructuredGrid readGmsh(const std::string &path, const LoadOptions &options = {},
                          int *timeStepCount = nullptr);

/// Exodus II (netCDF-3 or netCDF-4): element blocks of volume types merged, nodal variables and element
/// variables (per block, merged) at time step `timeStep` (0-based). Throws uvr::Error when uvr was built
/// without netCDF.
UnstructuredGrid readExodus(const std::string &path, int timeStep);
/// The time steps of an Exodus II file (1 where it holds no results).
int exodusTimeStepCount(const std::string &path);

/// The binary format of Wald's umesh library (UMesh::saveTo): vertices, named per-vertex scalars and the
/// cells of each type, little-endian, read straight into place. Cells are checked and wound as VTK expects;
/// they are ordered spatially as buildMesh does unless the file is in that order already (as uvr writes
/// it). Triangles and quads count as skipped cells; umesh's structured grids are refused.
Mesh readUmesh(const std::string &path);

/// Writes umesh's current layout (magic 0x234235568). umesh stores per-vertex scalars only, so a cell field
/// is refused with an error. umesh's own loader reads back only the first scalar field.
void writeUmesh(const std::string &path, const Mesh &mesh);

/// Writes a VTK XML unstructured grid: appended raw data, UInt64 headers, Int64 connectivity and offsets,
/// Float32 points and fields; each array zlib-compressed when `compress`.
void writeVtu(const std::string &path, const Mesh &mesh, bool compress = false);

/// Reads any supported format and builds the mesh. Throws uvr::Error naming the file and position.
/// Besides single files, `path` may name a time series: a ParaView .pvd collection (its DataSets sorted by
/// timestep; several parts of one step are merged), or files numbered by a pattern such as data_%d.vtu,
/// data_%04d.vtu or data_*.vtu (sorted by their numbers). `options.timeStep` picks the step.
Mesh loadMesh(const std::string &path, const LoadOptions &options = {});

/// Writes `mesh` in the format its extension names (.umesh, .vtu).
void saveMesh(const std::string &path, const Mesh &mesh);

} // namespace uvr
