#include "backend/cuda/cuda_backend.h"

#include "backend/cuda/boundary_crossings.cuh"
#include "backend/cuda/cuda_build.cuh"
#include "backend/cuda/device_buffer.cuh"
#include "backend/cuda/partition_metadata.cuh"
#include "mesh/cell_neighbors.h"
#include "render/scene.h"
#include <uvr/error.h>
#include <uvr/system.h>

#include <cub/device/device_radix_sort.cuh>
#include <cuda_runtime.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cstring>
#include <optional>
#include <string>
#include <vector>

namespace uvr {
namespace {

// 128 pixels per block.
constexpr unsigned kRenderBlockThreads = 128;

/// The block's shape for `mode`; `tiles`: for the skipping modes, warps of 8x4 pixels rather than rows of 32.
/// Marching every ray, warps of 16x2 pixels are fastest. Skipping, the better shape depends on the transfer
/// function (how coherent the rays' intervals are), so CudaBackend::render times both.
dim3 renderBlock(RenderMode mode, bool tiles) {
  if (!skipsSpace(mode))
    return dim3(16, kRenderBlockThreads / 16);
  return tiles ? dim3(8, kRenderBlockThreads / 8) : dim3(32, kRenderBlockThreads / 32);
}

/// Resident blocks per SM asked of the compiler, which caps registers. 5 blocks, 96 registers, suit the
/// marching modes: more warps in flight outweigh a few spills to L1. 4 blocks, 128 registers, suit the
/// skipping ones, whose rays carry their tet (RayCell) and would spill it at 96. (Measured in
/// docs/results/log.md.)
constexpr int kMarchingBlocksPerSm = 5, kSkippingBlocksPerSm = 4;

/// The isosurfaces are a __grid_constant__: the march reads them through a pointer, which would otherwise
/// copy them (140 bytes) to each thread's stack.
template <class Sampling, int BlocksPerSm, bool kPreintegrate, bool kShade, bool kIso>
__global__ void __launch_bounds__(kRenderBlockThreads, BlocksPerSm)
    renderKernel(SceneView scene, IntegratorSettings settings, CameraView camera, PixelTarget target,
                 int height, const uint64_t *crossingStart, const uint64_t *crossingKeys,
                 SampleTotals *samples, ShadingSettings shading, const __grid_constant__ IsoSettings iso,
                 const uint32_t *tileOrder, uint32_t *tileCost) {
  // Blocks start in the order of their index: the block of index i draws tile tileOrder[i] (the heaviest of
  // the last frame first, where given), and adds the time its warps took to that tile's cost.
  const long long begun = clock64();
  const uint32_t block = blockIdx.x + gridDim.x * blockIdx.y;
  const uint32_t tile = tileOrder ? tileOrder[block] : block;
  const int x = int((tile % gridDim.x) * blockDim.x + threadIdx.x);
  const int y = int((tile / gridDim.x) * blockDim.y + threadIdx.y);
  uint32_t taken = 0; // pixels past the frame's edge take none, and still join the warp's sums below
  if (x < target.width && y < height) {
    uint32_t hint = kNoCell; // no neighbouring ray to start from: the seed grid finds the first cell
    BoundaryCrossings crossings;
    if (crossingStart)
      crossings =
          pixelCrossings(crossingStart, crossingKeys, uint64_t(y) * uint64_t(target.width) + uint64_t(x));
    const RayResult result = integrateRay<Sampling, kPreintegrate, kShade, kIso>(
        scene, settings, camera.ray(x, y), hint, crossings, {}, &shading, &iso);
    target.store(x, y, result);
    taken = result.samples;
  }
  // The warp sums its samples by shuffles, and one lane adds them: one atomic per warp, no block barrier
  // holding warps that are done.
  unsigned long long total = taken;
  uint32_t most = taken;
  for (int offset = 16; offset > 0; offset /= 2) {
    total += __shfl_xor_sync(0xffffffffu, total, offset);
    most = max(most, __shfl_xor_sync(0xffffffffu, most, offset));
  }
  if ((threadIdx.x + blockDim.x * threadIdx.y) % 32 == 0) {
    atomicAdd(&samples->total, total);
    atomicMax(&samples->max, most);
    atomicAdd(&tileCost[tile], uint32_t(min((clock64() - begun) >> 6, 0xffffffffLL / 64)));
  }
}

/// The render kernel for `Sampling`, the marching or the skipping modes' block count, the compositing and
/// the shading.
template <class Sampling, bool kShade> auto chooseRenderKernel(bool skipping, bool preintegrate) {
  return preintegrate ? (skipping ? renderKernel<Sampling, kSkippingBlocksPerSm, true, kShade, false>
                                  : renderKernel<Sampling, kMarchingBlocksPerSm, true, kShade, false>)
                      : (skipping ? renderKernel<Sampling, kSkippingBlocksPerSm, false, kShade, false>
                                  : renderKernel<Sampling, kMarchingBlocksPerSm, false, kShade, false>);
}

/// Isosurfaces: a kernel per sampling and compositing, at the skipping modes' block count (their rays
/// carry more), which shades the volume at run time (IntegratorSettings::shade).
template <class Sampling> auto chooseRenderKernel(bool skipping, bool preintegrate, bool shade, bool iso) {
  if (iso)
    return preintegrate ? renderKernel<Sampling, kSkippingBlocksPerSm, true, false, true>
                        : renderKernel<Sampling, kSkippingBlocksPerSm, false, false, true>;
  return shade ? chooseRenderKernel<Sampling, true>(skipping, preintegrate)
               : chooseRenderKernel<Sampling, false>(skipping, preintegrate);
}

} // namespace

/// Page-locked host memory. Copies from the GPU into pageable memory go through the driver's own small pinned
/// buffer, at a fraction of the bus's speed; into this they run at full speed.
class PinnedBuffer {
public:
  PinnedBuffer() = default;
  PinnedBuffer(const PinnedBuffer &) = delete;
  PinnedBuffer &operator=(const PinnedBuffer &) = delete;
  ~PinnedBuffer() {
    if (data_)
      cudaFreeHost(data_);
  }

