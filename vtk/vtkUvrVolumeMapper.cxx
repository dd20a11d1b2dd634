#include "vtkUvrVolumeMapper.h"

#include <uvr/camera.h>
#include <uvr/color_map.h>
#include <uvr/error.h>
#include <uvr/mesh.h>
#include <uvr/renderer.h>
#include <uvr/settings.h>

#include <vtkCamera.h>
#include <vtkCellArray.h>
#include <vtkColorTransferFunction.h>
#include <vtkDataArray.h>
#include <vtkDoubleArray.h>
#include <vtkFloatArray.h>
#include <vtkMatrix4x4.h>
#include <vtkNew.h>
#include <vtkObjectFactory.h>
#include <vtkOpenGLRayCastImageDisplayHelper.h>
#include <vtkPiecewiseFunction.h>
#include <vtkPoints.h>
#include <vtkRenderWindow.h>
#include <vtkRenderer.h>
#include <vtkUnsignedCharArray.h>
#include <vtkUnstructuredGrid.h>
#include <vtkVolume.h>
#include <vtkVolumeProperty.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <string>
#include <vector>

namespace {

// Enough entries that a function's control points are resolved to a 1/1024 of its range.
constexpr int kTableSize = 1024;

// An array (or vtkPoints) and its modification time: a pipeline's shallow copies share these, not the data
// objects that hold them.
struct ArrayKey {
  const void *array = nullptr;
  vtkMTimeType time = 0;
  explicit ArrayKey(vtkObject *a = nullptr) : array(a), time(a ? a->GetMTime() : 0) {}
  bool operator==(const ArrayKey &) const = default;
};

struct MeshKey {
  ArrayKey points, offsets, connectivity, types;
  bool operator==(const MeshKey &) const = default;
};

struct FieldKey {
  ArrayKey values;
  int centering = -1;
  bool operator==(const FieldKey &) const = default;
};

// VTK's arrays as uvr views them: in place where their layout is uvr's (float or double, 64-bit cell
// storage), else converted into `copy`.
uvr::ArrayView viewArray(vtkDataArray *array, std::vector<float> &copy) {
  const int components = array->GetNumberOfComponents();
  const size_t values = size_t(array->GetNumberOfTuples()) * size_t(components);
  if (auto *f = vtkFloatArray::SafeDownCast(array))
    return uvr::ArrayView(std::span<const float>(f->GetPointer(0), values), components);
  if (auto *d = vtkDoubleArray::SafeDownCast(array))
    return uvr::ArrayView(std::span<const double>(d->GetPointer(0), values), components);
  copy.resize(values);
  for (vtkIdType t = 0; t < array->GetNumberOfTuples(); ++t)
    for (int c = 0; c < components; ++c)
      copy[size_t(t) * size_t(components) + size_t(c)] = float(array->GetComponent(t, c));
  return uvr::ArrayView(std::span<const float>(copy), components);
}

std::span<const int64_t> viewIds(vtkDataArray *array, std::vector<int64_t> &copy) {
  if (array->GetDataType() == VTK_TYPE_INT64 && array->GetNumberOfComponents() == 1)
    return {static_cast<const int64_t *>(array->GetVoidPointer(0)), size_t(array->GetNumberOfTuples())};
  copy.resize(size_t(array->GetNumberOfTuples()));
  for (vtkIdType i = 0; i < array->GetNumberOfTuples(); ++i)
    copy[size_t(i)] = int64_t(array->GetComponent(i, 0));
  return copy;
}

bool isIdentity(vtkMatrix4x4 *m) {
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j)
      if (m->GetElement(i, j) != (i == j ? 1.0 : 0.0))
        return false;
  return true;
}

uvr::Vec3f transformPoint(vtkMatrix4x4 *m, const double p[3]) {
  const double in[4] = {p[0], p[1], p[2], 1.0};
  double out[4];
  m->MultiplyPoint(in, out);
  return {float(out[0] / out[3]), float(out[1] / out[3]), float(out[2] / out[3])};
}

} // namespace

