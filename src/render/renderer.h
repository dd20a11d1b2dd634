// The host-side renderer: owns the acceleration data for one mesh and field, the transfer function and its
// per-partition metadata, and draws frames on a backend.
#pragma once

#include "accel/bvh.h"
#include "accel/occupancy.h"
#include "accel/partitions.h"
#include "accel/seed_grid.h"
#include "image/image.h"
#include "mesh/mesh.h"
#include "mesh/tet_affine.h"
#include "render/camera.h"
#include "render/integrator.h"
#include "render/transfer_function.h"

#include <uvr/settings.h>

#include <memory>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace uvr {

struct RenderSettings {
  IntegratorSettings integrator;
  Vec3f background{0.f, 0.f, 0.f};
  int width = 1024;
  int height = 1024;
  Backend backend = Backend::Cpu;
  /// Per-pixel buffers a frame keeps besides the image (its sample totals are always there): a GPU frame
  /// copies each one back to the host.
  bool keepOpacity = true;
  bool keepSamplesPerPixel = true;
};

class CudaRenderer;
struct PixelTarget;
struct SampleTotals;

/// Acceleration data in host memory: what the CPU backend renders with, or what the GPU built, copied back.
struct HostAcceleration {
  Bvh bvh;
  OccupancyGrid occupancy;
  SeedGrid seeds;
  std::vector<uint32_t> tetNeighbors;
  std::vector<uint32_t> cellNeighbors;    ///< empty for tets alone, or where memory is short
  std::vector<Vec4f> cellFacePlanes;      ///< likewise
  std::vector<uint32_t> boundaryFaceList; ///< for the per-frame crossings; empty where the grid lists none
  Partitions partitions;
  std::vector<TetAffine> tetAffine; ///< host walks only; empty where they would take too much memory
};

struct Frame {
  Image image;
  std::vector<float> opacity; ///< accumulated opacity per pixel, row-major, top row first; or empty
  std::vector<uint32_t> samplesPerPixel; ///< row-major, top row first; or empty
  uint64_t samplesTotal = 0;
  uint32_t samplesMax = 0;
  double kernelMs = 0.0; ///< the GPU time of the frame's kernels (CUDA), without copies; 0 on the CPU
};

class Renderer {
public:
  /// Renders field `fieldIndex` of `mesh`, which must outlive the renderer. The acceleration data (tet
  /// adjacency, point-location hierarchy, occupancy and seed grids, partitions of up to `leafSize` cells) is
  /// built where a backend first needs it: on the host for the CPU, on the GPU for CUDA. kAutoLeafSize
  /// asks for defaultLeafSize.
  Renderer(const Mesh &mesh, int fieldIndex, uint32_t leafSize = kAutoLeafSize);
  ~Renderer();

  /// Replaces the transfer function and recomputes the partitions' metadata, on the GPU once CUDA has been
  /// prepared, else on the host; the mesh is not touched.
  void setTransferFunction(TransferFunction tf);

  /// Sets up `backend` ahead of the first frame, so that frame times exclude it: builds the acceleration data
  /// on the host, or uploads the mesh, builds there and uploads the transfer function if one is set.
  /// Preparing CUDA before setTransferFunction times the GPU's update.
  void prepare(Backend backend) const;

  Frame render(const Camera &camera, const RenderSettings &settings) const;
  /// The same into `frame`, whose buffers are reused when their size matches (no allocation per frame).
  void render(const Camera &camera, const RenderSettings &settings, Frame &frame) const;

  /// The GPU's name and the device memory this renderer holds; empty and 0 until CUDA has been prepared.
  std::string deviceName() const;
  size_t deviceMemoryBytes() const;
  size_t deviceSceneBytes() const; ///< without the frame buffers

  /// The host's partitions, built on first use.
  const Partitions &partitions() const;
  uint32_t partitionCount(Backend backend) const;
  /// The most cells per partition, as given or by default.
  uint32_t leafSize() const;
  /// Milliseconds the acceleration build for `backend` took (on the GPU for CUDA, the mesh's upload
  /// excluded); 0 before it was prepared.
  double buildMs(Backend backend) const;
  /// The GPU build's steps and their milliseconds; empty until CUDA has been prepared.
  std::vector<std::pair<std::string, double>> deviceBuildSteps() const;
  /// What the GPU built, copied back; needs CUDA prepared.
  HostAcceleration deviceAcceleration() const;
  /// The metadata on the host: after an update on the GPU, computed there on first use.
  const PartitionMetadata &metadata() const;
  /// The metadata the GPU computed, copied back; empty until CUDA has been prepared.
  PartitionMetadata deviceMetadata() const;
  /// Partitions the current transfer function makes fully transparent (skipped by the skipping modes).
  uint32_t transparentPartitions() const { return transparentPartitions_; }
  /// The current transfer function; throws uvr::Error before the first setTransferFunction.
  const TransferFunction &transferFunction() const;
  double tfUpdateMs() const { return tfUpdateMs_; }

private:
  const HostAcceleration &host() const; ///< built on first use
  SceneView sceneView() const;          ///< all a ray reads on the host; needs the transfer function

  const Mesh &mesh_;
  MeshView meshView_;
  uint32_t leafSize_;
  mutable std::unique_ptr<HostAcceleration> host_;
  mutable double hostBuildMs_ = 0.0;
  std::optional<TransferFunction> tf_;
  mutable PartitionMetadata metadata_;
  mutable bool metadataCurrent_ = false; // false after an update that only the GPU made
  uint32_t transparentPartitions_ = 0;
  double tfUpdateMs_ = 0.0;
  mutable std::shared_ptr<CudaRenderer> cuda_; // created on first use of the CUDA backend
};

/// Draws a frame with all cores: one ray per pixel, composited over `settings.background`; returns the
/// samples taken. The skipping modes march each ray between its crossings with `boundaryFaces`, where these
/// apply (see boundary_crossings.h).
SampleTotals renderCpu(const SceneView &scene, std::span<const uint32_t> boundaryFaces,
                       const CameraView &camera, const RenderSettings &settings, const PixelTarget &target);

} // namespace uvr
