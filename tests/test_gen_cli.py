#!/usr/bin/env python3
"""`uvr gen` end to end on the real T1 scan: counts, grading seen by `uvr info`, identical files from the same
inputs, raw input, and errors.

Usage: test_gen_cli.py UVR_BINARY SHARED_DATA_DIR
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


def info(uvr, path):
    return json.loads(run([uvr, "info", path, "--json"]).stdout)


def main():
    uvr, shared = sys.argv[1], sys.argv[2]
    scan = os.path.join(shared, "source", "ch2better.nii.gz")
    with tempfile.TemporaryDirectory() as tmp:
        out = lambda name: os.path.join(tmp, name)
        for cell_type, cells in (("tet", 150000), ("hex", 60000)):
            path = out(f"brain_{cell_type}.umesh")
            run([uvr, "gen", scan, "--cells", str(cells), "--cell-type", cell_type, "-o", path])
            stats = info(uvr, path)
            count = stats["cell_types"][cell_type]
            if abs(count - cells) > 0.1 * cells or stats["cells"] != count:
                sys.exit(f"FAIL: {cell_type}: asked for {cells} cells, got {stats['cell_types']}")
            if stats["volume_ratio"] < 10 or stats["volume_ratio_p99_p1"] < 5:
                sys.exit(f"FAIL: {cell_type}: not graded: {stats['volume_ratio']}, {stats['volume_ratio_p99_p1']}")
            if stats["inverted_cells"] != 0:
                sys.exit(f"FAIL: {cell_type}: {stats['inverted_cells']} inverted cells")
            field = stats["fields"][0]
            if field["name"] != "ch2better" or field["max"] < 100:
                sys.exit(f"FAIL: {cell_type}: field {field}")
            # The brain of the scan: the same bounds as the tetgen meshes made from it, within a few mm.
            reference = [-72.5, 71.7, -105.8, 74.2, -69.9, 84.8]  # brain_t1_tet_3M.vtu
            if any(abs(a - b) > 6 for a, b in zip(stats["bounds"], reference)):
                sys.exit(f"FAIL: {cell_type}: bounds {stats['bounds']}")

        # Same inputs, same bytes; the cell field goes to .vtu.
        a, b = out("a.vtu"), out("b.vtu")
        for path in (a, b):
            run([uvr, "gen", scan, "--cells", "100000", "--seed", "5", "--cell-field", "-o", path])
        with open(a, "rb") as fa, open(b, "rb") as fb:
            if fa.read() != fb.read():
                sys.exit("FAIL: two runs with the same inputs wrote different files")
        names = [f["name"] for f in info(uvr, a)["fields"]]
        if names != ["ch2better", "ch2better_cell"]:
            sys.exit(f"FAIL: fields {names}")

        # A raw float32 volume: a ball, values 0..100.
        import struct
        n = 24
        values = []
        for k in range(n):
            for j in range(n):
                for i in range(n):
                    r = ((i - 11.5) ** 2 + (j - 11.5) ** 2 + (k - 11.5) ** 2) ** 0.5
                    values.append(max(0.0, 100.0 - 10.0 * r))
        raw = out("ball.raw")
        with open(raw, "wb") as f:
            f.write(struct.pack(f"<{len(values)}f", *values))
        ball = out("ball.vtu")
        run([uvr, "gen", raw, "--dims", f"{n},{n},{n}", "--type", "float32", "--spacing", "2,2,2",
             "--threshold", "20", "--cells", "20000", "-o", ball])
        stats = info(uvr, ball)
        if abs(stats["cells"] - 20000) > 2000 or stats["bounds"][1] > 2 * (n - 1) + 1e-3:
            sys.exit(f"FAIL: raw ball: {stats['cells']} cells, bounds {stats['bounds']}")

        # Errors: exit status 2 with the file named.
        bad = out("bad.nii")
        with open(bad, "wb") as f:
            f.write(b"\0" * 400)
        result = run([uvr, "gen", bad, "--cells", "10000", "-o", out("x.umesh")], expect=2)
        if "bad.nii" not in result.stderr:
            sys.exit(f"FAIL: error does not name the file: {result.stderr}")
        run([uvr, "gen", scan, "--cells", "10000", "-o", out("x.obj")], expect=2)
    print("test_gen_cli: ok")


if __name__ == "__main__":
    main()
