"""Tests of the `uvr` Python module against the `uvr` command.

Run by ctest (python/CMakeLists.txt sets PYTHONPATH, UVR_BINARY and UVR_SOURCE_DIR), or by hand:
PYTHONPATH=build/python /usr/bin/python3 -m pytest python/tests
"""
import json
import os
import subprocess
import threading
import time

import numpy as np
import pytest

import uvr

SOURCE_DIR = os.environ.get("UVR_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))
UVR_BINARY = os.environ.get("UVR_BINARY", os.path.join(SOURCE_DIR, "build", "uvr"))
DISK = os.path.join(SOURCE_DIR, "data", "disk_out_ref.vtu")
PRESETS = os.path.join(SOURCE_DIR, "tests", "data", "presets", "two_presets.json")

VTK_TETRA, VTK_HEXAHEDRON, VTK_WEDGE, VTK_PYRAMID = 10, 12, 13, 14


def box_grid(n=4):
    """A cube of n^3 hexahedra with a point field and a cell field, as PyVista's arrays (flat cells)."""
    ticks = np.linspace(0.0, 1.0, n + 1)
    z, y, x = np.meshgrid(ticks, ticks, ticks, indexing="ij")
    points = np.stack([x.ravel(), y.ravel(), z.ravel()], axis=1)

    def index(i, j, k):
        return (k * (n + 1) + j) * (n + 1) + i

    cells = []
    for k in range(n):
        for j in range(n):
            for i in range(n):
                cells.append([8, index(i, j, k), index(i + 1, j, k), index(i + 1, j + 1, k), index(i, j + 1, k),
                              index(i, j, k + 1), index(i + 1, j, k + 1), index(i + 1, j + 1, k + 1),
                              index(i, j + 1, k + 1)])
    cells = np.array(cells, dtype=np.int64)
    point_field = np.sin(3 * points[:, 0]) + points[:, 1] * points[:, 2]
    cell_field = np.arange(len(cells), dtype=np.float64)
    celltypes = np.full(len(cells), VTK_HEXAHEDRON, dtype=np.uint8)
    return points, cells.ravel(), celltypes, {"wave": point_field}, {"id": cell_field}


def split_flat(cells, count):
    """VTK 9's offsets and connectivity for a flat [n, i0, ...] cells array."""
    offsets, connectivity, at = [0], [], 0
    for _ in range(count):
        n = cells[at]
        connectivity.extend(cells[at + 1:at + 1 + n])
        offsets.append(len(connectivity))
        at += n + 1
    return np.array(offsets, dtype=np.int64), np.array(connectivity, dtype=np.int64)


def cell_corner_sets(points, cells, celltypes):
    """Each cell as (type, sorted corner coordinates): independent of point and cell order."""
    result, at = [], 0
    for t in celltypes:
        n = cells[at]
        corners = points[cells[at + 1:at + 1 + n]]
        result.append((int(t), tuple(sorted(map(tuple, np.round(corners, 6))))))
        at += n + 1
    return sorted(result)


def run_cli(*args):
    return subprocess.run([UVR_BINARY, *args], capture_output=True, text=True)


def cli_error(*args):
    result = run_cli(*args)
    assert result.returncode == 2, result.stderr
    prefix = "uvr: error: "
    line = result.stderr.strip().splitlines()[-1]
    assert line.startswith(prefix)
    return line[len(prefix):]


def test_arrays_round_trip():
    points, cells, celltypes, point_data, cell_data = box_grid()
    mesh = uvr.Mesh(points, cells, celltypes, point_data=point_data, cell_data=cell_data)
    assert mesh.n_points == len(points) and mesh.n_cells == len(celltypes)
    assert mesh.points.dtype == np.float32 and mesh.points.shape == (len(points), 3)
    # Cells keep their corners (uvr reorders cells and points spatially, so compare as sets).
    assert cell_corner_sets(mesh.points, mesh.cells, mesh.celltypes) == \
        cell_corner_sets(points.astype(np.float32), cells, celltypes)
    # Each point keeps its value, each cell its value.
    by_position = {tuple(np.round(p, 6)): v for p, v in zip(points.astype(np.float32), point_data["wave"])}
    for p, v in zip(mesh.points, mesh.point_data["wave"]):
        assert v == pytest.approx(by_position[tuple(np.round(p, 6))], abs=1e-6)
    centroid_id = {}
    for c in range(len(celltypes)):
        centroid_id[tuple(np.round(points[cells[9 * c + 1:9 * c + 9]].mean(axis=0), 5))] = cell_data["id"][c]
    out_cells = mesh.cells.reshape(-1, 9)
    for c, value in enumerate(mesh.cell_data["id"]):
        assert value == centroid_id[tuple(np.round(mesh.points[out_cells[c, 1:]].astype(np.float64).mean(axis=0), 5))]
    assert mesh.bounds == pytest.approx((0, 1, 0, 1, 0, 1))

    # The arrays it gives back build the same mesh, which renders the same image.
    again = uvr.Mesh(mesh.points, mesh.cells, mesh.celltypes, point_data=mesh.point_data, cell_data=mesh.cell_data)
    np.testing.assert_array_equal(again.points, mesh.points)
    np.testing.assert_array_equal(again.cells, mesh.cells)
    first = uvr.Renderer(mesh, field="wave", leaf_size=8).render(size=(64, 48))
    second = uvr.Renderer(again, field="wave", leaf_size=8).render(size=(64, 48))
    np.testing.assert_array_equal(first, second)
    assert first.std() > 0


def test_field_centring_prefixes():
    """field="point:p" / "cell:p" pick one of two fields named p; a plain "p" is the point field."""
    points, cells, celltypes, point_data, cell_data = box_grid(3)
    mesh = uvr.Mesh(points, cells, celltypes, point_data={"p": point_data["wave"]}, cell_data={"p": cell_data["id"]})
    image = {field: uvr.Renderer(mesh, field=field).render(size=(48, 48)) for field in ("point:p", "cell:p", "p")}
    np.testing.assert_array_equal(image["p"], image["point:p"])
    assert not np.array_equal(image["point:p"], image["cell:p"])
    with pytest.raises(uvr.Error, match="point:p, cell:p"):
        uvr.Renderer(mesh, field="cell:q")


def test_offsets_and_flat_layouts_agree():
    points, cells, celltypes, point_data, _ = box_grid(3)
    offsets, connectivity = split_flat(cells, len(celltypes))
    flat = uvr.Mesh(points, cells, celltypes, point_data=point_data)
    split = uvr.Mesh(points, connectivity, celltypes, offsets=offsets, point_data=point_data)
    np.testing.assert_array_equal(flat.points, split.points)
    np.testing.assert_array_equal(flat.cells, split.cells)
    np.testing.assert_array_equal(flat.point_data["wave"], split.point_data["wave"])
    # int32 indices and float32 points are converted, not refused.
    narrow = uvr.Mesh(points.astype(np.float32), cells.astype(np.int32), celltypes, point_data=point_data)
    np.testing.assert_array_equal(flat.cells, narrow.cells)


def test_mixed_cells_and_vector_fields():
    # One tet, one pyramid and one wedge sharing nothing; a 3-component field becomes its magnitude.
    points = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1],
                       [2, 0, 0], [3, 0, 0], [3, 1, 0], [2, 1, 0], [2.5, 0.5, 1],
                       [4, 0, 0], [5, 0, 0], [4, 1, 0], [4, 0, 1], [5, 0, 1], [4, 1, 1]], dtype=np.float64)
    cells = np.array([4, 0, 1, 2, 3, 5, 4, 5, 6, 7, 8, 6, 9, 10, 11, 12, 13, 14])
    celltypes = np.array([VTK_TETRA, VTK_PYRAMID, VTK_WEDGE], dtype=np.uint8)
    vectors = np.tile([3.0, 4.0, 0.0], (len(points), 1))
    mesh = uvr.Mesh(points, cells, celltypes, point_data={"v": vectors})
    assert sorted(mesh.celltypes.tolist()) == sorted([VTK_TETRA, VTK_PYRAMID, VTK_WEDGE])
    np.testing.assert_allclose(mesh.point_data["v"], 5.0)


