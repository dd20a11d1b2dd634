#!/usr/bin/env python3
"""uvr.vtk.VolumeMapper in VTK's Python (python3-vtk9), under a virtual X server:

- disk_out_ref (point scalars) and the 857k-tet brain (cell scalars) against `uvr render` with the same camera,
  function, unit and size: SSIM >= 0.99;
- the acceleration data is built once and kept across camera and transfer-function changes and new scalars
  (their values replaced), and built again when the grid's points change;
- opaque geometry: a sphere in front of the volume shows as it is, one inside it is tinted by the volume in
  front of it only, the volume elsewhere is unchanged.

Usage: test_vtk_mapper.py UVR_BINARY SOURCE_DIR SHARED_DATA (run by ctest with PYTHONPATH=build/python)
"""
import json
import os
import subprocess
import sys
import tempfile

import numpy as np

try:
    import vtkmodules.vtkRenderingOpenGL2  # noqa: F401 (the OpenGL classes behind the render window)
except ImportError:
    print("SKIPPED: VTK's Python (Debian's python3-vtk9) is not installed")
    sys.exit(77)
import vtkmodules.vtkRenderingVolumeOpenGL2  # noqa: F401
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkCommonDataModel import vtkPiecewiseFunction
from vtkmodules.vtkFiltersSources import vtkSphereSource
from vtkmodules.vtkIOImage import vtkPNGWriter
from vtkmodules.vtkIOXML import vtkXMLUnstructuredGridReader
from vtkmodules.vtkRenderingCore import (vtkActor, vtkColorTransferFunction, vtkPolyDataMapper, vtkRenderer,
                                         vtkRenderWindow, vtkVolume, vtkVolumeProperty,
                                         vtkWindowToImageFilter)

from uvr.vtk import VolumeMapper, options, set_options, stats

SIZE = 256
# Colour and opacity control points at fractions of the range: a ParaView preset for `uvr render`, the same
# points for VTK's functions.
RGB = [(0.0, 0.23, 0.30, 0.75), (0.5, 0.87, 0.87, 0.87), (1.0, 0.71, 0.02, 0.15)]
OPACITY = [(0.0, 0.0), (0.3, 0.05), (1.0, 0.9)]


def read(path):
    reader = vtkXMLUnstructuredGridReader()
    reader.SetFileName(path)
    reader.Update()
    return reader.GetOutput()


def volume_property(lo, hi, unit):
    ctf = vtkColorTransferFunction()
    for x, r, g, b in RGB:
        ctf.AddRGBPoint(lo + x * (hi - lo), r, g, b)
    otf = vtkPiecewiseFunction()
    for x, a in OPACITY:
        otf.AddPoint(lo + x * (hi - lo), a)
    prop = vtkVolumeProperty()
    prop.SetColor(ctf)
    prop.SetScalarOpacity(otf)
    prop.SetScalarOpacityUnitDistance(unit)
    return prop


def preset(path, lo, hi):
    rgb = [v for x, r, g, b in RGB for v in (lo + x * (hi - lo), r, g, b)]
    points = [v for x, a in OPACITY for v in (lo + x * (hi - lo), a, 0.5, 0.0)]
    with open(path, "w") as f:
        json.dump([{"Name": "test", "ColorSpace": "RGB", "RGBPoints": rgb, "Points": points}], f)


