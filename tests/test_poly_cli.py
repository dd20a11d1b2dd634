#!/usr/bin/env python3
"""Polyhedra and field centrings through the command: `uvr info` on a polyhedral .vtu and a legacy .vtk
(counts, JSON keys), a point and a cell field of one name (both listed, each rendered by its prefix), and
`uvr render` of polyhedra against their hexahedral twin compared with `uvr compare`.

Usage: test_poly_cli.py UVR_BINARY SHARED_DATA_DIR
"""
import json
import os
import subprocess
import sys
import tempfile


def run(command, expect=0):
    result = subprocess.run(command, capture_output=True, text=True)
    if result.returncode != expect:
        sys.exit(f"FAIL: {' '.join(command)} exited with {result.returncode}, expected {expect}:\n"
                 f"{result.stderr.strip()}")
    return result


def cube(n, poly):
    """n^3 unit-cube hexahedra as (points, cells, types, faces): polyhedra (type 42) where poly(c)."""
    m = n + 1
    points = [(i / n, j / n, k / n) for k in range(m) for j in range(m) for i in range(m)]
    cells, types, faces = [], [], []
    for k in range(n):
        for j in range(n):
            for i in range(n):
                at = lambda a, b, c: (k + c) * m * m + (j + b) * m + i + a
                v = [at(0, 0, 0), at(1, 0, 0), at(1, 1, 0), at(0, 1, 0),
                     at(0, 0, 1), at(1, 0, 1), at(1, 1, 1), at(0, 1, 1)]
                poly_cell = poly(len(cells))
                cells.append(v)
                types.append(42 if poly_cell else 12)
                faces.append([[v[0], v[3], v[2], v[1]], [v[4], v[5], v[6], v[7]], [v[0], v[1], v[5], v[4]],
                              [v[1], v[2], v[6], v[5]], [v[2], v[3], v[7], v[6]], [v[3], v[0], v[4], v[7]]]
                             if poly_cell else None)
    return points, cells, types, faces


def linear(point):
    """The point field p."""
    x, y, z = point
    return x + 2 * y + 3 * z


def cell_p(grid):
    """The cell field p: the point field p at each cell's centre, as a finite-volume result's cell mean (a
    polyhedron's centre point takes it)."""
    points, cells = grid[0], grid[1]
    return [linear([sum(points[i][k] for i in c) / len(c) for k in range(3)]) for c in cells]


def stream(faces):
    s = [len(faces)]
    for f in faces:
        s += [len(f)] + f
    return s


def write_vtu(path, grid):
    points, cells, types, faces = grid
    text = lambda values: " ".join(str(v) for v in values)
    offsets, end = [], 0
    for c in cells:
        end += len(c)
        offsets.append(end)
    face_stream, face_offsets = [], []
    for t, f in zip(types, faces):
        if t == 42:
            face_stream += stream(f)
        face_offsets.append(len(face_stream) if t == 42 else -1)
    p_point = [linear(p) for p in points]
    p_cell = cell_p(grid)
    arrays = (f'<DataArray type="Int64" Name="faces" format="ascii">{text(face_stream)}</DataArray>\n'
              f'<DataArray type="Int64" Name="faceoffsets" format="ascii">{text(face_offsets)}</DataArray>\n'
              if 42 in types else "")
    with open(path, "w") as out:
        out.write(f"""<?xml version="1.0"?>
<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian">
<UnstructuredGrid><Piece NumberOfPoints="{len(points)}" NumberOfCells="{len(cells)}">
<PointData><DataArray type="Float32" Name="p" format="ascii">{text(p_point)}</DataArray></PointData>
<CellData><DataArray type="Float32" Name="p" format="ascii">{text(p_cell)}</DataArray></CellData>
<Points><DataArray type="Float32" NumberOfComponents="3" format="ascii">{text(x for p in points for x in p)}</DataArray></Points>
<Cells>
<DataArray type="Int64" Name="connectivity" format="ascii">{text(i for c in cells for i in c)}</DataArray>
<DataArray type="Int64" Name="offsets" format="ascii">{text(offsets)}</DataArray>
<DataArray type="UInt8" Name="types" format="ascii">{text(types)}</DataArray>
{arrays}</Cells>
</Piece></UnstructuredGrid></VTKFile>
""")


