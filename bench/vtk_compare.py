#!/usr/bin/python3
"""An independent check: renders the cases of the cases file's "vtk" section with VTK's
vtkUnstructuredGridVolumeRayCastMapper and with uvr (reference and full), same mesh, transfer function, opacity
unit and camera, and reports the time per frame of each and the SSIM between VTK's image and uvr's.

Needs Debian's python3-vtk9 and an X display: run it under `xvfb-run -a` on a headless machine.

usage: xvfb-run -a bench/vtk_compare.py UVR OUTDIR [--cases bench/cases.json] [--data ../shared/data] [--quick]
                                        [--only NAME ...]

Conventions matched (see docs/cli.md, "Conventions that differ from ParaView"):
- Camera: both get the same explicit eye, focal point, view-up and vertical view angle.
- Transfer function: the preset is stretched over the same scalar range; colours interpolate in the preset's
  colour space (vtkColorTransferFunction); opacity points keep their midpoint and sharpness (vtkPiecewiseFunction).
- Opacity: uvr reads a preset's opacity a as the opacity of a slab one unit thick, α = 1 − (1 − a)^(s/u), as
  VTK's volume mappers for image data do. VTK's unstructured-grid ray integrators read the opacity function as an
  attenuation coefficient τ per unit distance, α = 1 − exp(−τ·s/u). The same slab opacity needs
  τ = −ln(1 − a), so VTK gets the opacity function resampled through that mapping.
- Pixels: VTK's ray caster casts rays through pixel corners, uvr through pixel centres; VTK's window centre is
  shifted by half a pixel to match.
- Cells: VTK's ray cast mapper takes tetrahedra only; other meshes are split into tets by vtkDataSetTriangleFilter.
  That changes the interpolant (a hexahedron's trilinear field becomes piecewise linear over 5 or 6 tets), so where
  a mesh is split uvr also renders VTK's tets at the ground truth's step ("truth on VTK's tets"): the renderers
  compared on the same input.
- Ray integration: for point data VTK's mapper uses vtkUnstructuredGridPreIntegration, a table over (front value,
  back value, segment length), built incrementally: each length's entries from shorter ones, the split point's
  value rounded to a table bin. With the default 128 bins over the data range the rounding compounds over the
  254 length steps (crosses along the tets of windAroundBuildings' thin cells); 512 bins (a 1 GiB table) keep it
  small. The exact integrators (vtkUnstructuredGridPartialPreIntegration, vtkUnstructuredGridLinearRayIntegrator)
  leave white and black specks on turbineSiting, and the first crashed there.
- Degenerate tets: tets of zero or negative volume (slivers of vtkDataSetTriangleFilter's split of non-convex
  hexahedra, pyramids of foamToVTK's split of concave polyhedra whose apex lies outside a face) are left out of
  VTK's input: overlapping its neighbours, an inverted tet gives VTK's Bunyk ray caster segments that darken the
  rest of the ray (black triangles where the transfer function is opaque). uvr renders the mesh as it is.
"""
import argparse
import json
import math
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import uvr_bench as ub  # noqa: E402

# VTK's Bunyk ray caster casts the ray of pixel (i, j) through the image-plane point (i, j) in pixel units, the
# pixel's lower-left corner; uvr (like OpenGL rasterisation) casts it through the centre (i + 1/2, j + 1/2).
# Shifting VTK's window centre by half a pixel lines the two up.
PIXEL_SHIFT = (0.5, 0.5)
# Opacity 1 is infinite attenuation; the cap leaves e^-25 of the light through a unit slab.
MAX_ATTENUATION = 25.0
TABLE_SAMPLES = 256
# Scalar bins of VTK's pre-integration table (its default 128): see the top.
PREINTEGRATION_SCALAR_BINS = 512


def read_preset(path, name):
    with open(path) as f:
        presets = json.load(f)
    if isinstance(presets, dict):
        presets = [presets]
    for preset in presets:
        if "RGBPoints" in preset and (not name or preset.get("Name") == name):
            return preset
    sys.exit(f"{path}: no preset named {name!r}")


