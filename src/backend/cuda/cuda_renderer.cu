#include "backend/cuda/cuda_renderer.h"

#include "backend/cuda/cuda_build.cuh"
#include "backend/cuda/device_buffer.cuh"
#include "core/error.h"
#include "core/timer.h"

#include <cub/block/block_reduce.cuh>
#include <cub/device/device_scan.cuh>
#include <cub/device/device_segmented_sort.cuh>
#include <cuda_runtime.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstring>
#include <string>
#include <type_traits>
#include <vector>

namespace uvr {

void checkCuda(cudaError_t status, const char *call, const char *file, int line) {
  if (status == cudaSuccess)
    return;
  std::string what = std::string("CUDA: ") + call + " failed at " + file + ":" + std::to_string(line) + ": " +
                     cudaGetErrorString(status);
  if (status == cudaErrorMemoryAllocation) {
    size_t free = 0, total = 0;
    if (cudaMemGetInfo(&free, &total) == cudaSuccess)
      what += " (" + std::to_string(free) + " of " + std::to_string(total) + " bytes free)";
  }
  throw Error(what);
}

void throwOutOfMemory(size_t bytes) {
  size_t free = 0, total = 0;
  cudaMemGetInfo(&free, &total);
  throw Error("GPU out of memory: asked for " + std::to_string(bytes) + " bytes, " + std::to_string(free) +
              " of " + std::to_string(total) + " free");
}

namespace {

// 128 pixels per block.
constexpr unsigned kRenderBlockThreads = 128;

/// The block's shape for `mode`; `tiles`: for the skipping modes, warps of 8x4 pixels rather than rows of 32.
/// Marching every ray, warps of 16x2 pixels are fastest (on an H200, side by side: `reference` 3-13 % faster
/// than in rows). Skipping, the better shape depends on the transfer function: on an H100, `full` 857k with
/// the binary brain preset 0.79 ms in rows against 0.97 in tiles, with the translucent one 1.67 against
/// 1.52. CudaRenderer::render times both.
dim3 renderBlock(RenderMode mode, bool tiles) {
  if (!skipsSpace(mode))
    return dim3(16, kRenderBlockThreads / 16);
  return tiles ? dim3(8, kRenderBlockThreads / 8) : dim3(32, kRenderBlockThreads / 32);
}

/// Resident blocks per SM asked of the compiler, which caps registers. 5 blocks, 96 registers (156
/// unbounded), suit the marching modes: on an H200 `reference` 12-18 % faster than unbounded, for a few
/// spills to L1. 4 blocks, 128 registers, suit the skipping ones, whose rays carry their tet (RayCell)
/// without spilling: `full` 857k translucent 2.34-2.37 against 2.47-2.49 ms at 96; `reference` 3-4 % slower
/// at 128.
constexpr int kMarchingBlocksPerSm = 5, kSkippingBlocksPerSm = 4;

template <int BlocksPerSm>
__global__ void __launch_bounds__(kRenderBlockThreads, BlocksPerSm)
    renderKernel(SceneView scene, IntegratorSettings settings, CameraView camera, PixelTarget target,
                 int height, const uint64_t *crossingStart, const uint64_t *crossingKeys,
                 SampleTotals *samples) {
  const int x = int(blockIdx.x * blockDim.x + threadIdx.x);
  const int y = int(blockIdx.y * blockDim.y + threadIdx.y);
  uint32_t taken = 0; // pixels past the frame's edge take none, and still join the warp's sums below
  if (x < target.width && y < height) {
    uint32_t hint = kNoCell; // no neighbouring ray to start from: the seed grid finds the first cell
    BoundaryCrossings crossings;
    if (crossingStart)
      crossings =
          pixelCrossings(crossingStart, crossingKeys, uint64_t(y) * uint64_t(target.width) + uint64_t(x));
    const RayResult result = integrateRay<DeviceSampling>(scene, settings, camera.ray(x, y), hint, crossings);
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
  }
}

/// Each boundary face's crossings with the rays of the pixels it covers: with no `keys`, counted into
/// start[pixel + 1]; with them, placed at start[pixel + 1], which moves on by one each (findBoundaryCrossings
/// says how start's entries change).
__global__ void crossingsKernel(MeshView mesh, const uint32_t *faces, uint64_t faceCount, CameraView camera,
                                uint64_t *start, uint64_t *keys) {
  const uint64_t i = uint64_t(blockIdx.x) * blockDim.x + threadIdx.x;
  if (i >= faceCount)
    return;
  auto *slots = reinterpret_cast<unsigned long long *>(start) + 1;
  forEachPixelCrossing(mesh, faces[i], camera, [&](uint64_t pixel, uint64_t key) {
    const unsigned long long slot = atomicAdd(slots + pixel, 1ull);
    if (keys)
      keys[slot] = key;
  });
}

/// Links each KD node to its parent and each partition to its leaf node, for the metadata kernel's walk up.
__global__ void linkNodesKernel(const KdNode *nodes, uint32_t nodeCount, uint32_t *parents,
                                uint32_t *partitionNodes) {
  const uint32_t node = blockIdx.x * blockDim.x + threadIdx.x;
  if (node >= nodeCount)
    return;
  const KdNode n = nodes[node];
  if (n.axis == KdNode::kLeaf) {
    partitionNodes[n.child] = node;
  } else {
    parents[n.child] = node;
    parents[n.child + 1] = node;
  }
}

/// What the partitions' metadata is normalised by, reduced over all partitions. Non-negative floats order
/// as their bit patterns, which lets integer atomics take their minimum and maximum.
struct MetadataTotals {
  uint32_t lowestVariance;  ///< bits of the smallest variance over the partitions drawn
  uint32_t highestVariance; ///< bits of the largest
  uint32_t transparent;     ///< partitions the transfer function makes fully transparent
};
constexpr MetadataTotals kEmptyTotals{0x7f800000u /* +inf */, 0u, 0u};
constexpr int kMetadataBlock = 256;

/// Per partition, as computePartitionMetadata on the host: the maximum opacity (at its leaf node, and raised
/// into the nodes above, zeroed beforehand) and the colour variance (into `variance`, normalised by
/// normalizeSigmaKernel).
__global__ void partitionMetadataKernel(TransferFunctionRangeView tf, PartitionsView parts,
                                        const uint32_t *parents, const uint32_t *partitionNodes,
                                        float *variance, float *nodeMaxOpacity, MetadataTotals *totals) {
  const uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
  bool drawn = false;
  float v = 0.f;
  if (i < parts.count) {
    const float opacity = maxf(tf.maxOpacity(parts.valueMin[i], parts.valueMax[i]), 0.f);
    v = tf.colorVariance(parts.valueMin[i], parts.valueMax[i]);
    variance[i] = v;
    drawn = opacity > 0.f;
    // Raise the nodes above to this maximum; stop at one that holds as much already: whoever raised it
    // carries that value on to the root.
    uint32_t node = partitionNodes[i];
    nodeMaxOpacity[node] = opacity;
    const uint32_t bits = __float_as_uint(opacity);
    while (drawn && node != 0) {
      node = parents[node];
      if (atomicMax(reinterpret_cast<uint32_t *>(nodeMaxOpacity + node), bits) >= bits)
        break;
    }
  }
  using Reduce = cub::BlockReduce<uint32_t, kMetadataBlock>;
  __shared__ typename Reduce::TempStorage storage;
  const uint32_t varianceBits = __float_as_uint(v);
  const uint32_t lowest = Reduce(storage).Reduce(drawn ? varianceBits : kEmptyTotals.lowestVariance,
                                                 [](uint32_t a, uint32_t b) { return a < b ? a : b; });
  __syncthreads();
  const uint32_t highest =
      Reduce(storage).Reduce(drawn ? varianceBits : 0u, [](uint32_t a, uint32_t b) { return a > b ? a : b; });
  __syncthreads();
  const uint32_t transparent = Reduce(storage).Sum(i < parts.count && !drawn ? 1u : 0u);
  if (threadIdx.x == 0) {
    atomicMin(&totals->lowestVariance, lowest);
    atomicMax(&totals->highestVariance, highest);
    atomicAdd(&totals->transparent, transparent);
  }
}

/// Per partition, its sigma from the variance in `sigma`, lowered into the nodes above it as their
/// nodeMinSigma (set above any sigma beforehand). Sigmas and kTransparentSigma order as their bits do as
/// signed integers, which lets integer atomics take their minimum.
__global__ void normalizeSigmaKernel(uint32_t count, const MetadataTotals *totals, const uint32_t *parents,
                                     const uint32_t *partitionNodes, const float *nodeMaxOpacity,
                                     float *sigma, float *nodeMinSigma) {
  const uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i >= count)
    return;
  sigma[i] = normalizedSigma(sigma[i], __uint_as_float(totals->lowestVariance),
                             __uint_as_float(totals->highestVariance));
  uint32_t node = partitionNodes[i];
  const float lowest = nodeMaxOpacity[node] > 0.f ? sigma[i] : kTransparentSigma;
  nodeMinSigma[node] = lowest;
  const int bits = __float_as_int(lowest);
  while (node != 0) {
    node = parents[node];
    if (atomicMin(reinterpret_cast<int *>(nodeMinSigma + node), bits) <= bits)
      break;
  }
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

struct CudaRenderer::Impl {
  std::string deviceName;
  SceneView scene; // device pointers
  DeviceBuffer<Vec3f> points;
  DeviceBuffer<uint32_t> tets, pyramids, wedges, hexes;
  DeviceBuffer<float> values, nodeMaxOpacity, nodeMinSigma, sigma;
  DeviceAcceleration accel;
  double buildMs = 0.0;
  DeviceBuffer<uint32_t> kdParents, partitionNodes;
  DeviceBuffer<MetadataTotals> totals;
  DeviceBuffer<double> tfPrefixSum, tfPrefixSquares;
  DeviceBuffer<float> tfOpacityMax;
  DeviceBuffer<Vec4f> tfTable;
  DeviceBuffer<uint8_t> rgb;
  DeviceBuffer<float> opacity;
  DeviceBuffer<uint32_t> samples;
  DeviceBuffer<SampleTotals> sampleTotals;
  DeviceBuffer<uint64_t> crossingStart, crossingKeys, placedCrossings; // see findBoundaryCrossings
  CubScratch scratch;
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

CudaRenderer::CudaRenderer(const MeshView &mesh, uint64_t pointCount, uint32_t leafSize)
    : impl_(std::make_unique<Impl>()) {
  int devices = 0;
  const cudaError_t status = cudaGetDeviceCount(&devices);
  if (status != cudaSuccess || devices == 0)
    throw Error(std::string("no CUDA GPU available") +
                (status != cudaSuccess ? std::string(": ") + cudaGetErrorString(status) : std::string()));
  cudaDeviceProp properties{};
  UVR_CUDA_CHECK(cudaGetDeviceProperties(&properties, 0));
  impl_->deviceName = properties.name;

  Impl &d = *impl_;
  UVR_CUDA_CHECK(cudaEventCreate(&d.kernelStart));
  UVR_CUDA_CHECK(cudaEventCreate(&d.kernelEnd));
  UVR_CUDA_CHECK(cudaEventCreate(&d.renderStart));
  SceneView &scene = d.scene;
  scene.mesh = mesh;
  scene.mesh.points = d.points.upload(mesh.points, pointCount);
  scene.mesh.tets = d.tets.upload(mesh.tets, 4 * mesh.tetCount);
  scene.mesh.pyramids = d.pyramids.upload(mesh.pyramids, 5 * mesh.pyramidCount);
  scene.mesh.wedges = d.wedges.upload(mesh.wedges, 6 * mesh.wedgeCount);
  scene.mesh.hexes = d.hexes.upload(mesh.hexes, 8 * mesh.hexCount);
  scene.mesh.values =
      mesh.values ? d.values.upload(mesh.values, mesh.cellCentered ? mesh.cellCount() : pointCount) : nullptr;

  const Timer timer;
  DeviceAcceleration &accel = d.accel;
  buildOnDevice(scene.mesh, pointCount, leafSize, accel);
  d.buildMs = timer.milliseconds();
  scene.tetNeighbors = accel.tetNeighbors.size() > 0 ? accel.tetNeighbors.data() : nullptr;
  scene.bvh = {accel.bvhNodes.data(), accel.bvhCellIds.data()};
  scene.occupancy = accel.occupancy;
  scene.seeds = accel.seeds;
  const uint32_t nodeCount = uint32_t(accel.kdNodes.size()), partitionCount = accel.partitionCount;
  scene.partitions = {accel.kdNodes.data(),  accel.nodeBounds.data(), accel.valueMin.data(),
                      accel.valueMax.data(), accel.rootBounds,        partitionCount};

  d.kdParents.resize(nodeCount);
  d.partitionNodes.resize(partitionCount);
  linkNodesKernel<<<blocksFor(nodeCount, kMetadataBlock), kMetadataBlock>>>(
      scene.partitions.nodes, nodeCount, d.kdParents.data(), d.partitionNodes.data());
  UVR_CUDA_CHECK(cudaGetLastError());
  d.sigma.resize(partitionCount);
  d.nodeMaxOpacity.resize(nodeCount);
  d.nodeMinSigma.resize(nodeCount);
  d.totals.resize(1);
  scene.sigma = d.sigma.data();
  scene.nodeMaxOpacity = d.nodeMaxOpacity.data();
  scene.nodeMinSigma = d.nodeMinSigma.data();
  UVR_CUDA_CHECK(cudaDeviceSynchronize());
}

CudaRenderer::~CudaRenderer() = default;

uint32_t CudaRenderer::setTransferFunction(const TransferFunction &tf) {
  Impl &d = *impl_;
  TransferFunctionRangeView ranges = tf.rangeView();
  ranges.function.table = d.tfTable.upload(tf.table().data(), tf.table().size());
  ranges.prefixSum = d.tfPrefixSum.upload(tf.prefixSums().data(), tf.prefixSums().size());
  ranges.prefixSquares = d.tfPrefixSquares.upload(tf.prefixSquares().data(), tf.prefixSquares().size());
  ranges.opacityMax = d.tfOpacityMax.upload(tf.opacityMaxima().data(), tf.opacityMaxima().size());
  d.scene.tf = ranges.function;
  d.skippingFrames = 0;
  d.tiles = false;

  const uint32_t count = d.scene.partitions.count;
  UVR_CUDA_CHECK(cudaMemset(d.nodeMaxOpacity.data(), 0, d.nodeMaxOpacity.bytes()));
  UVR_CUDA_CHECK(cudaMemcpy(d.totals.data(), &kEmptyTotals, sizeof kEmptyTotals, cudaMemcpyHostToDevice));
  partitionMetadataKernel<<<blocksFor(count, kMetadataBlock), kMetadataBlock>>>(
      ranges, d.scene.partitions, d.kdParents.data(), d.partitionNodes.data(), d.sigma.data(),
      d.nodeMaxOpacity.data(), d.totals.data());
  UVR_CUDA_CHECK(cudaGetLastError());
  UVR_CUDA_CHECK(cudaMemset(d.nodeMinSigma.data(), 0x7f, d.nodeMinSigma.bytes())); // 3.4e38, above any sigma
  normalizeSigmaKernel<<<blocksFor(count, kMetadataBlock), kMetadataBlock>>>(
      count, d.totals.data(), d.kdParents.data(), d.partitionNodes.data(), d.nodeMaxOpacity.data(),
      d.sigma.data(), d.nodeMinSigma.data());
  UVR_CUDA_CHECK(cudaGetLastError());
  MetadataTotals totals{};
  d.totals.download(&totals, 1); // waits for the kernels; a fault surfaces here
  return totals.transparent;
}

PartitionMetadata CudaRenderer::metadata() const {
  const Impl &d = *impl_;
  PartitionMetadata meta;
  const uint32_t count = d.scene.partitions.count;
  meta.sigma.resize(count);
  meta.nodeMaxOpacity.resize(d.nodeMaxOpacity.bytes() / sizeof(float));
  meta.nodeMinSigma.resize(meta.nodeMaxOpacity.size());
  d.sigma.download(meta.sigma.data(), count);
  d.nodeMaxOpacity.download(meta.nodeMaxOpacity.data(), meta.nodeMaxOpacity.size());
  d.nodeMinSigma.download(meta.nodeMinSigma.data(), meta.nodeMinSigma.size());
  // A partition's maximum is its leaf node's.
  std::vector<uint32_t> leafNodes(count);
  d.partitionNodes.download(leafNodes.data(), count);
  meta.maxOpacity.resize(count);
  for (uint32_t i = 0; i < count; ++i)
    meta.maxOpacity[i] = meta.nodeMaxOpacity[leafNodes[i]];
  MetadataTotals totals{};
  d.totals.download(&totals, 1);
  meta.transparentCount = totals.transparent;
  return meta;
}

void CudaRenderer::findCrossings(const CameraView &camera, size_t pixels) {
  Impl &d = *impl_;
  const uint64_t faces = d.accel.boundaryFaceList.size();
  const unsigned blocks = blocksFor(faces, kRenderBlockThreads);
  // What the host's findBoundaryCrossings makes, by testing the faces twice: once to count each pixel's
  // crossings, once to place them from its start on; then ordered pixel by pixel.
  d.crossingStart.resize(pixels + 2);
  UVR_CUDA_CHECK(cudaMemsetAsync(d.crossingStart.data(), 0, d.crossingStart.bytes()));
  crossingsKernel<<<blocks, kRenderBlockThreads>>>(d.scene.mesh, d.accel.boundaryFaceList.data(), faces,
                                                   camera, d.crossingStart.data(), nullptr);
  UVR_CUDA_CHECK(cudaGetLastError());
  uint64_t *counts = d.crossingStart.data() + 1;
  d.scratch.run([&](void *storage, size_t &bytes) {
    return cub::DeviceScan::ExclusiveSum(storage, bytes, counts, counts, int64_t(pixels + 1));
  });
  uint64_t total = 0;
  UVR_CUDA_CHECK(cudaMemcpy(&total, counts + pixels, sizeof total, cudaMemcpyDeviceToHost));
  if (total == 0)
    return;
  d.placedCrossings.grow(total, 0);
  d.crossingKeys.grow(total, 0);
  crossingsKernel<<<blocks, kRenderBlockThreads>>>(d.scene.mesh, d.accel.boundaryFaceList.data(), faces,
                                                   camera, d.crossingStart.data(), d.placedCrossings.data());
  UVR_CUDA_CHECK(cudaGetLastError());
  const uint64_t *start = d.crossingStart.data();
  d.scratch.run([&](void *storage, size_t &bytes) {
    return cub::DeviceSegmentedSort::SortKeys(storage, bytes, d.placedCrossings.data(), d.crossingKeys.data(),
                                              int64_t(total), int64_t(pixels), start, start + 1);
  });
}

double CudaRenderer::render(const CameraView &camera, const IntegratorSettings &settings,
                            const PixelTarget &target, int height, SampleTotals &samples) {
  Impl &d = *impl_;
  const size_t pixels = size_t(target.width) * size_t(height);
  d.rgb.resize(3 * pixels);
  d.opacity.resize(target.opacity ? pixels : 0);
  d.samples.resize(target.samples ? pixels : 0);
  d.sampleTotals.resize(1);
  UVR_CUDA_CHECK(cudaMemsetAsync(d.sampleTotals.data(), 0, d.sampleTotals.bytes()));
  PixelTarget device = target;
  device.rgb = d.rgb.data();
  device.opacity = target.opacity ? d.opacity.data() : nullptr;
  device.samples = target.samples ? d.samples.data() : nullptr;
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
    findCrossings(camera, pixels);
  const uint64_t *crossingStart = crossings ? d.crossingStart.data() : nullptr;
  const auto kernel = skipping ? renderKernel<kSkippingBlocksPerSm> : renderKernel<kMarchingBlocksPerSm>;
  UVR_CUDA_CHECK(cudaEventRecord(d.renderStart));
  kernel<<<grid, block>>>(d.scene, settings, camera, device, height, crossingStart, d.crossingKeys.data(),
                          d.sampleTotals.data());
  UVR_CUDA_CHECK(cudaGetLastError());
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
                        {target.samples, d.samples.data(), d.samples.bytes()}};
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
  float kernelMs = 0.f;
  UVR_CUDA_CHECK(cudaEventElapsedTime(&kernelMs, d.kernelStart, d.kernelEnd));
  return kernelMs;
}

size_t CudaRenderer::memoryBytes() const {
  const Impl &d = *impl_;
  return sceneBytes() + d.rgb.bytes() + d.opacity.bytes() + d.samples.bytes() + d.sampleTotals.bytes() +
         d.crossingStart.bytes() + d.crossingKeys.bytes() + d.placedCrossings.bytes();
}

size_t CudaRenderer::sceneBytes() const {
  const Impl &d = *impl_;
  return d.points.bytes() + d.tets.bytes() + d.pyramids.bytes() + d.wedges.bytes() + d.hexes.bytes() +
         d.values.bytes() + d.accel.bytes() + d.nodeMaxOpacity.bytes() + d.nodeMinSigma.bytes() +
         d.sigma.bytes() + d.kdParents.bytes() + d.partitionNodes.bytes() + d.totals.bytes() +
         d.tfTable.bytes() + d.tfPrefixSum.bytes() + d.tfPrefixSquares.bytes() + d.tfOpacityMax.bytes();
}

uint32_t CudaRenderer::partitionCount() const { return impl_->scene.partitions.count; }
double CudaRenderer::buildMs() const { return impl_->buildMs; }
const std::vector<std::pair<std::string, double>> &CudaRenderer::buildSteps() const {
  return impl_->accel.stepMs;
}

HostAcceleration CudaRenderer::acceleration() const {
  const DeviceAcceleration &accel = impl_->accel;
  auto copy = [](const auto &buffer) {
    std::vector<std::remove_cv_t<std::remove_pointer_t<decltype(buffer.data())>>> host(buffer.size());
    buffer.download(host.data(), host.size());
    return host;
  };
  HostAcceleration out;
  out.bvh.nodes = copy(accel.bvhNodes);
  out.bvh.cellIds = copy(accel.bvhCellIds);
  out.tetNeighbors = copy(accel.tetNeighbors);
  OccupancyGrid &grid = out.occupancy;
  grid.bits = copy(accel.occupancyBits);
  grid.grid = accel.occupancy.grid;
  SeedGrid &seeds = out.seeds;
  seeds.seeds = copy(accel.seedCells);
  seeds.boundaryStart = copy(accel.boundaryStart);
  seeds.boundaryFaces = copy(accel.boundaryFaces);
  seeds.boundaryOctants = copy(accel.boundaryOctants);
  seeds.grid = accel.seeds.grid;
  out.boundaryFaceList = copy(accel.boundaryFaceList);
  Partitions &parts = out.partitions;
  parts.nodes = copy(accel.kdNodes);
  parts.nodeBounds = copy(accel.nodeBounds);
  parts.valueMin = copy(accel.valueMin);
  parts.valueMax = copy(accel.valueMax);
  const std::vector<unsigned long long> counts = copy(accel.cellCounts);
  parts.cellCounts.assign(counts.begin(), counts.end());
  parts.rootBounds = accel.rootBounds;
  parts.bounds.resize(accel.partitionCount);
  for (size_t node = 0; node < parts.nodes.size(); ++node)
    if (parts.nodes[node].axis == KdNode::kLeaf)
      parts.bounds[parts.nodes[node].child] = parts.nodeBounds[node];
  return out;
}

const std::string &CudaRenderer::deviceName() const { return impl_->deviceName; }

} // namespace uvr
