// Every pixel's boundary crossings for a frame, found on the GPU: what the host's findBoundaryCrossings
// makes, for the render kernel's skipping modes.
#pragma once

#include "backend/cuda/device_buffer.cuh"
#include "mesh/mesh_view.h"
#include "render/camera.h"

#include <cstddef>
#include <cstdint>

namespace uvr {

class DeviceCrossings {
public:
  /// The crossings of `camera`'s rays, `pixels` of them, with the boundary faces of `mesh` in `faceList`.
  void find(const MeshView &mesh, const DeviceBuffer<uint32_t> &faceList, const CameraView &camera,
            size_t pixels);
  /// Where each pixel's crossings start in keys() (pixels + 1 entries; see findBoundaryCrossings), and the
  /// crossings, pixel by pixel; as the last find left them.
  const uint64_t *start() const { return start_.data(); }
  const uint64_t *keys() const { return keys_.data(); }
  size_t bytes() const { return start_.bytes() + keys_.bytes() + placed_.bytes(); }

private:
  DeviceBuffer<uint64_t> start_, keys_, placed_; // see findBoundaryCrossings
  CubScratch scratch_;
};

} // namespace uvr
