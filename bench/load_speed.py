#!/usr/bin/python3
"""Mesh loading speed, side by side in one run: uvr against VTK 9.1 on a .vtu, and uvr's .umesh throughput.

usage: /usr/bin/python3 bench/load_speed.py [UVR_BINARY] [MESH.vtu] [--runs 3]

- uvr: `uvr info --json` reports `load_ms` and `load_cpu_ms`, the whole loadMesh (read, decode, group cells
  by type, fix winding, order spatially): wall-clock, and CPU time summed over threads.
- VTK: vtkXMLUnstructuredGridReader.Update() of Debian's python3-vtk9 (VTK 9.1), timed in this process
  (wall-clock and process CPU time).
On a machine shared with other work, wall-clock times stretch with the load; the CPU times say how much work
each side did.
- .umesh: the mesh converted by `uvr convert` into a temporary directory (point fields only: .umesh holds no
  cell fields), read once to warm the page cache, then loaded by `uvr info --json`; throughput = file size /
  load_ms.
Each figure is the median of --runs runs, all files read from a warm page cache (one untimed read first).
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
DEFAULT_UVR = os.path.join(HERE, "..", "build", "uvr")
DEFAULT_MESH = os.path.join(HERE, "..", "..", "shared", "data", "large", "brain_t1_tet_3M.vtu")


def run(command):
    result = subprocess.run(command, capture_output=True, text=True)
    if result.returncode != 0:
        sys.exit(f"failed: {' '.join(command)}\n{result.stderr}")
    return result.stdout


def warm(path):
    with open(path, "rb") as f:
        while f.read(1 << 24):
            pass


def uvr_load_ms(uvr, path):
    info = json.loads(run([uvr, "info", "--json", path]))
    return info["load_ms"], info["load_cpu_ms"]


def vtk_load_ms(path):
    from vtkmodules.vtkIOXML import vtkXMLUnstructuredGridReader

    reader = vtkXMLUnstructuredGridReader()
    reader.SetFileName(path)
    start, cpu_start = time.perf_counter(), time.process_time()
    reader.Update()
    elapsed = ((time.perf_counter() - start) * 1000.0, (time.process_time() - cpu_start) * 1000.0)
    cells = reader.GetOutput().GetNumberOfCells()
    if cells == 0:
        sys.exit(f"VTK read no cells from {path}")
    return elapsed


def median_of(runs, measure):
    """Medians of the wall-clock and of the CPU times."""
    results = [measure() for _ in range(runs)]
    return statistics.median(r[0] for r in results), statistics.median(r[1] for r in results)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("uvr", nargs="?", default=DEFAULT_UVR)
    parser.add_argument("mesh", nargs="?", default=DEFAULT_MESH)
    parser.add_argument("--runs", type=int, default=3)
    args = parser.parse_args()

    info = json.loads(run([args.uvr, "info", "--json", args.mesh]))
    point_fields = [f["name"] for f in info["fields"] if f["centering"] == "point"]
    size_mb = os.path.getsize(args.mesh) / 1e6
    print(f"{os.path.basename(args.mesh)}: {size_mb:.1f} MB, {info['points']} points, {info['cells']} cells; "
          f"{os.cpu_count()} CPUs, load average {os.getloadavg()[0]:.1f}")

    warm(args.mesh)
    uvr_ms = median_of(args.runs, lambda: uvr_load_ms(args.uvr, args.mesh))
    vtk_ms = median_of(args.runs, lambda: vtk_load_ms(args.mesh))

    with tempfile.TemporaryDirectory() as tmp:
        umesh = os.path.join(tmp, "mesh.umesh")
        fields = [arg for name in point_fields for arg in ("--field", name)]
        run([args.uvr, "convert", args.mesh, umesh] + fields)
        umesh_bytes = os.path.getsize(umesh)
        warm(umesh)
        umesh_ms = median_of(args.runs, lambda: uvr_load_ms(args.uvr, umesh))

    print()
    print(f"| load (median of {args.runs}) | wall ms | CPU ms | |")
    print("|---|---:|---:|---|")
    print(f"| uvr, .vtu | {uvr_ms[0]:.0f} | {uvr_ms[1]:.0f} | {vtk_ms[0] / uvr_ms[0]:.2f}x VTK's speed "
          f"(wall), {vtk_ms[1] / uvr_ms[1]:.2f}x (CPU) |")
    print(f"| VTK 9.1 vtkXMLUnstructuredGridReader, .vtu | {vtk_ms[0]:.0f} | {vtk_ms[1]:.0f} | |")
    gb = umesh_bytes / 1e9
    print(f"| uvr, .umesh ({umesh_bytes / 1e6:.1f} MB) | {umesh_ms[0]:.0f} | {umesh_ms[1]:.0f} | "
          f"{gb / (umesh_ms[0] / 1000.0):.2f} GB/s (wall), {gb / (umesh_ms[1] / 1000.0):.2f} GB/s per CPU second |")

if __name__ == "__main__":
    main()
