// The `uvr` Python module: meshes from files or numpy arrays (PyVista's layout), transfer functions, and the
// renderer, with the defaults and error messages of `uvr render`.
#include "front_end.h"

#include <uvr/uvr.h>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <dlfcn.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <deque>
#include <filesystem>
#include <memory>
#include <mutex>
#include <optional>

namespace py = pybind11;
using namespace uvr;

namespace {

/// A mesh; its errors name its source: the file's path, as `uvr render` reports it, or "uvr.Mesh".
struct PyMesh {
  VolumeMesh mesh;
};

/// A preset and the scalar range it is stretched over; no range = the rendered field's range.
struct PyTransferFunction {
  ColorMap map;
  std::optional<std::pair<float, float>> range;
};

// Only C-contiguous arrays of exactly this type pass through without a copy; others are converted once.
template <class T> using InArray = py::array_t<T, py::array::c_style | py::array::forcecast>;

/// A numpy array owning `values` without copying them.
template <class T> py::array_t<T> ownedArray(std::vector<T> &&values, std::vector<py::ssize_t> shape) {
  auto *heap = new std::vector<T>(std::move(values));
  py::capsule owner(heap, [](void *p) { delete static_cast<std::vector<T> *>(p); });
  return py::array_t<T>(shape, heap->data(), owner);
}

/// A read-only numpy view of memory that `owner` keeps alive.
template <class T> py::array_t<T> viewArray(const T *data, std::vector<py::ssize_t> shape, py::handle owner) {
  py::array_t<T> array(shape, data, owner);
  array.attr("setflags")(py::arg("write") = false);
  return array;
}

Vec3f toVec3(const py::handle &value, const char *what) {
  std::vector<float> v;
  try {
    v = value.cast<std::vector<float>>();
  } catch (const py::cast_error &) {
    throw Error(std::string(what) + " expects 3 numbers");
  }
  if (v.size() != 3)
    throw Error(std::string(what) + " expects 3 numbers");
  return {v[0], v[1], v[2]};
}

/// A keyword argument that is None (0: the default) or a finite number > 0; uvr.Error naming it otherwise.
float optionalPositive(const py::handle &value, const char *name) {
  if (value.is_none())
    return 0.f;
  double number = 0.0;
  try {
    number = value.cast<double>();
  } catch (const py::cast_error &) {
    throw Error(std::string(name) + " expects a number or None");
  }
  if (!(number > 0.0) || !std::isfinite(number) || !std::isfinite(float(number)))
    throw Error(std::string(name) + " must be a finite number > 0 (None: the default); got " +
                std::to_string(number));
  return float(number);
}

/// A transfer-function range (lo, hi), checked where it is given rather than at the first frame.
std::optional<std::pair<float, float>> checkRange(const std::optional<std::pair<float, float>> &range) {
  if (range && !(range->first < range->second && std::isfinite(range->first) && std::isfinite(range->second)))
    throw Error("range (" + std::to_string(range->first) + ", " + std::to_string(range->second) +
                ") must be (lo, hi) with lo below hi, both finite");
  return range;
}

py::tuple fromVec3(Vec3f v) { return py::make_tuple(v.x, v.y, v.z); }

/// Whether a numpy array holds numbers uvr can take: integers, or floats too when `floats`.
bool numericArray(const py::array &array, bool floats) {
  const char kind = array.dtype().kind();
  return kind == 'i' || kind == 'u' || (floats && kind == 'f');
}

/// The values of `object` converted to T and copied, with the GIL held: the library reads only this copy
/// with the GIL released, so another thread writing into the caller's array cannot change what was counted.
template <class T> std::vector<T> copyOf(const py::array &object) {
  const InArray<T> array = object;
  return std::vector<T>(array.data(), array.data() + array.size());
}

/// Arrays a mesh is built from: private copies, which the library reads with the GIL released.
struct PyArrays {
  MeshArrays arrays;
  std::deque<std::vector<float>> floats; // a deque: growing it moves none of the vectors viewed
  std::deque<std::vector<double>> doubles;

  /// float32 arrays are copied as they are; any other is converted to float64.
  ArrayView view(const py::array &object, int components, const std::string &what) {
    if (!numericArray(object, true))
      throw Error("uvr.Mesh", "",
                  what + " must hold numbers, not dtype " + std::string(py::str(object.dtype())));
    if (py::isinstance<py::array_t<float>>(object)) {
      const std::vector<float> &values = floats.emplace_back(copyOf<float>(object));
      return ArrayView(std::span<const float>(values), components);
    }
    const std::vector<double> &values = doubles.emplace_back(copyOf<double>(object));
    return ArrayView(std::span<const double>(values), components);
  }

