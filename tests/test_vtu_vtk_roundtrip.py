#!/usr/bin/env python3
"""Checks that VTK reads the .vtu files uvr writes, and that they hold what the input held.

Usage: test_vtu_vtk_roundtrip.py UVR_BINARY SHARED_DATA_DIR

Each input (of the shared data) is converted by `uvr convert` to .vtu (raw and zlib) and through .umesh back
to .vtu. VTK 9.1's own readers (Debian python3-vtk9) read the input and uvr's output; they must agree on the
number of points, the volume cells by type, the points, every cell's corners and every field value. uvr
reorders points and cells spatially and rewinds inverted cells, so points are compared as sorted arrays
(with their field values) and cells by their sorted corner coordinates (with their cell values).
Multi-component arrays of the input are compared as their magnitudes, which is what uvr keeps.
"""
import os
import subprocess
import sys
import tempfile

try:
    import numpy as np
    from vtkmodules.util.numpy_support import vtk_to_numpy
    from vtkmodules.vtkIOLegacy import vtkUnstructuredGridReader
    from vtkmodules.vtkIOXML import vtkXMLUnstructuredGridReader
except ImportError as error:
    sys.exit(f"test_vtu_vtk_roundtrip: needs numpy and VTK (Debian python3-vtk9): {error}")

# Inputs of the shared data with only linear volume cells (and lower-dimensional ones, which uvr drops).
INPUTS = ["small/uGridEx.vtk", "small/pyramid_ug.vtu", "small/fieldfile.vtk", "small/sfepy_cylinder.vtk",
          "medium/disk_out_ref.vtu"]
VOLUME_TYPES = {10: "tet", 11: "hex", 12: "hex", 13: "wedge", 14: "pyramid"}


def run(command):
    result = subprocess.run(command, capture_output=True, text=True)
    if result.returncode != 0:
        sys.exit(f"FAIL: {' '.join(command)} exited with {result.returncode}:\n{result.stderr.strip()}")


def read_vtk(path):
    reader = vtkXMLUnstructuredGridReader() if path.endswith(".vtu") else vtkUnstructuredGridReader()
    reader.SetFileName(path)
    if path.endswith(".vtk"):
        reader.ReadAllScalarsOn()
        reader.ReadAllVectorsOn()
        reader.ReadAllFieldsOn()
    reader.Update()
    grid = reader.GetOutput()
    if grid is None or grid.GetNumberOfPoints() == 0:
        sys.exit(f"FAIL: VTK read no points from {path}")
    return grid


def arrays(data):
    """Numeric arrays by name, several components as their magnitude."""
    result = {}
    for i in range(data.GetNumberOfArrays()):
        array = data.GetArray(i)
        if array is None:
            continue
        values = vtk_to_numpy(array).astype(np.float64)
        if values.ndim == 2:
            values = np.linalg.norm(values, axis=1)
        result[array.GetName()] = values
    return result


def describe(grid):
    """Points and volume cells as comparable arrays: sorted rows of coordinates, with field values."""
    points = vtk_to_numpy(grid.GetPoints().GetData()).astype(np.float32).astype(np.float64)
    point_fields = arrays(grid.GetPointData())
    all_cell_fields = arrays(grid.GetCellData())
    cells, kept, counts = {}, {}, {}
    for c in range(grid.GetNumberOfCells()):
        kind = VOLUME_TYPES.get(grid.GetCellType(c))
        if kind is None:
            continue
        ids = grid.GetCell(c).GetPointIds()
        corners = sorted(tuple(points[ids.GetId(i)]) for i in range(ids.GetNumberOfIds()))
        cells.setdefault(kind, []).append(np.array(corners).ravel())
        kept.setdefault(kind, []).append(c)
        counts[kind] = counts.get(kind, 0) + 1

    point_order = np.lexsort(points.T[::-1])
    described = {"counts": counts, "points": points[point_order]}
    for name, values in point_fields.items():
        described["point " + name] = values[point_order].astype(np.float32)
    for kind, rows in cells.items():
        rows = np.array(rows)
        order = np.lexsort(rows.T[::-1])
        described[kind + " cells"] = rows[order]
        for name, values in all_cell_fields.items():
            described[f"{kind} cell {name}"] = values[np.array(kept[kind])][order].astype(np.float32)
    return described


