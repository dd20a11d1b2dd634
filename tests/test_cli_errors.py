#!/usr/bin/env python3
"""Every wrong option of every subcommand gets a clear error: exit status 2, one `uvr: error: ` line naming the
option, and no output file; --help exits 0. Outputs are checked before any work and written whole.

Usage: test_cli_errors.py UVR_BINARY SHARED_DATA (run by ctest)
"""
import os
import subprocess
import sys
import tempfile

SOURCE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
DISK = os.path.join(SOURCE, "data", "disk_out_ref.vtu")
NUMBERS = ["0", "-1", "nan", "inf", "abc"]


def run(uvr, args):
    return subprocess.run([uvr, *args], capture_output=True, text=True, timeout=300)


def constant_vtu(path):
    """One tetrahedron whose point field is 3 everywhere."""
    with open(path, "w") as f:
        f.write("""<?xml version="1.0"?>
<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian">
 <UnstructuredGrid><Piece NumberOfPoints="4" NumberOfCells="1">
  <Points><DataArray type="Float32" NumberOfComponents="3" format="ascii">0 0 0 1 0 0 0 1 0 0 0 1</DataArray></Points>
  <Cells>
   <DataArray type="Int64" Name="connectivity" format="ascii">0 1 2 3</DataArray>
   <DataArray type="Int64" Name="offsets" format="ascii">4</DataArray>
   <DataArray type="UInt8" Name="types" format="ascii">10</DataArray>
  </Cells>
  <PointData><DataArray type="Float32" Name="c" format="ascii">3 3 3 3</DataArray></PointData>
 </Piece></UnstructuredGrid>
</VTKFile>
""")