  /// One value per tuple: several components become their Euclidean magnitude, as the file readers do.
  void addFields(Centering centering, const py::object &data) {
    if (data.is_none())
      return;
    // PyVista's DataSetAttributes is a mapping with keys() and []; so is a dict.
    for (const py::handle &key : data.attr("keys")()) {
      const std::string name = py::str(key);
      const py::array array = py::cast<py::array>(data[key]);
      if (array.ndim() != 1 && array.ndim() != 2)
        throw Error("uvr.Mesh", "", "field '" + name + "' must have 1 or 2 dimensions");
      const int components = array.ndim() == 2 ? int(array.shape(1)) : 1;
      arrays.fields.push_back({name, centering, view(array, components, "field '" + name + "'")});
    }
  }
};

/// An integer array's values as int64, copied; floats, strings and the like are refused, not truncated.
std::vector<int64_t> integers(const py::array &object, const char *what) {
  if (!numericArray(object, false))
    throw Error("uvr.Mesh", "",
                std::string(what) + " must hold integers, not dtype " + std::string(py::str(object.dtype())));
  if (object.dtype().kind() == 'u' && object.itemsize() == 8) { // above 2^63 would wrap to negative
    const InArray<uint64_t> wide = object;
    for (py::ssize_t i = 0; i < wide.size(); ++i)
      if (wide.data()[i] > uint64_t(INT64_MAX))
        throw Error("uvr.Mesh", "", std::string(what) + " entry " + std::to_string(i) + " is out of range");
  }
  return copyOf<int64_t>(object);
}

/// Builds a mesh from VTK's arrays: `cells` is the flat [n, i0, i1, ...] layout, or the connectivity when
/// `offsets` (cell count + 1 entries) are given. Every array is checked and copied with the GIL held; the
/// library then checks the mesh as it does each file's (VolumeMesh::fromArrays).
std::shared_ptr<PyMesh> makeMesh(const py::array &pointsArray, const py::array &cellsArray,
                                 const py::array &typesArray, const py::object &offsetsObject,
                                 const py::object &pointData, const py::object &cellData) {
  const std::string source = "uvr.Mesh";
  PyArrays in;
  if (pointsArray.ndim() != 2 || pointsArray.shape(1) != 3)
    throw Error(source, "", "points must have shape (n, 3)");
  in.arrays.points = in.view(pointsArray, 3, "points");
  if (cellsArray.ndim() != 1 || typesArray.ndim() != 1)
    throw Error(source, "", "cells and celltypes must be one-dimensional");
  const std::vector<int64_t> cellValues = integers(cellsArray, "cells");
  const std::vector<int64_t> typeCodes = integers(typesArray, "celltypes");
  const size_t cellCount = typeCodes.size();
  std::vector<uint8_t> types(cellCount);
  for (size_t c = 0; c < cellCount; ++c) {
    if (typeCodes[c] < 0 || typeCodes[c] > 255) // a VTK type code is a byte: 266 must not wrap to 10
      throw Error(source, "cell " + std::to_string(c),
                  "cell type " + std::to_string(typeCodes[c]) + " is not a VTK type code");
    types[c] = uint8_t(typeCodes[c]);
  }
  in.addFields(Centering::Point, pointData);
  in.addFields(Centering::Cell, cellData);

  auto result = std::make_shared<PyMesh>();
  const std::span<const int64_t> cellSpan(cellValues);
  in.arrays.types = types;
  if (!offsetsObject.is_none()) {
    const py::array offsetsArray = py::cast<py::array>(offsetsObject);
    if (offsetsArray.ndim() != 1 || size_t(offsetsArray.shape(0)) != cellCount + 1)
      throw Error(source, "", "offsets must have one entry more than celltypes (VTK 9's layout)");
    const std::vector<int64_t> offsets = integers(offsetsArray, "offsets");
    in.arrays.offsets = offsets;
    in.arrays.connectivity = cellSpan;
    py::gil_scoped_release release;
    result->mesh = VolumeMesh::fromArrays(in.arrays, source);
    return result;
  }
  // The flat layout interleaves counts with point indices: split it into offsets and connectivity.
  std::vector<int64_t> offsets(cellCount + 1, 0), connectivity;
  connectivity.reserve(cellSpan.size() >= cellCount ? cellSpan.size() - cellCount : 0);
  size_t at = 0;
  for (size_t c = 0; c < cellCount; ++c) {
    if (at >= cellSpan.size() || cellSpan[at] < 0 || uint64_t(cellSpan[at]) > cellSpan.size() - at - 1)
      throw Error(source, "cell " + std::to_string(c), "cells array ends inside the cell");
    const size_t n = size_t(cellSpan[at]);
    connectivity.insert(connectivity.end(), cellSpan.begin() + ptrdiff_t(at + 1),
                        cellSpan.begin() + ptrdiff_t(at + 1 + n));
    at += n + 1;
    offsets[c + 1] = int64_t(connectivity.size());
  }
  if (at != cellSpan.size())
    throw Error(source, "",
                "cells array holds more entries than its " + std::to_string(cellCount) + " cells");
  in.arrays.offsets = offsets;
  in.arrays.connectivity = connectivity;
  py::gil_scoped_release release;
  result->mesh = VolumeMesh::fromArrays(in.arrays, source);
  return result;
}

/// PyVista's UnstructuredGrid, duck-typed: VTK 9's offsets + cell_connectivity when present, else cells.
std::shared_ptr<PyMesh> meshFromPyvista(const py::object &grid) {
  const bool vtk9 = py::hasattr(grid, "offsets") && py::hasattr(grid, "cell_connectivity");
  const py::object cells = grid.attr(vtk9 ? "cell_connectivity" : "cells");
  const py::object offsets = vtk9 ? py::object(grid.attr("offsets")) : py::object(py::none());
  return makeMesh(grid.attr("points"), cells, grid.attr("celltypes"), offsets, grid.attr("point_data"),
                  grid.attr("cell_data"));
}

std::shared_ptr<PyMesh> load(const std::string &path, const std::optional<std::string> &field,
                             const std::optional<int> &timeStep) {
  if (timeStep && *timeStep != 0)
    throw Error(path, "", "time steps other than 0 are not supported by this build's readers");
  auto result = std::make_shared<PyMesh>();
  {
    py::gil_scoped_release release;
    result->mesh = VolumeMesh::load(path);
  }
  if (field) {
    const int index = result->mesh.chooseField(*field);
    result->mesh = std::move(result->mesh).withFields({index});
  }
  return result;
}

/// uvr's cells in VTK's flat layout [n, i0, i1, ...] with their type codes, in the mesh's order.
std::pair<std::vector<int64_t>, std::vector<uint8_t>> flatCells(const VolumeMesh &mesh) {
  std::vector<int64_t> cells;
  std::vector<uint8_t> types;
  const CellType order[] = {CellType::Tetra, CellType::Pyramid, CellType::Wedge, CellType::Hexahedron};
  const int corners[] = {4, 5, 6, 8};
  size_t indices = 0;
  for (CellType type : order)
    indices += mesh.cells(type).size();
  cells.reserve(indices + mesh.cellCount());
  types.reserve(mesh.cellCount());
  for (int t = 0; t < 4; ++t) {
    const std::span<const uint32_t> ids = mesh.cells(order[t]);
    for (size_t i = 0; i < ids.size(); i += size_t(corners[t])) {
      cells.push_back(corners[t]);
      cells.insert(cells.end(), ids.begin() + ptrdiff_t(i), ids.begin() + ptrdiff_t(i) + corners[t]);
      types.push_back(uint8_t(order[t]));
    }
  }
  return {std::move(cells), std::move(types)};
}

py::dict fieldViews(const PyMesh &m, Centering centering, py::handle owner) {
  py::dict result;
  for (int i = 0; i < m.mesh.fieldCount(); ++i) {
    const FieldInfo field = m.mesh.field(i);
    if (field.centering == centering) {
      const std::span<const float> values = m.mesh.fieldValues(i);
      result[py::str(field.name)] = viewArray(values.data(), {py::ssize_t(values.size())}, owner);
    }
  }
  return result;
}

PyTransferFunction transferFunctionFromArrays(const py::array &colorsObject,
                                              const py::object &opacitiesObject,
                                              const std::optional<std::pair<float, float>> &range,
                                              const std::string &colorSpace) {
  const InArray<float> colors = colorsObject;
  if (colors.ndim() != 2 || colors.shape(1) != 4 || colors.shape(0) < 1)
    throw Error("uvr.TransferFunction", "", "colors must have shape (n, 4): x, r, g, b per point");
  PyTransferFunction tf;
  tf.map.name = "arrays";
  tf.map.colorSpace = colorSpace;
  tf.map.rgbPoints.assign(colors.data(), colors.data() + colors.size());
  if (!opacitiesObject.is_none()) {
    const InArray<float> opacities = py::cast<py::array>(opacitiesObject);
    if (opacities.ndim() != 2 || (opacities.shape(1) != 2 && opacities.shape(1) != 4) ||
        opacities.shape(0) < 1)
      throw Error(
          "uvr.TransferFunction", "",
          "opacities must have shape (n, 2) (x, opacity) or (n, 4) (x, opacity, midpoint, sharpness)");
    for (py::ssize_t i = 0; i < opacities.shape(0); ++i) {
      const float *row = opacities.data(i, 0);
      const bool full = opacities.shape(1) == 4;
      tf.map.opacityPoints.insert(tf.map.opacityPoints.end(),
                                  {row[0], row[1], full ? row[2] : 0.5f, full ? row[3] : 0.f});
    }
  }
  for (const float v : tf.map.rgbPoints)
    if (!std::isfinite(v))
      throw Error("uvr.TransferFunction", "", "colors must be finite");
  for (const float v : tf.map.opacityPoints)
    if (!std::isfinite(v))
      throw Error("uvr.TransferFunction", "", "opacities must be finite");
  tf.range = checkRange(range);
  return tf;
}

/// The renderer of one mesh and field, keeping the mesh alive and the last frame's statistics and samples.
class PyRenderer {
public:
  PyRenderer(std::shared_ptr<PyMesh> mesh, const std::optional<std::string> &field,
             const std::string &backend, int64_t leafSize)
      : mesh_(std::move(mesh)) {
    backendKind_ = parseBackendOption(backend);
    if (leafSize < 0 || leafSize > int64_t(UINT32_MAX))
      throw Error("leaf_size must be 0 (the default) or a positive cell count; got " +
                  std::to_string(leafSize));
    const int fieldIndex = mesh_->mesh.chooseField(field.value_or(""));
    py::gil_scoped_release release;
    renderer_ = std::make_unique<VolumeRenderer>(mesh_->mesh, fieldIndex, uint32_t(leafSize));
    // The acceleration data is built here, as users expect of the constructor, not at the first frame.
    renderer_->prepare(backendKind_);
  }