class PyvistaShaped:
    """What Mesh.from_pyvista reads of a pyvista.UnstructuredGrid, without PyVista."""

    def __init__(self, points, cells, celltypes, point_data, cell_data, vtk9):
        self.points, self.cells, self.celltypes = points, cells, celltypes
        self.point_data, self.cell_data = point_data, cell_data
        if vtk9:
            self.offsets, self.cell_connectivity = split_flat(cells, len(celltypes))


@pytest.mark.parametrize("vtk9", [False, True])
def test_pyvista_shaped_input(vtk9):
    points, cells, celltypes, point_data, cell_data = box_grid(3)
    grid = PyvistaShaped(points, cells, celltypes, point_data, cell_data, vtk9)
    mesh = uvr.Mesh.from_pyvista(grid)
    direct = uvr.Mesh(points, cells, celltypes, point_data=point_data, cell_data=cell_data)
    assert mesh.field_names == ["wave", "id"]
    np.testing.assert_array_equal(mesh.cells, direct.cells)
    np.testing.assert_array_equal(mesh.cell_data["id"], direct.cell_data["id"])
    # A uvr.Mesh has the same attributes, so it converts too.
    np.testing.assert_array_equal(uvr.Mesh.from_pyvista(mesh).cells, mesh.cells)


def test_same_image_as_the_command(tmp_path):
    png, stats_path = tmp_path / "cli.png", tmp_path / "cli.json"
    eye, at, up = (30.0, -20.0, 15.0), (0.0, 0.0, 2.0), (0.0, 0.0, 1.0)
    result = run_cli("render", DISK, "--field", "Pres", "--tf", PRESETS, "--tf-name", "Ramp with Points (test)",
                     "--range", "0.005", "0.02", "--mode", "adaptive", "--s2", "1.5", "--size", "96x64",
                     "--eye", ",".join(map(str, eye)), "--at", ",".join(map(str, at)), "--up",
                     ",".join(map(str, up)), "--fovy", "40", "--background", "0.1,0.2,0.3", "-o", str(png),
                     "--stats", str(stats_path))
    assert result.returncode == 0, result.stderr
    cli_stats = json.loads(stats_path.read_text())

    mesh = uvr.load(DISK)
    renderer = uvr.Renderer(mesh, field="Pres")
    tf = uvr.TransferFunction(PRESETS, name="Ramp with Points (test)", range=(0.005, 0.02))
    image = renderer.render(camera={"eye": eye, "at": at, "up": up, "fovy": 40}, tf=tf, mode="adaptive", s2=1.5,
                            size=(96, 64), background=(0.1, 0.2, 0.3))
    assert image.shape == (64, 96, 4) and image.dtype == np.uint8
    cli_image = uvr.read_png(str(png))
    assert uvr.compare(image, cli_image)["ssim"] >= 0.999
    np.testing.assert_array_equal(image[:, :, :3], cli_image)

    stats = renderer.last_stats
    assert set(stats) == set(cli_stats) - {"load_ms", "frames", "time_step"}
    for key in ("mode", "width", "height", "cells", "partitions", "partitions_skipped", "samples_total",
                "samples_per_pixel_max", "s1", "s2", "p", "unit", "leaf_size", "field", "range", "backend"):
        assert stats[key] == pytest.approx(cli_stats[key], rel=1e-6), key
    samples = renderer.last_samples
    assert samples.shape == (64, 96) and int(samples.sum()) == stats["samples_total"]
    assert renderer.heatmap().shape == (64, 96, 3)


