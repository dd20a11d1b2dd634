#!/usr/bin/env python3
"""`uvr render --iso`: good values parse and change the image (and the statistics say so); bad ones are refused
with status 2 and the option named, before any output is written.

Usage: test_iso_cli.py UVR_BINARY SHARED_DATA (run by ctest)
"""
import json
import os
import subprocess
import sys
import tempfile

SOURCE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
DISK = os.path.join(SOURCE, "data", "disk_out_ref.vtu")


def run(uvr, args):
    return subprocess.run([uvr, *args], capture_output=True, text=True, timeout=300)


def main():
    uvr = sys.argv[1]
    failures = []
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "out.png")
        stats = os.path.join(tmp, "s.json")
        render = ["render", DISK, "--size", "48x48", "--view", "iso"]
        cases = [
            (["--iso", "abc"], "--iso"),
            (["--iso", ""], "--iso"),
            (["--iso", "1,"], "--iso"),
            (["--iso", "1,,2"], "--iso"),
            (["--iso", "nan"], "--iso"),
            (["--iso", "inf"], "--iso"),
            (["--iso", "1 2"], "--iso"),
            (["--iso", ",".join(["1"] * 9)], "--iso"),
            (["--iso", "1", "--iso-color", "2,0,0"], "--iso-color"),
            (["--iso", "1", "--iso-color", "a,b,c"], "--iso-color"),
            (["--iso-color", "1,0,0"], "--iso-color"),
            (["--iso", "1", "--iso-opacity", "0"], "--iso-opacity"),
            (["--iso", "1", "--iso-opacity", "1.5"], "--iso-opacity"),
            (["--iso", "1", "--iso-opacity", "nan"], "--iso-opacity"),
            (["--iso-only"], "--iso-only"),
        ]
        for args, option in cases:
            result = run(uvr, render + ["-o", out] + args)
            lines = result.stderr.strip().splitlines()
            label = " ".join(args)
            if result.returncode != 2:
                failures.append(f"{label}: exit {result.returncode}, expected 2: {result.stderr.strip()}")
            elif not lines or not lines[-1].startswith("uvr: error: ") or option not in lines[-1]:
                failures.append(f"{label}: the last line does not name {option}: {result.stderr.strip()}")
            elif os.path.exists(out):
                failures.append(f"{label}: an output was written")

        # The field's range, then a surface in its middle: the image changes, and the statistics count it.
        plain = os.path.join(tmp, "plain.png")
        result = run(uvr, render + ["-o", plain, "--stats", stats])
        if result.returncode != 0:
            failures.append(f"a plain render: exit {result.returncode}: {result.stderr.strip()}")
        else:
            low, high = json.load(open(stats))["range"]
            middle = f"{0.5 * (low + high):g}"
            images = {}
            for name, extra in [("iso", ["--iso", middle]),
                                ("two", ["--iso", f"{middle},{0.75 * low + 0.25 * high:g}", "--iso-color", "1,0,0",
                                         "--iso-opacity", "0.5", "--light", "1,1,1"]),
                                ("only", ["--iso", middle, "--iso-only"])]:
                path = os.path.join(tmp, name + ".png")
                result = run(uvr, render + ["-o", path, "--stats", stats] + extra)
                if result.returncode != 0:
                    failures.append(f"{' '.join(extra)}: exit {result.returncode}: {result.stderr.strip()}")
                    continue
                s = json.load(open(stats))
                expected = 2 if name == "two" else 1
                if s.get("iso_surfaces") != expected or s.get("iso_only") != (name == "only"):
                    failures.append(f"{' '.join(extra)}: statistics {s.get('iso_surfaces')}, {s.get('iso_only')}")
                with open(path, "rb") as f:
                    images[name] = f.read()
            with open(plain, "rb") as f:
                base = f.read()
            for name, data in images.items():
                if data == base:
                    failures.append(f"{name}: the isosurface changed nothing in the image")
            if images.get("iso") is not None and images.get("iso") == images.get("only"):
                failures.append("--iso-only draws what the volume with the surface draws")

    for failure in failures:
        print("FAIL:", failure)
    if failures:
        sys.exit(1)
    print(f"{len(cases)} wrong --iso command lines refused; --iso, --iso-color, --iso-opacity, --iso-only draw")


if __name__ == "__main__":
    main()