  /// Renders `field` of `mesh`, whose points and cells must be this renderer's, keeping the acceleration
  /// data.
  void setField(std::shared_ptr<PyMesh> mesh, const std::optional<std::string> &field) {
    const int fieldIndex = mesh->mesh.chooseField(field.value_or(""));
    {
      py::gil_scoped_release release;
      const std::lock_guard<std::mutex> lock(frameMutex_);
      renderer_->setField(mesh->mesh, fieldIndex);
    }
    mesh_ = std::move(mesh);
  }

  Camera defaultCamera(float fovy, float aspect, const std::string &view) const {
    return frameBounds(mesh_->mesh.bounds(), view, fovy, aspect);
  }

  /// None: the default camera for an image of this aspect (width / height); a dict's keys (eye, at, up, fovy)
  /// replace those of the default camera.
  Camera toCamera(const py::object &object, float aspect) const {
    if (object.is_none())
      return defaultCamera(30.f, aspect, "+z");
    if (py::isinstance<Camera>(object))
      return object.cast<Camera>();
    const py::dict dict = object.cast<py::dict>();
    for (const auto &item : dict) {
      const std::string key = py::str(item.first);
      if (key != "eye" && key != "at" && key != "up" && key != "fovy" && key != "view")
        throw Error("unknown camera key '" + key + "': expected eye, at, up, fovy, view");
    }
    float fovy = 30.f;
    if (dict.contains("fovy")) {
      try {
        fovy = dict["fovy"].cast<float>();
      } catch (const py::cast_error &) {
        throw Error("camera fovy expects a number of degrees");
      }
    }
    const std::string view = dict.contains("view") ? std::string(py::str(dict["view"])) : "+z";
    Camera camera = defaultCamera(fovy, aspect, view);
    if (dict.contains("at"))
      camera.at = toVec3(dict["at"], "at");
    if (dict.contains("eye"))
      camera.eye = toVec3(dict["eye"], "eye");
    if (dict.contains("up"))
      camera.up = toVec3(dict["up"], "up");
    return camera;
  }

