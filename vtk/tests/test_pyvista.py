#!/usr/bin/env python3
"""uvr.vtk.VolumeMapper in a PyVista plotter: a vtkVolume with the mapper, added to the plotter, draws the
volume (docs/python.md's example). Skipped where PyVista is not installed (Debian 12 has no package of it).

Usage: test_pyvista.py SOURCE_DIR (run by ctest with PYTHONPATH=build/python, under a virtual X server)
"""
import os
import sys

try:
    import pyvista as pv
except ImportError:
    print("SKIPPED: PyVista is not installed")
    sys.exit(77)
from vtkmodules.vtkCommonDataModel import vtkPiecewiseFunction
from vtkmodules.vtkRenderingCore import vtkColorTransferFunction, vtkVolume

from uvr.vtk import VolumeMapper, stats


def main():
    grid = pv.read(os.path.join(sys.argv[1], "data", "disk_out_ref.vtu"))
    lo, hi = grid.get_data_range("Temp")
    mapper = VolumeMapper()
    mapper.SetInputData(grid)
    mapper.SetScalarModeToUsePointFieldData()
    mapper.SelectScalarArray("Temp")
    color = vtkColorTransferFunction()
    color.AddRGBPoint(lo, 0.23, 0.30, 0.75)
    color.AddRGBPoint(hi, 0.71, 0.02, 0.15)
    opacity = vtkPiecewiseFunction()
    opacity.AddPoint(lo, 0.0)
    opacity.AddPoint(hi, 0.8)
    volume = vtkVolume()
    volume.SetMapper(mapper)
    volume.GetProperty().SetColor(color)
    volume.GetProperty().SetScalarOpacity(opacity)
    plotter = pv.Plotter(off_screen=True, window_size=(256, 256))
    plotter.background_color = "black"
    plotter.add_actor(volume)
    image = plotter.screenshot(return_img=True)
    lit = (image[:, :, :3].sum(axis=2) > 30).mean()
    print(f"PyVista: {lit:.0%} of the pixels lit; {stats(mapper)}")
    assert lit > 0.05, "the volume was not drawn"


if __name__ == "__main__":
    main()
