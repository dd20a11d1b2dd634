#!/usr/bin/python3
"""Issue 31 through the command: hostile input gets exit status 2 and a message saying what is wrong, at
once (a FIFO, a frame over the memory limit, a 5000-character path, a field name XML cannot hold, a NIfTI
with a NaN affine), and the memory limit is set by --memory-limit or UVR_MEMORY_LIMIT.

Usage: test_hostile_cli.py UVR_BINARY SHARED_DATA
"""
import os
import struct
import subprocess
import sys
import tempfile

failures = []


def run(uvr, *args, env=None, timeout=60):
    try:
        return subprocess.run([uvr, *args], capture_output=True, text=True, errors="replace", timeout=timeout,
                              env=env)
    except subprocess.TimeoutExpired:
        failures.append(f"uvr {' '.join(args)[:200]}: still running after {timeout} s")
        return None


def expect_error(uvr, args, expected, env=None, timeout=60):
    result = run(uvr, *args, env=env, timeout=timeout)
    if result is None:
        return
    last = result.stderr.strip().splitlines()[-1] if result.stderr.strip() else ""
    what = f"uvr {' '.join(args)[:160]}"
    if result.returncode != 2:
        failures.append(f"{what}: exit status {result.returncode}, expected 2; stderr {result.stderr[-500:]!r}")
    elif expected not in last:
        failures.append(f"{what}: expected {expected!r} in {last[:500]!r}")
    elif len(last) > 4000:
        failures.append(f"{what}: a {len(last)}-character message")


def nifti(path, sform):
    header = bytearray(352)
    struct.pack_into("<i", header, 0, 348)
    struct.pack_into("<8h", header, 40, 3, 8, 8, 8, 1, 1, 1, 1)
    struct.pack_into("<hh", header, 70, 2, 8)
    struct.pack_into("<4f", header, 76, 1, 1, 1, 1)
    struct.pack_into("<f", header, 108, 352)
    struct.pack_into("<h", header, 254, 1)
    struct.pack_into("<12f", header, 280, *sform)
    header[344:348] = b"n+1\0"
    with open(path, "wb") as f:
        f.write(bytes(header) + bytes(range(256)) * 2)


def graded_tets_vtu():
    """One tet of edge 1000 and two of edge 1e-6, as ASCII .vtu."""
    points = [(0, 0, 0), (1000, 0, 0), (0, 1000, 0), (0, 0, 1000)]
    for base in ((10, 10, 10), (20, 20, 20)):
        points += [base, (base[0] + 1e-6, base[1], base[2]), (base[0], base[1] + 1e-6, base[2]),
                   (base[0], base[1], base[2] + 1e-6)]
    coords = " ".join(f"{c:.9g}" for p in points for c in p)
    values = " ".join(str(i) for i in range(len(points)))
    return (f'<VTKFile type="UnstructuredGrid" version="1.0"><UnstructuredGrid><Piece NumberOfPoints="12" '
            f'NumberOfCells="3"><PointData><DataArray type="Float32" Name="f" format="ascii">{values}</DataArray>'
            f'</PointData><Points><DataArray type="Float64" NumberOfComponents="3" format="ascii">{coords}'
            '</DataArray></Points><Cells><DataArray type="Int64" Name="connectivity" format="ascii">'
            '0 1 2 3 4 5 6 7 8 9 10 11</DataArray><DataArray type="Int64" Name="offsets" format="ascii">4 8 12'
            '</DataArray><DataArray type="UInt8" Name="types" format="ascii">10 10 10</DataArray></Cells>'
            '</Piece></UnstructuredGrid></VTKFile>')