  py::array_t<uint8_t> render(const py::object &cameraObject, const std::optional<PyTransferFunction> &tf,
                              const py::object &mode, const py::object &s1, const py::object &s2,
                              const py::object &p, const py::object &unit, const py::object &size,
                              const py::object &background, const py::object &compositing,
                              const py::object &steps, const py::object &shade, const py::object &light,
                              const py::object &iso, const py::object &isoColor, const py::object &isoOpacity,
                              const py::object &isoOnly) {
    // Every keyword is checked here, naming it, before any work (uvr.Error).
    std::vector<int64_t> sides;
    try {
      sides = size.cast<std::vector<int64_t>>();
    } catch (const py::cast_error &) {
    }
    if (sides.size() != 2 || sides[0] < 1 || sides[1] < 1 || sides[0] > 16384 || sides[1] > 16384)
      throw Error("size expects (width, height) with each side from 1 to 16384");
    const int width = int(sides[0]), height = int(sides[1]);
    if (!py::isinstance<py::str>(mode))
      throw Error("mode expects reference, skip, adaptive or full");
    FrameSettings settings;
    settings.backend = backendKind_;
    settings.width = width;
    settings.height = height;
    settings.background = toVec3(background, "background");
    if (!py::isinstance<py::bool_>(shade))
      throw Error("shade expects True or False");
    settings.shade = shade.cast<bool>();
    if (!light.is_none())
      settings.light = toVec3(light, "light");
    if (!iso.is_none()) {
      try {
        settings.isoValues = iso.cast<std::vector<float>>();
      } catch (const py::cast_error &) {
        throw Error("iso expects a list of numbers or None");
      }
      if (settings.isoValues.empty())
        throw Error("iso expects at least one value (None: no isosurfaces)");
    }
    if (!isoColor.is_none()) {
      settings.isoColor = toVec3(isoColor, "iso_color");
      for (const float c : {settings.isoColor->x, settings.isoColor->y, settings.isoColor->z})
        if (!(c >= 0.f && c <= 1.f))
          throw Error("iso_color expects (r, g, b) each in [0, 1]");
    }
    try {
      settings.isoOpacity = isoOpacity.cast<float>();
    } catch (const py::cast_error &) {
      settings.isoOpacity = NAN;
    }
    if (!(settings.isoOpacity > 0.f && settings.isoOpacity <= 1.f))
      throw Error("iso_opacity expects a number in (0, 1]");
    if (!py::isinstance<py::bool_>(isoOnly))
      throw Error("iso_only expects True or False");
    settings.isoOnly = isoOnly.cast<bool>();
    if (settings.isoOnly && settings.isoValues.empty())
      throw Error("iso_only needs iso values to draw");
    settings.mode = parseMode(mode.cast<std::string>());
    if (!py::isinstance<py::str>(compositing))
      throw Error("compositing expects auto, point or preintegrated");
    settings.compositing = parseCompositing(compositing.cast<std::string>());
    if (!py::isinstance<py::str>(steps))
      throw Error("steps expects auto, global or local");
    settings.steps = parseStepSizing(steps.cast<std::string>());
    settings.s1 = optionalPositive(s1, "s1");
    settings.s2 = optionalPositive(s2, "s2");
    settings.p = optionalPositive(p, "p");
    settings.unit = optionalPositive(unit, "unit");
    validateSettings(settings);
    const Camera camera = toCamera(cameraObject, float(width) / float(height));
    validateCamera(camera);
    const PyTransferFunction function = tf ? *tf : PyTransferFunction{chooseColorMap(""), std::nullopt};
    const ValueRange range = function.range
                                 ? ValueRange{function.range->first, function.range->second}
                                 : defaultTransferRange(mesh_->mesh.fieldRange(renderer_->fieldIndex()));

    FrameResult frame;
    {
      py::gil_scoped_release release;
      // Taken without the GIL (a thread holding it waits for none), and held over the transfer function's
      // change and the frame: another thread's function cannot slip in between.
      const std::lock_guard<std::mutex> lock(frameMutex_);
      // A function already set changes nothing; a new one recomputes the partitions' metadata alone.
      renderer_->setTransferFunction(function.map, range);
      renderer_->prepare(backendKind_); // uploads the scene for CUDA once, outside the frame time
      frame = renderer_->render(camera, settings);
    }
    lastStats_ = frameStatsJson(frame.stats);
    width_ = width;
    height_ = height;

    std::vector<uint8_t> rgba(size_t(width) * size_t(height) * 4);
    for (size_t i = 0; i < frame.opacity.size(); ++i) {
      for (int c = 0; c < 3; ++c)
        rgba[4 * i + size_t(c)] = frame.image.rgb[3 * i + size_t(c)];
      rgba[4 * i + 3] = uint8_t(std::lround(std::clamp(frame.opacity[i], 0.f, 1.f) * 255.f));
    }
    lastSamples_ = std::move(frame.samplesPerPixel);
    return ownedArray(std::move(rgba), {height, width, 4});
  }