def test_default_view_matches_the_command(tmp_path):
    png = tmp_path / "cli.png"
    result = run_cli("render", DISK, "--size", "80x80", "-o", str(png))
    assert result.returncode == 0, result.stderr
    renderer = uvr.Renderer(uvr.load(DISK))
    image = renderer.render(size=(80, 80))
    np.testing.assert_array_equal(image[:, :, :3], uvr.read_png(str(png)))
    # Opacity: zero where rays miss the mesh (the corners), and the camera default is the command's.
    assert image[0, 0, 3] == 0 and image[40, 40, 3] > 0
    camera = renderer.default_camera()
    same = renderer.render(camera=camera, size=(80, 80))
    np.testing.assert_array_equal(image, same)
    # A transfer function from arrays: the default preset's points give the default image.
    default = uvr.TransferFunction()
    from_arrays = uvr.TransferFunction.from_arrays(default.rgb_points, default.opacity_points,
                                                   color_space="Diverging")
    np.testing.assert_array_equal(renderer.render(size=(80, 80), tf=from_arrays), image)


def test_render_releases_the_gil():
    renderer = uvr.Renderer(uvr.load(DISK))
    started, ticks = threading.Event(), []
    done = threading.Event()

    def work():
        started.set()
        renderer.render(size=(256, 256))
        done.set()

    thread = threading.Thread(target=work)
    thread.start()
    started.wait()
    while not done.is_set():
        ticks.append(1)  # runs only while the render thread does not hold the GIL
        done.wait(0.001)
    thread.join()
    assert len(ticks) > 3


