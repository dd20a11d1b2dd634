"""The scene that the ParaView tests render, and its check against `uvr render`: disk_out_ref's Temp shown as
"uvr Volume" with a fixed colour map and opacity function, seen from a fixed camera. Shared by the tests that
run in pvbatch, in pvpython connected to a pvserver and in the paraview GUI; the check itself imports nothing
of ParaView, so that a plain Python can run it on what a ParaView process wrote.
"""
import json
import os
import subprocess
import tempfile

SIZE = 256
RGB = [(0.0, 0.23, 0.30, 0.75), (0.5, 0.87, 0.87, 0.87), (1.0, 0.71, 0.02, 0.15)]
OPACITY = [(0.0, 0.0), (0.3, 0.05), (1.0, 0.9)]
UNIT = 1.0
MIN_SSIM = 0.99


def show_uvr_volume(simple, source, view):
    """Shows `source` in `view` as "uvr Volume" with the scene's function and camera; returns the display."""
    source.UpdatePipeline()
    lo, hi = source.PointData["Temp"].GetRange()
    view.ViewSize = [SIZE, SIZE]
    view.OrientationAxesVisibility = 0
    if view.GetProperty("UseColorPaletteForBackground") is not None:
        view.UseColorPaletteForBackground = 0
    view.Background = [0, 0, 0]
    display = simple.Show(source, view)
    available = display.GetProperty("Representation").Available
    assert "uvr Volume" in available, f"no 'uvr Volume' among {available}"
    display.SetRepresentationType("uvr Volume")
    simple.ColorBy(display, ("POINTS", "Temp"))
    lut = simple.GetColorTransferFunction("Temp")
    lut.AutomaticRescaleRangeMode = "Never"
    lut.ColorSpace = "RGB"
    lut.RGBPoints = rgb_points(lo, hi)
    simple.GetOpacityTransferFunction("Temp").Points = opacity_points(lo, hi)
    display.ScalarOpacityUnitDistance = UNIT
    view.ResetCamera()
    camera = view.GetActiveCamera()
    camera.Azimuth(30)
    camera.Elevation(20)
    camera.OrthogonalizeViewUp()
    return display


def save_screenshot(simple, view, path):
    """Renders `view` into `path`; returns the scene of that frame (Temp's range in the colour map and the
    camera, read after the render: paraview.simple's first render resets the camera's distance)."""
    simple.Render(view)
    simple.SaveScreenshot(path, view, ImageResolution=[SIZE, SIZE])
    points = simple.GetColorTransferFunction("Temp").RGBPoints
    camera = view.GetActiveCamera()
    return {"range": [points[0], points[-4]], "eye": list(camera.GetPosition()),
            "at": list(camera.GetFocalPoint()), "up": list(camera.GetViewUp()), "fovy": camera.GetViewAngle()}


def rgb_points(lo, hi):
    return [v for x, r, g, b in RGB for v in (lo + x * (hi - lo), r, g, b)]


def opacity_points(lo, hi):
    return [v for x, a in OPACITY for v in (lo + x * (hi - lo), a, 0.5, 0.0)]


def compare(uvr, a, b):
    result = subprocess.run([uvr, "compare", a, b, "--json"], check=True, capture_output=True, text=True,
                            timeout=60)
    return json.loads(result.stdout)["ssim"]


def check_against_uvr(uvr, mesh, scene, shot, label):
    """Renders `mesh` with `uvr render` in `scene`'s view and function and asserts that `shot`, ParaView's
    frame, matches it (SSIM >= MIN_SSIM). Returns the SSIM."""
    lo, hi = scene["range"]
    fmt = lambda v: ",".join(f"{c:.9g}" for c in v)  # noqa: E731
    with tempfile.TemporaryDirectory() as tmp:
        tf = os.path.join(tmp, "tf.json")
        with open(tf, "w") as f:
            json.dump([{"Name": "test", "ColorSpace": "RGB", "RGBPoints": rgb_points(lo, hi),
                        "Points": opacity_points(lo, hi)}], f)
        reference = os.path.join(tmp, "uvr.png")
        command = [uvr, "render", mesh, "--field", "point:Temp", "--tf", tf, "--range", repr(lo), repr(hi),
                   "--unit", repr(UNIT), "--size", f"{SIZE}x{SIZE}", "-o", reference,
                   "--eye", fmt(scene["eye"]), "--at", fmt(scene["at"]), "--up", fmt(scene["up"]),
                   "--fovy", f"{scene['fovy']:.9g}"]
        subprocess.run(command, check=True, capture_output=True, timeout=120)
        ssim = compare(uvr, reference, shot)
    print(f"uvr Volume in {label}: SSIM {ssim:.4f} against {' '.join(command)}", flush=True)
    assert ssim >= MIN_SSIM, f"{label}: SSIM {ssim:.4f} < {MIN_SSIM}"
    return ssim