def build_transfer_functions(vtk, preset, low, high):
    """vtkColorTransferFunction and vtkPiecewiseFunction (attenuation per unit) for `preset` stretched over
    [low, high], as uvr stretches it: the preset's own x range (colour and opacity points together) maps onto
    the range."""
    rgb = preset["RGBPoints"]
    points = preset.get("Points") or [rgb[0], 0.0, 0.5, 0.0, rgb[-4], 1.0, 0.5, 0.0]
    own_low = min(rgb[0], points[0])
    own_high = max(rgb[-4], points[-4])
    scale = (high - low) / (own_high - own_low) if own_high > own_low else 0.0

    def stretch(x):
        return low + (x - own_low) * scale

    color = vtk.vtkColorTransferFunction()
    space = preset.get("ColorSpace", "RGB").lower()
    if space in ("lab", "cielab"):
        color.SetColorSpaceToLab()
    elif space == "lab/ciede2000":
        color.SetColorSpaceToLabCIEDE2000()
    elif space == "hsv":
        color.SetColorSpaceToHSV()
    elif space == "diverging":
        color.SetColorSpaceToDiverging()
    elif space == "step":
        color.SetColorSpaceToStep()
    else:
        color.SetColorSpaceToRGB()
    for i in range(0, len(rgb), 4):
        color.AddRGBPoint(stretch(rgb[i]), rgb[i + 1], rgb[i + 2], rgb[i + 3])

    opacity = vtk.vtkPiecewiseFunction()
    for i in range(0, len(points), 4):
        opacity.AddPoint(stretch(points[i]), points[i + 1], points[i + 2], points[i + 3])
    # VTK's partial pre-integration takes the colour function's control points as the only nodes of both
    # functions (9.1 collects only the first opacity point) and interpolates linearly in RGB between them; the
    # dense resampling makes it follow the preset's colour space and the opacity between its points.
    dense_color = vtk.vtkColorTransferFunction()
    attenuation = vtk.vtkPiecewiseFunction()
    for i in range(TABLE_SAMPLES):
        x = low + (high - low) * i / (TABLE_SAMPLES - 1)
        dense_color.AddRGBPoint(x, *color.GetColor(x))
        a = min(max(opacity.GetValue(x), 0.0), 1.0)
        attenuation.AddPoint(x, min(-math.log1p(-a), MAX_ATTENUATION) if a < 1.0 else MAX_ATTENUATION)
    return dense_color, attenuation


def vtk_scalars(vtk, grid, field):
    """The name of the array VTK is to render for uvr's `field` (from `uvr info`): the array of that name and
    centring (a "point:" or "cell:" prefix is uvr's, not the file's), or, for an array of several components
    (OpenFOAM's U), a new array of its magnitudes at the same points or cells, as uvr renders it."""
    data = grid.GetCellData() if field["centering"] == "cell" else grid.GetPointData()
    source = data.GetArray(field["name"])
    if source is None:
        sys.exit(f"VTK: no {field['centering']} array {field['name']!r}")
    if source.GetNumberOfComponents() == 1:
        return field["name"]
    from vtk.util.numpy_support import numpy_to_vtk, vtk_to_numpy
    import numpy
    magnitude = numpy_to_vtk(numpy.linalg.norm(vtk_to_numpy(source).astype(numpy.float64), axis=1), deep=True)
    magnitude.SetName(field["name"] + "_magnitude")
    data.AddArray(magnitude)
    return magnitude.GetName()


def without_degenerate_tets(vtk, grid):
    """`grid` (tets only) without its tets of zero or negative volume, and their count."""
    from vtk.util.numpy_support import vtk_to_numpy
    import numpy
    points = vtk_to_numpy(grid.GetPoints().GetData()).astype(numpy.float64)
    tets = vtk_to_numpy(grid.GetCells().GetConnectivityArray()).reshape(-1, 4)
    a, b, c, d = (points[tets[:, i]] for i in range(4))
    # Either orientation is a valid tet to VTK: a tet is inverted if its volume's sign differs from most tets'.
    volume = numpy.einsum("ij,ij->i", b - a, numpy.cross(c - a, d - a))
    sign = 1.0 if (volume > 0).sum() >= (volume < 0).sum() else -1.0
    bad = numpy.flatnonzero(sign * volume <= 0)
    if not len(bad):
        return grid, 0
    keep = vtk.vtkIdList()
    for i in numpy.setdiff1d(numpy.arange(len(tets)), bad):
        keep.InsertNextId(int(i))
    extract = vtk.vtkExtractCells()
    extract.SetInputData(grid)
    extract.SetCellList(keep)
    extract.Update()
    return extract.GetOutput(), len(bad)