class Scene:
    def __init__(self, grid, field, cell, lo, hi, unit, mode="full"):
        self.mapper = VolumeMapper(mode=mode)
        self.mapper.SetInputData(grid)
        if cell:
            self.mapper.SetScalarModeToUseCellFieldData()
        else:
            self.mapper.SetScalarModeToUsePointFieldData()
        self.mapper.SelectScalarArray(field)
        self.volume = vtkVolume()
        self.volume.SetMapper(self.mapper)
        self.volume.SetProperty(volume_property(lo, hi, unit))
        self.renderer = vtkRenderer()
        self.renderer.AddVolume(self.volume)
        self.renderer.ResetCamera()
        self.window = vtkRenderWindow()
        self.window.SetOffScreenRendering(1)
        self.window.SetSize(SIZE, SIZE)
        self.window.AddRenderer(self.renderer)

    def image(self):
        """The window's RGB, top row first."""
        self.renderer.ResetCameraClippingRange()
        self.window.Render()
        grab = vtkWindowToImageFilter()
        grab.SetInput(self.window)
        grab.ReadFrontBufferOff()
        grab.Update()
        out = grab.GetOutput()
        w, h, _ = out.GetDimensions()
        pixels = vtk_to_numpy(out.GetPointData().GetScalars()).reshape(h, w, -1)[:, :, :3]
        return pixels[::-1].astype(float)

    def save(self, path):
        self.window.Render()
        grab = vtkWindowToImageFilter()
        grab.SetInput(self.window)
        grab.ReadFrontBufferOff()
        writer = vtkPNGWriter()
        writer.SetFileName(path)
        writer.SetInputConnection(grab.GetOutputPort())
        writer.Write()

    def camera_args(self):
        cam = self.renderer.GetActiveCamera()
        fmt = lambda v: ",".join(f"{c:.9g}" for c in v)  # noqa: E731
        return ["--eye", fmt(cam.GetPosition()), "--at", fmt(cam.GetFocalPoint()), "--up",
                fmt(cam.GetViewUp()), "--fovy", f"{cam.GetViewAngle():.9g}"]


def against_uvr_render(uvr, tmp, name, path, field, cell, unit):
    grid = read(path)
    data = grid.GetCellData() if cell else grid.GetPointData()
    lo, hi = data.GetArray(field).GetRange()
    scene = Scene(grid, field, cell, lo, hi, unit)
    scene.renderer.GetActiveCamera().Azimuth(30)
    scene.renderer.GetActiveCamera().Elevation(20)
    scene.renderer.GetActiveCamera().OrthogonalizeViewUp()
    mapped = os.path.join(tmp, f"{name}_vtk.png")
    scene.save(mapped)
    tf = os.path.join(tmp, "tf.json")
    preset(tf, lo, hi)
    reference = os.path.join(tmp, f"{name}_uvr.png")
    command = [uvr, "render", path, "--field", ("cell:" if cell else "point:") + field, "--tf", tf, "--range",
               repr(lo), repr(hi), "--unit", repr(unit), "--size", f"{SIZE}x{SIZE}", "-o", reference,
               *scene.camera_args()]
    subprocess.run(command, check=True, capture_output=True)
    compare = subprocess.run([uvr, "compare", reference, mapped, "--json"], check=True, capture_output=True,
                             text=True)
    ssim = json.loads(compare.stdout)["ssim"]
    lit = (scene.image().sum(axis=2) > 30).mean()
    print(f"{name}: SSIM {ssim:.4f} against uvr render ({lit:.0%} of the pixels lit), "
          f"{stats(scene.mapper)}")
    assert lit > 0.05, f"{name}: the mapper drew almost nothing ({lit:.1%} of the pixels lit)"
    assert ssim >= 0.99, f"{name}: SSIM {ssim:.4f} < 0.99 against {' '.join(command)}"


def builds_once(path):
    grid = read(path)
    lo, hi = grid.GetPointData().GetArray("Temp").GetRange()
    scene = Scene(grid, "Temp", False, lo, hi, 1.0)
    first = scene.image()
    scene.renderer.GetActiveCamera().Azimuth(40)
    turned = scene.image()
    scene.volume.GetProperty().GetScalarOpacity().AddPoint(hi, 0.2)
    scene.volume.GetProperty().SetScalarOpacityUnitDistance(2.0)
    faded = scene.image()
    set_options(scene.mapper, mode="reference", s1=0.05)
    assert options(scene.mapper)["mode"] == "reference" and options(scene.mapper)["s1"] == 0.05
    before = scene.image()
    assert stats(scene.mapper)["builds"] == 1, f"rebuilt for a camera or function change: {stats(scene.mapper)}"
    assert np.abs(first - turned).max() > 20 and np.abs(turned - faded).max() > 20, "the frames did not change"
    # New scalars (a time step): taken without a rebuild, and drawn.
    temp = grid.GetPointData().GetArray("Temp")
    for i in range(temp.GetNumberOfTuples()):
        temp.SetValue(i, hi + lo - temp.GetValue(i))
    temp.Modified()
    flipped = scene.image()
    s = stats(scene.mapper)
    assert s["builds"] == 1 and s["field_updates"] == 1, f"new scalars rebuilt the acceleration data: {s}"
    assert np.abs(flipped - before).max() > 20, "the new scalars were not drawn"
    grid.GetPoints().Modified()
    scene.image()
    assert stats(scene.mapper)["builds"] == 2, f"not rebuilt for moved points: {stats(scene.mapper)}"
    try:
        set_options(scene.mapper, p=0.5)
    except ValueError:
        pass
    else:
        raise AssertionError("p = 0.5 was taken")
    print("builds: once across camera, function and setting changes and new scalars; again for moved points")


