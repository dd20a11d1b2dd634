#include "accel/partitions.h"
#include "api/access.h"
#include "io/mesh_io.h"
#include "mesh/mesh_stats.h"
#include <uvr/error.h>
#include <uvr/renderer.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>

namespace uvr {

namespace {

/// One value per tuple: several components become their Euclidean magnitude, as the file readers do.
ScalarField toField(const FieldArray &array, const std::string &source) {
  const ArrayView &v = array.values;
  if (v.components < 1 || (v.tuples > 0 && !v.data))
    throw Error(source, "", "field '" + array.name + "' has no values");
  ScalarField field{array.name, array.centering, UninitVector<float>(v.tuples)};
  const size_t components = size_t(v.components);
  const auto component = [&](size_t i) {
    return v.isDouble ? static_cast<const double *>(v.data)[i]
                      : double(static_cast<const float *>(v.data)[i]);
  };
  for (size_t i = 0; i < v.tuples; ++i) {
    if (components == 1) {
      field.values[i] = float(component(i));
      continue;
    }
    double sum = 0.0;
    for (size_t c = 0; c < components; ++c)
      sum += component(i * components + c) * component(i * components + c);
    field.values[i] = float(std::sqrt(sum));
  }
  return field;
}

UninitVector<Vec3f> toPoints(const ArrayView &v, const std::string &source) {
  if (v.components != 3 || (v.tuples > 0 && !v.data))
    throw Error(source, "", "points must have 3 components");
  UninitVector<Vec3f> points(v.tuples);
  if (!v.isDouble) {
    if (v.tuples > 0)
      std::memcpy(points.data(), v.data, v.tuples * sizeof(Vec3f));
    return points;
  }
  const double *p = static_cast<const double *>(v.data);
  for (size_t i = 0; i < 3 * points.size(); ++i)
    if (std::isfinite(p[i]) && std::fabs(p[i]) > double(std::numeric_limits<float>::max()))
      throw Error(source, "point " + std::to_string(i / 3), "a coordinate is out of float range");
  for (size_t i = 0; i < points.size(); ++i)
    points[i] = {float(p[3 * i]), float(p[3 * i + 1]), float(p[3 * i + 2])};
  return points; // buildMesh refuses those not finite, as it does for every reader
}

const ScalarField &fieldAt(const Mesh &mesh, const std::string &source, int index) {
  if (index < 0 || size_t(index) >= mesh.fields.size())
    throw Error(source, "", "no field " + std::to_string(index));
  return mesh.fields[size_t(index)];
}

} // namespace

VolumeMesh detail::Access::make(Mesh &&mesh, const std::string &source) {
  auto impl = std::make_shared<VolumeMesh::Impl>();
  impl->mesh = std::move(mesh);
  impl->source = source;
  return VolumeMesh(std::move(impl));
}

VolumeMesh::VolumeMesh() : impl_(std::make_shared<Impl>()) {}

VolumeMesh::VolumeMesh(std::shared_ptr<Impl> impl) : impl_(std::move(impl)) {}

VolumeMesh VolumeMesh::load(const std::string &path, const LoadOptions &options) {
  try {
    return detail::Access::make(loadMesh(path, options), path);
  } catch (const std::filesystem::filesystem_error &e) { // e.g. a name too long, a directory unreadable
    throw Error(path, "", std::string("cannot read: ") + e.code().message());
  }
}

VolumeMesh VolumeMesh::fromArrays(const MeshArrays &arrays, const std::string &source) {
  UninitVector<Vec3f> points = toPoints(arrays.points, source);
  std::vector<ScalarField> fields;
  for (const FieldArray &array : arrays.fields)
    fields.push_back(toField(array, source));
  const CellArraysView cells{arrays.offsets, arrays.connectivity, arrays.types};
  return detail::Access::make(buildMesh(std::move(points), cells, std::move(fields), source), source);
}

void VolumeMesh::save(const std::string &path, const SaveOptions &options) const {
  if (!options.compress) {
    saveMesh(path, impl_->mesh);
    return;
  }
  if (!path.ends_with(".vtu") && !path.ends_with(".VTU"))
    throw Error(path, "", "compression applies to .vtu files only");
  writeVtu(path, impl_->mesh, true);
}

const std::string &VolumeMesh::source() const { return impl_->source; }
uint64_t VolumeMesh::pointCount() const { return impl_->mesh.points.size(); }
uint64_t VolumeMesh::cellCount() const { return impl_->mesh.cellCount(); }

CellCounts VolumeMesh::cellCounts() const {
  const Mesh &m = impl_->mesh;
  CellCounts counts;
  counts.tet = m.tetCount();
  counts.hex = m.hexCount();
  counts.wedge = m.wedgeCount();
  counts.pyramid = m.pyramidCount();
  counts.skipped = m.skippedCells;
  counts.inverted = m.invertedCells;
  counts.polyhedron = m.polyhedra.polyhedra;
  counts.polyhedronTets = m.polyhedra.tets;
  counts.polyhedronPyramids = m.polyhedra.pyramids;
  return counts;
}

Box3f VolumeMesh::bounds() const {
  std::call_once(impl_->boundsOnce, [&] { impl_->bounds = impl_->mesh.bounds(); });
  return impl_->bounds;
}

std::span<const Vec3f> VolumeMesh::points() const { return impl_->mesh.points; }

std::span<const uint32_t> VolumeMesh::cells(CellType type) const {
  const Mesh &m = impl_->mesh;
  switch (type) {
  case CellType::Tetra:
    return m.tets;
  case CellType::Pyramid:
    return m.pyramids;
  case CellType::Wedge:
    return m.wedges;
  case CellType::Hexahedron:
    return m.hexes;
  }
  return {};
}

int VolumeMesh::fieldCount() const { return int(impl_->mesh.fields.size()); }

FieldInfo VolumeMesh::field(int index) const {
  const ScalarField &f = fieldAt(impl_->mesh, impl_->source, index);
  return {f.name, f.centering};
}

std::span<const float> VolumeMesh::fieldValues(int index) const {
  return fieldAt(impl_->mesh, impl_->source, index).values;
}

ValueRange VolumeMesh::fieldRange(int index) const {
  return valueRange(fieldAt(impl_->mesh, impl_->source, index));
}

int VolumeMesh::findField(const std::string &name) const { return impl_->mesh.findField(name); }

int VolumeMesh::chooseField(const std::string &name) const {
  const Mesh &mesh = impl_->mesh;
  const std::string &source = impl_->source;
  if (mesh.cellCount() == 0)
    throw Error(source, "", "the file holds no volume cells (tetra, hexahedron, wedge or pyramid)");
  if (mesh.fields.empty())
    throw Error(source, "", "the mesh has no scalar field to render");
  if (name.empty())
    return 0;
  const int index = mesh.findField(name);
  if (index < 0) {
    // Names shared by a point and a cell field are listed with the prefix that tells them apart.
    std::string names;
    for (const ScalarField &f : mesh.fields) {
      const bool shared = std::count_if(mesh.fields.begin(), mesh.fields.end(),
                                        [&](const ScalarField &g) { return g.name == f.name; }) > 1;
      const std::string prefix = !shared ? "" : f.centering == Centering::Point ? "point:" : "cell:";
      names += (names.empty() ? "" : ", ") + prefix + f.name;
    }
    throw Error(source, "", "no field named '" + name + "'; fields: " + names);
  }
  return index;
}

VolumeMesh VolumeMesh::withFields(const std::vector<int> &indices) && {
  for (int index : indices)
    fieldAt(impl_->mesh, impl_->source, index);
  // A handle of its own gives its fields up; a shared one is copied, so that other handles see no change.
  std::shared_ptr<Impl> impl = std::move(impl_);
  impl_ = std::make_shared<Impl>();
  if (impl.use_count() > 1) {
    auto copy = std::make_shared<Impl>();
    copy->mesh = impl->mesh;
    copy->source = impl->source;
    impl = std::move(copy);
  }
  std::vector<ScalarField> all = std::move(impl->mesh.fields);
  impl->mesh.fields.clear();
  for (size_t i = 0; i < indices.size(); ++i) {
    ScalarField &field = all[size_t(indices[i])];
    const bool usedAgain =
        std::find(indices.begin() + ptrdiff_t(i) + 1, indices.end(), indices[i]) != indices.end();
    impl->mesh.fields.push_back(usedAgain ? field : std::move(field));
  }
  return VolumeMesh(std::move(impl));
}

VolumeMesh VolumeMesh::selectCells(std::span<const uint8_t> keep, const std::vector<int> &indices) const {
  if (keep.size() != cellCount())
    throw Error(impl_->source, "",
                "a selection of " + std::to_string(keep.size()) + " entries for " +
                    std::to_string(cellCount()) + " cells");
  for (int index : indices)
    fieldAt(impl_->mesh, impl_->source, index);
  return detail::Access::make(uvr::selectCells(impl_->mesh, keep, indices), impl_->source);
}

VolumeStats VolumeMesh::volumeStats() const {
  std::call_once(impl_->statsOnce, [&] { impl_->stats = uvr::volumeStats(impl_->mesh); });
  return impl_->stats;
}

float VolumeMesh::defaultStep() const { return defaultStepSize(volumeStats(), bounds()); }

MeshRegions splitIntoRegions(const VolumeMesh &mesh, int count) {
  const RegionSplit split = splitRegions(makeMeshView(detail::Access::mesh(mesh), -1), count);
  MeshRegions regions;
  regions.regions = split.regions;
  for (const RegionSplit::Node &n : split.nodes)
    regions.nodes.push_back({n.axis, n.position, n.below, n.above, n.region});
  return regions;
}

namespace {
void appendFrontToBack(const MeshRegions &regions, int node, Vec3f eye, std::vector<int> &order) {
  const MeshRegions::Node &n = regions.nodes[size_t(node)];
  if (n.axis < 0) {
    order.push_back(n.region);
    return;
  }
  const bool eyeBelow = eye[n.axis] < n.position;
  appendFrontToBack(regions, eyeBelow ? n.below : n.above, eye, order);
  appendFrontToBack(regions, eyeBelow ? n.above : n.below, eye, order);
}
} // namespace

std::vector<int> MeshRegions::frontToBack(Vec3f eye) const {
  std::vector<int> order;
  if (!nodes.empty())
    appendFrontToBack(*this, 0, eye, order);
  return order;
}

VolumeMesh::StepScaleReference VolumeMesh::stepScaleReference(uint32_t leafSize) const {
  if (cellCount() == 0)
    return {};
  const uint32_t size = leafSize != kAutoLeafSize ? leafSize : defaultLeafSize();
  StepScaleShare whole;
  whole.cellCounts = buildPartitions(makeMeshView(impl_->mesh, -1), size, &whole.sizeLog2Sums).cellCounts;
  return stepScaleReference({whole});
}

VolumeMesh::StepScaleShare VolumeMesh::stepScaleShare(const Box3f &region, const Box3f &wholeBounds,
                                                      uint32_t leafSize) const {
  if (cellCount() == 0)
    return {};
  MeshView view = makeMeshView(impl_->mesh, -1);
  view.pieceRegion = region;
  view.pieceWholeBounds = wholeBounds;
  StepScaleShare share;
  share.cellCounts = buildPartitions(view, leafSize, &share.sizeLog2Sums).cellCounts;
  return share;
}

VolumeMesh::StepScaleReference VolumeMesh::stepScaleReference(const std::vector<StepScaleShare> &shares) {
  StepScaleShare all;
  for (const StepScaleShare &share : shares) {
    all.sizeLog2Sums.insert(all.sizeLog2Sums.end(), share.sizeLog2Sums.begin(), share.sizeLog2Sums.end());
    all.cellCounts.insert(all.cellCounts.end(), share.cellCounts.begin(), share.cellCounts.end());
  }
  if (all.cellCounts.empty())
    return {};
  const StepScales scales = computeStepScales(all.sizeLog2Sums, all.cellCounts, {});
  return {scales.mean, scales.finest};
}

uint32_t VolumeMesh::defaultLeafSize() const { return uvr::defaultLeafSize(cellCount()); }

uint32_t VolumeMesh::partitionCount(uint32_t leafSize) const {
  if (cellCount() == 0)
    return 0;
  const uint32_t size = leafSize != kAutoLeafSize ? leafSize : defaultLeafSize();
  return buildPartitions(makeMeshView(impl_->mesh, -1), size).count();
}

} // namespace uvr