@pytest.mark.parametrize("cli_args, call", [
    (["render", "missing.vtu", "-o", "x.png"], lambda: uvr.load("missing.vtu")),
    (["render", DISK, "--field", "Nope", "-o", "x.png"], lambda: uvr.Renderer(uvr.load(DISK), field="Nope")),
    (["render", DISK, "--tf", "Nope", "-o", "x.png"], lambda: uvr.TransferFunction("Nope")),
    (["render", DISK, "--tf", "missing.json", "-o", "x.png"], lambda: uvr.TransferFunction("missing.json")),
    (["render", DISK, "--tf", PRESETS, "--tf-name", "Nope", "-o", "x.png"],
     lambda: uvr.TransferFunction(PRESETS, name="Nope")),
    (["render", DISK, "--backend", "metal", "-o", "x.png"],
     lambda: uvr.Renderer(uvr.load(DISK), backend="metal")),
    (["render", DISK, "--eye", "0,1,0", "--at", "0,0,0", "--up", "0,1,0", "-o", "x.png"],
     lambda: uvr.Renderer(uvr.load(DISK)).render(camera={"eye": (0, 1, 0), "at": (0, 0, 0), "up": (0, 1, 0)},
                                                 size=(8, 8))),
    (["render", DISK, "--s1", "1", "--s2", "0.5", "-o", "x.png"],
     lambda: uvr.Renderer(uvr.load(DISK)).render(s1=1, s2=0.5, size=(8, 8))),
])
def test_errors_carry_the_command_messages(tmp_path, cli_args, call):
    """The library's message, which the command follows with the options it concerns."""
    os.chdir(tmp_path)
    message = cli_error(*cli_args)
    with pytest.raises(uvr.Error) as error:
        call()
    assert message == str(error.value) or message.startswith(str(error.value) + " (--"), message


BAD_NUMBERS = [0, -1, float("nan"), float("inf"), "abc", [1, 2]]


