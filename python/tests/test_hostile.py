"""Issue 31 in the module: one Renderer shared by threads, meshes built while other threads write into their
arrays, and arrays checked as the file readers check files.

Run by ctest with test_uvr.py (python/CMakeLists.txt).
"""
import os
import threading

import numpy as np
import pytest

import uvr

SOURCE_DIR = os.environ.get("UVR_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))
DISK = os.path.join(SOURCE_DIR, "data", "disk_out_ref.vtu")

TET = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=np.float64)
TET_CELLS = np.array([4, 0, 1, 2, 3], dtype=np.int64)
TET_TYPES = np.array([10], dtype=np.uint8)


def test_one_renderer_shared_by_threads_each_with_its_transfer_function():
    renderer = uvr.Renderer(uvr.load(DISK))  # built lazily, by whichever thread renders first
    functions = [uvr.TransferFunction(name) for name in ("viridis", "inferno", "grayscale", "Cool to Warm")]
    alone = uvr.Renderer(uvr.load(DISK))
    expected = [alone.render(size=(48, 48), tf=tf) for tf in functions]
    assert not np.array_equal(expected[0], expected[1])
    wrong, errors = [], []

    def work(t):
        try:
            for _ in range(10):
                if not np.array_equal(renderer.render(size=(48, 48), tf=functions[t]), expected[t]):
                    wrong.append(t)
        except Exception as e:  # noqa: BLE001 - any failure is the finding
            errors.append(repr(e))

    threads = [threading.Thread(target=work, args=(t,)) for t in range(4)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    assert errors == []
    assert wrong == [], f"{len(wrong)} of 40 frames wrong"


def test_mesh_built_while_another_thread_writes_its_arrays():
    mesh = uvr.load(DISK)
    points = np.array(mesh.points, dtype=np.float64)
    cells, celltypes = np.array(mesh.cells), np.array(mesh.celltypes)
    stop = threading.Event()

    def scribble():
        rng = np.random.default_rng(1)
        while not stop.is_set():  # counts and indices changing between any two reads
            cells[rng.integers(0, len(cells), 64)] = rng.integers(-5, 1 << 40, 64)
            celltypes[rng.integers(0, len(celltypes), 8)] = rng.integers(0, 256, 8)

    writer = threading.Thread(target=scribble)
    writer.start()
    built = refused = 0
    try:
        for _ in range(30):
            try:
                uvr.Mesh(points, cells, celltypes)
                built += 1
            except uvr.Error:
                refused += 1
    finally:
        stop.set()
        writer.join()
    assert built + refused == 30


@pytest.mark.parametrize("bad, message", [
    (np.nan, "not finite"), (np.inf, "not finite"), (-np.inf, "not finite"), (1e39, "out of float range"),
])
def test_points_checked_as_the_readers_check_files(bad, message):
    points = TET.copy()
    points[2, 1] = bad
    with pytest.raises(uvr.Error, match=f"point 2.*{message}"):
        uvr.Mesh(points, TET_CELLS, TET_TYPES)


@pytest.mark.parametrize("cells", [
    TET_CELLS.astype(np.float64), TET_CELLS.astype(np.float64) + 0.5, TET_CELLS.astype(str),
])
def test_cells_must_be_integers(cells):
    with pytest.raises(uvr.Error, match="cells must hold integers"):
        uvr.Mesh(TET, cells, TET_TYPES)
    offsets = np.array([0, 4], dtype=np.int64)
    with pytest.raises(uvr.Error, match="must hold integers"):
        uvr.Mesh(TET, cells[1:], TET_TYPES, offsets=offsets.astype(cells.dtype))


@pytest.mark.parametrize("types, message", [
    (np.array([266]), "cell type 266 is not a VTK type code"),
    (np.array([-246]), "cell type -246 is not a VTK type code"),
    (np.array([10.9]), "celltypes must hold integers"),
    (np.array([2 ** 63 + 10], dtype=np.uint64), "out of range"),
])
def test_cell_types_are_not_wrapped(types, message):
    with pytest.raises(uvr.Error, match=message):
        uvr.Mesh(TET, TET_CELLS, types)
    assert uvr.Mesh(TET, TET_CELLS, np.array([10], dtype=np.int64)).n_cells == 1


def test_points_and_fields_must_be_numbers():
    with pytest.raises(uvr.Error, match="points must hold numbers"):
        uvr.Mesh(TET.astype(str), TET_CELLS, TET_TYPES)
    with pytest.raises(uvr.Error, match="field 'f' must hold numbers"):
        uvr.Mesh(TET, TET_CELLS, TET_TYPES, point_data={"f": np.array(["a", "b", "c", "d"])})


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf, 1e39])
def test_transfer_function_arrays_must_be_finite(bad):
    colors = np.array([[0, 0, 0, 0], [1, 1, 1, 1]], dtype=np.float64)
    opacities = np.array([[0, 0], [1, 1]], dtype=np.float64)
    bad_colors = colors.copy()
    bad_colors[1, 2] = bad
    with pytest.raises(uvr.Error, match="colors must be finite"):
        uvr.TransferFunction.from_arrays(bad_colors, opacities)
    bad_opacities = opacities.copy()
    bad_opacities[0, 0] = bad
    with pytest.raises(uvr.Error, match="opacities must be finite"):
        uvr.TransferFunction.from_arrays(colors, bad_opacities)
    with pytest.raises(uvr.Error, match="range .* both finite"):
        uvr.TransferFunction.from_arrays(colors, opacities, range=(0.0, bad))
    uvr.TransferFunction.from_arrays(colors, opacities, range=(0.0, 1.0))


def test_frame_beyond_the_memory_limit_is_refused_at_once():
    renderer = uvr.Renderer(uvr.load(DISK))
    with pytest.raises(uvr.Error, match="16384x16384 frame needs 8.0 GiB, over the memory limit"):
        renderer.render(size=(16384, 16384))