struct vtkUvrVolumeMapper::Internals {
  MeshKey meshKey;
  FieldKey fieldKey;
  vtkMTimeType transferTime = 0;
  std::optional<uvr::VolumeRenderer> renderer;
  bool haveTransfer = false;
  int builds = 0, fieldUpdates = 0;
  double buildMs = 0.0, renderMs = 0.0;
  uvr::Backend backend = uvr::Backend::Cpu;
  bool cudaFailed = false;
  bool warnedParallel = false;
  std::string lastError;
  uvr::FrameResult frame;
  std::vector<float> limits, depth;
  std::vector<unsigned char> rgba;
  vtkNew<vtkOpenGLRayCastImageDisplayHelper> display;

  void error(vtkUvrVolumeMapper *self, const std::string &message) {
    // Once per distinct message: a failing mapper would say it again every frame.
    if (message == lastError)
      return;
    lastError = message;
    vtkErrorWithObjectMacro(self, << message);
  }
};

vtkStandardNewMacro(vtkUvrVolumeMapper);

vtkUvrVolumeMapper::vtkUvrVolumeMapper() : Internal(std::make_unique<Internals>()) {
  this->Internal->display->SetPreMultipliedColors(1);
}

vtkUvrVolumeMapper::~vtkUvrVolumeMapper() = default;

double vtkUvrVolumeMapper::GetLastBuildMs() const { return this->Internal->buildMs; }
double vtkUvrVolumeMapper::GetLastRenderMs() const { return this->Internal->renderMs; }
int vtkUvrVolumeMapper::GetBuildCount() const { return this->Internal->builds; }
int vtkUvrVolumeMapper::GetFieldUpdateCount() const { return this->Internal->fieldUpdates; }
const char *vtkUvrVolumeMapper::GetLastBackend() const { return uvr::backendName(this->Internal->backend); }

void vtkUvrVolumeMapper::ReleaseGraphicsResources(vtkWindow *window) {
  this->Internal->display->ReleaseGraphicsResources(window);
}