@pytest.mark.parametrize("keyword, values", [
    ("s1", BAD_NUMBERS), ("s2", BAD_NUMBERS), ("unit", BAD_NUMBERS), ("p", BAD_NUMBERS + [0.5]),
    ("size", [(0, 8), (-1, 8), (8, 0), (20000, 8), (8,), "abc", (float("nan"), 8), None]),
    ("background", [(255, 255, 255), (-1, 0, 0), (float("nan"), 0, 0), (float("inf"), 0, 0), (1, 2), "abc"]),
    ("mode", ["bogus", 3, None]),
    ("compositing", ["bogus", 3, None]),
    ("steps", ["bogus", 3, None]),
    ("shade", ["yes", 1, None]),
    ("light", [(1, 2), "abc", (float("nan"), 0, 0), (float("inf"), 0, 0)]),
    ("iso", ["abc", [], [float("nan")], [1] * 9, 3]),
    ("iso_color", [(2, 0, 0), (1, 2), "abc", (float("nan"), 0, 0)]),
    ("iso_opacity", [0, 1.5, float("nan"), "abc", None]),
    ("iso_only", ["yes", 1, None, True]),
    ("camera", [{"fovy": 0}, {"fovy": 180}, {"fovy": 200}, {"fovy": float("nan")}, {"fovy": "abc"},
                {"eye": (0, 0, 0), "at": (0, 0, 0)}, {"eye": (float("nan"), 0, 0)}, {"at": (float("inf"), 0, 0)},
                {"up": (0, 0, 1)}, {"up": (0, 0, 0)}, {"up": (float("nan"), 0, 1)}, {"view": "bogus"},
                {"view": "+x", "up": (1, 0, 0)}, {"eye": (1, 2)}, {"bogus": 1}]),
])
def test_every_render_keyword_is_checked(keyword, values):
    renderer = uvr.Renderer(uvr.load(DISK))
    for value in values:
        with pytest.raises((uvr.Error, ValueError)) as error:
            renderer.render(size=(8, 8), **{keyword: value}) if keyword != "size" else renderer.render(size=value)
        named = {"camera": ("fovy", "eye", "at", "up", "view", "camera", "bogus")}.get(keyword, (keyword,))
        assert any(name in str(error.value) for name in named), (keyword, value, str(error.value))


def test_compositing_and_steps_as_the_command(tmp_path):
    """The keywords draw what the command's options draw, and the statistics say how each frame was drawn."""
    renderer = uvr.Renderer(uvr.load(DISK), field="Temp")
    camera = {"eye": (40.0, 22.5, 20.08), "at": (0.0, 0.0, 0.08), "up": (0, 0, 1)}
    images = {}
    for compositing, steps in (("point", "global"), ("preintegrated", "local")):
        png, stats_path = tmp_path / f"{compositing}.png", tmp_path / f"{compositing}.json"
        result = run_cli("render", DISK, "--field", "Temp", "--eye", "40,22.5,20.08", "--at", "0,0,0.08", "--up",
                         "0,0,1", "--size", "64x64", "--compositing", compositing, "--steps", steps, "-o", str(png),
                         "--stats", str(stats_path))
        assert result.returncode == 0, result.stderr
        image = renderer.render(camera=camera, size=(64, 64), compositing=compositing, steps=steps)
        np.testing.assert_array_equal(image[:, :, :3], uvr.read_png(str(png)))
        cli_stats = json.loads(stats_path.read_text())
        assert renderer.last_stats["compositing"] == cli_stats["compositing"] == compositing
        assert renderer.last_stats["steps"] == cli_stats["steps"] == steps
        images[compositing] = image
    assert not np.array_equal(images["point"], images["preintegrated"])
    renderer.render(camera=camera, size=(8, 8))
    assert (renderer.last_stats["compositing"], renderer.last_stats["steps"]) == ("preintegrated", "local")
    renderer.render(camera=camera, size=(8, 8), mode="reference")
    assert (renderer.last_stats["compositing"], renderer.last_stats["steps"]) == ("point", "global")


def test_iso_as_the_command(tmp_path):
    """iso, iso_color, iso_opacity and iso_only draw what --iso and its options draw; a surface changes the image."""
    renderer = uvr.Renderer(uvr.load(DISK), field="Temp")
    camera = {"eye": (40.0, 22.5, 20.08), "at": (0.0, 0.0, 0.08), "up": (0, 0, 1)}
    plain = renderer.render(camera=camera, size=(64, 64))
    low, high = renderer.last_stats["range"]
    value = round(0.5 * (low + high), 2)
    for extra, keywords in ((["--iso", repr(value)], {"iso": [value]}),
                            (["--iso", repr(value), "--iso-color", "1,0,0", "--iso-opacity", "0.5", "--iso-only"],
                             {"iso": [value], "iso_color": (1, 0, 0), "iso_opacity": 0.5, "iso_only": True})):
        png = tmp_path / "iso.png"
        result = run_cli("render", DISK, "--field", "Temp", "--eye", "40,22.5,20.08", "--at", "0,0,0.08", "--up",
                         "0,0,1", "--size", "64x64", "-o", str(png), *extra)
        assert result.returncode == 0, result.stderr
        image = renderer.render(camera=camera, size=(64, 64), **keywords)
        np.testing.assert_array_equal(image[:, :, :3], uvr.read_png(str(png)))
        assert not np.array_equal(image, plain)
        assert renderer.last_stats["iso_surfaces"] == 1
        assert renderer.last_stats["iso_only"] == keywords.get("iso_only", False)