def render_vtk(vtk, mesh, case, field, camera, unit, size, frames, png, pixel_shift=(0.0, 0.0), tets_out=None):
    """Renders `frames` frames; returns (first frame ms, later frames ms list, threads, tets dropped, whether
    the mesh was split). tets_out: where the mesh is split, also write the tets VTK renders there, the scalars under
    the field's name."""
    from vtk.util.numpy_support import vtk_to_numpy
    from PIL import Image

    reader = vtk.vtkXMLUnstructuredGridReader() if mesh.endswith(".vtu") else vtk.vtkUnstructuredGridReader()
    reader.SetFileName(mesh)
    reader.Update()
    grid = reader.GetOutput()
    array = vtk_scalars(vtk, grid, field)
    types = vtk.vtkCellTypes()
    grid.GetCellTypes(types)
    split = types.GetNumberOfTypes() != 1 or types.GetCellType(0) != vtk.VTK_TETRA
    if split:
        splitter = vtk.vtkDataSetTriangleFilter()
        splitter.SetInputData(grid)
        splitter.TetrahedraOnlyOn()
        splitter.Update()
        grid = splitter.GetOutput()
    grid, dropped = without_degenerate_tets(vtk, grid)
    if tets_out and split:
        data = grid.GetCellData() if field["centering"] == "cell" else grid.GetPointData()
        out = vtk.vtkUnstructuredGrid()
        out.SetPoints(grid.GetPoints())
        out.SetCells(vtk.VTK_TETRA, grid.GetCells())
        scalars = vtk.vtkFloatArray()
        scalars.DeepCopy(data.GetArray(array))
        scalars.SetName(field["name"])
        (out.GetCellData() if field["centering"] == "cell" else out.GetPointData()).AddArray(scalars)
        writer = vtk.vtkXMLUnstructuredGridWriter()
        writer.SetFileName(tets_out)
        writer.SetInputData(out)
        writer.Write()

    mapper = vtk.vtkUnstructuredGridVolumeRayCastMapper()
    mapper.SetInputData(grid)
    if field["centering"] == "cell":
        mapper.SetScalarModeToUseCellFieldData()
    else:
        mapper.SetScalarModeToUsePointFieldData()
        # The default for point data, with a finer table (see the top).
        integrator = vtk.vtkUnstructuredGridPreIntegration()
        integrator.SetIntegrationTableScalarResolution(PREINTEGRATION_SCALAR_BINS)
        mapper.SetRayIntegrator(integrator)
    mapper.SelectScalarArray(array)
    mapper.SetAutoAdjustSampleDistances(0)  # else VTK lowers the resolution to meet a frame-time target
    mapper.SetImageSampleDistance(1.0)

    preset = read_preset(ub.resolve(case["tf"], ""), case["tf_name"])
    color, attenuation = build_transfer_functions(vtk, preset, field["min"], field["max"])
    prop = vtk.vtkVolumeProperty()
    prop.SetColor(color)
    prop.SetScalarOpacity(attenuation)
    prop.SetScalarOpacityUnitDistance(unit)
    prop.ShadeOff()
    prop.SetInterpolationTypeToLinear()
    volume = vtk.vtkVolume()
    volume.SetMapper(mapper)
    volume.SetProperty(prop)

    renderer = vtk.vtkRenderer()
    renderer.SetBackground(0, 0, 0)
    renderer.AddVolume(volume)
    window = vtk.vtkRenderWindow()
    window.SetOffScreenRendering(1)
    window.AddRenderer(renderer)
    width, height = (int(v) for v in size.split("x"))
    window.SetSize(width, height)
    vcam = renderer.GetActiveCamera()
    vcam.SetPosition(*camera["eye"])
    vcam.SetFocalPoint(*camera["at"])
    vcam.SetViewUp(*camera["up"])
    vcam.SetViewAngle(camera["fovy"])  # vertical, as UseHorizontalViewAngle is off
    vcam.SetWindowCenter(2.0 * pixel_shift[0] / width, 2.0 * pixel_shift[1] / height)
    renderer.ResetCameraClippingRange()

    times = []
    for _ in range(frames):
        started = time.perf_counter()
        window.Render()
        times.append(1000.0 * (time.perf_counter() - started))
    grab = vtk.vtkWindowToImageFilter()
    grab.SetInput(window)
    grab.SetInputBufferTypeToRGB()
    grab.ReadFrontBufferOff()
    grab.Update()
    image = grab.GetOutput()
    w, h, _ = image.GetDimensions()
    pixels = vtk_to_numpy(image.GetPointData().GetScalars()).reshape(h, w, -1)[::-1]
    Image.fromarray(pixels[:, :, :3].copy()).save(png)
    return times[0], times[1:], mapper.GetNumberOfThreads(), dropped, split