  uint8_t *data() { return data_; }
  void resize(size_t bytes) {
    if (bytes <= capacity_)
      return;
    if (data_)
      UVR_CUDA_CHECK(cudaFreeHost(data_));
    data_ = nullptr;
    capacity_ = 0;
    void *p = nullptr;
    UVR_CUDA_CHECK(cudaMallocHost(&p, bytes));
    data_ = static_cast<uint8_t *>(p);
    capacity_ = bytes;
  }

private:
  uint8_t *data_ = nullptr;
  size_t capacity_ = 0;
};

struct CudaBackend::Impl {
  int device = 0; // made current on entry: a process may hold backends on several GPUs
  std::string deviceName;
  SceneView scene; // device pointers
  DeviceBuffer<Vec3f> points;
  DeviceBuffer<uint32_t> tets, pyramids, wedges, hexes;
  DeviceBuffer<float> values;
  DeviceBuffer<Vec3f> gradients; // per point, for shaded frames and isosurfaces
  IsoSettings iso;               // the isosurfaces of frames that draw them
  uint32_t transparent = 0;      // partitions skipped under the last metadata
  uint64_t pointCount = 0;
  DeviceAcceleration accel;
  double buildMs = 0.0;
  std::vector<std::pair<std::string, double>> buildSteps;
  size_t peakBytes = 0; // the device's peak seen by this backend (devicePeakBytes)
  bool lean = false;
  DeviceMetadata metadata;
  std::optional<TransferFunctionRangeView> tf; // the function's tables on the device, once set
  DeviceBuffer<double> tfPrefixSum, tfPrefixSquares;
  DeviceBuffer<float> tfOpacityMax;
  DeviceBuffer<Vec4f> tfTable, tfExtinction, tfExtinctionIntegral;
  DeviceBuffer<uint8_t> rgb;
  DeviceBuffer<float> opacity;
  DeviceBuffer<float> rgba;
  DeviceBuffer<uint16_t> rgba16;
  DeviceBuffer<uint32_t> samples;
  DeviceBuffer<SampleTotals> sampleTotals;
  DeviceBuffer<float> rayLimits;
  DeviceCrossings crossings;
  PinnedBuffer staging;                                   // the frame's arrays on their way to the caller's
  cudaEvent_t kernelStart = nullptr, kernelEnd = nullptr; // around the frame's kernels
  cudaEvent_t renderStart = nullptr;                      // from there to kernelEnd, the render kernel alone
  // The skipping modes' warp shape for the current transfer function (see renderBlock): after a change, the
  // first frame loads the kernel, the second is drawn in rows and the third in tiles, both timed; later
  // frames take the faster shape.
  int skippingFrames = 0; // since the change, counted up to 3
  float rowsMs = 0.f;
  bool tiles = false;
  std::vector<cudaEvent_t> pieceCopied; // per piece of the frame on its way back
  // The order of the next frame's tiles (its blocks' places in the image): the heaviest of the last frame
  // first, as a greedy scheduler would take them. Blocks in index order, the last ones heavy, left most SMs
  // idle for a third of the kernel while a few finished them. The rays of consecutive frames are coherent.
  DeviceBuffer<uint32_t> tileCost, tileCostSorted, tileIndex, tileOrder;
  CubScratch tileScratch;
  dim3 tileGrid, tileBlock; // what tileOrder is for
  bool tileOrdered = false;

