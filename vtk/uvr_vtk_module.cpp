// uvr.vtk: vtkUvrVolumeMapper for VTK's Python (python3-vtk9) and PyVista. See docs/python.md.
#include "vtkUvrVolumeMapper.h"

#include <uvr/settings.h>

#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cinttypes>
#include <cstdint>
#include <cstdio>
#include <optional>
#include <string>

namespace py = pybind11;
using namespace pybind11::literals;

namespace {

// The C++ mapper behind a VTK Python object, by the address its __this__ names ("_<hex>_p_<class>").
vtkUvrVolumeMapper *unwrap(const py::object &mapper) {
  if (!py::hasattr(mapper, "__this__"))
    throw py::type_error("expected a mapper made by uvr.vtk.VolumeMapper()");
  const std::string text = py::str(mapper.attr("__this__"));
  unsigned long long address = 0;
  if (std::sscanf(text.c_str(), "_%llx_", &address) != 1 || address == 0)
    throw py::type_error("expected a mapper made by uvr.vtk.VolumeMapper(); got " + text);
  auto *object = reinterpret_cast<vtkObjectBase *>(uintptr_t(address));
  vtkUvrVolumeMapper *uvrMapper = vtkUvrVolumeMapper::SafeDownCast(object);
  if (!uvrMapper)
    throw py::type_error(std::string("expected a mapper made by uvr.vtk.VolumeMapper(); got a ") +
                         object->GetClassName());
  return uvrMapper;
}

void configure(vtkUvrVolumeMapper *mapper, const std::optional<std::string> &mode, std::optional<double> s1,
               std::optional<double> s2, std::optional<double> p, std::optional<bool> useCuda) {
  const auto positive = [](std::optional<double> value, const char *name) {
    if (value && !(*value >= 0.0))
      throw py::value_error(std::string(name) + " must be >= 0 (0: uvr's default)");
  };
  positive(s1, "s1");
  positive(s2, "s2");
  positive(p, "p");
  if (p && *p > 0.0 && *p < 1.0)
    throw py::value_error("p must be at least 1 (0: uvr's default)");
  if (mode)
    mapper->SetMode(int(uvr::parseMode(*mode)));
  if (s1)
    mapper->SetS1(*s1);
  if (s2)
    mapper->SetS2(*s2);
  if (p)
    mapper->SetP(*p);
  if (useCuda)
    mapper->SetUseCuda(*useCuda);
}

} // namespace

PYBIND11_MODULE(vtk, m) {
  m.doc() = "uvr's VTK volume mapper for VTK's Python and PyVista: add a vtkVolume with "
            "uvr.vtk.VolumeMapper() to a renderer (or a PyVista plotter).";
  const auto none = py::none();
  m.def(
      "VolumeMapper",
      [](const std::optional<std::string> &mode, std::optional<double> s1, std::optional<double> s2,
         std::optional<double> p, std::optional<bool> useCuda) {
        py::object base =
            py::module_::import("vtkmodules.vtkRenderingVolume").attr("vtkUnstructuredGridVolumeMapper");
        vtkUvrVolumeMapper *mapper = vtkUvrVolumeMapper::New();
        py::object wrapped;
        try {
          configure(mapper, mode, s1, s2, p, useCuda);
          char address[96];
          std::snprintf(address, sizeof address, "_%" PRIxPTR "_p_vtkUnstructuredGridVolumeMapper",
                        reinterpret_cast<uintptr_t>(mapper));
          // The Python object takes its own reference; ours goes.
          wrapped = base(std::string(address));
        } catch (...) {
          mapper->Delete();
          throw;
        }
        mapper->Delete();
        return wrapped;
      },
      py::kw_only(), "mode"_a = none, "s1"_a = none, "s2"_a = none, "p"_a = none, "use_cuda"_a = none,
      "A new vtkUvrVolumeMapper, as a vtkUnstructuredGridVolumeMapper of VTK's Python. mode: reference, "
      "skip, adaptive or full (default); s1, s2, p: uvr's steps and power (0: the mesh's defaults); "
      "use_cuda: render on the GPU where the library has CUDA and one is found (default True).");
  m.def(
      "set_options",
      [](const py::object &mapper, const std::optional<std::string> &mode, std::optional<double> s1,
         std::optional<double> s2, std::optional<double> p, std::optional<bool> useCuda) {
        vtkUvrVolumeMapper *m = unwrap(mapper);
        configure(m, mode, s1, s2, p, useCuda);
      },
      "mapper"_a, py::kw_only(), "mode"_a = none, "s1"_a = none, "s2"_a = none, "p"_a = none,
      "use_cuda"_a = none,
      "Changes uvr's settings of a mapper made by VolumeMapper(); None leaves one as it is.");
  m.def(
      "options",
      [](const py::object &mapper) {
        vtkUvrVolumeMapper *m = unwrap(mapper);
        return py::dict("mode"_a = uvr::modeName(uvr::RenderMode(m->GetMode())), "s1"_a = m->GetS1(),
                        "s2"_a = m->GetS2(), "p"_a = m->GetP(), "use_cuda"_a = m->GetUseCuda());
      },
      "mapper"_a, "uvr's settings of a mapper made by VolumeMapper().");
  m.def(
      "stats",
      [](const py::object &mapper) {
        vtkUvrVolumeMapper *m = unwrap(mapper);
        return py::dict("builds"_a = m->GetBuildCount(), "field_updates"_a = m->GetFieldUpdateCount(),
                        "build_ms"_a = m->GetLastBuildMs(), "render_ms"_a = m->GetLastRenderMs(),
                        "backend"_a = m->GetLastBackend());
      },
      "mapper"_a,
      "The last frame of a mapper made by VolumeMapper(): builds (how often the acceleration data was "
      "built), "
      "build_ms, render_ms (uvr's frame alone) and backend.");
}
