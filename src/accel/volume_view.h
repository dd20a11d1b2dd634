// The volume as the sampler reads it (Open VKL's split: volume, sampler, interval iterator): the mesh and
// its field, and the acceleration data that point location walks and queries. Plain pointers, on host and
// device alike; the renderer's SceneView adds what the intervals and the march read.
#pragma once

#include "accel/bvh.h"
#include "accel/occupancy.h"
#include "accel/seed_grid.h"
#include "mesh/mesh_view.h"
#include "mesh/tet_affine.h"

#include <cstdint>

namespace uvr {

struct VolumeView {
  MeshView mesh;
  BvhView bvh;
  OccupancyView occupancy;                 ///< used by the skipping modes
  SeedGridView seeds;                      ///< where far walks start; boundary faces per voxel
  const uint32_t *tetNeighbors = nullptr;  ///< 4 per tet; see buildTetNeighbors, linkTetsToOtherCells
  const TetAffine *tetAffine = nullptr;    ///< per tet, or null: walks then read the corners
  const uint32_t *cellNeighbors = nullptr; ///< the other cells' faces' neighbours; see buildCellNeighbors
  const Vec4f *cellFacePlanes = nullptr;   ///< and their planes; see buildCellFacePlanes
};

} // namespace uvr
