// The volume renderer: acceleration data for one mesh and field, built once and kept across camera and
// transfer-function changes, and frames drawn from it (paper: Morrical et al., IEEE VIS 2019).
#pragma once

#include <uvr/camera.h>
#include <uvr/color_map.h>
#include <uvr/image.h>
#include <uvr/mesh.h>
#include <uvr/settings.h>

#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace uvr {

/// What one frame cost and took, with the settings it was drawn with (defaults filled in).
struct FrameStats {
  RenderMode mode = RenderMode::Full;
  /// Whether segments were composited pre-integrated (FrameSettings::compositing), and steps followed the
  /// mesh (FrameSettings::steps).
  bool preintegrated = false, localSteps = false;
  int width = 0, height = 0;
  uint64_t cells = 0;
  uint32_t partitions = 0;
  uint32_t partitionsSkipped = 0; ///< fully transparent under the transfer function; 0 unless skipping
  uint64_t samplesTotal = 0;
  double samplesPerPixelMean = 0.0;
  uint32_t samplesPerPixelMax = 0;
  double buildMs = 0.0;    ///< the acceleration build for the backend used
  double tfUpdateMs = 0.0; ///< the transfer-function update since the previous frame; 0 when unchanged
  double renderMs = 0.0;   ///< this frame, wall clock
  float s1 = 0.f, s2 = 0.f, p = 0.f, unit = 0.f;
  uint32_t leafSize = 0;
  bool shaded = false;        ///< lit by the field's gradient (FrameSettings::shade)
  uint64_t gradientBytes = 0; ///< host memory of the gradient per point; 0 until a frame is shaded
  uint32_t isoSurfaces = 0;   ///< isosurfaces drawn (FrameSettings::isoValues)
  bool isoOnly = false;       ///< the volume hidden (FrameSettings::isoOnly)
  std::string field;
  ValueRange range; ///< what the transfer function spans
  Backend backend = Backend::Cpu;
  int threads = 0;                                   ///< of the host
  MemoryLayout memoryLayout = MemoryLayout::Default; ///< what the backend built (Default or Lean)
  uint64_t hostPeakRssBytes = 0; ///< the process's peak resident memory so far (loading included)
  // CUDA only: empty or 0 on the CPU.
  std::string device;
  uint64_t gpuMemoryBytes = 0; ///< all the renderer holds on the GPU
  uint64_t gpuSceneBytes = 0;  ///< without the frame buffers
  /// The device's peak memory in use (cudaMemGetInfo's total - free, the CUDA context and other processes
  /// included) over the build and the frames so far.
  uint64_t gpuPeakBytes = 0;
  double gpuKernelMs = 0.0; ///< the frame's GPU work, without the copies to the host
  std::vector<std::pair<std::string, double>> gpuBuildSteps; ///< the GPU build's steps and their ms
};

struct FrameResult {
  /// RGB composited over the background, top row first; its rgb empty unless FrameSettings::keepImage.
  Image image;
  std::vector<float> opacity;            ///< accumulated opacity per pixel, row-major; empty unless kept
  std::vector<uint32_t> samplesPerPixel; ///< row-major; empty unless kept
  /// Premultiplied red, green, blue and opacity per pixel, before the background, row-major, top row first;
  /// empty unless FrameSettings::keepPremultipliedRgba.
  std::vector<float> premultipliedRgba;
  /// The same in 16 bits a channel, rounded (65535 for 1); empty unless
  /// FrameSettings::keepPremultipliedRgba16.
  std::vector<uint16_t> premultipliedRgba16;
  FrameStats stats;
};

/// The range a transfer function spans over a field of range `fieldRange` by default: that range, or for a
/// constant field (min == max, or no finite values: {0, 0}) one of width max(1, |value| / 1000) centred on
/// the value, so that the field shows in the preset's middle colour rather than at its transparent end.
ValueRange defaultTransferRange(ValueRange fieldRange);

/// What a renderer of one piece of a mesh split among processes (data-parallel rendering) takes from the
/// whole mesh, so that its frames sample as the whole mesh's frames do and the pieces' frames composite to
/// the whole mesh's.
struct MeshPiece {
  /// The region of space this piece draws (one of splitIntoRegions' for the whole mesh): rays are clipped to
  /// it. The piece holds every cell whose box touches it.
  Box3f region;
  /// The whole mesh's bounds: rays' sample grids start where they enter them.
  Box3f wholeBounds;
  /// VolumeMesh::stepScaleReference of the whole mesh, for its leaf size: steps that follow the mesh scale
  /// against its mean cell size, on a sample grid of its finest step scale.
  VolumeMesh::StepScaleReference wholeStepScales;
};