  py::object lastStats() const {
    if (lastStats_.is_null())
      return py::none();
    return py::module_::import("json").attr("loads")(lastStats_.dump());
  }

  py::object lastSamples() const {
    if (lastSamples_.empty())
      return py::none();
    return py::array_t<uint32_t>({height_, width_}, lastSamples_.data());
  }

  py::object heatmap() const {
    if (lastSamples_.empty())
      return py::none();
    Image image = heatmapImage(lastSamples_, width_, height_);
    return ownedArray(std::move(image.rgb), {height_, width_, 3});
  }

  std::string fieldName() const { return mesh_->mesh.field(renderer_->fieldIndex()).name; }
  std::shared_ptr<PyMesh> mesh() const { return mesh_; }

private:
  std::shared_ptr<PyMesh> mesh_;
  Backend backendKind_ = Backend::Cpu;
  std::unique_ptr<VolumeRenderer> renderer_;
  std::mutex frameMutex_;
  nlohmann::json lastStats_;
  std::vector<uint32_t> lastSamples_;
  int width_ = 0, height_ = 0;
};

Image toImage(const py::array &object) {
  const InArray<uint8_t> array = object;
  if (array.ndim() != 3 || (array.shape(2) != 3 && array.shape(2) != 4))
    throw Error("an image must be a (height, width, 3 or 4) uint8 array");
  Image image(int(array.shape(1)), int(array.shape(0)));
  const size_t channels = size_t(array.shape(2));
  const uint8_t *data = array.data();
  for (size_t i = 0; i < size_t(image.width) * size_t(image.height); ++i)
    for (size_t c = 0; c < 3; ++c)
      image.rgb[3 * i + c] = data[channels * i + c];
  return image;
}

} // namespace