def compare_case(vtk, uvr, case, data_dir, outdir, keep_images):
    mesh = ub.resolve(case["mesh"], data_dir)
    info = ub.mesh_info(uvr, mesh)
    field = ub.field_info(info, case["field"])
    camera = ub.camera_for(case, info)
    name = "".join(c if c.isalnum() else "_" for c in case["name"]).strip("_")
    common = ["--field", case["field"], "--tf", ub.resolve(case["tf"], data_dir), "--tf-name", case["tf_name"],
              "--size", case["size"], "--range", repr(field["min"]), repr(field["max"]), *ub.camera_args(camera)]
    result = {"case": case, "camera": camera, "uvr": {}}
    for mode in ("reference", "full"):
        ub.log(f"{case['name']}: uvr {mode}")
        stem = os.path.join(outdir, f"{name}_uvr_{mode}")
        result["uvr"][mode] = ub.render(uvr, mesh, stem, common + ["--mode", mode, "--frames", case["uvr_frames"]])
        os.remove(stem + "_samples.png")
    unit = result["uvr"]["reference"]["unit"]
    if case["ground_truth_divisor"]:
        ub.log(f"{case['name']}: uvr ground truth")
        stem = os.path.join(outdir, f"{name}_uvr_truth")
        s1 = result["uvr"]["reference"]["s1"] / case["ground_truth_divisor"]
        result["uvr"]["truth"] = ub.render(uvr, mesh, stem, common + ["--mode", "reference", "--s1", repr(s1),
                                                                      "--unit", repr(unit), "--frames", 1])
        os.remove(stem + "_samples.png")

    ub.log(f"{case['name']}: VTK, {case['frames']} frames")
    vtk_png = os.path.join(outdir, f"{name}_vtk.png")
    tets = os.path.join(outdir, f"{name}_vtk_tets.vtu") if case["ground_truth_divisor"] else None
    first, later, threads, dropped, split = render_vtk(vtk, mesh, case, field, camera, unit, case["size"],
                                                       case["frames"], vtk_png, PIXEL_SHIFT, tets)
    result["vtk"] = {"first_ms": first, "later_ms": later, "threads": threads,
                     "frame_ms": ub.median(later) if later else first, "degenerate_tets_dropped": dropped}
    if tets and split:
        ub.log(f"{case['name']}: uvr ground truth on VTK's tets")
        stem = os.path.join(outdir, f"{name}_uvr_truth_tets")
        tets_common = common[:]
        tets_common[1] = f"{field['centering']}:{field['name']}"
        result["uvr"]["truth_tets"] = ub.render(uvr, tets, stem, tets_common + [
            "--mode", "reference", "--s1", repr(result["uvr"]["truth"]["s1"]), "--unit", repr(unit), "--frames", 1])
        os.remove(stem + "_samples.png")
        os.remove(tets)
    for mode in result["uvr"]:
        quality = ub.compare(uvr, vtk_png, os.path.join(outdir, f"{name}_uvr_{mode}.png"))
        result["uvr"][mode]["ssim_vtk"] = quality["ssim"]
        result["uvr"][mode]["psnr_vtk"] = quality["psnr"]
    labels = ["VTK", "uvr reference", "uvr full"] + (["uvr truth"] if "truth" in result["uvr"] else []) + \
        (["uvr truth, VTK's tets"] if "truth_tets" in result["uvr"] else [])
    paths = [vtk_png] + [os.path.join(outdir, f"{name}_uvr_{m}.png") for m in result["uvr"]]
    result["montage"] = f"{name}.png"
    ub.montage(paths, labels, os.path.join(outdir, result["montage"]), 256)
    if not keep_images:
        for path in paths:
            os.remove(path)
    return result


