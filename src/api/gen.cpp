#include "api/access.h"
#include "gen/mesher.h"
#include "gen/volume.h"
#include "io/volume_io.h"
#include <uvr/error.h>

#include <uvr/gen.h>

namespace uvr {

struct VoxelVolume::Impl {
  Volume volume;
};

VoxelVolume::VoxelVolume(std::shared_ptr<const Impl> impl) : impl_(std::move(impl)) {}

VoxelVolume VoxelVolume::readNifti(const std::string &path) {
  return VoxelVolume(std::make_shared<const Impl>(Impl{uvr::readNifti(path)}));
}

VoxelVolume VoxelVolume::readRaw(const std::string &path, std::array<int64_t, 3> dims, VoxelType type,
                                 std::array<double, 3> spacing) {
  return VoxelVolume(std::make_shared<const Impl>(Impl{readRawVolume(path, dims, type, spacing)}));
}

const std::string &VoxelVolume::name() const { return impl_->volume.name; }

std::array<int64_t, 3> VoxelVolume::dims() const { return impl_->volume.dims; }

float VoxelVolume::threshold(const GenOptions &options) const {
  return effectiveThreshold(impl_->volume, options);
}

VolumeMesh VoxelVolume::generateMesh(const GenOptions &options, CellType type) const {
  const Volume &volume = impl_->volume;
  if (type != CellType::Tetra && type != CellType::Hexahedron)
    throw Error("meshes are generated of tetrahedra or hexahedra only");
  Mesh mesh = type == CellType::Tetra ? generateTetMesh(volume, options) : generateHexMesh(volume, options);
  // In the order every loaded mesh is given, so that a .umesh written from it is read without reordering
  // (which takes more memory than the mesh: UmeshReader).
  orderSpatially(mesh);
  return detail::Access::make(std::move(mesh), volume.name);
}

} // namespace uvr