void vtkUvrVolumeMapper::Render(vtkRenderer *ren, vtkVolume *vol) {
  Internals &in = *this->Internal;
  if (this->GetInputAlgorithm())
    this->GetInputAlgorithm()->Update();
  auto *grid = vtkUnstructuredGrid::SafeDownCast(this->GetInput());
  if (!grid || !grid->GetPoints() || grid->GetNumberOfCells() == 0)
    return; // nothing to draw
  int centering = -1;
  vtkDataArray *scalars = vtkAbstractMapper::GetScalars(grid, this->ScalarMode, this->ArrayAccessMode,
                                                        this->ArrayId, this->ArrayName, centering);
  if (!scalars || centering > 1) {
    in.error(this, "uvr needs point or cell scalars to render; the grid has none the scalar mode selects");
    return;
  }
  vtkCamera *cam = ren->GetActiveCamera();
  if (cam->GetParallelProjection()) {
    if (!in.warnedParallel)
      vtkWarningMacro(
          << "uvr renders perspective views only: the volume is not drawn in parallel projection");
    in.warnedParallel = true;
    return;
  }
  int width, height, x0, y0;
  ren->GetTiledSizeAndOrigin(&width, &height, &x0, &y0);
  if (width < 1 || height < 1)
    return;

  try {
    // The mesh and its field: built again only when the grid's points, cells or scalars changed.
    vtkCellArray *cells = grid->GetCells();
    vtkUnsignedCharArray *types = grid->GetCellTypesArray();
    const MeshKey meshKey{ArrayKey(grid->GetPoints()), ArrayKey(cells->GetOffsetsArray()),
                          ArrayKey(cells->GetConnectivityArray()), ArrayKey(types)};
    const FieldKey fieldKey{ArrayKey(scalars), centering};
    const bool newMesh = !in.renderer || !(meshKey == in.meshKey);
    if (newMesh || !(fieldKey == in.fieldKey)) {
      std::vector<float> pointCopy, fieldCopy;
      std::vector<int64_t> offsetCopy, connectivityCopy;
      uvr::MeshArrays arrays;
      arrays.points = viewArray(grid->GetPoints()->GetData(), pointCopy);
      arrays.offsets = viewIds(cells->GetOffsetsArray(), offsetCopy);
      arrays.connectivity = viewIds(cells->GetConnectivityArray(), connectivityCopy);
      arrays.types = {types->GetPointer(0), size_t(types->GetNumberOfTuples())};
      const std::string name = scalars->GetName() ? scalars->GetName() : "scalars";
      arrays.fields.push_back({name, centering == 1 ? uvr::Centering::Cell : uvr::Centering::Point,
                               viewArray(scalars, fieldCopy)});
      uvr::VolumeMesh mesh = uvr::VolumeMesh::fromArrays(arrays, "the vtkUnstructuredGrid");
      bool kept = false;
      if (!newMesh) {
        // New scalars on the same grid: the acceleration data stays, the transfer function too.
        try {
          in.renderer->setField(mesh, 0);
          kept = true;
          ++in.fieldUpdates;
        } catch (const uvr::Error &) {
          // the cells' order came out otherwise: built afresh below
        }
      }
      if (!kept) {
        in.renderer.reset();
        in.renderer.emplace(std::move(mesh), 0);
        in.haveTransfer = false;
        ++in.builds;
      }
      in.meshKey = meshKey;
      in.fieldKey = fieldKey;
    }

    // The transfer function: the property's functions sampled over the union of their ranges.
    vtkVolumeProperty *property = vol->GetProperty();
    vtkPiecewiseFunction *opacity = property->GetScalarOpacity(0);
    const bool grey = property->GetColorChannels(0) == 1;
    vtkColorTransferFunction *color = grey ? nullptr : property->GetRGBTransferFunction(0);
    vtkPiecewiseFunction *greyFunction = grey ? property->GetGrayTransferFunction(0) : nullptr;
    const vtkMTimeType transferTime =
        std::max({property->GetMTime(), opacity->GetMTime(), color ? color->GetMTime() : 0,
                  greyFunction ? greyFunction->GetMTime() : 0});
    if (!in.haveTransfer || transferTime != in.transferTime) {
      double range[2];
      opacity->GetRange(range);
      double colorRange[2];
      if (color)
        color->GetRange(colorRange);
      else
        greyFunction->GetRange(colorRange);
      uvr::ValueRange span{float(std::min(range[0], colorRange[0])),
                           float(std::max(range[1], colorRange[1]))};
      if (!(span.min < span.max))
        span = uvr::defaultTransferRange(span);
      std::vector<uvr::Vec4f> table(kTableSize);
      for (int i = 0; i < kTableSize; ++i) {
        const double x = span.min + (span.max - span.min) * double(i) / double(kTableSize - 1);
        double rgb[3];
        if (color) {
          color->GetColor(x, rgb);
        } else {
          rgb[0] = rgb[1] = rgb[2] = greyFunction->GetValue(x);
        }
        table[size_t(i)] = {float(rgb[0]), float(rgb[1]), float(rgb[2]), float(opacity->GetValue(x))};
      }
      in.renderer->setTransferFunction(uvr::colorMapFromTable(table), span);
      in.transferTime = transferTime;
      in.haveTransfer = true;
    }

    // The camera, in the grid's coordinates where the volume has a matrix of its own.
    vtkNew<vtkMatrix4x4> toGrid;
    vol->GetMatrix(toGrid);
    const bool moved = !isIdentity(toGrid);
    toGrid->Invert();
    const double aspect = double(width) / double(height);
    uvr::Camera camera;
    double position[3], focal[3], up[3];
    cam->GetPosition(position);
    cam->GetFocalPoint(focal);
    cam->GetViewUp(up);
    camera.eye = transformPoint(toGrid, position);
    camera.at = transformPoint(toGrid, focal);
    if (moved) {
      const double tip[3] = {position[0] + up[0], position[1] + up[1], position[2] + up[2]};
      camera.up = transformPoint(toGrid, tip) - camera.eye;
    } else {
      camera.up = {float(up[0]), float(up[1]), float(up[2])};
    }
    double angle = cam->GetViewAngle();
    if (cam->GetUseHorizontalViewAngle())
      angle = 2.0 * std::atan(std::tan(0.5 * angle * M_PI / 180.0) / aspect) * 180.0 / M_PI;
    camera.fovy = float(angle);

    // Where each ray meets the opaque geometry drawn so far: the depth buffer taken back through the
    // inverse projection to a point, and its distance from the eye (+inf where nothing was drawn).
    const size_t pixels = size_t(width) * size_t(height);
    in.depth.resize(pixels);
    in.limits.resize(pixels);
    ren->GetRenderWindow()->GetZbufferData(x0, y0, x0 + width - 1, y0 + height - 1, in.depth.data());
    vtkNew<vtkMatrix4x4> unproject;
    unproject->DeepCopy(cam->GetCompositeProjectionTransformMatrix(aspect, -1.0, 1.0));
    unproject->Invert();
    vtkMatrix4x4::Multiply4x4(toGrid, unproject, unproject);
    const double *m = unproject->GetData();
    for (int j = 0; j < height; ++j) {
      const double ny = 2.0 * (j + 0.5) / height - 1.0;
      for (int i = 0; i < width; ++i) {
        const float z = in.depth[size_t(j) * size_t(width) + size_t(i)];
        float &limit = in.limits[size_t(height - 1 - j) * size_t(width) + size_t(i)]; // uvr: top row first
        if (!(z < 1.f)) {
          limit = std::numeric_limits<float>::infinity();
          continue;
        }
        const double p[4] = {2.0 * (i + 0.5) / width - 1.0, ny, 2.0 * z - 1.0, 1.0};
        double q[4];
        for (int r = 0; r < 4; ++r)
          q[r] = m[4 * r] * p[0] + m[4 * r + 1] * p[1] + m[4 * r + 2] * p[2] + m[4 * r + 3] * p[3];
        const uvr::Vec3f hit{float(q[0] / q[3]), float(q[1] / q[3]), float(q[2] / q[3])};
        limit = uvr::length(hit - camera.eye);
      }
    }

    uvr::FrameSettings settings;
    settings.mode = uvr::RenderMode(this->Mode);
    settings.s1 = float(this->S1);
    settings.s2 = float(this->S2);
    settings.p = float(this->P);
    settings.unit = float(property->GetScalarOpacityUnitDistance(0));
    settings.width = width;
    settings.height = height;
    settings.keepOpacity = true;
    settings.keepSamplesPerPixel = false;
    settings.rayLimits = in.limits;
    settings.backend = uvr::Backend::Cpu;
    if (this->UseCuda && !in.cudaFailed && uvr::backendAvailable(uvr::Backend::Cuda)) {
      try {
        in.renderer->prepare(uvr::Backend::Cuda);
        settings.backend = uvr::Backend::Cuda;
      } catch (const uvr::Error &) {
        in.cudaFailed = true; // no GPU here: the CPU from now on
      }
    }
    in.renderer->render(camera, settings, in.frame);
    in.backend = settings.backend;
    in.buildMs = in.frame.stats.buildMs;
    in.renderMs = in.frame.stats.renderMs;

    // The image over the framebuffer, premultiplied (on a black background the colour is), bottom row
    // first as OpenGL has it.
    in.rgba.resize(4 * pixels);
    const std::vector<uint8_t> &rgb = in.frame.image.rgb;
    for (int y = 0; y < height; ++y) {
      const size_t from = size_t(height - 1 - y) * size_t(width), to = size_t(y) * size_t(width);
      for (int x = 0; x < width; ++x) {
        const size_t a = from + size_t(x), b = to + size_t(x);
        in.rgba[4 * b + 0] = rgb[3 * a + 0];
        in.rgba[4 * b + 1] = rgb[3 * a + 1];
        in.rgba[4 * b + 2] = rgb[3 * a + 2];
        in.rgba[4 * b + 3] = uint8_t(std::clamp(in.frame.opacity[a], 0.f, 1.f) * 255.f + 0.5f);
      }
    }
    int size[2] = {width, height}, origin[2] = {0, 0};
    // In front of everything: the rays already ended at the surfaces.
    constexpr float kNearestDepth = 1e-6f;
    in.display->RenderTexture(vol, ren, size, size, size, origin, kNearestDepth, in.rgba.data());
    in.lastError.clear();
  } catch (const uvr::Error &e) {
    in.error(this, std::string("uvr: ") + e.what());
  }
}

void vtkUvrVolumeMapper::PrintSelf(ostream &os, vtkIndent indent) {
  this->Superclass::PrintSelf(os, indent);
  os << indent << "Mode: " << uvr::modeName(uvr::RenderMode(this->Mode)) << "\n"
     << indent << "S1: " << this->S1 << "\n"
     << indent << "S2: " << this->S2 << "\n"
     << indent << "P: " << this->P << "\n"
     << indent << "UseCuda: " << this->UseCuda << "\n"
     << indent << "BuildCount: " << this->Internal->builds << "\n";
}
