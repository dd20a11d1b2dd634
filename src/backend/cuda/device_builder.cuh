// The GPU acceleration build's parts shared by its sources: the helpers its kernels use and the builder
// whose steps each source defines beside the kernels they launch (cuda_build.cu runs them; bvh_build.cu,
// occupancy_build.cu, partitions_build.cu, seed_grid_build.cu and tet_neighbors.cu are named for their host
// twins). Kernels live in the source that launches them (no separable compilation), and every source that
// holds build kernels is compiled with --fmad=false (see CMakeLists.txt).
#pragma once

#include "backend/cuda/cuda_build.cuh"
#include "core/progress.h"
#include "mesh/cell.h"

#include <cstdint>
#include <cstring>
#include <string>
#include <utility>
#include <vector>

namespace uvr::gpu_build {

constexpr int kBlock = 256;

/// Floats as unsigned integers of the same order, for integer atomics and radix sorts.
UVR_HOST_DEVICE inline uint32_t orderedBits(float f) {
  uint32_t u;
  memcpy(&u, &f, sizeof u);
  return (u & 0x80000000u) ? ~u : (u | 0x80000000u);
}

UVR_HOST_DEVICE inline float fromOrderedBits(uint32_t u) {
  u = (u & 0x80000000u) ? (u & 0x7fffffffu) : ~u;
  float f;
  memcpy(&f, &u, sizeof f);
  return f;
}

/// A box reduced by integer atomics on ordered bits; starts empty.
struct AtomicBox {
  uint32_t lower[3], upper[3];

  static AtomicBox empty() {
    const uint32_t inf = orderedBits(INFINITY), negInf = orderedBits(-INFINITY);
    return {{inf, inf, inf}, {negInf, negInf, negInf}};
  }
  __device__ void extend(const Box3f &box) {
    const uint32_t lo[3] = {orderedBits(box.lower.x), orderedBits(box.lower.y), orderedBits(box.lower.z)},
                   hi[3] = {orderedBits(box.upper.x), orderedBits(box.upper.y), orderedBits(box.upper.z)};
    extendBits(lo, hi);
  }
  /// The same for a box given as ordered bits.
  __device__ void extendBits(const uint32_t lo[3], const uint32_t hi[3]) {
    for (int k = 0; k < 3; ++k) {
      atomicMin(&lower[k], lo[k]);
      atomicMax(&upper[k], hi[k]);
    }
  }
  UVR_HOST_DEVICE Box3f box() const {
    return {{fromOrderedBits(lower[0]), fromOrderedBits(lower[1]), fromOrderedBits(lower[2])},
            {fromOrderedBits(upper[0]), fromOrderedBits(upper[1]), fromOrderedBits(upper[2])}};
  }
};

__device__ inline uint64_t globalIndex() { return uint64_t(blockIdx.x) * blockDim.x + threadIdx.x; }

/// Cell `c`'s centroid as the partitions and the BVH order cells by, from its box: computed where it is
/// read rather than kept (12 bytes a cell).
__device__ inline Vec3f cellCentroid(const MeshView &mesh, uint64_t c) {
  return partitionCentroid(cellBounds(mesh, c));
}

template <typename T> T downloadOne(const T *device) {
  T value;
  UVR_CUDA_CHECK(cudaMemcpy(&value, device, sizeof(T), cudaMemcpyDeviceToHost));
  return value;
}

/// Builds `out` from the mesh a step at a time; each step is defined beside the kernels it launches.
class DeviceBuilder {
public:
  DeviceBuilder(const MeshView &mesh, uint64_t pointCount, uint32_t leafSize, bool lean,
                DeviceAcceleration &out)
      : mesh_(mesh), cells_(mesh.cellCount()), pointCount_(pointCount), leafSize_(leafSize), lean_(lean),
        out_(out) {}

  const std::vector<std::pair<std::string, double>> &stepMs() const { return stepMs_; }

  void build();

private:
  void step(const char *name, void (DeviceBuilder::*work)(), Progress &progress);

  unsigned cellBlocks() const { return blocksFor(cells_, kBlock); }

  // The steps, in build's order: those that need the most memory for the time they run come first, while
  // little of what stays is built yet (docs/design.md, "GPU memory").
  void bounds();
  void partitions();
  void tetAdjacency();
  void bvh();
  void occupancy();
  void seeds();
  /// Every boundary face, for the per-frame crossings: counted, then listed.
  void boundaryFaceList();

  /// Compressed rows of the boundary faces per voxel, as the host lists them: counted, offset by a scan, then
  /// filled (part of seeds).
  void boundaryFaces();
  /// The cells' indices ordered by `keys` (one per cell, their low `bits` bits; ties by index) into `order`;
  /// `keys` is left sorted. Sorts in place between two buffers each, so that the sort takes no temporary
  /// storage of its own beyond a few histograms.
  void sortCells(DeviceBuffer<uint32_t> &keys, int bits, DeviceBuffer<uint32_t> &order);
  /// As sortCells, by a 32-bit key per cell that `digitsOf(order, digit, digits)` writes a byte at a time
  /// (digit 0 the least significant) for the cells in `order`'s order: four stable passes from the order by
  /// index give sortCells' order in 10 bytes a cell rather than 16, the key recomputed each pass.
  template <class DigitsOf> void sortCellsByDigits(DigitsOf digitsOf, DeviceBuffer<uint32_t> &order) {
    identityOrder(order);
    DeviceBuffer<uint32_t> orderOther;
    DeviceBuffer<uint8_t> digits, digitsOther;
    orderOther.resize(cells_);
    digits.resize(cells_);
    digitsOther.resize(cells_);
    for (int digit = 0; digit < 4; ++digit) {
      digitsOf(order.data(), digit, digits.data());
      UVR_CUDA_CHECK(cudaGetLastError());
      sortByDigit(digits, digitsOther, order, orderOther);
    }
  }
  /// The cells' indices in order, into `order`.
  void identityOrder(DeviceBuffer<uint32_t> &order);
  /// One stable pass of sortCellsByDigits: `order` reordered by `digits`, each with a spare to sort between.
  void sortByDigit(DeviceBuffer<uint8_t> &digits, DeviceBuffer<uint8_t> &digitsOther,
                   DeviceBuffer<uint32_t> &order, DeviceBuffer<uint32_t> &orderOther);

  MeshView mesh_;
  uint64_t cells_, pointCount_;
  uint32_t leafSize_;
  bool lean_; // no tet adjacency, seed grid or boundary faces (MemoryLayout::Lean)
  DeviceAcceleration &out_;
  std::vector<std::pair<std::string, double>> stepMs_;
  Box3f meshBounds_;
  CubScratch scratch_;
};

} // namespace uvr::gpu_build