def test_shade_as_the_command(tmp_path):
    """shade and light draw what --shade and --light draw; shading changes the image."""
    renderer = uvr.Renderer(uvr.load(DISK), field="Temp")
    camera = {"eye": (40.0, 22.5, 20.08), "at": (0.0, 0.0, 0.08), "up": (0, 0, 1)}
    png = tmp_path / "shaded.png"
    result = run_cli("render", DISK, "--field", "Temp", "--eye", "40,22.5,20.08", "--at", "0,0,0.08", "--up", "0,0,1",
                     "--size", "64x64", "--shade", "--light", "1,1,1", "-o", str(png))
    assert result.returncode == 0, result.stderr
    shaded = renderer.render(camera=camera, size=(64, 64), shade=True, light=(1, 1, 1))
    np.testing.assert_array_equal(shaded[:, :, :3], uvr.read_png(str(png)))
    plain = renderer.render(camera=camera, size=(64, 64))
    assert not np.array_equal(shaded, plain)


def test_every_constructor_keyword_is_checked():
    mesh = uvr.load(DISK)
    for value in (-1, 2 ** 40):
        with pytest.raises((uvr.Error, ValueError), match="leaf_size"):
            uvr.Renderer(mesh, leaf_size=value)
    for rng in ((5, 1), (5, 5), (float("nan"), 1), (0, float("inf"))):
        # Refused where it is given, not at the first frame.
        with pytest.raises((uvr.Error, ValueError), match="range"):
            uvr.TransferFunction("viridis", range=rng)
        with pytest.raises((uvr.Error, ValueError), match="range"):
            uvr.TransferFunction.from_arrays(np.array([[0, 0, 0, 0], [1, 1, 1, 1]], dtype=np.float32), range=rng)
    with pytest.raises((uvr.Error, ValueError), match="view"):
        uvr.Renderer(mesh).default_camera(view="sideways")
    with pytest.raises((uvr.Error, ValueError), match="fovy"):
        uvr.Renderer(mesh).default_camera(fovy=0)


def test_named_views_match_the_command(tmp_path):
    assert uvr.view_names() == ["+x", "-x", "+y", "-y", "+z", "-z", "iso"]
    renderer = uvr.Renderer(uvr.load(DISK))
    at = np.array(renderer.default_camera().at)
    for name in uvr.view_names():
        camera = renderer.default_camera(view=name)
        direction = np.array(camera.eye) - at
        direction /= np.linalg.norm(direction)
        expected = {"+x": (1, 0, 0), "-x": (-1, 0, 0), "+y": (0, 1, 0), "-y": (0, -1, 0), "+z": (0, 0, 1),
                    "-z": (0, 0, -1), "iso": np.ones(3) / np.sqrt(3)}[name]
        np.testing.assert_allclose(direction, expected, atol=1e-6)
        # Framed as the reset camera: the same distance from the focal point.
        assert np.linalg.norm(np.array(camera.eye) - at) == pytest.approx(
            np.linalg.norm(np.array(renderer.default_camera().eye) - at), rel=1e-5)
    png = tmp_path / "iso.png"
    result = run_cli("render", DISK, "--view", "iso", "--size", "48x40", "-o", str(png))
    assert result.returncode == 0, result.stderr
    image = renderer.render(camera={"view": "iso"}, size=(48, 40))
    np.testing.assert_array_equal(image[:, :, :3], uvr.read_png(str(png)))
    assert not np.array_equal(image, renderer.render(size=(48, 40)))