def main():
    uvr = sys.argv[1]
    failures = []
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "out.png")
        missing_dir = os.path.join(tmp, "no", "such", "folder")
        volume = os.path.join(tmp, "v.raw")
        with open(volume, "wb") as f:
            f.write(bytes(range(256)) * 32)  # 8192 bytes: 16 x 16 x 32 uint8
        raw = ["gen", volume, "--dims", "16,16,32", "--type", "uint8", "--cells", "1000"]

        render = ["render", DISK, "--size", "16x16", "-o", out]
        view = ["view", DISK, "--size", "16x16"]
        cases = []  # (arguments, the text the message must hold)
        camera_values = ["nan,0,0", "inf,0,0", "1,2", "a,b,c", "1,2,3,4"]
        for base in (render, view):
            for option in ("--s1", "--s2", "--unit"):
                cases += [(base + [option, v], option) for v in NUMBERS]
            cases += [(base + ["--p", v], "--p") for v in NUMBERS + ["0.5"]]
            cases += [(base + ["--leaf-size", v], "--leaf-size") for v in NUMBERS + ["1.5"]]
            cases += [(base + ["--fovy", v], "--fovy") for v in NUMBERS + ["180", "200"]]
            cases += [(base + ["--time-step", v], "--time-step") for v in ["-1", "nan", "inf", "abc", "1.5"]]
            cases += [(base + ["--range", *v.split()], "--range")
                      for v in ["5 5", "5 1", "nan 1", "0 inf", "a b"]]
            cases += [(base + ["--background", v], "--background")
                      for v in ["255,255,255", "-1,0,0", "0,0,1.5", "nan,0,0", "inf,0,0", "1,2", "a,b,c"]]
            cases += [(base + ["--size", v], "--size")
                      for v in ["0x10", "-1x10", "10x0", "20000x10", "nanxnan", "abc", "10"]]
            for option in ("--eye", "--at", "--up"):
                cases += [(base + [option, v], option) for v in camera_values]
            cases += [(base + ["--view", v], "--view") for v in ["bogus", "x", "+w", ""]]
            cases += [(base + ["--mode", "bogus"], "--mode"), (base + ["--backend", "bogus"], "--backend")]
            cases += [(base + ["--shade", "--light", v], "--light") for v in ["nan,0,0", "inf,0,0", "1,2", "a,b,c"]]
            cases += [(base + ["--light", "1,0,0"], "--light")]  # without --shade
            cases += [(base + ["--tf", "no-such-preset"], "--tf"),
                      (base + ["--tf", os.path.join(tmp, "missing.json")], "--tf")]
            cases += [(base + ["--bogus-option"], "--bogus-option")]
        cases += [(render + ["--frames", v], "--frames") for v in ["0", "-1", "nan", "abc", "1.5"]]
        cases += [(render + ["--field", "no-such-field"], "--field")]
        cases += [(render + ["--eye", "0,0,0", "--at", "0,0,0"], "--eye"),
                  (render + ["--up", "0,0,1"], "--up"), (render + ["--up", "0,0,0"], "--up"),
                  (render + ["--view", "+x", "--up", "1,0,0"], "--up")]
        cases += [(["render", DISK, "-o", os.path.join(tmp, "out.jpg")], "-o"),
                  (["render", DISK, "-o", os.path.join(missing_dir, "x.png")], "-o"),
                  (["render", DISK, "-o", tmp], "-o"),
                  (render + ["--heatmap", os.path.join(tmp, "h.jpg")], "--heatmap"),
                  (render + ["--heatmap", os.path.join(missing_dir, "h.png")], "--heatmap"),
                  (render + ["--stats", os.path.join(missing_dir, "s.json")], "--stats"),
                  (["render", DISK], "--output"), (["render", "-o", out], "MESH"), ([], "subcommand")]
        cases += [(view + ["--script", os.path.join(tmp, "missing.txt")], "--script"),
                  (view + ["--screenshot", os.path.join(missing_dir, "shot")], "--screenshot"), (["view"], "MESH")]
        cases += [(["info", DISK, "--time-step", v], "--time-step") for v in ["-1", "nan", "inf", "abc", "1.5"]]
        cases += [(["info"], "MESH"), (["info", DISK, "--bogus"], "--bogus")]
        cases += [(["compare", out], "B"), (["compare"], "A"),
                  (["compare", os.path.join(tmp, "a.png"), os.path.join(tmp, "b.png")], "a.png")]
        convert = ["convert", DISK, os.path.join(tmp, "c.vtu")]
        cases += [(convert + ["--time-step", v], "--time-step") for v in ["-1", "nan", "inf", "abc"]]
        cases += [(convert + ["--field", "no-such-field"], "--field"),
                  (["convert", DISK, os.path.join(tmp, "c.txt")], "OUT"),
                  (["convert", DISK, os.path.join(missing_dir, "c.vtu")], "OUT"),
                  (["convert", DISK, os.path.join(tmp, "c.umesh"), "--zlib"], "--zlib"), (["convert", DISK], "OUT")]
        gen = raw + ["-o", os.path.join(tmp, "g.umesh")]
        cases += [(gen + ["--cells", v], "--cells") for v in ["5", "0", "-1", "nan", "inf", "abc"]]
        cases += [(gen + ["--threshold", v], "--threshold") for v in ["nan", "inf", "abc"]]
        cases += [(gen + ["--seed", v], "--seed") for v in ["-1", "nan", "abc", "1.5"]]
        cases += [(gen + ["--cell-type", "bogus"], "--cell-type")]
        cases += [(["gen", volume, "--dims", v, "--type", "uint8", "-o", os.path.join(tmp, "g.umesh")], "--dims")
                  for v in ["0,16,32", "-1,16,32", "nan,16,32", "inf,16,32", "1,2", "a,b,c"]]
        cases += [(gen + ["--spacing", v], "--spacing") for v in ["0,1,1", "-1,1,1", "nan,1,1", "inf,1,1", "1,2"]]
        cases += [(["gen", volume, "--dims", "16,16,32", "--type", "bogus", "-o", os.path.join(tmp, "g.umesh")],
                   "--type"),
                  (raw + ["-o", os.path.join(tmp, "g.txt")], "umesh"),
                  (raw + ["-o", os.path.join(missing_dir, "g.umesh")], "-o"), (raw, "--output")]

        for args, named in cases:
            result = run(uvr, args)
            lines = result.stderr.strip().splitlines()
            label = "uvr " + " ".join(a.replace(tmp, "TMP") for a in args)
            if result.returncode != 2:
                failures.append(f"{label}: exit {result.returncode}, expected 2: {result.stderr.strip()}")
            elif not lines or not lines[-1].startswith("uvr: error: "):
                failures.append(f"{label}: the last line lacks 'uvr: error: ': {result.stderr.strip()}")
            elif named not in lines[-1]:
                failures.append(f"{label}: the message does not name {named}: {lines[-1]}")
            if os.path.exists(out):
                failures.append(f"{label}: left {out} behind")
                os.remove(out)

        # --help succeeds; render's lists the built-in colour maps and the named views.
        for command in ["render", "info", "compare", "convert", "gen", "view"]:
            result = run(uvr, [command, "--help"])
            if result.returncode != 0:
                failures.append(f"uvr {command} --help: exit {result.returncode}")
        help_text = run(uvr, ["render", "--help"]).stdout
        for name in ["Cool to Warm", "Viridis (matplotlib)", "Inferno (matplotlib)", "Grayscale", "+x|-x|+y|-y|+z|-z|iso"]:
            if name not in help_text:
                failures.append(f"uvr render --help does not list {name}")

        # Output errors come before the work: a missing folder fails within the time of parsing, not a render.
        stats = os.path.join(tmp, "s.json")
        result = run(uvr, render + ["--stats", os.path.join(missing_dir, "s.json")])
        if "No such file or directory" not in result.stderr:
            failures.append(f"--stats in a missing folder: no reason given: {result.stderr.strip()}")

        # A good render writes exactly its outputs, no temporary files beside them.
        result = run(uvr, render + ["--stats", stats])
        leftovers = sorted(set(os.listdir(tmp)) - {"out.png", "s.json", "v.raw"})
        if result.returncode != 0 or not os.path.exists(out) or not os.path.exists(stats) or leftovers:
            failures.append(f"a good render: exit {result.returncode}, files left: {leftovers}: {result.stderr}")

        # --shade and --light parse, render, and say so in the statistics.
        result = run(uvr, render + ["--shade", "--light", "1,1,1", "--stats", stats])
        if result.returncode != 0 or '"shaded": true' not in open(stats).read():
            failures.append(f"a shaded render: exit {result.returncode}: {result.stderr.strip()}")
        os.remove(out)

        # A constant field is rendered visibly, with a warning; --range 5 5 on it is refused above.
        constant = os.path.join(tmp, "constant.vtu")
        constant_vtu(constant)
        shot = os.path.join(tmp, "constant.png")
        result = run(uvr, ["render", constant, "--size", "32x32", "-o", shot, "--view", "iso"])
        if result.returncode != 0 or "constant" not in result.stderr:
            failures.append(f"a constant field: exit {result.returncode}, no warning: {result.stderr.strip()}")
        else:
            with open(shot, "rb") as f:
                data = f.read()
            compare = run(uvr, ["compare", shot, shot, "--json"])
            if compare.returncode != 0:
                failures.append("compare of an image with itself failed")
            black = os.path.join(tmp, "black.png")
            run(uvr, ["render", constant, "--size", "32x32", "-o", black, "--range", "100", "200"])
            differs = run(uvr, ["compare", shot, black, "--json"]).stdout
            if '"psnr":null' in differs.replace(" ", "") or not data:
                failures.append("a constant field renders as black as one outside its range")

    for failure in failures:
        print("FAIL:", failure)
    if failures:
        sys.exit(1)
    print(f"{len(cases)} wrong command lines refused with status 2 and the option named")


if __name__ == "__main__":
    main()
