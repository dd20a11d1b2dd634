// The CUDA backend's host side: device copies of everything a ray reads, uploaded once per mesh; on each
// transfer-function change the table is uploaded and the partitions' metadata recomputed on the GPU. A plain
// C++ header: no CUDA types leak out.
#pragma once

#include "render/camera.h"
#include "render/integrator.h"
#include "render/pixel.h"

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

namespace uvr {

/// Element counts of the arrays a SceneView points to, so that they can be copied.
struct SceneSizes {
  uint64_t points = 0, values = 0, bvhNodes = 0, bvhCellIds = 0, partitionNodes = 0, occupancyWords = 0;
};

class CudaRenderer {
public:
  /// Uploads the scene to the current GPU (all but the transfer function and the metadata it sets); throws
  /// uvr::Error when there is none or memory runs out.
  CudaRenderer(const SceneView &scene, const SceneSizes &sizes);
  ~CudaRenderer();
  CudaRenderer(const CudaRenderer &) = delete;
  CudaRenderer &operator=(const CudaRenderer &) = delete;

  /// Uploads `tf` and recomputes the partitions' metadata on the GPU, as computePartitionMetadata does on the
  /// host; returns the number of fully transparent partitions.
  uint32_t setTransferFunction(const TransferFunction &tf);
  /// Copies the metadata of the last setTransferFunction back, for checks against the host's.
  PartitionMetadata metadata() const;

  /// Renders into `target`'s host buffers (width x height pixels); returns the milliseconds the kernel took
  /// on the GPU, without the copies.
  double render(const CameraView &camera, const IntegratorSettings &settings, const PixelTarget &target,
                int height);

  /// Device memory held: the scene alone (mesh, field, acceleration, partitions, transfer function), and all
  /// of it including the frame buffers.
  size_t sceneBytes() const;
  size_t memoryBytes() const;
  const std::string &deviceName() const;

private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

} // namespace uvr