def write_vtk(path, grid):
    """Legacy 4.2 ascii: a polyhedron's CELLS entry is its face stream; cell data before point data."""
    points, cells, types, faces = grid
    entries = [stream(f) if t == 42 else c for c, t, f in zip(cells, types, faces)]
    lines = ["# vtk DataFile Version 4.2", "poly", "ASCII", "DATASET UNSTRUCTURED_GRID",
             f"POINTS {len(points)} float"]
    lines += [f"{x} {y} {z}" for x, y, z in points]
    lines.append(f"CELLS {len(entries)} {sum(len(e) + 1 for e in entries)}")
    lines += [" ".join(str(v) for v in [len(e)] + e) for e in entries]
    lines += [f"CELL_TYPES {len(types)}"] + [str(t) for t in types]
    lines += [f"CELL_DATA {len(cells)}", "SCALARS p float", "LOOKUP_TABLE default"]
    lines += [str(v) for v in cell_p(grid)]
    lines += [f"POINT_DATA {len(points)}", "SCALARS p float", "LOOKUP_TABLE default"]
    lines += [str(linear(p)) for p in points]
    with open(path, "w") as out:
        out.write("\n".join(lines) + "\n")


def main():
    uvr = sys.argv[1]
    with tempfile.TemporaryDirectory() as tmp:
        out = lambda name: os.path.join(tmp, name)
        write_vtu(out("twin.vtu"), cube(3, lambda c: False))
        write_vtu(out("poly.vtu"), cube(3, lambda c: True))
        write_vtk(out("poly.vtk"), cube(3, lambda c: c % 2 == 0))

        for name, polyhedra in (("poly.vtu", 27), ("poly.vtk", 14)):
            stats = json.loads(run([uvr, "info", out(name), "--json"]).stdout)
            expected = {"polyhedron": polyhedra, "tet": 0, "pyramid": 6 * polyhedra}
            if stats["polyhedra"] != expected:
                sys.exit(f"FAIL: {name}: polyhedra {stats['polyhedra']}, expected {expected}")
            if stats["cell_types"]["pyramid"] != 6 * polyhedra or stats["cell_types"]["hex"] != 27 - polyhedra:
                sys.exit(f"FAIL: {name}: cell types {stats['cell_types']}")
            if stats["inverted_cells"] != 0:
                sys.exit(f"FAIL: {name}: {stats['inverted_cells']} inverted cells")
            fields = sorted((f["name"], f["centering"]) for f in stats["fields"])
            if fields != [("p", "cell"), ("p", "point")]:
                sys.exit(f"FAIL: {name}: fields {stats['fields']}")
            text = run([uvr, "info", out(name)]).stdout
            line = f"polyhedron      {polyhedra} (decomposed into 0 tetrahedra, {6 * polyhedra} pyramids)"
            if line not in text or "p (point)" not in text or "p (cell)" not in text:
                sys.exit(f"FAIL: {name}: uvr info says:\n{text}")
        twin = json.loads(run([uvr, "info", out("twin.vtu"), "--json"]).stdout)
        if twin["polyhedra"]["polyhedron"] != 0:
            sys.exit(f"FAIL: twin.vtu: polyhedra {twin['polyhedra']}")

        # A fixed step: the default follows the cell volumes, which the decomposition changes.
        view = ["--size", "160x160", "--mode", "reference", "--s1", "0.005", "--unit", "0.15",
                "--eye", "2.6,2.1,3.3", "--at", "0.5,0.5,0.5"]

        def render(name, field):
            png = out(f"{name}-{field.replace(':', '_')}.png")
            run([uvr, "render", out(name), "--field", field, "-o", png] + view)
            return png

        def similarity(a, b):
            return json.loads(run([uvr, "compare", a, b, "--json"]).stdout)["ssim"]

        for field in ("point:p", "cell:p", "p"):
            for name in ("poly.vtu", "poly.vtk"):
                value = similarity(render("twin.vtu", field), render(name, field))
                if value < 0.999:
                    sys.exit(f"FAIL: {name} --field {field}: SSIM {value} against its hexahedral twin")
        # The prefixes choose different fields; the plain name is the point field in both formats.
        for name in ("twin.vtu", "poly.vtk"):
            if similarity(render(name, "point:p"), render(name, "cell:p")) > 0.99:
                sys.exit(f"FAIL: {name}: point:p and cell:p render alike")
            if similarity(render(name, "point:p"), render(name, "p")) != 1.0:
                sys.exit(f"FAIL: {name}: --field p is not the point field")
        missing = run([uvr, "render", out("twin.vtu"), "--field", "cell:q", "-o", out("x.png")], expect=2)
        if "point:p, cell:p" not in missing.stderr:
            sys.exit(f"FAIL: a missing field's error does not list both p: {missing.stderr}")
    print("ok")


if __name__ == "__main__":
    main()