def occlusion(path):
    grid = read(path)
    lo, hi = grid.GetPointData().GetArray("Temp").GetRange()
    bounds = grid.GetBounds()
    centre = [(bounds[2 * i] + bounds[2 * i + 1]) / 2 for i in range(3)]
    radius = 0.15 * (bounds[1] - bounds[0])
    # An opaque, unlit green sphere.
    sphere = vtkSphereSource()
    sphere.SetRadius(radius)
    sphere.SetThetaResolution(48)
    sphere.SetPhiResolution(48)
    sphere_mapper = vtkPolyDataMapper()
    sphere_mapper.SetInputConnection(sphere.GetOutputPort())
    actor = vtkActor()
    actor.SetMapper(sphere_mapper)
    actor.GetProperty().SetColor(0.0, 1.0, 0.0)
    actor.GetProperty().SetAmbient(1.0)
    actor.GetProperty().SetDiffuse(0.0)
    actor.GetProperty().SetSpecular(0.0)
    scene = Scene(grid, "Temp", False, lo, hi, 1.0)
    cam = scene.renderer.GetActiveCamera()
    view = np.array(cam.GetDirectionOfProjection())
    black = scene.image()
    scene.renderer.SetBackground(1, 1, 1)
    white = scene.image()
    scene.renderer.SetBackground(0, 0, 0)
    alpha = np.clip(1 - (white - black) / 255, 0, 1)[:, :, 0]
    scene.renderer.AddActor(actor)
    mid = SIZE // 2

    # In front of the volume, between it and the eye: the sphere as it is.
    near = np.array(centre) - view * (0.5 * np.linalg.norm(np.array(cam.GetPosition()) - centre))
    actor.SetPosition(*near)
    front = scene.image()
    footprint = np.all(np.abs(front - [0, 255, 0]) < 3, axis=2)
    assert footprint.mean() > 0.02, f"the sphere in front covers {footprint.mean():.1%} of the image"

    # At the volume's centre: the volume in front of it only. Were the volume behind it drawn too, the
    # sphere would show through (1 - opacity of the whole ray).
    actor.SetPosition(*centre)
    inside = scene.image()
    unclipped_green = black[mid, mid, 1] + (1 - alpha[mid, mid]) * 255
    print(f"occlusion: centre pixel with the sphere inside {inside[mid, mid]}, volume alone {black[mid, mid]} "
          f"(opacity {alpha[mid, mid]:.2f}), green were it not hidden {unclipped_green:.0f}")
    assert alpha[mid, mid] > 0.3, "the volume is too thin at the centre for this test"
    assert inside[mid, mid, 1] > unclipped_green + 20, "the volume behind the sphere was drawn over it"
    assert inside[mid, mid, 1] < 250 and np.abs(inside[mid, mid] - [0, 255, 0]).max() > 10, \
        "the volume in front of the sphere was not drawn"
    # Away from the sphere, the volume is unchanged.
    rows, cols = np.mgrid[0:SIZE, 0:SIZE]
    away = np.abs(inside - black)[(np.hypot(rows - mid, cols - mid) > 0.4 * SIZE) & ~footprint]
    assert away.max() <= 3, f"the volume changed away from the sphere by {away.max()}"


def main():
    uvr, source, shared = sys.argv[1:4]
    disk = os.path.join(source, "data", "disk_out_ref.vtu")
    brain = os.path.join(shared, "medium", "brain_t1_tet_857k.vtu")
    with tempfile.TemporaryDirectory() as tmp:
        against_uvr_render(uvr, tmp, "disk_out_ref", disk, "Temp", False, 1.0)
        if os.path.exists(brain):
            against_uvr_render(uvr, tmp, "brain 857k", brain, "T1_cell", True, 4.0)
        else:
            print(f"SKIPPED: the brain: {brain} is not there")
    builds_once(disk)
    occlusion(disk)


if __name__ == "__main__":
    main()