def write_report(results, outdir, command, machine):
    f = ub.fmt
    lines = ["# uvr against VTK's vtkUnstructuredGridVolumeRayCastMapper", "",
             f"Machine: {machine['cpu']}, {machine['cores']} cores, load average {machine['load_average'][0]:.1f} "
             f"(may be shared: times are indicative). Command: `{command}`.", "",
             "VTK: 9.1 (Debian's python3-vtk9), vtkUnstructuredGridVolumeRayCastMapper (Bunyk ray casting, "
             f"for point data a pre-integration table of {PREINTEGRATION_SCALAR_BINS} scalar bins), image sample "
             "distance 1, no automatic adjustment; its first frame includes building its own structures. uvr: "
             "time per frame is the median over its frames, excluding load and build (given separately). Same "
             "camera, range, preset and opacity unit (see bench/vtk_compare.py for the opacity mapping). VTK's "
             "input leaves out the tets of zero or negative volume (count given); a mesh of other cells is split "
             "into tets for VTK, and \"truth, VTK's tets\" is uvr's ground truth rendered from those same tets.", "",
             "| case | size | VTK first frame ms | VTK later frames ms | VTK threads | uvr reference ms | uvr full ms | "
             "uvr load + build ms | full speed-up over VTK | SSIM VTK vs reference | SSIM VTK vs full | "
             "SSIM VTK vs truth | SSIM VTK vs truth, VTK's tets | VTK tets dropped |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in results:
        u = r["uvr"]
        truth = u.get("truth", {}).get("ssim_vtk")
        truth_tets = u.get("truth_tets", {}).get("ssim_vtk")
        lines.append(
            f"| {r['case']['name']} | {r['case']['size']} | {f(r['vtk']['first_ms'], 0)} | "
            f"{', '.join(f(t, 0) for t in r['vtk']['later_ms']) or '–'} | {r['vtk']['threads']} | "
            f"{f(u['reference']['render_ms'], 0)} | {f(u['full']['render_ms'], 0)} | "
            f"{f(u['full']['load_ms'] + u['full']['build_ms'], 0)} | "
            f"{f(r['vtk']['frame_ms'] / u['full']['render_ms'], 1)}× | {f(u['reference']['ssim_vtk'], 4)} | "
            f"{f(u['full']['ssim_vtk'], 4)} | {f(truth, 4)} | {f(truth_tets, 4)} | "
            f"{r['vtk'].get('degenerate_tets_dropped', 0)} |")
    lines.append("")
    for r in results:
        lines += [f"![{r['case']['name']}]({r['montage']})", ""]
    with open(os.path.join(outdir, "vtk_compare.md"), "w") as out:
        out.write("\n".join(lines))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ub.add_case_arguments(parser)
    parser.add_argument("--keep-images", action="store_true", help="keep the full-size images in OUTDIR")
    parser.add_argument("--size", help="override every case's image size, WxH")
    parser.add_argument("--frames", type=int, help="override every case's VTK frame count")
    args = parser.parse_args()
    import vtk

    uvr = os.path.abspath(args.uvr)
    cases = ub.selected_cases(args, "vtk")
    for case in cases:
        case.update({k: v for k, v in (("size", args.size), ("frames", args.frames)) if v})
    os.makedirs(args.outdir, exist_ok=True)
    command = "xvfb-run -a bench/vtk_compare.py " + " ".join(sys.argv[1:])
    machine = ub.machine()
    results = [compare_case(vtk, uvr, case, args.data, args.outdir, args.keep_images) for case in cases]
    write_report(results, args.outdir, command, machine)
    with open(os.path.join(args.outdir, "vtk_compare.json"), "w") as out:
        json.dump({"command": command, "machine": machine, "vtk": vtk.vtkVersion.GetVTKVersion(),
                   "results": results}, out, indent=1)


if __name__ == "__main__":
    main()
