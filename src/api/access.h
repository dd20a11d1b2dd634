// What the API's implementation shares: the data behind a VolumeMesh handle.
#pragma once

#include "mesh/mesh.h"

#include <uvr/mesh.h>

#include <mutex>
#include <string>

namespace uvr {

struct VolumeMesh::Impl {
  Mesh mesh;
  std::string source;
  mutable std::once_flag statsOnce; // volume statistics are computed on first use
  mutable VolumeStats stats;
  // The bounds, a pass over the points, also on first use: every frame with default settings reads them.
  mutable std::once_flag boundsOnce;
  mutable Box3f bounds;
};

namespace detail {

struct Access {
  static const Mesh &mesh(const VolumeMesh &handle) { return handle.impl_->mesh; }
  static VolumeMesh make(Mesh &&mesh, const std::string &source);
};

} // namespace detail

} // namespace uvr
