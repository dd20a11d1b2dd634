#include "backend/cpu/cpu_backend.h"

#include "render/boundary_crossings.h"
#include "render/scene.h"
#include <uvr/error.h>
#include <uvr/system.h>

#include <tbb/blocked_range2d.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <vector>

namespace uvr {

CpuBackend::CpuBackend(const Mesh &mesh, const MeshView &view, uint32_t leafSize, MemoryLayout layout)
    : mesh_(view), layout_(layout == MemoryLayout::Lean ? MemoryLayout::Lean : MemoryLayout::Default) {
  const Timer timer;
  accel_ = buildHostAcceleration(mesh, view, leafSize, layout_ == MemoryLayout::Lean);
  buildMs_ = timer.milliseconds();
}

uint32_t CpuBackend::setTransferFunction(const TransferFunction &tf) {
  tf_.emplace(tf);
  metadata_ = computePartitionMetadata(accel_.partitions, *tf_, &iso_);
  return metadata_.transparentCount;
}

uint32_t CpuBackend::setIsoSurfaces(const IsoSettings &iso) {
  const bool same = iso_.sameSkipping(iso);
  iso_ = iso;
  if (!same && tf_)
    metadata_ = computePartitionMetadata(accel_.partitions, *tf_, &iso_);
  return metadata_.transparentCount;
}

uint32_t CpuBackend::setField(const MeshView &view) {
  mesh_ = view;
  Partitions &parts = accel_.partitions;
  computePartitionValueRanges(view, parts.nodes, parts.count(), parts.valueMin, parts.valueMax);
  if (!accel_.tetAffine.empty()) // the records hold the field
    accel_.tetAffine = buildTetAffine(view);
  if (!tf_)
    return 0;
  metadata_ = computePartitionMetadata(parts, *tf_, &iso_);
  return metadata_.transparentCount;
}

SceneView CpuBackend::sceneView() const {
  if (!tf_)
    throw Error("no transfer function set");
  SceneView scene = makeSceneView(mesh_, accel_);
  scene.nodeMaxOpacity = metadata_.nodeMaxOpacity.data();
  scene.nodeMinSigma = metadata_.nodeMinSigma.data();
  scene.sigma = metadata_.sigma.data();
  scene.tf = tf_->view();
  return scene;
}

SampleTotals CpuBackend::render(const CameraView &camera, const IntegratorSettings &settings,
                                const ShadingSettings &shading, const PixelTarget &target, double &kernelMs) {
  kernelMs = 0.0;
  const SceneView scene = sceneView();
  if ((settings.shade || settings.iso) && !gradients_)
    throw Error("a shaded frame, or one with isosurfaces, needs the field's gradients");
  ShadingSettings lit = shading;
  lit.gradients = gradients_;
  const std::vector<uint32_t> &boundaryFaces = accel_.boundaryFaceList;
  std::vector<uint64_t> crossingStart, crossingKeys;
  const bool crossings = skipsSpace(settings.mode) && !boundaryFaces.empty() &&
                         crossingsApply(camera, scene.partitions.rootBounds);
  if (crossings)
    findBoundaryCrossings(scene.mesh, boundaryFaces, camera, crossingStart, crossingKeys);
  std::atomic<unsigned long long> total{0};
  std::atomic<uint32_t> max{0};
  // Small tiles: rays through dense parts of the mesh cost far more than others, so balance finely. The
  // simple partitioner splits down to them; the default one handed out ranges of up to 64×128 pixels.
  constexpr int kTile = 16;
  // A trail entry per grid point along the longest ray through the mesh bounds, within reason.
  // (For a piece of a mesh, along the whole mesh's bounds: its sample grid is the whole mesh's.)
  const Box3f &bounds = settings.clip.empty() ? scene.partitions.rootBounds : settings.gridBounds;
  const float gridPoints =
      length(bounds.upper - bounds.lower) / gridSpacing(settings, scene.partitions) + 2.f;
  const uint32_t trailSize = scene.tetNeighbors ? uint32_t(minf(gridPoints, float(1 << 20))) : 0;
  tbb::parallel_for(
      tbb::blocked_range2d<int>(0, camera.height, kTile, 0, camera.width, kTile),
      [&](const tbb::blocked_range2d<int> &tile) {
        uint32_t hint = kNoCell;
        std::vector<uint32_t> trailCells(trailSize, kNoCell);
        SampleTotals tileSamples;
        const int left = tile.cols().begin(), right = tile.cols().end() - 1;
        Ray ray = camera.ray(left, tile.rows().begin());
        for (int y = tile.rows().begin(); y < tile.rows().end(); ++y) {
          // Serpentine, so that each ray's predecessor is its neighbour (see CellTrail).
          const bool leftward = (y - tile.rows().begin()) % 2 == 1;
          for (int i = 0; i <= right - left; ++i) {
            const int x = leftward ? right - i : left + i;
            const size_t pixel = size_t(y) * size_t(camera.width) + size_t(x);
            // The next ray in this order, across the row or below at its end, reads the trail this one
            // writes; made once, for both.
            const bool rowEnd = i == right - left;
            const int nextX = rowEnd ? x : leftward ? x - 1 : x + 1, nextY = rowEnd ? y + 1 : y;
            const Ray next = camera.ray(nextX, nextY);
            const CellTrail trail{trailCells.data(), trailSize, nextY < tile.rows().end() ? &next : nullptr};
            const BoundaryCrossings along =
                crossings ? pixelCrossings(crossingStart.data(), crossingKeys.data(), pixel)
                          : BoundaryCrossings{};
            // A ray that crosses no boundary face is done at once.
            const RayResult result =
                along.none() ? RayResult{}
                : settings.iso
                    ? settings.preintegrate
                          ? integrateRay<HostSampling, true, false, true>(scene, settings, ray, hint, along,
                                                                          trail, &lit, &iso_)
                          : integrateRay<HostSampling, false, false, true>(scene, settings, ray, hint, along,
                                                                           trail, &lit, &iso_)
                : settings.shade ? settings.preintegrate
                                       ? integrateRay<HostSampling, true, true>(scene, settings, ray, hint,
                                                                                along, trail, &lit)
                                       : integrateRay<HostSampling, false, true>(scene, settings, ray, hint,
                                                                                 along, trail, &lit)
                : settings.preintegrate
                    ? integrateRay<HostSampling, true>(scene, settings, ray, hint, along, trail)
                    : integrateRay<HostSampling, false>(scene, settings, ray, hint, along, trail);
            ray = next;
            target.store(x, y, result);
            tileSamples.total += result.samples;
            tileSamples.max = std::max(tileSamples.max, result.samples);
          }
        }
        total += tileSamples.total;
        for (uint32_t seen = max;
             seen < tileSamples.max && !max.compare_exchange_weak(seen, tileSamples.max);)
          ;
      },
      tbb::simple_partitioner());
  return {total, max};
}

} // namespace uvr