def main():
    uvr, shared = sys.argv[1], sys.argv[2]
    mesh = os.path.join(shared, "small", "pyramid_ug.vtu")
    with tempfile.TemporaryDirectory(prefix="uvr_hostile_cli_") as tmp:
        png = os.path.join(tmp, "out.png")
        # A FIFO blocks open() unless refused first: as the mesh, in a collection, as --tf.
        fifo = os.path.join(tmp, "pipe.vtu")
        os.mkfifo(fifo)
        expect_error(uvr, ["info", fifo], "not a regular file", timeout=20)
        pvd = os.path.join(tmp, "pipe.pvd")
        with open(pvd, "w") as f:
            f.write('<VTKFile type="Collection"><Collection><DataSet file="pipe.vtu"/></Collection></VTKFile>')
        expect_error(uvr, ["info", pvd], "not a regular file", timeout=20)
        tf_fifo = os.path.join(tmp, "pipe.json")
        os.mkfifo(tf_fifo)
        expect_error(uvr, ["render", mesh, "--tf", tf_fifo, "-o", png], "not a regular file", timeout=20)

        # The frame's buffers against the memory limit: the default, the option, the environment.
        expect_error(uvr, ["render", mesh, "--size", "16384x16384", "-o", png], "over the memory limit of 4.0 GiB",
                     timeout=20)
        expect_error(uvr, ["render", mesh, "--size", "64x64", "--memory-limit", "64K", "-o", png],
                     "a 64x64 frame needs 128.0 KiB, over the memory limit of 64.0 KiB")
        env = dict(os.environ, UVR_MEMORY_LIMIT="100K")
        expect_error(uvr, ["render", mesh, "--size", "64x64", "-o", png], "over the memory limit of 100.0 KiB",
                     env=env)
        result = run(uvr, "render", mesh, "--size", "64x64", "--memory-limit", "1M", "-o", png, env=env)
        if result is not None and (result.returncode != 0 or not os.path.exists(png)):
            failures.append(f"--memory-limit 1M did not raise the environment's limit: {result.stderr[-300:]}")
        expect_error(uvr, ["info", mesh, "--memory-limit", "lots"], "memory limit 'lots' is malformed")

        # A 5000-character path: an error saying so, not a std::filesystem exception.
        long_tf = os.path.join(tmp, "x" * 5000)
        expect_error(uvr, ["render", mesh, "--tf", long_tf, "-o", png], "File name too long")
        expect_error(uvr, ["render", mesh, "--tf", long_tf + ".json", "-o", png], "File name too long")
        expect_error(uvr, ["info", long_tf + ".vtu"], "File name too long")

        # A field name with %00 (legacy VTK's escape of NUL): convert refuses it rather than write a .vtu
        # that no reader takes.
        vtk = os.path.join(tmp, "nul.vtk")
        with open(os.path.join(shared, "small", "uGridEx.vtk"), "rb") as f:
            grid = f.read()
        with open(vtk, "wb") as f:
            f.write(grid.replace(b"SCALARS scalars float", b"SCALARS sca%00lars float", 1))
        expect_error(uvr, ["convert", vtk, os.path.join(tmp, "nul.vtu")], "control character 0")

        # Steps: a step taking more than 10^4 samples along the diagonal is warned of, more than 2^20 refused;
        # the default step of a mesh of one large and two tiny tets stays within 10^4 (it used to take 5.6e-7,
        # and the march never ended); a camera too far for the step is refused, not marched in place.
        disk = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "data", "disk_out_ref.vtu")
        result = run(uvr, "render", disk, "--s1", "0.002", "--size", "8x8", "-o", png, timeout=60)
        if result is not None and (result.returncode != 0 or "warning: --s1 0.002 takes" not in result.stderr):
            failures.append(f"--s1 0.002: no warning of the samples it takes: {result.stderr[-300:]!r}")
        expect_error(uvr, ["render", disk, "--s1", "1e-9", "--size", "8x8", "-o", png], "a ray may take",
                     timeout=20)
        expect_error(uvr, ["render", disk, "--eye", "3,3,1e30", "--up", "1,0,0", "--size", "8x8", "-o", png],
                     "too far from the mesh", timeout=20)
        graded = os.path.join(tmp, "graded.vtu")
        with open(graded, "w") as f:
            f.write(graded_tets_vtu())
        stats = os.path.join(tmp, "graded.json")
        result = run(uvr, "render", graded, "--size", "32x32", "-o", png, "--stats", stats, timeout=20)
        if result is not None:
            if result.returncode != 0:
                failures.append(f"one large and two tiny tets: exit {result.returncode}: {result.stderr[-300:]!r}")
            else:
                import json
                with open(stats) as f:
                    s1 = json.load(f)["s1"]
                if not s1 >= 1e-4 * 1000:
                    failures.append(f"one large and two tiny tets: default s1 {s1}, below 1e-4 of the diagonal")

        # uvr gen on a NIfTI with a NaN in its sform.
        nii = os.path.join(tmp, "nan.nii")
        nifti(nii, [1, 0, 0, 0, 0, float("nan"), 0, 0, 0, 0, 1, 0])
        expect_error(uvr, ["gen", nii, "--cells", "1000", "-o", os.path.join(tmp, "nan.vtu")],
                     "finite voxel-to-world map")
        if os.path.exists(os.path.join(tmp, "nan.vtu")):
            failures.append("uvr gen wrote a mesh from a NaN affine")

    for failure in failures:
        print("FAIL", failure)
    print(f"{len(failures)} failures")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
