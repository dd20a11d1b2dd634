// The view a ray reads, made from the mesh and an acceleration structure of either storage; the caller adds
// the transfer function and the partitions' metadata under it.
#pragma once

#include "accel/acceleration.h"
#include "mesh/mesh_view.h"
#include "render/scene_view.h"

namespace uvr {

template <typename Storage>
SceneView makeSceneView(const MeshView &mesh, const Acceleration<Storage> &accel) {
  SceneView scene;
  scene.mesh = mesh;
  scene.bvh = accel.bvh.view();
  scene.occupancy = accel.occupancy.view();
  scene.seeds = accel.seeds.view();
  scene.tetNeighbors = dataOrNull(accel.tetNeighbors);
  scene.tetAffine = dataOrNull(accel.tetAffine);
  scene.cellNeighbors = dataOrNull(accel.cellNeighbors);
  scene.cellFacePlanes = dataOrNull(accel.cellFacePlanes);
  scene.partitions = accel.partitions.view();
  return scene;
}

} // namespace uvr
