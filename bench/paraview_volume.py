"""Frame times in pvbatch of "uvr Volume" (the uvrParaView plugin) against ParaView's volume representation
of unstructured grids (its default mapper, projected tetrahedra, and "Resample To Image" at its default
128^3), one mesh and field, side by side in one process; each image's SSIM against a converged uvr image
(`uvr render --mode reference --s1 <default s1 / 8>`) of the same view and function. Results in
docs/results/cpu.md.

Usage: pvbatch bench/paraview_volume.py UVR_BINARY PLUGIN MESH FIELD SIZE FRAMES OUT_DIR [PRESETS NAME]
  FIELD: a point field; vectors are taken as their magnitude. FRAMES: frames timed after the first, each
  turning the camera by a degree. PRESETS, NAME: a ParaView preset file and the preset to take (its colour
  and opacity points stretched over the field's range, in its colour space); default: a translucent ramp.
  Prints one JSON line per representation.
"""
import json
import math
import os
import subprocess
import sys
import time

from paraview import simple

# The default function: colour (x, r, g, b) and opacity (x, opacity, midpoint, sharpness) over [0, 1].
RGB = [(0.0, 0.23, 0.30, 0.75), (0.5, 0.87, 0.87, 0.87), (1.0, 0.71, 0.02, 0.15)]
OPACITY = [(0.0, 0.0, 0.5, 0.0), (0.3, 0.05, 0.5, 0.0), (1.0, 0.9, 0.5, 0.0)]


def read_preset(path, name):
    """A preset's points over [0, 1] of its own colour range, and its colour space."""
    with open(path) as f:
        presets = json.load(f)
    preset = next(p for p in (presets if isinstance(presets, list) else [presets]) if p.get("Name") == name)
    rgb = [tuple(preset["RGBPoints"][i:i + 4]) for i in range(0, len(preset["RGBPoints"]), 4)]
    x0, x1 = rgb[0][0], rgb[-1][0]
    scale = lambda x: (x - x0) / (x1 - x0)  # noqa: E731
    opacity = [tuple(preset["Points"][i:i + 4]) for i in range(0, len(preset.get("Points", [])), 4)]
    return ([(scale(x), r, g, b) for x, r, g, b in rgb], [(scale(x), a, m, s) for x, a, m, s in opacity],
            preset.get("ColorSpace", "RGB"))