  ~Impl() {
    if (kernelStart)
      cudaEventDestroy(kernelStart);
    if (kernelEnd)
      cudaEventDestroy(kernelEnd);
    if (renderStart)
      cudaEventDestroy(renderStart);
    for (cudaEvent_t event : pieceCopied)
      cudaEventDestroy(event);
  }
};

namespace {
std::atomic<int> cudaDeviceChoice{0};
} // namespace

int cudaDevicesVisible() {
  int devices = 0;
  return cudaGetDeviceCount(&devices) == cudaSuccess ? devices : 0;
}
void selectCudaDevice(int ordinal) { cudaDeviceChoice = ordinal; }
int selectedCudaDevice() { return cudaDeviceChoice; }

uint64_t defaultLayoutPeakBytes(uint64_t cells, uint64_t tets, uint64_t points) {
  // The largest of the steps' (rounded up): the partitions' lists; the tet adjacency's rows; the BVH's
  // temporaries, or at the end the grids and boundary faces, beside the adjacency.
  return std::max({25 * cells, 32 * tets + 16 * points, 16 * tets + 24 * cells});
}

CudaBackend::CudaBackend(const Mesh &hostMesh, const MeshView &mesh, uint32_t leafSize, MemoryLayout layout)
    : impl_(std::make_unique<Impl>()) {
  const uint64_t pointCount = hostMesh.points.size();
  int devices = 0;
  const cudaError_t status = cudaGetDeviceCount(&devices);
  if (status != cudaSuccess || devices == 0)
    throw Error(std::string("no CUDA GPU available") +
                (status != cudaSuccess ? std::string(": ") + cudaGetErrorString(status) : std::string()));
  Impl &d = *impl_;
  d.device = selectedCudaDevice() < devices ? selectedCudaDevice() : 0;
  UVR_CUDA_CHECK(cudaSetDevice(d.device));
  cudaDeviceProp properties{};
  UVR_CUDA_CHECK(cudaGetDeviceProperties(&properties, d.device));
  d.deviceName = properties.name;
  resetDeviceMemoryPeak();

  UVR_CUDA_CHECK(cudaEventCreate(&d.kernelStart));
  UVR_CUDA_CHECK(cudaEventCreate(&d.kernelEnd));
  UVR_CUDA_CHECK(cudaEventCreate(&d.renderStart));
  d.pointCount = pointCount;
  d.lean = layout == MemoryLayout::Lean;
  if (layout == MemoryLayout::Auto) {
    size_t freeBytes = 0, totalBytes = 0;
    UVR_CUDA_CHECK(cudaMemGetInfo(&freeBytes, &totalBytes));
    const uint64_t meshBytes =
        sizeof(Vec3f) * pointCount +
        sizeof(uint32_t) *
            (4 * mesh.tetCount + 5 * mesh.pyramidCount + 6 * mesh.wedgeCount + 8 * mesh.hexCount) +
        (mesh.values ? sizeof(float) * (mesh.cellCentered ? mesh.cellCount() : pointCount) : 0);
    constexpr uint64_t kFrameReserve = uint64_t(1) << 30; // frame buffers, crossings, the kernels' stacks
    d.lean = meshBytes + defaultLayoutPeakBytes(mesh.cellCount(), mesh.tetCount, pointCount) + kFrameReserve >
             freeBytes;
  }
  MeshView onDevice = mesh;
  onDevice.points = d.points.upload(mesh.points, pointCount);
  onDevice.tets = d.tets.upload(mesh.tets, 4 * mesh.tetCount);
  onDevice.pyramids = d.pyramids.upload(mesh.pyramids, 5 * mesh.pyramidCount);
  onDevice.wedges = d.wedges.upload(mesh.wedges, 6 * mesh.wedgeCount);
  onDevice.hexes = d.hexes.upload(mesh.hexes, 8 * mesh.hexCount);
  onDevice.values =
      mesh.values ? d.values.upload(mesh.values, mesh.cellCentered ? mesh.cellCount() : pointCount) : nullptr;

  const Timer timer;
  d.buildSteps = buildOnDevice(onDevice, pointCount, leafSize, d.lean, d.accel);
  const uint64_t otherCells = mesh.cellCount() - mesh.tetCount;
  size_t freeBytes = 0, totalBytes = 0;
  UVR_CUDA_CHECK(cudaMemGetInfo(&freeBytes, &totalBytes));
  if (!d.lean && otherCells > 0) {
    const Timer adjacency;
    const std::vector<uint32_t> cellNeighbors = buildCellNeighbors(hostMesh);
    // The boundary faces of the tets and the other cells, for the frames' crossings: a few bytes a cell,
    // kept where the walks' adjacency and planes would not fit.
    std::vector<uint32_t> tetNeighbors;
    copyMember(tetNeighbors, d.accel.tetNeighbors);
    copyMember(d.accel.boundaryFaceList,
               listBoundaryCellFaces(mesh, dataOrNull(tetNeighbors), cellNeighbors));
    if (cellAdjacencyBytes(mesh) <= freeBytes / 8) {
      copyMember(d.accel.cellNeighbors, cellNeighbors);
      copyMember(d.accel.cellFacePlanes, buildCellFacePlanes(mesh));
      linkTetsToOtherCells(mesh, cellNeighbors, tetNeighbors);
      copyMember(d.accel.tetNeighbors, tetNeighbors);
    }
    d.buildSteps.emplace_back("cell adjacency (host)", adjacency.milliseconds());
  }
  d.buildMs = timer.milliseconds();
  SceneView &scene = d.scene;
  scene = makeSceneView(onDevice, d.accel);
  d.metadata.link(scene, uint32_t(d.accel.partitions.nodes.size()));
  UVR_CUDA_CHECK(cudaDeviceSynchronize());
  sampleDeviceMemory(); // what the build's kernels took at launch (their stacks) besides our allocations
  d.peakBytes = deviceMemoryPeak(d.device);
}

CudaBackend::~CudaBackend() = default;

uint32_t CudaBackend::setTransferFunction(const TransferFunction &tf) {
  Impl &d = *impl_;
  UVR_CUDA_CHECK(cudaSetDevice(d.device));
  TransferFunctionRangeView ranges = tf.rangeView();
  ranges.function.table = d.tfTable.upload(tf.table().data(), tf.table().size());
  ranges.function.extinction = d.tfExtinction.upload(tf.extinction().data(), tf.extinction().size());
  ranges.function.extinctionIntegral =
      d.tfExtinctionIntegral.upload(tf.extinctionIntegral().data(), tf.extinctionIntegral().size());
  ranges.prefixSum = d.tfPrefixSum.upload(tf.prefixSums().data(), tf.prefixSums().size());
  ranges.prefixSquares = d.tfPrefixSquares.upload(tf.prefixSquares().data(), tf.prefixSquares().size());
  ranges.opacityMax = d.tfOpacityMax.upload(tf.opacityMaxima().data(), tf.opacityMaxima().size());
  d.scene.tf = ranges.function;
  d.tf = ranges;
  d.skippingFrames = 0;
  d.tiles = false;

  return d.transparent = d.metadata.update(ranges, d.scene.partitions, d.iso);
}

uint32_t CudaBackend::setField(const MeshView &view) {
  Impl &d = *impl_;
  MeshView &onDevice = d.scene.mesh;
  onDevice.values = view.values
                        ? d.values.upload(view.values, view.cellCentered ? view.cellCount() : d.pointCount)
                        : nullptr;
  onDevice.cellCentered = view.cellCentered;
  // The ranges from the host's copy of the mesh: the tree is small to fetch, and one pass over the cells on
  // all cores costs little beside a rebuild.
  PartitionArrays<DeviceStorage> &parts = d.accel.partitions;
  std::vector<KdNode> nodes(parts.nodes.size());
  parts.nodes.download(nodes.data(), nodes.size());
  const uint32_t count = d.scene.partitions.count;
  std::vector<float> valueMin(count), valueMax(count);
  computePartitionValueRanges(view, nodes, count, valueMin, valueMax);
  parts.valueMin.upload(valueMin.data(), count);
  parts.valueMax.upload(valueMax.data(), count);
  d.skippingFrames = 0;
  d.tiles = false;
  return d.transparent = d.tf ? d.metadata.update(*d.tf, d.scene.partitions, d.iso) : 0;
}

uint32_t CudaBackend::setIsoSurfaces(const IsoSettings &iso) {
  Impl &d = *impl_;
  const bool same = d.iso.sameSkipping(iso);
  d.iso = iso;
  if (!same && d.tf) {
    UVR_CUDA_CHECK(cudaSetDevice(d.device));
    d.transparent = d.metadata.update(*d.tf, d.scene.partitions, d.iso);
  }
  return d.transparent;
}

void CudaBackend::setGradients(const Vec3f *gradients, uint64_t count) {
  Impl &d = *impl_;
  if (gradients)
    d.gradients.upload(gradients, count);
  else
    d.gradients.release();
}

PartitionMetadata CudaBackend::metadata() const {
  return impl_->metadata.download(impl_->scene.partitions.count);
}

SampleTotals CudaBackend::render(const CameraView &camera, const IntegratorSettings &settings,
                                 const ShadingSettings &shading, const PixelTarget &target,
                                 double &kernelMs) {
  Impl &d = *impl_;
  UVR_CUDA_CHECK(cudaSetDevice(d.device));
  const int height = camera.height;
  SampleTotals samples;
  const size_t pixels = size_t(target.width) * size_t(height);
  d.rgb.resize(target.rgb ? 3 * pixels : 0);
  d.opacity.resize(target.opacity ? pixels : 0);
  d.samples.resize(target.samples ? pixels : 0);
  d.rgba.resize(target.rgba ? 4 * pixels : 0);
  d.rgba16.resize(target.rgba16 ? 4 * pixels : 0);
  d.sampleTotals.resize(1);
  UVR_CUDA_CHECK(cudaMemsetAsync(d.sampleTotals.data(), 0, d.sampleTotals.bytes()));
  // The rays read their limits on the GPU.
  CameraView deviceCamera = camera;
  if (camera.limits)
    deviceCamera.limits = d.rayLimits.upload(camera.limits, pixels);
  PixelTarget device = target;
  device.rgb = target.rgb ? d.rgb.data() : nullptr;
  device.opacity = target.opacity ? d.opacity.data() : nullptr;
  device.samples = target.samples ? d.samples.data() : nullptr;
  device.rgba = target.rgba ? d.rgba.data() : nullptr;
  device.rgba16 = target.rgba16 ? d.rgba16.data() : nullptr;
  const bool skipping = skipsSpace(settings.mode);
  const int trial = skipping ? d.skippingFrames : 0; // 1: rows timed, 2: tiles timed
  if (skipping && d.skippingFrames < 3)
    ++d.skippingFrames;
  const dim3 block = renderBlock(settings.mode, trial == 2 || (trial == 3 && d.tiles));
  const dim3 grid((unsigned(target.width) + block.x - 1) / block.x,
                  (unsigned(height) + block.y - 1) / block.y);
  UVR_CUDA_CHECK(cudaEventRecord(d.kernelStart));
  const uint64_t faces = d.accel.boundaryFaceList.size();
  const bool crossings =
      skipsSpace(settings.mode) && faces > 0 && crossingsApply(camera, d.scene.partitions.rootBounds);
  if (crossings)
    d.crossings.find(d.scene.mesh, d.accel.boundaryFaceList, deviceCamera, pixels);
  const uint64_t *crossingStart = crossings ? d.crossings.start() : nullptr;
  if ((settings.shade || settings.iso) && d.gradients.size() == 0)
    throw Error("a shaded frame, or one with isosurfaces, needs the field's gradients");
  ShadingSettings lit = shading;
  lit.gradients = d.gradients.data();
  const auto kernel =
      d.accel.cellNeighbors.size() > 0
          ? chooseRenderKernel<DeviceCellWalkSampling>(skipping, settings.preintegrate, settings.shade,
                                                       settings.iso)
          : chooseRenderKernel<DeviceSampling>(skipping, settings.preintegrate, settings.shade, settings.iso);
  const uint32_t tiles = grid.x * grid.y;
  if (grid.x != d.tileGrid.x || grid.y != d.tileGrid.y || block.x != d.tileBlock.x ||
      block.y != d.tileBlock.y) {
    d.tileGrid = grid;
    d.tileBlock = block;
    d.tileOrdered = false;
    d.tileCost.resize(tiles);
    d.tileCostSorted.resize(tiles);
    d.tileOrder.resize(tiles);
    std::vector<uint32_t> index(tiles);
    for (uint32_t i = 0; i < tiles; ++i)
      index[i] = i;
    d.tileIndex.upload(index.data(), tiles);
    UVR_CUDA_CHECK(cudaMemsetAsync(d.tileCost.data(), 0, d.tileCost.bytes()));
  }
  UVR_CUDA_CHECK(cudaEventRecord(d.renderStart));
  kernel<<<grid, block>>>(d.scene, settings, deviceCamera, device, height, crossingStart, d.crossings.keys(),
                          d.sampleTotals.data(), lit, d.iso, d.tileOrdered ? d.tileOrder.data() : nullptr,
                          d.tileCost.data());
  UVR_CUDA_CHECK(cudaGetLastError());
  d.tileScratch.run([&](void *storage, size_t &bytes) {
    return cub::DeviceRadixSort::SortPairsDescending(storage, bytes, d.tileCost.data(),
                                                     d.tileCostSorted.data(), d.tileIndex.data(),
                                                     d.tileOrder.data(), int(tiles));
  });
  UVR_CUDA_CHECK(cudaMemsetAsync(d.tileCost.data(), 0, d.tileCost.bytes()));
  d.tileOrdered = true;
  UVR_CUDA_CHECK(cudaEventRecord(d.kernelEnd));
  // The frame comes back through pinned memory, piece by piece, each copied on all cores into the caller's
  // arrays while the next crosses the bus: copies into pageable memory run at a fraction of the bus's speed.
  // Buffers the caller did not ask for stay on the GPU.
  struct Part {
    void *destination;
    const void *source;
    size_t bytes; // 0 for a buffer not kept
  };
  const Part parts[] = {{&samples, d.sampleTotals.data(), d.sampleTotals.bytes()},
                        {target.rgb, d.rgb.data(), d.rgb.bytes()},
                        {target.opacity, d.opacity.data(), d.opacity.bytes()},
                        {target.samples, d.samples.data(), d.samples.bytes()},
                        {target.rgba, d.rgba.data(), d.rgba.bytes()},
                        {target.rgba16, d.rgba16.data(), d.rgba16.bytes()}};
  size_t stagedBytes = 0;
  for (const Part &part : parts)
    stagedBytes += part.bytes;
  d.staging.resize(stagedBytes);
  uint8_t *staged = d.staging.data();
  struct Piece {
    uint8_t *destination;
    size_t offset, bytes; // in the staging buffer
  };
  constexpr size_t kPiece = size_t(1) << 20;
  std::vector<Piece> pieces;
  size_t offset = 0;
  for (const Part &part : parts) {
    for (size_t at = 0; at < part.bytes; at += kPiece) {
      const size_t bytes = std::min(kPiece, part.bytes - at);
      UVR_CUDA_CHECK(cudaMemcpyAsync(staged + offset + at, static_cast<const uint8_t *>(part.source) + at,
                                     bytes, cudaMemcpyDeviceToHost));
      if (d.pieceCopied.size() == pieces.size()) {
        d.pieceCopied.emplace_back();
        UVR_CUDA_CHECK(cudaEventCreateWithFlags(&d.pieceCopied.back(), cudaEventDisableTiming));
      }
      UVR_CUDA_CHECK(cudaEventRecord(d.pieceCopied[pieces.size()]));
      pieces.push_back({static_cast<uint8_t *>(part.destination) + at, offset + at, bytes});
    }
    offset += part.bytes;
  }
  for (size_t i = 0; i < pieces.size(); ++i) {
    UVR_CUDA_CHECK(cudaEventSynchronize(d.pieceCopied[i])); // a kernel fault surfaces at the first
    const Piece &piece = pieces[i];
    tbb::parallel_for(
        tbb::blocked_range<size_t>(0, piece.bytes, kPiece / 4), [&](const tbb::blocked_range<size_t> &r) {
          std::memcpy(piece.destination + r.begin(), staged + piece.offset + r.begin(), r.size());
        });
  }
  if (trial == 1 || trial == 2) {
    float renderMs = 0.f;
    UVR_CUDA_CHECK(cudaEventElapsedTime(&renderMs, d.renderStart, d.kernelEnd));
    if (trial == 1)
      d.rowsMs = renderMs;
    else
      d.tiles = renderMs < d.rowsMs;
  }
  // The kernel's stacks are taken at its launch, not by an allocation of ours.
  sampleDeviceMemory();
  d.peakBytes = std::max(d.peakBytes, deviceMemoryPeak(d.device));
  float kernelTime = 0.f;
  UVR_CUDA_CHECK(cudaEventElapsedTime(&kernelTime, d.kernelStart, d.kernelEnd));
  kernelMs = kernelTime;
  return samples;
}

size_t CudaBackend::deviceMemoryBytes() const {
  const Impl &d = *impl_;
  return deviceSceneBytes() + d.rgb.bytes() + d.opacity.bytes() + d.samples.bytes() + d.rgba.bytes() +
         d.rgba16.bytes() + d.sampleTotals.bytes() + d.crossings.bytes() + d.tileCost.bytes() +
         d.tileCostSorted.bytes() + d.tileIndex.bytes() + d.tileOrder.bytes();
}

size_t CudaBackend::devicePeakBytes() const {
  // Uploads after the last frame (setField, setGradients) raised the device's peak only.
  return std::max(impl_->peakBytes, deviceMemoryPeak(impl_->device));
}

size_t CudaBackend::deviceSceneBytes() const {
  const Impl &d = *impl_;
  return d.points.bytes() + d.tets.bytes() + d.pyramids.bytes() + d.wedges.bytes() + d.hexes.bytes() +
         d.values.bytes() + d.gradients.bytes() + d.accel.bytes() + d.metadata.bytes() + d.tfTable.bytes() +
         d.tfPrefixSum.bytes() + d.tfPrefixSquares.bytes() + d.tfOpacityMax.bytes() + d.tfExtinction.bytes() +
         d.tfExtinctionIntegral.bytes();
}

uint32_t CudaBackend::partitionCount() const { return impl_->scene.partitions.count; }
MemoryLayout CudaBackend::layout() const { return impl_->lean ? MemoryLayout::Lean : MemoryLayout::Default; }
double CudaBackend::buildMs() const { return impl_->buildMs; }
std::vector<std::pair<std::string, double>> CudaBackend::buildSteps() const { return impl_->buildSteps; }

HostAcceleration CudaBackend::acceleration() const {
  HostAcceleration out;
  copyStorage(out, impl_->accel);
  return out;
}

std::string CudaBackend::deviceName() const { return impl_->deviceName; }

} // namespace uvr
