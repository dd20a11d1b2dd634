#!/usr/bin/python3
"""Runs bench/evaluate.py --quick (disk_out_ref at 64x64) and checks that the report, its tables, images and
plots are there and hold numbers; then, when VTK and an X server are available, bench/vtk_compare.py --quick
and that VTK's image agrees with uvr's.

usage: test_bench_quick.py UVR_BINARY SHARED_DATA_DIR
"""
import importlib.util
import json
import os
import shutil
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
BENCH = os.path.join(HERE, "..", "bench")
PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def check(condition, message):
    if not condition:
        sys.exit("FAIL: " + message)


def check_png(path):
    check(os.path.isfile(path), f"missing {path}")
    with open(path, "rb") as f:
        check(f.read(8) == PNG_MAGIC, f"{path} is not a PNG")


def table_rows(markdown, header_start):
    """Rows (lists of cells) of the first table whose header starts with `header_start`."""
    lines = markdown.splitlines()
    for i, line in enumerate(lines):
        if line.startswith(header_start):
            rows = []
            for row in lines[i + 2:]:
                if not row.startswith("|"):
                    break
                rows.append([cell.strip() for cell in row.strip("|").split("|")])
            return rows
    sys.exit(f"FAIL: no table starting with {header_start!r}")


def number(cell):
    return float(cell.rstrip("×").split()[0])


def main():
    uvr, data = sys.argv[1], sys.argv[2]
    out = tempfile.mkdtemp(prefix="uvr-bench-quick-")
    try:
        subprocess.run([sys.executable, os.path.join(BENCH, "evaluate.py"), uvr, out, "--quick", "--data", data],
                       check=True)
        with open(os.path.join(out, "report.md")) as f:
            report = f.read()
        for plot in ("speedup.png", "sweep_s2.png"):
            check_png(os.path.join(out, plot))

        headline = table_rows(report, "| case | kind |")
        check(len(headline) == 2, f"expected 2 headline rows, got {len(headline)}")
        for row in headline:
            reference_ms, full_ms, speedup = number(row[3]), number(row[4]), number(row[5])
            check(reference_ms > 0 and full_ms > 0, f"render times not positive: {row}")
            # The times are printed rounded to whole milliseconds.
            rounding = speedup * (0.5 / full_ms + 0.5 / reference_ms) + 0.01
            check(abs(speedup - reference_ms / full_ms) <= rounding, f"speed-up inconsistent: {row}")
            for cell in row[7:10]:
                check(0.5 < number(cell) <= 1.0, f"SSIM out of range: {row}")

        modes = table_rows(report, "| mode |")
        check([row[0] for row in modes] == ["reference", "skip", "adaptive", "full"], f"modes: {modes}")
        for row in modes:
            check(number(row[1]) > 0 and number(row[2]) >= number(row[1]), f"samples per pixel: {row}")
        # Skipping transparent partitions and empty space changes no sample that contributes.
        check(number(modes[1][6]) >= 0.9999, f"skip differs from reference: {modes[1]}")
        check(number(modes[1][1]) < number(modes[0][1]), f"skip takes no fewer samples: {modes}")

        sweep = table_rows(report, "| s2 / s1 |")
        check(len(sweep) == 2 and all(number(row[4]) > 0 for row in sweep), f"s2 sweep: {sweep}")
        # A larger s2 never takes more samples.
        check(number(sweep[1][3]) <= number(sweep[0][3]), f"samples grow with s2: {sweep}")

        with open(os.path.join(out, "results.json")) as f:
            results = json.load(f)["results"]
        for result in results:
            check_png(os.path.join(out, result["montage"]))
            check_png(os.path.join(out, result["heatmaps"]))
            check(result["modes"]["reference"]["ssim_truth"] > 0.95, "reference far from the ground truth")

        if importlib.util.find_spec("vtk") is None or not (os.environ.get("DISPLAY") or shutil.which("xvfb-run")):
            print("VTK comparison not run: python3-vtk9 or xvfb missing")
            return
        command = [sys.executable, os.path.join(BENCH, "vtk_compare.py"), uvr, os.path.join(out, "vtk"), "--quick",
                   "--data", data]
        if not os.environ.get("DISPLAY"):
            command = ["xvfb-run", "-a"] + command
        subprocess.run(command, check=True)
        with open(os.path.join(out, "vtk", "vtk_compare.json")) as f:
            vtk_results = json.load(f)["results"]
        for result in vtk_results:
            check_png(os.path.join(out, "vtk", result["montage"]))
            ssim = result["uvr"]["truth"]["ssim_vtk"]
            check(ssim >= 0.95, f"uvr's ground truth and VTK's image differ: SSIM {ssim}")
        print("ok")
    finally:
        shutil.rmtree(out, ignore_errors=True)


if __name__ == "__main__":
    main()
