// ParaView's representation "uvr Volume": the unstructured-grid volume representation with uvr's mapper
// (vtk/vtkUvrVolumeMapper.h) as its only mapper and the grid passed as it is, not split into tetrahedra.
// ParaView's volume controls (colour map, opacity function, unit distance, data range) apply as to "Volume";
// uvr's mode, s1, s2 and p are its own.
#pragma once

#include <vtkUnstructuredGridVolumeRepresentation.h>

#include <uvrParaViewRepresentationModule.h> // the export macro

class vtkUvrVolumeMapper;

class UVRPARAVIEWREPRESENTATION_EXPORT vtkUvrVolumeRepresentation
    : public vtkUnstructuredGridVolumeRepresentation {
public:
  static vtkUvrVolumeRepresentation *New();
  vtkTypeMacro(vtkUvrVolumeRepresentation, vtkUnstructuredGridVolumeRepresentation);
  void PrintSelf(ostream &os, vtkIndent indent) override;

  /// uvr's sampling mode: 0 reference, 1 skip, 2 adaptive, 3 full.
  void SetUvrMode(int mode);
  /// uvr's smallest step, largest adaptive step and adaptive power; 0: the mesh's defaults.
  void SetUvrS1(double s1);
  void SetUvrS2(double s2);
  void SetUvrP(double p);

  /// uvr's mapper stays the active one, whatever the inherited SelectMapper property asks for.
  void SetActiveVolumeMapper(const char *name) override;

protected:
  vtkUvrVolumeRepresentation();
  ~vtkUvrVolumeRepresentation() override;

private:
  vtkUvrVolumeRepresentation(const vtkUvrVolumeRepresentation &) = delete;
  void operator=(const vtkUvrVolumeRepresentation &) = delete;

  vtkUvrVolumeMapper *UvrMapper;
};
