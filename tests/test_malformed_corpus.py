#!/usr/bin/python3
"""Every file of the malformed corpus (malformed_corpus.py: real files altered one way each) makes `uvr info`
and `uvr render` exit with status 2 and an error naming the file, a position and the expected problem, with
no other output: nothing on stdout, no PNG written.

Usage: test_malformed_corpus.py UVR_BINARY SHARED_DATA
"""
import os
import re
import shutil
import subprocess
import sys
import tempfile
from concurrent.futures import ThreadPoolExecutor

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import malformed_corpus  # noqa: E402

POSITION = r"(byte \d+|line \d+|cell \d+|variable '[^']*'|dimension '[^']*'|netCDF header)"
SOURCES = ["small/uGridEx.vtk", "small/fieldfile.vtk", "small/sfepy_cylinder.vtk", "small/pyramid_ug.vtu",
           "medium/disk_out_ref.vtu", "medium/disk_out_ref.ex2"]


def check(uvr, directory, name, expected):
    """Problems with one corpus file, as text lines."""
    path = os.path.join(directory, name)
    png = os.path.join(directory, name + ".png")
    problems = []
    for command in ([uvr, "info", path], [uvr, "render", path, "--size", "16x16", "-o", png]):
        run = subprocess.run(command, capture_output=True, text=True, errors="replace", timeout=120)
        what = f"{name}: uvr {command[1]}"
        stderr = run.stderr.strip()
        if run.returncode != 2:
            problems.append(f"{what}: exit status {run.returncode}, expected 2; stderr: {stderr[-2000:]}")
            continue
        # Only the error line, after any notes (e.g. skipped element blocks).
        last = stderr.splitlines()[-1] if stderr else ""
        if not re.match(re.escape(f"uvr: error: {path}, ") + POSITION + ": ", last):
            problems.append(f"{what}: the error does not name the file and a position: {last!r}")
        if expected not in last:
            problems.append(f"{what}: expected {expected!r} in {last!r}")
        if run.stdout:
            problems.append(f"{what}: printed {run.stdout[:200]!r}")
        if "Sanitizer" in stderr or "runtime error" in stderr:
            problems.append(f"{what}: sanitizer report: {stderr[-2000:]}")
    if os.path.exists(png):
        problems.append(f"{name}: uvr render wrote {png}")
    return problems


def main():
    uvr, shared = sys.argv[1], sys.argv[2]
    failures = []
    # The unaltered sources load, so each error comes from its alteration.
    for source in SOURCES:
        run = subprocess.run([uvr, "info", os.path.join(shared, source)], capture_output=True, text=True)
        if run.returncode != 0:
            failures.append(f"{source} does not load: {run.stderr.strip()}")
    if not shutil.which("ncgen"):
        failures.append("ncgen (Debian's netcdf-bin) is missing: the Exodus cases cannot be made")
    with tempfile.TemporaryDirectory(prefix="uvr_malformed_") as directory:
        cases = malformed_corpus.generate(shared, directory)
        if len(cases) < 40:
            failures.append(f"only {len(cases)} corpus files")
        with ThreadPoolExecutor(max_workers=2) as pool:
            for problems in pool.map(lambda case: check(uvr, directory, *case), cases):
                failures += problems
    for failure in failures:
        print("FAIL", failure)
    print(f"{len(cases)} malformed files, {len(failures)} failures")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
