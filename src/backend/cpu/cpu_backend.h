// The CPU backend: the acceleration data built on the host, frames drawn with all cores through TBB.
#pragma once

#include "backend/backend.h"

#include <optional>

namespace uvr {

class CpuBackend final : public RenderBackend {
public:
  /// Builds the acceleration data for `view` (of `mesh`, which must outlive the backend).
  /// `layout`: Lean leaves the walks' structures out (Auto is Default on the host).
  CpuBackend(const Mesh &mesh, const MeshView &view, uint32_t leafSize,
             MemoryLayout layout = MemoryLayout::Default);

  uint32_t setTransferFunction(const TransferFunction &tf) override;
  uint32_t setField(const MeshView &view) override;
  void setGradients(const Vec3f *gradients, uint64_t) override { gradients_ = gradients; }
  uint32_t setIsoSurfaces(const IsoSettings &iso) override;
  SampleTotals render(const CameraView &camera, const IntegratorSettings &settings,
                      const ShadingSettings &shading, const PixelTarget &target, double &kernelMs) override;
  uint32_t partitionCount() const override { return accel_.partitions.count(); }
  double buildMs() const override { return buildMs_; }
  MemoryLayout layout() const override { return layout_; }
  HostAcceleration acceleration() const override { return accel_; }
  PartitionMetadata metadata() const override { return metadata_; }

  /// What it built, in place.
  const HostAcceleration &data() const { return accel_; }
  const PartitionMetadata &currentMetadata() const { return metadata_; }

private:
  SceneView sceneView() const; ///< all a ray reads; needs the transfer function

  MeshView mesh_;
  const Vec3f *gradients_ = nullptr;
  HostAcceleration accel_;
  double buildMs_ = 0.0;
  MemoryLayout layout_;
  std::optional<TransferFunction> tf_;
  PartitionMetadata metadata_;
  IsoSettings iso_;
};

} // namespace uvr
