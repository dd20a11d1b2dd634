// The interface below the Renderer façade: one backend holds one mesh's acceleration data on its processor,
// the current transfer function and the partitions' metadata under it, and draws frames. Each is built whole
// when made; nothing is built or computed on a later read.
#pragma once

#include "accel/acceleration.h"
#include "mesh/mesh.h"
#include "mesh/mesh_view.h"
#include "render/camera.h"
#include "render/integrator.h"
#include "render/isosurface.h"
#include "render/pixel.h"
#include "render/transfer_function.h"

#include <uvr/settings.h>

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace uvr {

class RenderBackend {
public:
  virtual ~RenderBackend() = default;

  /// Takes `tf` and recomputes the partitions' metadata; returns how many partitions it makes fully
  /// transparent.
  virtual uint32_t setTransferFunction(const TransferFunction &tf) = 0;
  /// Takes the field of `view`, a view of the same points and cells as the backend's (new values, or another
  /// field), keeping the acceleration data: the partitions' value ranges, and the metadata under the current
  /// transfer function, are recomputed. Returns how many partitions are fully transparent (0 without a
  /// transfer function).
  virtual uint32_t setField(const MeshView &view) = 0;
  /// Takes the field's gradient, `count` vectors per point (host memory, which must outlive the backend or
  /// the next call), for shaded frames (IntegratorSettings::shade); null drops it.
  virtual void setGradients(const Vec3f *gradients, uint64_t count) = 0;
  /// Takes the isosurfaces that frames with IntegratorSettings::iso draw; where the values or hideVolume
  /// change, recomputes the metadata (partitions holding a surface are marched). Returns the partitions
  /// skipped, as setTransferFunction does.
  virtual uint32_t setIsoSurfaces(const IsoSettings &iso) = 0;
  /// Draws a frame of `camera.width` x `camera.height` pixels into `target` (its host buffers) with the
  /// current transfer function, lit as `shading` says where `settings.shade`, with the isosurfaces of the
  /// last setIsoSurfaces where `settings.iso`; returns the samples taken.
  /// `kernelMs` is the GPU time of the frame's kernels, without copies; 0 on the CPU.
  virtual SampleTotals render(const CameraView &camera, const IntegratorSettings &settings,
                              const ShadingSettings &shading, const PixelTarget &target,
                              double &kernelMs) = 0;

  virtual uint32_t partitionCount() const = 0;
  /// The layout built: Default or Lean, never Auto.
  virtual MemoryLayout layout() const = 0;
  /// Milliseconds the acceleration build took (on a GPU, the mesh's upload excluded), in all and per step
  /// where the backend reports steps.
  virtual double buildMs() const = 0;
  virtual std::vector<std::pair<std::string, double>> buildSteps() const { return {}; }
  /// The device and the device memory held, the scene alone and all of it with the frame buffers; empty
  /// and 0 on the host.
  virtual std::string deviceName() const { return {}; }
  virtual size_t deviceSceneBytes() const { return 0; }
  virtual size_t deviceMemoryBytes() const { return 0; }
  /// The most device memory in use (total - free, as cudaMemGetInfo gives it: the CUDA context and other
  /// processes included) at any allocation of the build, later uploads or a frame since the backend was
  /// made; 0 on the host.
  virtual size_t devicePeakBytes() const { return 0; }

  /// Copies of what the backend holds, for checks against the host's builds: the acceleration data and the
  /// metadata under the current transfer function.
  virtual HostAcceleration acceleration() const = 0;
  virtual PartitionMetadata metadata() const = 0;
};

/// Makes `backend` for `mesh` (`view` of its field), building its acceleration data with partitions of at
/// most `leafSize` cells in `layout`. Throws uvr::Error where the build has no such backend, or its device
/// fails.
std::unique_ptr<RenderBackend> makeBackend(Backend backend, const Mesh &mesh, const MeshView &view,
                                           uint32_t leafSize, MemoryLayout layout);

} // namespace uvr
