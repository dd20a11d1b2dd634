#include "mesh/polyhedra.h"

#include <uvr/error.h>

#include <algorithm>
#include <cmath>

namespace uvr {

void PolyhedronFaces::appendStream(std::span<const int64_t> stream, const std::string &source,
                                   const std::string &where) {
  if (stream.empty() || stream[0] < 1)
    throw Error(source, where, "a polyhedron needs a face count of at least 1");
  // Every face takes at least 4 entries of the stream, which bounds the count before anything is kept.
  const auto faceCount = uint64_t(stream[0]);
  if (faceCount > (stream.size() - 1) / 4)
    throw Error(source, where,
                "polyhedron of " + std::to_string(faceCount) + " faces in a face stream of " +
                    std::to_string(stream.size()) + " entries");
  size_t at = 1;
  for (uint64_t f = 0; f < faceCount; ++f) {
    const int64_t n = at < stream.size() ? stream[at] : -1;
    if (n < 3 || uint64_t(n) > stream.size() - at - 1)
      throw Error(source, where,
                  "face " + std::to_string(f) + " of the polyhedron has " + std::to_string(n) +
                      " points: fewer than 3, or more than its face stream holds");
    faceIds.push_back(int64_t(faceOffsets.size()) - 1);
    facePoints.insert(facePoints.end(), stream.begin() + ptrdiff_t(at) + 1,
                      stream.begin() + ptrdiff_t(at) + 1 + n);
    faceOffsets.push_back(int64_t(facePoints.size()));
    at += size_t(n) + 1;
  }
  if (at != stream.size())
    throw Error(source, where,
                "the polyhedron's faces use " + std::to_string(at) + " entries of its face stream of " +
                    std::to_string(stream.size()));
  cellOffsets.push_back(int64_t(faceIds.size()));
}

namespace {

/// Checks the faces against the grid before anything is made from them. Errors name the file's cell.
void checkFaces(const UnstructuredGrid &grid, const PolyhedronFaces &faces, const std::string &source) {
  std::vector<size_t> cells; ///< the file's index of each polyhedron
  for (size_t c = 0; c < grid.types.size(); ++c)
    if (grid.types[c] == kVtkPolyhedron)
      cells.push_back(c);
  if (faces.polyhedronCount() != cells.size())
    throw Error(source, "",
                std::to_string(cells.size()) + " cells of type 42 (polyhedron), faces given for " +
                    std::to_string(faces.polyhedronCount()));
  const uint64_t faceCount = faces.faceOffsets.size() - 1;
  if (faces.cellOffsets[0] != 0 || uint64_t(faces.cellOffsets.back()) != faces.faceIds.size())
    throw Error(source, "", "polyhedron face offsets do not span the face list");
  if (faces.faceOffsets[0] != 0 || uint64_t(faces.faceOffsets.back()) != faces.facePoints.size())
    throw Error(source, "", "face offsets do not span the face points");
  for (size_t f = 0; f < faceCount; ++f)
    if (faces.faceOffsets[f + 1] - faces.faceOffsets[f] < 3)
      throw Error(source, "",
                  "face " + std::to_string(f) + " has fewer than 3 points, or face offsets decrease");
  // A face bounds at most two cells; more uses would let a short list of face ids ask for huge meshes.
  std::vector<uint8_t> uses(faceCount, 0);
  const uint64_t pointCount = grid.points.size();
  for (size_t k = 0; k < cells.size(); ++k) {
    const std::string cell = "cell " + std::to_string(cells[k]);
    if (faces.cellOffsets[k + 1] <= faces.cellOffsets[k])
      throw Error(source, cell, "a polyhedron without faces, or face offsets decreasing");
    for (int64_t slot = faces.cellOffsets[k]; slot < faces.cellOffsets[k + 1]; ++slot) {
      const int64_t id = faces.faceIds[size_t(slot)];
      if (id < 0 || uint64_t(id) >= faceCount)
        throw Error(source, cell,
                    "face id " + std::to_string(id) + " outside [0, " + std::to_string(faceCount) + ")");
      if (++uses[size_t(id)] > 2)
        throw Error(source, cell, "face " + std::to_string(id) + " is used by more than two polyhedra");
      for (int64_t i = faces.faceOffsets[size_t(id)]; i < faces.faceOffsets[size_t(id) + 1]; ++i) {
        const int64_t point = faces.facePoints[size_t(i)];
        if (point < 0 || uint64_t(point) >= pointCount)
          throw Error(source, cell,
                      "point index " + std::to_string(point) + " of a face outside [0, " +
                          std::to_string(pointCount) + ")");
      }
    }
  }
}

} // namespace

void decomposePolyhedra(UnstructuredGrid &grid, const PolyhedronFaces &faces, const std::string &source) {
  checkFaces(grid, faces, source);
  if (faces.polyhedronCount() == 0)
    return;
  const size_t cellCount = grid.types.size();
  std::vector<int64_t> offsets{0};
  std::vector<int64_t> connectivity;
  std::vector<uint8_t> types;
  std::vector<size_t> sourceCell; ///< the file's cell of each new cell, for the cell fields
  offsets.reserve(cellCount + 1);
  types.reserve(cellCount);
  sourceCell.reserve(cellCount);
  std::vector<size_t> pointFields, cellFields;
  for (size_t i = 0; i < grid.fields.size(); ++i)
    (grid.fields[i].centering == Centering::Point ? pointFields : cellFields).push_back(i);
  // Fields of the wrong size are reported by buildMesh; they are left alone here.
  std::erase_if(pointFields, [&](size_t i) { return grid.fields[i].values.size() != grid.points.size(); });
  std::erase_if(cellFields, [&](size_t i) { return grid.fields[i].values.size() != cellCount; });
  // At a centre, a point field takes the cell field of its name and component count where there is one: in
  // a finite-volume result that is the cell's mean, a second-order estimate at its centroid, where the
  // corners hold values interpolated from cells (foamToVTK's own decomposition gives its centres the same).
  std::vector<const ScalarField *> centreValues(pointFields.size(), nullptr);
  for (size_t i = 0; i < pointFields.size(); ++i) {
    const ScalarField &point = grid.fields[pointFields[i]];
    for (size_t j : cellFields)
      if (grid.fields[j].name == point.name && grid.fields[j].components == point.components) {
        centreValues[i] = &grid.fields[j];
        break;
      }
  }

  PolyhedronCounts &counts = grid.polyhedra;
  std::vector<int64_t> corners;
  size_t polyhedron = 0;
  auto emit = [&](uint8_t type, CellType kept, std::initializer_list<int64_t> ids, size_t cell) {
    uint32_t v[5];
    size_t n = 0;
    for (int64_t id : ids)
      v[n++] = uint32_t(id);
    orientCell(kept, v, grid.points);
    connectivity.insert(connectivity.end(), v, v + n);
    offsets.push_back(int64_t(connectivity.size()));
    types.push_back(type);
    sourceCell.push_back(cell);
  };
  for (size_t c = 0; c < cellCount; ++c) {
    if (grid.types[c] != kVtkPolyhedron) {
      if (uint64_t(grid.offsets[c + 1]) > grid.connectivity.size() || grid.offsets[c + 1] < grid.offsets[c])
        throw Error(source, "cell " + std::to_string(c), "cell offsets do not span the connectivity array");
      connectivity.insert(connectivity.end(), grid.connectivity.begin() + grid.offsets[c],
                          grid.connectivity.begin() + grid.offsets[c + 1]);
      offsets.push_back(int64_t(connectivity.size()));
      types.push_back(grid.types[c]);
      sourceCell.push_back(c);
      continue;
    }
    const size_t k = polyhedron++;
    auto facePoints = [&](int64_t slot) {
      const auto face = size_t(faces.faceIds[size_t(slot)]);
      return std::span<const int64_t>(faces.facePoints.data() + faces.faceOffsets[face],
                                      size_t(faces.faceOffsets[face + 1] - faces.faceOffsets[face]));
    };
    corners.clear();
    for (int64_t slot = faces.cellOffsets[k]; slot < faces.cellOffsets[k + 1]; ++slot)
      for (int64_t id : facePoints(slot))
        corners.push_back(id);
    std::sort(corners.begin(), corners.end());
    corners.erase(std::unique(corners.begin(), corners.end()), corners.end());
    if (corners.size() < 4)
      throw Error(source, "cell " + std::to_string(c),
                  "polyhedron with " + std::to_string(corners.size()) +
                      " distinct points (at least 4 needed)");
    if (grid.points.size() >= UINT32_MAX)
      throw Error(source, "", "more than 2^32 points are not supported");
    Vec3f centre{0.f, 0.f, 0.f};
    for (int64_t id : corners)
      centre = centre + grid.points[size_t(id)];
    const auto apex = int64_t(grid.points.size());
    grid.points.push_back(centre * (1.f / float(corners.size())));
    for (size_t i = 0; i < pointFields.size(); ++i) {
      UninitVector<float> &values = grid.fields[pointFields[i]].values;
      // NaN: the file has no value in this cell (an Exodus block without the variable).
      if (centreValues[i] && !std::isnan(centreValues[i]->values[c])) {
        values.push_back(centreValues[i]->values[c]);
        continue;
      }
      double sum = 0.0;
      for (int64_t id : corners)
        sum += values[size_t(id)];
      values.push_back(float(sum / double(corners.size())));
    }
    for (int64_t slot = faces.cellOffsets[k]; slot < faces.cellOffsets[k + 1]; ++slot) {
      const std::span<const int64_t> face = facePoints(slot);
      if (face.size() == 4) {
        emit(14, CellType::Pyramid, {face[0], face[1], face[2], face[3], apex}, c);
        ++counts.pyramids;
        continue;
      }
      // A fan from the face's lowest-numbered point: the cell on the other side, whose list runs the other
      // way round, makes the same triangles, so the pieces of neighbouring cells meet face to face.
      const size_t n = face.size();
      const auto first = size_t(std::min_element(face.begin(), face.end()) - face.begin());
      for (size_t i = 1; i + 1 < n; ++i) {
        emit(10, CellType::Tetra, {face[first], face[(first + i) % n], face[(first + i + 1) % n], apex}, c);
        ++counts.tets;
      }
    }
    ++counts.polyhedra;
  }
  for (size_t f : cellFields) {
    const UninitVector<float> &old = grid.fields[f].values;
    UninitVector<float> values(sourceCell.size());
    for (size_t i = 0; i < sourceCell.size(); ++i)
      values[i] = old[sourceCell[i]];
    grid.fields[f].values = std::move(values);
  }
  grid.offsets = std::move(offsets);
  grid.connectivity = std::move(connectivity);
  grid.types = std::move(types);
}

} // namespace uvr
