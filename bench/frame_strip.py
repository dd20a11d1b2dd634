#!/usr/bin/env python3
"""Puts frames side by side, 2 grey pixels apart, each with an optional label in its top-left corner: the
figure of a movie in the README.

  bench/frame_strip.py FRAME.png... -o STRIP.png [--labels "t = 0.1 s" ...]

Needs Pillow (Debian: python3-pil).
"""
import argparse
import sys

from PIL import Image, ImageDraw


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("frames", nargs="+")
    parser.add_argument("-o", "--output", required=True)
    parser.add_argument("--labels", nargs="*", default=[])
    a = parser.parse_args()
    if a.labels and len(a.labels) != len(a.frames):
        sys.exit(f"frame_strip: {len(a.labels)} labels for {len(a.frames)} frames")
    images = [Image.open(f).convert("RGB") for f in a.frames]
    gap = 2
    strip = Image.new("RGB", (sum(i.width for i in images) + gap * (len(images) - 1), max(i.height for i in images)),
                      (96, 96, 96))
    x = 0
    for n, image in enumerate(images):
        strip.paste(image, (x, 0))
        if a.labels:
            ImageDraw.Draw(strip).text((x + 4, 3), a.labels[n], fill=(230, 230, 230))
        x += image.width + gap
    strip.save(a.output, optimize=True)


if __name__ == "__main__":
    main()
