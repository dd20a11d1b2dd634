// Everything one ray reads: the volume (the mesh and its acceleration data, all the sampler reads), the
// partitions with their metadata for the current transfer function (what the interval iterator reads), and
// the transfer function (what the march reads). Plain data, on host and device alike.
#pragma once

#include "accel/partitions.h"
#include "accel/volume_view.h"
#include "render/transfer_function.h"

namespace uvr {

struct SceneView : VolumeView {
  PartitionsView partitions;
  const float *nodeMaxOpacity = nullptr; ///< per KD node, the maximum over the partitions below
  const float *nodeMinSigma = nullptr;   ///< per KD node, see PartitionMetadata
  const float *sigma = nullptr;          ///< per partition, normalised colour deviation
  TransferFunctionView tf;
};

} // namespace uvr