PYBIND11_MODULE(uvr, m) {
  m.doc() = "uvr: volume rendering of unstructured meshes with space skipping and adaptive sampling";
  // Every uvr::Error surfaces as uvr.Error (a RuntimeError) with the message `uvr render` prints.
  py::register_exception<Error>(m, "Error", PyExc_RuntimeError);
  // uvr.vtk, built where VTK is, lies in the folder uvr/ beside this module: as the module's __path__ it
  // lets `import uvr.vtk` find it.
  Dl_info self;
  if (dladdr(reinterpret_cast<void *>(&pybind11_init_uvr), &self) && self.dli_fname) {
    py::list path;
    path.append((std::filesystem::path(self.dli_fname).parent_path() / "uvr").string());
    m.attr("__path__") = path;
  }

  py::class_<Camera>(m, "Camera", "A pinhole camera as ParaView describes one; fovy in degrees, vertical.")
      .def(py::init([](const py::object &eye, const py::object &at, const py::object &up, float fovy) {
             Camera c;
             c.eye = toVec3(eye, "eye");
             c.at = toVec3(at, "at");
             c.up = toVec3(up, "up");
             c.fovy = fovy;
             return c;
           }),
           py::arg("eye"), py::arg("at"), py::arg("up") = py::make_tuple(0.f, 1.f, 0.f),
           py::arg("fovy") = 30.f)
      .def_property(
          "eye", [](const Camera &c) { return fromVec3(c.eye); },
          [](Camera &c, const py::object &v) { c.eye = toVec3(v, "eye"); })
      .def_property(
          "at", [](const Camera &c) { return fromVec3(c.at); },
          [](Camera &c, const py::object &v) { c.at = toVec3(v, "at"); })
      .def_property(
          "up", [](const Camera &c) { return fromVec3(c.up); },
          [](Camera &c, const py::object &v) { c.up = toVec3(v, "up"); })
      .def_readwrite("fovy", &Camera::fovy)
      .def("__repr__", [](const Camera &c) {
        return py::str("uvr.Camera(eye={}, at={}, up={}, fovy={})")
            .format(fromVec3(c.eye), fromVec3(c.at), fromVec3(c.up), c.fovy);
      });

  py::class_<PyMesh, std::shared_ptr<PyMesh>>(
      m, "Mesh", "A volume mesh: tets, pyramids, wedges and hexahedra with fields")
      .def(py::init(&makeMesh), py::arg("points"), py::arg("cells"), py::arg("celltypes"),
           py::arg("offsets") = py::none(), py::arg("point_data") = py::none(),
           py::arg("cell_data") = py::none(),
           "points (n, 3); cells: VTK's flat [n, i0, i1, ...] layout, or the connectivity when offsets "
           "(cells + 1 "
           "entries) are given; celltypes: VTK type codes; point_data / cell_data: name -> (n,) or (n, k) "
           "arrays")
      .def_static("from_pyvista", &meshFromPyvista, py::arg("grid"),
                  "From any object with PyVista's UnstructuredGrid attributes (points, cells, celltypes, "
                  "point_data, cell_data; offsets + cell_connectivity when present)")
      .def_property_readonly("points",
                             [](py::object self) {
                               const PyMesh &m = self.cast<const PyMesh &>();
                               const std::span<const Vec3f> points = m.mesh.points();
                               return viewArray(&points.data()->x, {py::ssize_t(points.size()), 3}, self);
                             })
      .def_property_readonly("cells",
                             [](const PyMesh &m) {
                               auto cells = flatCells(m.mesh).first;
                               const py::ssize_t n = py::ssize_t(cells.size());
                               return ownedArray(std::move(cells), {n});
                             })
      .def_property_readonly("celltypes",
                             [](const PyMesh &m) {
                               auto types = flatCells(m.mesh).second;
                               const py::ssize_t n = py::ssize_t(types.size());
                               return ownedArray(std::move(types), {n});
                             })
      .def_property_readonly(
          "point_data",
          [](py::object self) { return fieldViews(self.cast<const PyMesh &>(), Centering::Point, self); })
      .def_property_readonly(
          "cell_data",
          [](py::object self) { return fieldViews(self.cast<const PyMesh &>(), Centering::Cell, self); })
      .def_property_readonly("n_points", [](const PyMesh &m) { return m.mesh.pointCount(); })
      .def_property_readonly("n_cells", [](const PyMesh &m) { return m.mesh.cellCount(); })
      .def_property_readonly("field_names",
                             [](const PyMesh &m) {
                               std::vector<std::string> names;
                               for (int i = 0; i < m.mesh.fieldCount(); ++i)
                                 names.push_back(m.mesh.field(i).name);
                               return names;
                             })
      .def_property_readonly("bounds",
                             [](const PyMesh &m) {
                               const Box3f b = m.mesh.bounds();
                               return py::make_tuple(b.lower.x, b.upper.x, b.lower.y, b.upper.y, b.lower.z,
                                                     b.upper.z);
                             })
      .def_property_readonly("skipped_cells", [](const PyMesh &m) { return m.mesh.cellCounts().skipped; })
      .def_property_readonly("inverted_cells", [](const PyMesh &m) { return m.mesh.cellCounts().inverted; })
      .def("__repr__", [](const PyMesh &m) {
        return py::str("uvr.Mesh({} points, {} cells, fields {})")
            .format(m.mesh.pointCount(), m.mesh.cellCount(), py::cast(m.mesh.fieldCount()));
      });

  m.def("load", &load, py::arg("path"), py::arg("field") = py::none(), py::arg("time_step") = py::none(),
        "Reads a mesh file (.vtu, .vtk) as `uvr render` does; with `field`, keeps only that field");

  py::class_<PyTransferFunction>(m, "TransferFunction",
                                 "A colour and opacity preset stretched over a scalar range (ParaView's way)")
      .def(py::init([](const std::string &preset, const std::optional<std::string> &name,
                       const std::optional<std::pair<float, float>> &range) {
             return PyTransferFunction{chooseColorMap(preset, name.value_or("")), checkRange(range)};
           }),
           py::arg("preset") = builtinColorMapNames().front(), py::arg("name") = py::none(),
           py::arg("range") = py::none(),
           "preset: a ParaView preset JSON file (taking preset `name`, or the first) or a built-in name; "
           "range: (lo, hi), default the rendered field's range")
      .def_static(
          "from_arrays", &transferFunctionFromArrays, py::arg("colors"), py::arg("opacities") = py::none(),
          py::arg("range") = py::none(), py::arg("color_space") = "RGB",
          "colors (n, 4): x, r, g, b; opacities (m, 2): x, opacity or (m, 4) with midpoint, sharpness; "
          "the points' x span is stretched over range")
      .def_property_readonly("name", [](const PyTransferFunction &tf) { return tf.map.name; })
      .def_property_readonly("range", [](const PyTransferFunction &tf) { return tf.range; })
      .def_property_readonly("rgb_points",
                             [](const PyTransferFunction &tf) {
                               std::vector<float> v = tf.map.rgbPoints;
                               const py::ssize_t n = py::ssize_t(v.size() / 4);
                               return ownedArray(std::move(v), {n, 4});
                             })
      .def_property_readonly("opacity_points",
                             [](const PyTransferFunction &tf) {
                               std::vector<float> v = tf.map.opacityPoints;
                               const py::ssize_t n = py::ssize_t(v.size() / 4);
                               return ownedArray(std::move(v), {n, 4});
                             })
      .def(
          "table",
          [](const PyTransferFunction &tf, int count) {
            if (count < 2)
              throw Error("table needs at least 2 entries");
            std::vector<Vec4f> table = sampleColorMap(tf.map, count);
            std::vector<float> flat(size_t(count) * 4);
            std::memcpy(flat.data(), table.data(), flat.size() * sizeof(float));
            return ownedArray(std::move(flat), {count, 4});
          },
          py::arg("count") = 256, "r, g, b, opacity at `count` points evenly spaced over the preset");

  m.def("builtin_presets", &builtinColorMapNames, "Names of the built-in presets, the default first");
  m.def("view_names", &cameraViewNames, "Names of the views default_camera and `uvr render --view` take");

  py::class_<PyRenderer>(m, "Renderer",
                         "Acceleration structures for one mesh and field, and frames drawn from them")
      .def(py::init<std::shared_ptr<PyMesh>, const std::optional<std::string> &, const std::string &,
                    int64_t>(),
           py::arg("mesh"), py::arg("field") = py::none(), py::arg("backend") = "cpu",
           py::arg("leaf_size") = int64_t(kAutoLeafSize),
           "Builds the acceleration data for the backend (the GIL released); leaf_size 0: the default")
      .def("render", &PyRenderer::render, py::arg("camera") = py::none(), py::arg("tf") = py::none(),
           py::arg("mode") = "full", py::arg("s1") = py::none(), py::arg("s2") = py::none(),
           py::arg("p") = py::none(), py::arg("unit") = py::none(),
           py::arg("size") = std::pair<int, int>(1024, 1024),
           py::arg("background") = py::make_tuple(0.f, 0.f, 0.f), py::arg("compositing") = "auto",
           py::arg("steps") = "auto", py::arg("shade") = false, py::arg("light") = py::none(),
           py::arg("iso") = py::none(), py::arg("iso_color") = py::none(), py::arg("iso_opacity") = 1.f,
           py::arg("iso_only") = false,
           "Returns an (h, w, 4) uint8 array: RGB composited over the background, and accumulated opacity x "
           "255. shade: light by the field's gradient; light: (x, y, z) towards the light in camera space "
           "(None: a headlight); iso: field values whose isosurfaces to draw (at most 8), in iso_color "
           "(None: the transfer function's colour at each) and of iso_opacity; iso_only: the surfaces alone")
      .def("set_field", &PyRenderer::setField, py::arg("mesh"), py::arg("field") = py::none(),
           "Renders `field` of `mesh` (a later time step, or other values on the same grid) keeping the "
           "acceleration data: only the partitions' value ranges are recomputed. Its points and cells must "
           "be this renderer's, in the same order; uvr.Error otherwise")
      .def("default_camera", &PyRenderer::defaultCamera, py::arg("fovy") = 30.f, py::arg("aspect") = 1.f,
           py::arg("view") = "+z",
           "ParaView's reset camera for an image of this aspect (width / height) from the named view "
           "(uvr.view_names(): +x, -x, +y, -y, +z, -z, iso), as `uvr render --view` frames it")
      .def_property_readonly("last_stats", &PyRenderer::lastStats)
      .def_property_readonly("last_samples", &PyRenderer::lastSamples, "(h, w) uint32 samples per pixel")
      .def("heatmap", &PyRenderer::heatmap,
           "The last frame's samples per pixel as `uvr render --heatmap` draws them")
      .def_property_readonly("field", &PyRenderer::fieldName)
      .def_property_readonly("mesh", &PyRenderer::mesh);

  m.def(
      "read_png",
      [](const std::string &path) {
        Image image = readPng(path);
        const int w = image.width, h = image.height;
        return ownedArray(std::move(image.rgb), {h, w, 3});
      },
      py::arg("path"));
  m.def(
      "write_png", [](const std::string &path, const py::array &image) { writePng(path, toImage(image)); },
      py::arg("path"), py::arg("image"), "Writes the RGB channels of an (h, w, 3 or 4) uint8 array");
  m.def(
      "compare",
      [](const py::array &a, const py::array &b) {
        const Image ia = toImage(a), ib = toImage(b);
        py::dict result;
        result["ssim"] = ssim(ia, ib);
        result["psnr"] = psnr(ia, ib);
        return result;
      },
      py::arg("a"), py::arg("b"), "SSIM and PSNR of the RGB channels, as `uvr compare`");
}
