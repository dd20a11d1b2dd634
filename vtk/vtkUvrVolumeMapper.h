// A VTK volume mapper that renders a vtkUnstructuredGrid with uvr as the grid is given: tetrahedra,
// hexahedra, wedges and pyramids, no tetrahedralisation. See docs/python.md.
//
// - Scalars: the array the mapper's scalar mode and array selection pick (point or cell data); several
//   components are taken as their magnitude.
// - Colours and opacities: the volume property's colour (or grey) transfer function and scalar opacity
//   function, sampled over the union of their ranges; values outside it take the end values, as VTK clamps.
//   ScalarOpacityUnitDistance is uvr's opacity unit: the opacity function gives the opacity of a slab of that
//   thickness, as in VTK's other mappers (uvr's default, ParaView's, is the bounds' diagonal over the cube
//   root of the cell count).
// - Camera: the renderer's perspective camera (parallel projection is refused with a warning: uvr's cameras
//   are pinholes). The volume's own matrix (position, orientation, scale) is honoured.
// - Opaque geometry: the depth buffer is read before the volume is drawn and each ray ends at the surface
//   it shows, so that surfaces hide the volume behind them; the volume image is then blended over the
//   framebuffer, premultiplied, so that it hides what lies behind it as its opacity says.
// - The acceleration data (uvr::VolumeRenderer) is kept across camera and transfer-function changes and
//   rebuilt only when the grid's points or cells change (by their modification times); new scalars on the
//   same grid (a time step) replace the field's values only (VolumeRenderer::setField).
// - Backend: CUDA where the library was built with it and a GPU is found (unless UseCuda is off), else the
//   CPU on all cores.
#pragma once

#include <vtkUnstructuredGridVolumeMapper.h>

#include <memory>

class vtkRenderer;
class vtkVolume;
class vtkWindow;

class vtkUvrVolumeMapper : public vtkUnstructuredGridVolumeMapper {
public:
  static vtkUvrVolumeMapper *New();
  vtkTypeMacro(vtkUvrVolumeMapper, vtkUnstructuredGridVolumeMapper);
  void PrintSelf(ostream &os, vtkIndent indent) override;

  /// uvr's sampling mode, as uvr::RenderMode numbers them: 0 reference, 1 skip, 2 adaptive, 3 full (default).
  vtkSetClampMacro(Mode, int, 0, 3);
  vtkGetMacro(Mode, int);
  /// The smallest step s1, the largest adaptive step s2 and the adaptive power p (paper §2.4), in world
  /// units; 0 (the default) takes uvr's defaults for the mesh.
  vtkSetClampMacro(S1, double, 0.0, VTK_DOUBLE_MAX);
  vtkGetMacro(S1, double);
  vtkSetClampMacro(S2, double, 0.0, VTK_DOUBLE_MAX);
  vtkGetMacro(S2, double);
  vtkSetClampMacro(P, double, 0.0, VTK_DOUBLE_MAX);
  vtkGetMacro(P, double);
  /// Render on the GPU where the library has CUDA and a GPU is found (default on).
  vtkSetMacro(UseCuda, bool);
  vtkGetMacro(UseCuda, bool);
  vtkBooleanMacro(UseCuda, bool);

  /// What the last frame cost: the acceleration build (when it was built) and the frame itself, in ms.
  double GetLastBuildMs() const;
  double GetLastRenderMs() const;
  /// How often the acceleration data was built: once per mesh, again only when the grid's points or cells
  /// change.
  int GetBuildCount() const;
  /// How often new scalars on the same grid were taken while keeping the acceleration data.
  int GetFieldUpdateCount() const;
  /// The backend of the last frame: "cpu" or "cuda".
  const char *GetLastBackend() const;

  void Render(vtkRenderer *renderer, vtkVolume *volume) override;
  void ReleaseGraphicsResources(vtkWindow *window) override;

protected:
  vtkUvrVolumeMapper();
  ~vtkUvrVolumeMapper() override;

  int Mode = 3;
  double S1 = 0.0, S2 = 0.0, P = 0.0;
  bool UseCuda = true;

private:
  vtkUvrVolumeMapper(const vtkUvrVolumeMapper &) = delete;
  void operator=(const vtkUvrVolumeMapper &) = delete;

  struct Internals;
  std::unique_ptr<Internals> Internal;
};