def main():
    uvr, plugin, mesh, field, size, frames, out = sys.argv[1:8]
    size, frames = int(size), int(frames)
    rgb_points, opacity_points, color_space = (read_preset(*sys.argv[8:10]) if len(sys.argv) > 9 else
                                               (RGB, OPACITY, "RGB"))
    os.makedirs(out, exist_ok=True)
    simple.LoadPlugin(plugin, remote=False, ns=globals())
    reader = simple.XMLUnstructuredGridReader(FileName=[mesh])
    reader.PointArrayStatus = [field]
    reader.CellArrayStatus = []
    reader.UpdatePipeline()
    info = reader.GetDataInformation()
    array = reader.PointData[field]
    lo, hi = array.GetRange(-1 if array.GetNumberOfComponents() > 1 else 0)
    bounds = info.GetBounds()
    diagonal = math.sqrt(sum((bounds[2 * i + 1] - bounds[2 * i]) ** 2 for i in range(3)))
    # ParaView's default unit distance for a data set (and uvr's).
    unit = diagonal / info.GetNumberOfCells() ** (1 / 3)
    name = os.path.splitext(os.path.basename(mesh))[0]
    tf = os.path.join(out, "tf.json")
    with open(tf, "w") as f:
        json.dump([{"Name": "bench", "ColorSpace": color_space,
                    "RGBPoints": [v for x, r, g, b in rgb_points for v in (lo + x * (hi - lo), r, g, b)],
                    "Points": [v for x, a, m, s in opacity_points for v in (lo + x * (hi - lo), a, m, s)]}], f)

    camera_args = None
    results = []
    for label, representation, mapper in (("uvr Volume", "uvr Volume", None),
                                          ("Volume (projected tetra)", "Volume", "Projected tetra"),
                                          ("Resample To Image", "Volume", "Resample To Image")):
        view = simple.CreateRenderView()
        view.ViewSize = [size, size]
        view.OrientationAxesVisibility = 0
        if view.GetProperty("UseColorPaletteForBackground") is not None:
            view.UseColorPaletteForBackground = 0
        view.Background = [0, 0, 0]
        display = simple.Show(reader, view)
        display.SetRepresentationType(representation)
        if mapper:
            display.SelectMapper = mapper
        simple.ColorBy(display, ("POINTS", field, "Magnitude") if array.GetNumberOfComponents() > 1 else
                       ("POINTS", field))
        lut = simple.GetColorTransferFunction(field)
        lut.AutomaticRescaleRangeMode = "Never"
        if array.GetNumberOfComponents() > 1:
            lut.VectorMode = "Magnitude"
        lut.ColorSpace = color_space
        lut.RGBPoints = [v for x, r, g, b in rgb_points for v in (lo + x * (hi - lo), r, g, b)]
        opacity = simple.GetOpacityTransferFunction(field)
        opacity.Points = [v for x, a, m, s in opacity_points for v in (lo + x * (hi - lo), a, m, s)]
        display.ScalarOpacityUnitDistance = unit
        view.ResetCamera()
        camera = view.GetActiveCamera()
        camera.Azimuth(30)
        camera.Elevation(20)
        camera.OrthogonalizeViewUp()
        start = time.perf_counter()
        simple.Render(view)
        first = time.perf_counter() - start
        later = []
        for i in range(frames):
            camera.Azimuth(1 if i % 2 == 0 else -1)
            start = time.perf_counter()
            simple.Render(view)
            later.append(time.perf_counter() - start)
        if frames % 2:
            camera.Azimuth(-1)
        shot = os.path.join(out, f"{name}_{label.split()[0].lower()}.png")
        simple.SaveScreenshot(shot, view, ImageResolution=[size, size])
        if camera_args is None:
            fmt = lambda v: ",".join(f"{c:.9g}" for c in v)  # noqa: E731
            camera_args = ["--eye", fmt(camera.GetPosition()), "--at", fmt(camera.GetFocalPoint()), "--up",
                           fmt(camera.GetViewUp()), "--fovy", f"{camera.GetViewAngle():.9g}"]
        results.append({"mesh": name, "representation": label, "size": size, "first_s": round(first, 3),
                        "later_s_median": round(sorted(later)[len(later) // 2], 3) if later else None,
                        "later_s": [round(t, 3) for t in later], "image": shot})
        simple.Hide(reader, view)
        simple.Delete(view)

    common = [uvr, "render", mesh, "--field", "point:" + field, "--tf", tf, "--range", repr(lo), repr(hi),
              "--unit", repr(unit), "--size", f"{size}x{size}", *camera_args]
    stats_file = os.path.join(out, f"{name}_default_stats.json")
    subprocess.run(common + ["-o", os.path.join(out, f"{name}_uvr_default.png"), "--stats", stats_file],
                   check=True, capture_output=True)
    with open(stats_file) as f:
        s1 = json.load(f)["s1"]
    converged = os.path.join(out, f"{name}_converged.png")
    command = common + ["--mode", "reference", "--s1", repr(s1 / 8), "-o", converged]
    start = time.perf_counter()
    subprocess.run(command, check=True, capture_output=True)
    converged_s = time.perf_counter() - start
    for r in results:
        compare = subprocess.run([uvr, "compare", converged, r["image"], "--json"], check=True,
                                 capture_output=True, text=True)
        r["ssim_vs_converged"] = round(json.loads(compare.stdout)["ssim"], 4)
        r["converged_command"] = " ".join(command)
        r["converged_s"] = round(converged_s, 1)
        print(json.dumps(r), flush=True)


if __name__ == "__main__":
    main()