def compare(name, expected, got, failures):
    if expected.keys() != got.keys():
        failures.append(f"{name}: arrays differ: {sorted(expected.keys() ^ got.keys())}")
        return
    for key in expected:
        a, b = expected[key], got[key]
        if key == "counts":
            ok = a == b
        else:
            ok = a.shape == b.shape and np.array_equal(a, b)
        if not ok:
            failures.append(f"{name}: {key} differs")


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    uvr, shared = sys.argv[1], sys.argv[2]
    failures, checked = [], 0
    with tempfile.TemporaryDirectory() as tmp:
        for relative in INPUTS:
            source = os.path.join(shared, relative)
            if not os.path.exists(source):
                failures.append(f"{relative}: missing")
                continue
            expected = describe(read_vtk(source))
            stem = os.path.join(tmp, os.path.basename(relative).replace(".", "_"))
            outputs = [stem + ".vtu", stem + "_zlib.vtu"]
            run([uvr, "convert", source, outputs[0]])
            run([uvr, "convert", source, outputs[1], "--zlib"])
            cell_fields = sorted({key.split(" cell ", 1)[1] for key in expected if " cell " in key})
            point_fields = [key for key in expected if key.startswith("point ")]
            umesh_expected = {k: v for k, v in expected.items() if " cell " not in k}
            umesh = stem + ".umesh"
            # .umesh holds point fields only: cell fields are dropped and named in one line; a mesh with no
            # point field, or a cell field asked for by --field, is refused.
            result = subprocess.run([uvr, "convert", source, umesh], capture_output=True, text=True)
            if point_fields:
                wrote = [line for line in result.stderr.splitlines() if line.startswith("uvr: wrote")]
                if result.returncode != 0 or not wrote or f", {len(point_fields)} fields" not in wrote[0]:
                    failures.append(f"{relative} -> .umesh: exit {result.returncode}, expected {len(point_fields)} "
                                    f"fields written: {result.stderr.strip()}")
                dropped = [line for line in result.stderr.splitlines() if "dropped cell field" in line]
                if cell_fields and (len(dropped) != 1 or not all(f"'{n}'" in dropped[0] for n in cell_fields)):
                    failures.append(f"{relative} -> .umesh: cell fields {cell_fields} not named in one line: "
                                    f"{result.stderr.strip()}")
                if not cell_fields and dropped:
                    failures.append(f"{relative} -> .umesh: reports dropped fields it has not: {dropped}")
                if result.returncode == 0:
                    via = stem + "_via_umesh.vtu"
                    run([uvr, "convert", umesh, via])
                    compare(f"{relative} -> {os.path.basename(via)}", umesh_expected, describe(read_vtk(via)),
                            failures)
                    checked += 1
            elif result.returncode != 2 or "cell field" not in result.stderr or os.path.exists(umesh):
                failures.append(f"{relative} -> .umesh: expected a refusal (no point field), got "
                                f"{result.returncode}: {result.stderr.strip()}")
            if cell_fields:
                refused = subprocess.run([uvr, "convert", source, umesh + "2.umesh", "--field", cell_fields[0]],
                                         capture_output=True, text=True)
                if refused.returncode != 2 or "is a cell field" not in refused.stderr or "--field" not in refused.stderr:
                    failures.append(f"{relative} -> .umesh --field {cell_fields[0]}: expected a refusal naming "
                                    f"--field, got {refused.returncode}: {refused.stderr.strip()}")
            for output in outputs:
                compare(f"{relative} -> {os.path.basename(output)}", expected, describe(read_vtk(output)),
                        failures)
                checked += 1
    for failure in failures:
        print("FAIL:", failure)
    if failures:
        sys.exit(1)
    print(f"VTK read {checked} files written by uvr, all matching their inputs")


if __name__ == "__main__":
    main()
