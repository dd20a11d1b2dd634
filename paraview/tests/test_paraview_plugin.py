"""The ParaView plugin in pvbatch: LoadPlugin, disk_out_ref shown as "uvr Volume" with a colour map and an
opacity function, a screenshot; SSIM >= 0.99 against `uvr render` of the same view and function. uvr's own
properties (mode, s1) reach the mapper.

Usage: pvbatch test_paraview_plugin.py UVR_BINARY PLUGIN SOURCE_DIR (run by ctest under xvfb-run; ParaView's
Python must be importable: PYTHONPATH names python3-paraview's files where they are unpacked, not installed)
"""
import json
import os
import subprocess
import sys
import tempfile

try:
    from paraview import simple
except ImportError:
    print("SKIPPED: ParaView's Python (python3-paraview, or its files unpacked by scripts/setup-debian) is "
          "not found")
    sys.exit(77)

SIZE = 256
RGB = [(0.0, 0.23, 0.30, 0.75), (0.5, 0.87, 0.87, 0.87), (1.0, 0.71, 0.02, 0.15)]
OPACITY = [(0.0, 0.0), (0.3, 0.05), (1.0, 0.9)]
UNIT = 1.0


def compare(uvr, a, b):
    result = subprocess.run([uvr, "compare", a, b, "--json"], check=True, capture_output=True, text=True)
    return json.loads(result.stdout)["ssim"]


def main():
    uvr, plugin, source = sys.argv[1:4]
    disk = os.path.join(source, "data", "disk_out_ref.vtu")
    simple.LoadPlugin(plugin, remote=False, ns=globals())
    reader = simple.XMLUnstructuredGridReader(FileName=[disk])
    reader.UpdatePipeline()
    lo, hi = reader.PointData["Temp"].GetRange()
    view = simple.CreateRenderView()
    view.ViewSize = [SIZE, SIZE]
    view.OrientationAxesVisibility = 0
    if view.GetProperty("UseColorPaletteForBackground") is not None:
        view.UseColorPaletteForBackground = 0
    view.Background = [0, 0, 0]
    display = simple.Show(reader, view)
    available = display.GetProperty("Representation").Available
    assert "uvr Volume" in available, f"no 'uvr Volume' among {available}"
    display.SetRepresentationType("uvr Volume")
    simple.ColorBy(display, ("POINTS", "Temp"))
    lut = simple.GetColorTransferFunction("Temp")
    lut.AutomaticRescaleRangeMode = "Never"
    lut.ColorSpace = "RGB"
    lut.RGBPoints = [v for x, r, g, b in RGB for v in (lo + x * (hi - lo), r, g, b)]
    opacity = simple.GetOpacityTransferFunction("Temp")
    opacity.Points = [v for x, a in OPACITY for v in (lo + x * (hi - lo), a, 0.5, 0.0)]
    display.ScalarOpacityUnitDistance = UNIT
    view.ResetCamera()
    camera = view.GetActiveCamera()
    camera.Azimuth(30)
    camera.Elevation(20)
    camera.OrthogonalizeViewUp()

    with tempfile.TemporaryDirectory() as tmp:
        shot = os.path.join(tmp, "paraview.png")
        simple.Render(view)
        simple.SaveScreenshot(shot, view, ImageResolution=[SIZE, SIZE])
        tf = os.path.join(tmp, "tf.json")
        with open(tf, "w") as f:
            json.dump([{"Name": "test", "ColorSpace": "RGB",
                        "RGBPoints": [v for x, r, g, b in RGB for v in (lo + x * (hi - lo), r, g, b)],
                        "Points": [v for x, a in OPACITY for v in (lo + x * (hi - lo), a, 0.5, 0.0)]}], f)
        fmt = lambda v: ",".join(f"{c:.9g}" for c in v)  # noqa: E731
        reference = os.path.join(tmp, "uvr.png")
        command = [uvr, "render", disk, "--field", "point:Temp", "--tf", tf, "--range", repr(lo), repr(hi),
                   "--unit", repr(UNIT), "--size", f"{SIZE}x{SIZE}", "-o", reference,
                   "--eye", fmt(camera.GetPosition()), "--at", fmt(camera.GetFocalPoint()),
                   "--up", fmt(camera.GetViewUp()), "--fovy", f"{camera.GetViewAngle():.9g}"]
        subprocess.run(command, check=True, capture_output=True)
        ssim = compare(uvr, reference, shot)
        print(f"uvr Volume in pvbatch: SSIM {ssim:.4f} against {' '.join(command)}")
        assert ssim >= 0.99, f"SSIM {ssim:.4f} < 0.99"

        # uvr's own properties reach the mapper: a much coarser fixed step changes the picture.
        display.UvrMode = "reference"
        display.UvrS1 = 2.0
        coarse = os.path.join(tmp, "coarse.png")
        simple.Render(view)
        simple.SaveScreenshot(coarse, view, ImageResolution=[SIZE, SIZE])
        changed = compare(uvr, shot, coarse)
        print(f"mode reference, s1 2: SSIM {changed:.4f} against the default")
        assert changed < 0.98, "UvrMode and UvrS1 did not change the frame"


if __name__ == "__main__":
    main()
