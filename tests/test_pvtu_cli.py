#!/usr/bin/env python3
"""`uvr convert IN OUT.pvtu --pieces N` and reading .pvtu back: each cell in one piece, the pieces' regions in
split order, the union renders as the source does, and a missing piece is an error (status 2).

Usage: test_pvtu_cli.py UVR_BINARY SHARED_DATA_DIR
"""
import json
import os
import subprocess
import sys
import tempfile
import xml.etree.ElementTree as ElementTree


def run(command, expect=0):
    result = subprocess.run(command, capture_output=True, text=True)
    if result.returncode != expect:
        sys.exit(f"FAIL: {' '.join(command)} exited with {result.returncode}, expected {expect}:\n"
                 f"{result.stderr.strip()}")
    return result


def main():
    uvr = sys.argv[1]
    source = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "data", "disk_out_ref.vtu")
    with tempfile.TemporaryDirectory() as tmp:
        out = lambda name: os.path.join(tmp, name)
        run([uvr, "convert", source, out("disk.pvtu"), "--pieces", "4"])
        pieces = ElementTree.parse(out("disk.pvtu")).getroot().find("PUnstructuredGrid").findall("Piece")
        if [p.get("Source") for p in pieces] != [f"disk/disk_{i}.vtu" for i in range(4)]:
            sys.exit(f"FAIL: pieces {[p.attrib for p in pieces]}")
        counts = [json.loads(run([uvr, "info", os.path.join(tmp, p.get("Source")), "--json"]).stdout)["cells"]
                  for p in pieces]
        whole = json.loads(run([uvr, "info", source, "--json"]).stdout)["cells"]
        union = json.loads(run([uvr, "info", out("disk.pvtu"), "--json"]).stdout)["cells"]
        if sum(counts) != whole or union != whole or min(counts) < whole // 8:
            sys.exit(f"FAIL: piece cells {counts}, union {union}, source {whole}")
        # Regions: disjoint boxes that tile the first one's split (the first two share a face).
        regions = [[float(v) for v in p.get("uvr_region").split()] for p in pieces]
        if not any(regions[0][a + 3] == regions[1][a] for a in range(3)):
            sys.exit(f"FAIL: regions {regions}")
        for mode in ("reference", "full"):
            a, b = out(f"a_{mode}.png"), out(f"b_{mode}.png")
            run([uvr, "render", source, "--mode", mode, "--size", "96x96", "-o", a])
            run([uvr, "render", out("disk.pvtu"), "--mode", mode, "--size", "96x96", "-o", b])
            ssim = json.loads(run([uvr, "compare", a, b, "--json"]).stdout)["ssim"]
            if ssim < 0.999:
                sys.exit(f"FAIL: {mode}: the .pvtu renders with SSIM {ssim} against its source")
        os.remove(os.path.join(tmp, "disk", "disk_2.vtu"))
        result = run([uvr, "render", out("disk.pvtu"), "--size", "8x8", "-o", out("x.png")], expect=2)
        if "disk_2.vtu" not in result.stderr:
            sys.exit(f"FAIL: a missing piece: {result.stderr}")
        run([uvr, "convert", source, out("x.vtu"), "--pieces", "2"], expect=2)
        run([uvr, "convert", source, out("x.pvtu")], expect=2)


if __name__ == "__main__":
    main()
