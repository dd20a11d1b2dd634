#include "vtkUvrVolumeRepresentation.h"

#include "vtkUvrVolumeMapper.h"

#include <vtkObjectFactory.h>
#include <vtkVolumeRepresentationPreprocessor.h>

namespace {
constexpr const char *kMapperName = "uvr";
}

vtkStandardNewMacro(vtkUvrVolumeRepresentation);

vtkUvrVolumeRepresentation::vtkUvrVolumeRepresentation() : UvrMapper(vtkUvrVolumeMapper::New()) {
  // uvr takes hexahedra, wedges and pyramids as they are.
  this->Preprocessor->SetTetrahedraOnly(0);
  this->AddVolumeMapper(kMapperName, this->UvrMapper);
  this->Superclass::SetActiveVolumeMapper(kMapperName);
}

// uvr's settings change the frame, not the data: the next render takes them.
vtkUvrVolumeRepresentation::~vtkUvrVolumeRepresentation() { this->UvrMapper->Delete(); }

void vtkUvrVolumeRepresentation::SetActiveVolumeMapper(const char *) {
  this->Superclass::SetActiveVolumeMapper(kMapperName);
}

void vtkUvrVolumeRepresentation::SetUvrMode(int mode) { this->UvrMapper->SetMode(mode); }

void vtkUvrVolumeRepresentation::SetUvrS1(double s1) { this->UvrMapper->SetS1(s1); }

void vtkUvrVolumeRepresentation::SetUvrS2(double s2) { this->UvrMapper->SetS2(s2); }

void vtkUvrVolumeRepresentation::SetUvrP(double p) { this->UvrMapper->SetP(p); }

void vtkUvrVolumeRepresentation::PrintSelf(ostream &os, vtkIndent indent) {
  this->Superclass::PrintSelf(os, indent);
  os << indent << "UvrMapper:\n";
  this->UvrMapper->PrintSelf(os, indent.GetNextIndent());
}
