#!/usr/bin/env python3
"""The README's quick-start command, as the README writes it, renders the picture the README shows beside it
(docs/images/quickstart.png) to SSIM >= 0.99, and that picture shows structure, not one flat colour.

Usage: test_quickstart.py UVR_BINARY SHARED_DATA (run by ctest)
"""
import json
import os
import re
import shlex
import subprocess
import sys
import tempfile

import numpy as np
from skimage import io

SOURCE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
IMAGE = os.path.join(SOURCE, "docs", "images", "quickstart.png")


def main():
    uvr = sys.argv[1]
    with open(os.path.join(SOURCE, "README.md")) as f:
        readme = f.read()
    match = re.search(r"build/uvr (render data/disk_out_ref\.vtu[^\n&|]*)", readme)
    if not match:
        sys.exit("FAIL: no `build/uvr render data/disk_out_ref.vtu ...` command in README.md")
    if "docs/images/quickstart.png" not in readme:
        sys.exit("FAIL: README.md does not show docs/images/quickstart.png")
    args = shlex.split(match.group(1))
    output = args.index("-o") + 1
    with tempfile.TemporaryDirectory() as tmp:
        args[output] = os.path.join(tmp, os.path.basename(args[output]))
        result = subprocess.run([uvr, *args], cwd=SOURCE, capture_output=True, text=True)
        if result.returncode != 0:
            sys.exit(f"FAIL: uvr {' '.join(args)}: exit {result.returncode}: {result.stderr}")
        compare = subprocess.run([uvr, "compare", IMAGE, args[output], "--json"], capture_output=True, text=True)
        if compare.returncode != 0:
            sys.exit(f"FAIL: uvr compare: {compare.stderr}")
        ssim = json.loads(compare.stdout)["ssim"]
    image = io.imread(IMAGE)[:, :, :3].astype(float)
    # Structure: many distinct colours, and a spread of brightness across the covered pixels.
    covered = image.sum(axis=2) > 0
    colours = len({tuple(p) for p in image[covered].astype(int)})
    spread = image[covered].mean(axis=1).std()
    print(f"README quick start: SSIM {ssim:.4f} against {os.path.relpath(IMAGE, SOURCE)}; "
          f"{colours} colours, brightness spread {spread:.1f}")
    if ssim < 0.99:
        sys.exit(f"FAIL: SSIM {ssim:.4f} < 0.99")
    if image.shape[0] > 1024 or image.shape[1] > 1024:
        sys.exit(f"FAIL: the committed image is {image.shape[1]}x{image.shape[0]}; keep it modest")
    if colours < 500 or spread < 20:
        sys.exit(f"FAIL: the quick-start image is close to one flat colour ({colours} colours, spread {spread:.1f})")


if __name__ == "__main__":
    main()