def test_statistics_mean_the_same_as_the_command(tmp_path):
    """tf_update_ms: the transfer-function update the frame waited for (0 when unchanged); build_ms: the
    backend's build, done by the constructor."""
    mesh = uvr.load(DISK)
    started = time.perf_counter()
    renderer = uvr.Renderer(mesh)
    constructed_ms = (time.perf_counter() - started) * 1e3
    tf = uvr.TransferFunction("viridis")
    started = time.perf_counter()
    renderer.render(size=(16, 16), tf=tf)
    first_ms = (time.perf_counter() - started) * 1e3
    first = renderer.last_stats
    assert first["build_ms"] <= constructed_ms + 1.0, (first, constructed_ms)
    assert 0 < first["tf_update_ms"] < first_ms
    assert first["tf_update_ms"] != first["build_ms"]
    renderer.render(size=(16, 16), tf=tf)
    assert renderer.last_stats["tf_update_ms"] == 0
    assert renderer.last_stats["build_ms"] == first["build_ms"]
    renderer.render(size=(16, 16), tf=uvr.TransferFunction("inferno"))
    assert renderer.last_stats["tf_update_ms"] > 0
    # The command's --stats: the same definitions.
    stats_path = tmp_path / "s.json"
    result = run_cli("render", DISK, "--size", "16x16", "--tf", "viridis", "--frames", "2", "-o",
                     str(tmp_path / "s.png"), "--stats", str(stats_path))
    assert result.returncode == 0, result.stderr
    cli = json.loads(stats_path.read_text())
    assert 0 < cli["tf_update_ms"] < cli["build_ms"] + cli["render_ms"] and cli["tf_update_ms"] != cli["build_ms"]


def test_psnr_of_identical_images_is_infinite(tmp_path):
    image = uvr.Renderer(uvr.load(DISK)).render(size=(16, 16))
    result = uvr.compare(image, image)
    assert result["ssim"] == 1.0 and result["psnr"] == float("inf")
    png = tmp_path / "a.png"
    uvr.write_png(str(png), image)
    assert "PSNR inf dB" in run_cli("compare", str(png), str(png)).stdout
    assert json.loads(run_cli("compare", str(png), str(png), "--json").stdout)["psnr"] is None


def test_a_constant_field_is_visible():
    points, cells, celltypes, _, _ = box_grid(2)
    mesh = uvr.Mesh(points, cells, celltypes, point_data={"c": np.full(len(points), 7.0)})
    image = uvr.Renderer(mesh).render(size=(16, 16))
    assert image[8, 8, 3] > 0


def test_cuda_backend_as_the_command(tmp_path):
    """Whatever this build and machine have, the module does what the command does: fails with its message
    (no CUDA at build time, or no GPU) or renders the same image."""
    png = tmp_path / "cuda.png"
    result = run_cli("render", DISK, "--backend", "cuda", "--size", "64x64", "-o", str(png))
    if result.returncode != 0:
        assert result.returncode == 2, result.stderr
        message = result.stderr.strip().splitlines()[-1].removeprefix("uvr: error: ")
        with pytest.raises(uvr.Error) as error:
            uvr.Renderer(uvr.load(DISK), backend="cuda").render(size=(64, 64))
        assert str(error.value) == message
    else:
        renderer = uvr.Renderer(uvr.load(DISK), backend="cuda")
        image = renderer.render(size=(64, 64))
        assert uvr.compare(image, uvr.read_png(str(png)))["ssim"] >= 0.999
        assert renderer.last_stats["backend"] == "cuda"


def test_input_errors():
    points, cells, celltypes, point_data, _ = box_grid(2)
    with pytest.raises(uvr.Error, match="point index"):
        uvr.Mesh(points, np.where(cells == 8, 8, cells + 1000), celltypes)
    with pytest.raises(uvr.Error, match="ends inside the cell"):
        uvr.Mesh(points, cells[:-1], celltypes)
    with pytest.raises(uvr.Error, match="offsets"):
        uvr.Mesh(points, cells, celltypes, offsets=np.zeros(3, dtype=np.int64))
    with pytest.raises(uvr.Error, match="do not span"):
        offsets = np.arange(len(celltypes) + 1, dtype=np.int64) * 100
        uvr.Mesh(points, cells, celltypes, offsets=offsets)
    with pytest.raises(uvr.Error, match="has 3 values for 27 points"):
        uvr.Mesh(points, cells, celltypes, point_data={"short": np.zeros(3)})
    with pytest.raises(uvr.Error, match="time steps"):
        uvr.load(DISK, time_step=3)
    assert uvr.load(DISK, field="Temp").field_names == ["Temp"]


