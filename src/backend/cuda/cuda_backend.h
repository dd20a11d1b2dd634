// The CUDA backend's host side: the mesh uploaded once and its acceleration data built on the GPU; on each
// transfer-function change the table is uploaded and the partitions' metadata recomputed there. A plain C++
// header: no CUDA types leak out.
#pragma once

#include "backend/backend.h"

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace uvr {

/// The GPUs the CUDA runtime sees; 0 where it finds none.
int cudaDevicesVisible();
/// The GPU that backends made from now on use (0 where `ordinal` is not one of them).
void selectCudaDevice(int ordinal);
int selectedCudaDevice();

/// About the most GPU memory the default layout's build takes for a mesh of `cells` cells, `tets` of them
/// tets, and `points` points besides the mesh's own arrays (docs/design.md, "GPU memory").
uint64_t defaultLayoutPeakBytes(uint64_t cells, uint64_t tets, uint64_t points);

class CudaBackend final : public RenderBackend {
public:
  /// Uploads `view` of `mesh` to the current GPU and builds the acceleration data there, with partitions of
  /// at most `leafSize` cells; throws uvr::Error when there is no GPU or memory runs out. The adjacency of
  /// the cells other than tets, for walks between samples, is built on the host and uploaded where it takes
  /// no more than an eighth of the GPU memory left. `layout` Auto builds Lean where the default layout's
  /// build would not fit the GPU memory free (defaultLayoutPeakBytes).
  CudaBackend(const Mesh &mesh, const MeshView &view, uint32_t leafSize,
              MemoryLayout layout = MemoryLayout::Default);
  ~CudaBackend() override;
  CudaBackend(const CudaBackend &) = delete;
  CudaBackend &operator=(const CudaBackend &) = delete;

  /// Uploads `tf` and recomputes the partitions' metadata on the GPU, as computePartitionMetadata does on the
  /// host; returns the number of fully transparent partitions.
  uint32_t setTransferFunction(const TransferFunction &tf) override;
  /// Uploads the field of `view` (host pointers, same points and cells) and its partitions' value ranges,
  /// computed on the host, and recomputes the metadata on the GPU.
  uint32_t setField(const MeshView &view) override;
  /// Uploads the field's gradient per point, for shaded frames.
  void setGradients(const Vec3f *gradients, uint64_t count) override;
  /// Takes the isosurfaces and recomputes the metadata on the GPU where the partitions marched change.
  uint32_t setIsoSurfaces(const IsoSettings &iso) override;
  /// Copies the metadata of the last setTransferFunction back, for checks against the host's.
  PartitionMetadata metadata() const override;
  /// Copies the acceleration data the GPU built back, for checks against the host's builds.
  HostAcceleration acceleration() const override;

  uint32_t partitionCount() const override;
  MemoryLayout layout() const override;
  /// Milliseconds the build on the GPU took, in all and per step (upload of the mesh excluded).
  double buildMs() const override;
  std::vector<std::pair<std::string, double>> buildSteps() const override;

  /// Renders into `target`'s host buffers (those null are not copied back); `kernelMs`: the frame's
  /// kernels on the GPU (crossings pass and render kernel), without the copies.
  SampleTotals render(const CameraView &camera, const IntegratorSettings &settings,
                      const ShadingSettings &shading, const PixelTarget &target, double &kernelMs) override;

  /// Device memory held: the scene alone (mesh, field, acceleration, partitions, transfer function), and all
  /// of it including the frame buffers.
  size_t deviceSceneBytes() const override;
  size_t deviceMemoryBytes() const override;
  size_t devicePeakBytes() const override;
  std::string deviceName() const override;

private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

} // namespace uvr
