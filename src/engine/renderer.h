// The façade over the backends: one mesh and field, the transfer function, and a backend per processor asked
// for, each made when first prepared.
#pragma once

#include "backend/backend.h"
#include "core/vec.h"
#include "mesh/mesh.h"
#include "render/camera.h"
#include "render/integrator.h"
#include "render/transfer_function.h"
#include <uvr/image.h>

#include <memory>
#include <optional>
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
  bool keepImage = true;
  bool keepOpacity = true;
  bool keepSamplesPerPixel = true;
  bool keepPremultipliedRgba = false;
  bool keepPremultipliedRgba16 = false;
  /// Null, or width x height distances, top row first, where each pixel's ray ends
  /// (FrameSettings::rayLimits).
  const float *rayLimits = nullptr;
  /// How frames are lit where integrator.shade or there are isosurfaces (the light in camera space).
  ShadingSettings shading;
  /// The isosurfaces to draw (none where count is 0), in any order; integrator.iso is derived from them.
  IsoSettings iso;
};

struct Frame {
  Image image;
  std::vector<float> opacity; ///< accumulated opacity per pixel, row-major, top row first; or empty
  std::vector<uint32_t> samplesPerPixel;     ///< row-major, top row first; or empty
  std::vector<float> premultipliedRgba;      ///< 4 per pixel, before the background, row-major; or empty
  std::vector<uint16_t> premultipliedRgba16; ///< the same, 65535 for 1; or empty
  uint64_t samplesTotal = 0;
  uint32_t samplesMax = 0;
  double kernelMs = 0.0; ///< the GPU time of the frame's kernels (CUDA), without copies; 0 on the CPU
};

/// The most steps of s1 a ray may take along the mesh bounds' diagonal: far fewer are ever of use, and with
/// steps that follow the mesh (down to s1 / 16) the march's float grid indices stay exact (SampleGrid).
constexpr float kMostSamplesPerRay = float(1 << 20);

class Renderer {
public:
  /// Renders field `fieldIndex` of `mesh`, which must outlive the renderer, with partitions of up to
  /// `leafSize` cells (kAutoLeafSize: defaultLeafSize). Nothing is built until a backend is prepared.
  Renderer(const Mesh &mesh, int fieldIndex, uint32_t leafSize = kAutoLeafSize);
  ~Renderer();

  /// Renders the mesh as one piece of a larger one, before any backend is prepared: rays are clipped to
  /// `region` and sample on the grid of the whole mesh's bounds `wholeBounds`, the partitions are the whole
  /// mesh's within the region (on the host's build) and scale their steps against the whole mesh's mean cell
  /// size `meanCellSizeLog2`, on a grid of its finest step scale `finestStepScale` (see uvr::MeshPiece).
  void setPiece(const Box3f &region, const Box3f &wholeBounds, double meanCellSizeLog2,
                float finestStepScale);

  /// Replaces the transfer function and recomputes the partitions' metadata on every backend prepared; a
  /// backend prepared later takes it then. The mesh is not touched.
  void setTransferFunction(TransferFunction tf);
  /// Normalises the partitions' colour variances by [lowest, highest] from now on, under this and later
  /// transfer functions (NaN: by their own extremes); see TransferFunction::setVarianceRange.
  void setVarianceRange(float lowest, float highest);
  /// The extremes of the colour variances of the partitions drawn under the current transfer function on
  /// `backend` (PartitionMetadata::varianceLowest, varianceHighest).
  std::pair<float, float> varianceExtremes(Backend backend) const;

  /// Renders field `fieldIndex` of `mesh` from now on: a mesh with the same points and cells as the one
  /// rendered so far (the caller checks), which must outlive the renderer in its place. Every backend
  /// prepared keeps its acceleration data and recomputes the partitions' value ranges and metadata.
  void setField(const Mesh &mesh, int fieldIndex);

  /// Makes `backend` unless it exists: builds the acceleration data there (on the GPU for CUDA, after the
  /// mesh's upload) and hands it the transfer function if one is set. Frame times then exclude it, and
  /// preparing before setTransferFunction times the backend's own update.
  void prepare(Backend backend);

  /// Draws a frame on `settings.backend`, which render prepares first where it is not.
  Frame render(const Camera &camera, const RenderSettings &settings);
  /// The same into `frame`, whose buffers are reused when their size matches (no allocation per frame).
  void render(const Camera &camera, const RenderSettings &settings, Frame &frame);

  /// Whether `backend` has been prepared. The reads below that name a backend throw uvr::Error where not.
  bool prepared(Backend backend) const;
  uint32_t partitionCount(Backend backend) const;

  /// Milliseconds the acceleration build for `backend` took (on the GPU for CUDA, the mesh's upload
  /// excluded).
  double buildMs(Backend backend) const;
  /// The CPU backend's partitions and metadata, in place.
  const Partitions &partitions() const;
  const PartitionMetadata &metadata() const;
  /// The CUDA backend's device, memory (the scene alone, and all of it with the frame buffers) and build
  /// steps; empty and 0 until it has been prepared.
  std::string deviceName() const;
  size_t deviceMemoryBytes() const;
  size_t deviceSceneBytes() const;
  size_t devicePeakBytes() const;
  /// The memory layout `which` (prepared) built.
  MemoryLayout layout(Backend which) const;
  std::vector<std::pair<std::string, double>> deviceBuildSteps() const;
  /// What the GPU built, and the metadata it computed, copied back.
  HostAcceleration deviceAcceleration() const;
  PartitionMetadata deviceMetadata() const;

  /// The most cells per partition, as given or by default.
  uint32_t leafSize() const;
  /// Partitions the current transfer function makes fully transparent (skipped by the skipping modes); 0
  /// until a backend has taken it.
  uint32_t transparentPartitions() const { return transparentPartitions_; }
  /// The current transfer function; throws uvr::Error before the first setTransferFunction.
  const TransferFunction &transferFunction() const;
  /// Milliseconds the last setTransferFunction took on the backends prepared.
  double tfUpdateMs() const { return tfUpdateMs_; }
  /// Host memory held by the field's gradient per point (computePointGradients), built by the first shaded
  /// frame (or the first with isosurfaces) and rebuilt by setField; 0 until then.
  size_t gradientBytes() const { return gradients_.size() * sizeof(Vec3f); }

private:
  RenderBackend &backend(Backend backend) const; ///< throws where not prepared
  /// Computes the field's gradients and hands them to every backend prepared.
  void buildGradients();
  const class CpuBackend &cpu() const;

  const Mesh *mesh_;
  MeshView meshView_;
  float diagonal_ = 0.f;      ///< of the mesh bounds
  Vec3f center_;              ///< of the mesh bounds
  Box3f region_, gridBounds_; ///< a piece's (setPiece); empty for a whole mesh
  float wholeFinestStepScale_ = 0.f;
  uint32_t leafSize_;
  std::optional<TransferFunction> tf_;
  float varianceLowest_ = NAN, varianceHighest_ = NAN; ///< setVarianceRange's
  uint32_t transparentPartitions_ = 0;
  double tfUpdateMs_ = 0.0;
  std::vector<Vec3f> gradients_; // per point, once a frame is shaded
  bool gradientsBuilt_ = false;
  std::unique_ptr<RenderBackend> backends_[2]; // by Backend
};

} // namespace uvr
