#!/usr/bin/env python3
"""Renders meshes in every mode with the brain transfer functions and prints a Markdown table: samples per
pixel, render time (median of --frames), speed-up and SSIM against `reference`, build and TF-update times.

usage: bench/modes.py UVR_BINARY OUTDIR MESH [MESH ...] [--size 1024x1024] [--frames 3]
"""
import argparse
import json
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
PRESETS = os.path.join(HERE, "..", "data", "presets", "brain.json")
MODES = ["reference", "skip", "adaptive", "full"]
FUNCTIONS = ["Brain Binary", "Brain Translucent"]


def run(command):
    result = subprocess.run(command, capture_output=True, text=True)
    if result.returncode != 0:
        sys.exit(f"failed: {' '.join(command)}\n{result.stderr}")
    return result.stdout


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("uvr")
    parser.add_argument("outdir")
    parser.add_argument("meshes", nargs="+")
    parser.add_argument("--size", default="1024x1024")
    parser.add_argument("--frames", type=int, default=3)
    parser.add_argument("--field", default="T1")
    args = parser.parse_args()
    os.makedirs(args.outdir, exist_ok=True)

    print("| mesh | transfer function | mode | samples/pixel (mean, max) | render ms | speed-up | SSIM vs reference |"
          " skipped partitions |")
    print("|---|---|---|---|---|---|---|---|")
    builds = []
    for mesh in args.meshes:
        name = os.path.splitext(os.path.basename(mesh))[0]
        for function in FUNCTIONS:
            tag = function.split()[-1].lower()
            reference_ms = None
            for mode in MODES:
                stem = os.path.join(args.outdir, f"{name}_{tag}_{mode}")
                run([args.uvr, "render", mesh, "--field", args.field, "--tf", PRESETS, "--tf-name", function,
                     "--mode", mode, "--size", args.size, "--frames", str(args.frames), "-o", stem + ".png",
                     "--heatmap", stem + "_samples.png", "--stats", stem + ".json"])
                with open(stem + ".json") as f:
                    stats = json.load(f)
                if mode == "reference":
                    reference_ms = stats["render_ms"]
                    reference_png = stem + ".png"
                    builds.append((name, stats))
                ssim = json.loads(run([args.uvr, "compare", reference_png, stem + ".png", "--json"]))["ssim"]
                print(f"| {name} | {function} | {mode} | {stats['samples_per_pixel_mean']:.1f}, "
                      f"{stats['samples_per_pixel_max']} | {stats['render_ms']:.0f} | "
                      f"{reference_ms / stats['render_ms']:.2f}x | {ssim:.4f} | "
                      f"{stats['partitions_skipped']} / {stats['partitions']} |")
    print()
    print("| mesh | cells | load ms | build ms | TF update ms | threads |")
    print("|---|---|---|---|---|---|")
    seen = set()
    for name, stats in builds:
        if name in seen:
            continue
        seen.add(name)
        print(f"| {name} | {stats['cells']} | {stats['load_ms']:.0f} | {stats['build_ms']:.0f} | "
              f"{stats['tf_update_ms']:.2f} | {stats['threads']} |")


if __name__ == "__main__":
    main()