/// The regions of space that the pieces of a mesh split among processes draw: the top levels of the KD-tree
/// of the mesh's partitions (for a power of 2, its very median splits, so that each piece's partitions are
/// the whole mesh's within its region), and the order they composite in.
struct MeshRegions {
  struct Node {
    int axis = -1; ///< -1 for a region
    float position = 0.f;
    int below = -1, above = -1; ///< children: the sides axis < position and axis >= position
    int region = -1;            ///< for a region, its index
  };
  std::vector<Node> nodes; ///< the root first
  std::vector<Box3f> regions;

  /// The regions front to back as seen from `eye`: at each split, the eye's side first, since no ray from
  /// the eye crosses the plane back towards it.
  std::vector<int> frontToBack(Vec3f eye) const;
};

/// Splits the space around `mesh` into `count` regions (at least 1) of about as many cells each; the outer
/// faces of the outer regions lie just past the mesh's bounds. A region is empty where there are more regions
/// than cells.
MeshRegions splitIntoRegions(const VolumeMesh &mesh, int count);

/// Renders one field of a mesh. Built lazily, per backend, where it is first needed (prepare): tet
/// adjacency, point-location hierarchy, occupancy and seed grids, and the partitions whose per-partition
/// opacity and colour variance each transfer-function change recomputes (in time independent of the cell
/// count). Safe to share between threads: transfer-function changes, preparation and frames are serialised
/// (a caller wanting its own transfer function in a frame sets it and renders under its own lock).
class VolumeRenderer {
public:
  /// Renders field `fieldIndex` of `mesh` (see VolumeMesh::chooseField) in partitions of at most `leafSize`
  /// cells. Keeps the mesh.
  VolumeRenderer(VolumeMesh mesh, int fieldIndex, uint32_t leafSize = kAutoLeafSize);
  /// Renders `mesh` as `piece` of a larger mesh (see MeshPiece); pass the whole mesh's leaf size.
  VolumeRenderer(VolumeMesh mesh, int fieldIndex, uint32_t leafSize, const MeshPiece &piece);
  ~VolumeRenderer();
  VolumeRenderer(VolumeRenderer &&) noexcept;
  VolumeRenderer &operator=(VolumeRenderer &&) noexcept;

  const VolumeMesh &mesh() const;
  int fieldIndex() const;
  /// The most cells per partition, as given or by default.
  uint32_t leafSize() const;

  /// Renders field `fieldIndex` of `mesh` from now on, keeping the acceleration data: `mesh` must hold the
  /// same points and cells in the same order (a later step of a time series whose grid does not change, or
  /// the same grid with other values, made the same way). Only the field's values are taken; the partitions'
  /// value ranges and their metadata under the current transfer function are recomputed, in a pass over the
  /// cells. The transfer function and its range are kept. Throws uvr::Error, changing nothing, when the
  /// points or cells differ (a new renderer is needed then) or `mesh` has no field `fieldIndex`.
  void setField(VolumeMesh mesh, int fieldIndex);

  /// Colours and opacities of `map` stretched over `range` of the field's values (ParaView's way); needed
  /// before the first frame. Recomputes the partitions' metadata only, on the GPU once CUDA is prepared;
  /// the same function and range again change nothing. Throws uvr::Error unless range.min < range.max, both
  /// finite (defaultTransferRange widens a constant field's range).
  void setTransferFunction(const ColorMap &map, ValueRange range);

  /// The extremes of the colour variances of the partitions that the transfer function draws ({+inf, -inf}
  /// where none), on `backend` (prepared, with a transfer function set): what adaptive sampling normalises
  /// each partition's deviation by (paper §2.1).
  ValueRange colorVarianceRange(Backend backend) const;
  /// Normalises by `range` rather than by the partitions' own extremes, under this and later transfer
  /// functions ({NaN, NaN}: their own again): the pieces of a mesh split among processes take the extremes
  /// over all pieces, so that they sample adaptively as the whole mesh does.
  void setColorVarianceRange(ValueRange range);

  /// Builds what `backend` needs ahead of the first frame, so that frame times exclude it: the acceleration
  /// data on the host, or on the GPU (uploading the mesh and any transfer function). Throws uvr::Error when
  /// the backend is not in this build or no GPU is found.
  void prepare(Backend backend);

  /// Draws a frame: one ray per pixel through its centre. Throws uvr::Error for invalid settings
  /// (validateSettings), a degenerate camera (validateCamera), a frame whose buffers would pass the memory
  /// limit (<uvr/system.h>), or no transfer function yet. Prepares the backend where it is not. The frame's
  /// tfUpdateMs is the transfer-function update since the last frame (0 when unchanged); buildMs is the
  /// backend's acceleration build, whenever it was done.
  FrameResult render(const Camera &camera, const FrameSettings &settings);
  /// The same into `frame`, whose buffers are reused when their size matches (no allocation per frame).
  void render(const Camera &camera, const FrameSettings &settings, FrameResult &frame);

private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

} // namespace uvr
