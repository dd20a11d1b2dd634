// The GPU's twin of mesh/tet_neighbors.cpp: the tets' face adjacency, by the same per-tet search
// (findTetNeighbors) over incidence rows built by counts and a scan, and the list of boundary faces.
#include "backend/cuda/device_builder.cuh"

#include "mesh/cell.h"
#include "mesh/tet_neighbors.h"

#include <cub/device/device_scan.cuh>

namespace uvr::gpu_build {
namespace {

__global__ void countIncidentKernel(const uint32_t *tets, uint64_t entries, unsigned long long *counts) {
  const uint64_t i = globalIndex();
  if (i < entries)
    atomicAdd(counts + tets[i], 1ull);
}

__global__ void fillIncidentKernel(const uint32_t *tets, uint64_t entries, unsigned long long *next,
                                   uint32_t *incident) {
  const uint64_t i = globalIndex();
  if (i < entries)
    incident[atomicAdd(next + tets[i], 1ull)] = uint32_t(i / 4);
}

__global__ void tetNeighborsKernel(const uint32_t *tets, uint64_t tetCount, const uint64_t *first,
                                   const uint32_t *incident, uint32_t *neighbors) {
  const uint64_t t = globalIndex();
  if (t >= tetCount)
    return;
  uint32_t across[4];
  findTetNeighbors(tets, t, first, incident, across);
  for (int i = 0; i < 4; ++i)
    neighbors[4 * t + i] = across[i];
}

/// Each tet face with no neighbour (a boundary face), 4 * tet + i, counted in `count` and, with `faces`
/// given, put at the slot the count reached (the order is arbitrary).
__global__ void listBoundaryFacesKernel(const uint32_t *tetNeighbors, uint64_t entries,
                                        unsigned long long *count, uint32_t *faces) {
  const uint64_t entry = globalIndex();
  if (entry >= entries || tetNeighbors[entry] != kNoCell)
    return;
  const unsigned long long slot = atomicAdd(count, 1ull);
  if (faces)
    faces[slot] = uint32_t(entry);
}

} // namespace

void DeviceBuilder::tetAdjacency() {
  const uint64_t tets = mesh_.tetCount, entries = 4 * tets;
  if (tets == 0)
    return;
  DeviceBuffer<uint64_t> counts, first;
  counts.resize(pointCount_);
  first.resize(pointCount_ + 1);
  UVR_CUDA_CHECK(cudaMemset(counts.data(), 0, counts.bytes()));
  UVR_CUDA_CHECK(cudaMemset(first.data(), 0, sizeof(uint64_t)));
  auto *counters = reinterpret_cast<unsigned long long *>(counts.data());
  countIncidentKernel<<<blocksFor(entries, kBlock), kBlock>>>(mesh_.tets, entries, counters);
  UVR_CUDA_CHECK(cudaGetLastError());
  scratch_.run([&](void *storage, size_t &bytes) {
    return cub::DeviceScan::InclusiveSum(storage, bytes, counts.data(), first.data() + 1,
                                         int64_t(pointCount_));
  });
  // Each point's next free slot in its row: the row starts, shifted by one.
  UVR_CUDA_CHECK(cudaMemcpy(counts.data(), first.data(), counts.bytes(), cudaMemcpyDeviceToDevice));
  DeviceBuffer<uint32_t> incident;
  incident.resize(entries);
  fillIncidentKernel<<<blocksFor(entries, kBlock), kBlock>>>(mesh_.tets, entries, counters, incident.data());
  UVR_CUDA_CHECK(cudaGetLastError());
  out_.tetNeighbors.resize(entries);
  tetNeighborsKernel<<<blocksFor(tets, kBlock), kBlock>>>(mesh_.tets, tets, first.data(), incident.data(),
                                                          out_.tetNeighbors.data());
}

void DeviceBuilder::boundaryFaceList() {
  if (!listsBoundaryFaces(mesh_))
    return;
  const uint64_t entries = 4 * mesh_.tetCount;
  DeviceBuffer<unsigned long long> count;
  count.resize(1);
  UVR_CUDA_CHECK(cudaMemset(count.data(), 0, count.bytes()));
  listBoundaryFacesKernel<<<blocksFor(entries, kBlock), kBlock>>>(out_.tetNeighbors.data(), entries,
                                                                  count.data(), nullptr);
  UVR_CUDA_CHECK(cudaGetLastError());
  out_.boundaryFaceList.resize(downloadOne(count.data()));
  UVR_CUDA_CHECK(cudaMemset(count.data(), 0, count.bytes()));
  listBoundaryFacesKernel<<<blocksFor(entries, kBlock), kBlock>>>(out_.tetNeighbors.data(), entries,
                                                                  count.data(), out_.boundaryFaceList.data());
  UVR_CUDA_CHECK(cudaGetLastError());
}

} // namespace uvr::gpu_build
