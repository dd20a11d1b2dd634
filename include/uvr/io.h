// What a mesh file load or save may choose beyond the file (see VolumeMesh::load and VolumeMesh::save).
//
// Read: VTK XML .vtu, ParaView's partitioned .pvtu (the union of its pieces), legacy .vtk, Gmsh .msh (2.2,
// 4.1), Exodus II (.e, .ex2, .exo, .g; when built with netCDF), umesh .umesh; and time series: a ParaView
// .pvd collection or numbered files (data_%d.vtu, data_%04d.vtu, data_*.vtu). Written: .vtu and .umesh.
#pragma once

#include <string>

namespace uvr {

struct LoadOptions {
  /// The step (0-based) of a series, an Exodus file or a Gmsh file's data.
  int timeStep = 0;
};

struct SaveOptions {
  /// zlib-compress the arrays of a .vtu file (an error for other formats).
  bool compress = false;
};

/// The number of time steps `path` holds: of a series, an Exodus file or a Gmsh file's data; 1 otherwise.
int timeStepCount(const std::string &path);

} // namespace uvr