def graded_ticks(n, length, first):
    """n + 1 ticks from 0 to `length`, spacings growing geometrically from `first`."""
    lo, hi = 1.0 + 1e-9, 2.0
    for _ in range(100):
        ratio = (lo + hi) / 2
        lo, hi = (lo, ratio) if first * (ratio ** n - 1) / (ratio - 1) > length else (ratio, hi)
    ticks = np.concatenate([[0.0], np.cumsum(first * ratio ** np.arange(n))])
    return ticks * length / ticks[-1]


def test_default_opacity_unit_follows_the_domain_not_the_finest_cells():
    """A 20 m tunnel graded down to 1.6 cm at its walls: the default unit is ParaView's (diagonal / cbrt(cells)),
    and the image shows more of the field than with a unit of the median cell (the earlier default)."""
    xs, ys, zs = graded_ticks(24, 20.0, 0.016), graded_ticks(8, 4.0, 0.016), graded_ticks(8, 4.0, 0.016)
    z, y, x = np.meshgrid(zs, ys, xs, indexing="ij")
    points = np.stack([x.ravel(), y.ravel(), z.ravel()], axis=1)
    nx, ny = len(xs), len(ys)
    index = lambda i, j, k: (k * ny + j) * nx + i
    cells = [[8, index(i, j, k), index(i + 1, j, k), index(i + 1, j + 1, k), index(i, j + 1, k), index(i, j, k + 1),
              index(i + 1, j, k + 1), index(i + 1, j + 1, k + 1), index(i, j + 1, k + 1)]
             for k in range(len(zs) - 1) for j in range(ny - 1) for i in range(nx - 1)]
    mesh = uvr.Mesh(points, np.array(cells, dtype=np.int64).ravel(), np.full(len(cells), 12, dtype=np.uint8),
                    point_data={"f": np.sin(points[:, 0] / 3) + points[:, 1] / 4})
    renderer = uvr.Renderer(mesh)
    image = renderer.render(size=(128, 128), camera={"view": "-y"})
    stats = renderer.last_stats
    assert stats["unit"] == pytest.approx(np.sqrt(20 ** 2 + 4 ** 2 + 4 ** 2) / len(cells) ** (1 / 3), rel=1e-5)
    thin = renderer.render(size=(128, 128), camera={"view": "-y"}, unit=stats["s1"])
    spread = lambda img: img[:, :, :3].astype(float).mean(axis=2)[img[:, :, 3] > 0].std()
    # Converged images (reference, s1 / 8) of the two units differ by 1.13x in spread.
    assert spread(image) > 1.1 * spread(thin)


def test_set_field_keeps_the_grid_and_renders_as_a_new_renderer():
    """A later step on the same grid: set_field renders it as a renderer built for it; another grid is refused."""
    points, cells, celltypes, point_data, _ = box_grid(4)
    step = [uvr.Mesh(points, cells, celltypes, point_data={"p": point_data["wave"] * scale}) for scale in (1.0, 0.3)]
    tf = uvr.TransferFunction("viridis", range=(-1.0, 2.0))
    kept = uvr.Renderer(step[0], field="p")
    first = kept.render(tf=tf, size=(48, 48))
    kept.set_field(step[1], field="p")
    second = kept.render(tf=tf, size=(48, 48))
    np.testing.assert_array_equal(second, uvr.Renderer(step[1], field="p").render(tf=tf, size=(48, 48)))
    assert not np.array_equal(first, second)
    moved = points.copy()
    moved[0, 0] += 0.01
    with pytest.raises(uvr.Error, match="differ"):
        kept.set_field(uvr.Mesh(moved, cells, celltypes, point_data={"p": point_data["wave"]}), field="p")
    np.testing.assert_array_equal(kept.render(tf=tf, size=(48, 48)), second)
