#!/usr/bin/env python3
"""Checks `uvr compare` against scikit-image on synthetic image pairs and on real renders.

Usage: test_compare_skimage.py UVR_BINARY SHARED_DATA_DIR

For each pair, `uvr compare A B --json` must agree with scikit-image 0.19's
structural_similarity(channel_axis=2, gaussian_weights=True, sigma=1.5, use_sample_covariance=False,
data_range=255) to 1e-4 and with peak_signal_noise_ratio(data_range=255) to 1e-3 dB. The real pairs are a
reference render and an adaptive one (`--mode full` with a large s2) of two meshes from the shared data.
"""
import json
import math
import os
import subprocess
import sys
import tempfile

try:
    import numpy as np
    from skimage import io
    from skimage.metrics import peak_signal_noise_ratio, structural_similarity
except ImportError as error:
    sys.exit(f"test_compare_skimage: needs numpy and scikit-image (Debian python3-skimage): {error}")

SSIM_TOLERANCE = 1e-4
PSNR_TOLERANCE_DB = 1e-3
SIZE = "256x256"
MESHES = ["medium/brain_t1_tet_857k.vtu", "medium/disk_out_ref.vtu"]
S2_FACTOR = 16  # times s1: larger than uvr's default of 8, so that the adaptive image differs visibly


def run(command):
    result = subprocess.run(command, capture_output=True, text=True)
    if result.returncode != 0:
        sys.exit(f"FAIL: {' '.join(command)} exited with {result.returncode}:\n{result.stderr.strip()}")
    return result.stdout


def read_rgb(path):
    image = io.imread(path)
    if image.ndim != 3 or image.shape[2] != 3 or image.dtype != np.uint8:
        sys.exit(f"FAIL: {path} is not 8-bit RGB (shape {image.shape}, {image.dtype})")
    return image


def check_pair(uvr, name, a_path, b_path, failures):
    """Compares uvr's numbers for one pair with skimage's; returns a summary line."""
    result = json.loads(run([uvr, "compare", a_path, b_path, "--json"]))
    a, b = read_rgb(a_path), read_rgb(b_path)
    ssim = structural_similarity(a, b, channel_axis=2, gaussian_weights=True, sigma=1.5,
                                 use_sample_covariance=False, data_range=255)
    if np.array_equal(a, b):
        psnr = math.inf  # skimage divides by a zero error here; uvr writes null
        psnr_ok = result["psnr"] is None
    else:
        psnr = peak_signal_noise_ratio(a, b, data_range=255)
        psnr_ok = result["psnr"] is not None and abs(result["psnr"] - psnr) < PSNR_TOLERANCE_DB
    ssim_ok = abs(result["ssim"] - ssim) < SSIM_TOLERANCE
    if not ssim_ok:
        failures.append(f"{name}: SSIM uvr {result['ssim']:.9f} vs skimage {ssim:.9f}")
    if not psnr_ok:
        failures.append(f"{name}: PSNR uvr {result['psnr']} vs skimage {psnr}")

    # The text form must say the same, rounded.
    lines = run([uvr, "compare", a_path, b_path]).split("\n")
    expected_psnr = "PSNR inf dB" if math.isinf(psnr) else f"PSNR {result['psnr']:.2f} dB"
    if lines[0] != f"SSIM {result['ssim']:.6f}" or lines[1] != expected_psnr:
        failures.append(f"{name}: text output {lines[:2]} disagrees with the JSON {result}")

    ssim_diff = abs(result["ssim"] - ssim)
    psnr_text = "inf" if math.isinf(psnr) else f"{psnr:.3f} dB"
    return f"  {name:<28} SSIM {ssim:.6f} (|diff| {ssim_diff:.1e})  PSNR {psnr_text}"


def synthetic_pairs(directory):
    """Pairs of PNGs made here: noise, a smooth image and a noisy copy, an odd size, an identical pair."""
    rng = np.random.default_rng(7)
    y, x = np.mgrid[0:181, 0:240]
    smooth = np.stack([x + y // 2, 128 + 100 * np.sin(x / 17.0) * np.cos(y / 23.0), 255 - y], axis=2)
    smooth = np.clip(smooth, 0, 255).astype(np.uint8)
    noisy = np.clip(smooth + rng.normal(0, 12, smooth.shape), 0, 255).astype(np.uint8)
    pairs = {
        "synthetic noise": (rng.integers(0, 256, (64, 64, 3), dtype=np.uint8),
                            rng.integers(0, 256, (64, 64, 3), dtype=np.uint8)),
        "synthetic smooth + noise": (smooth, noisy),
        "synthetic 11x13": (smooth[:13, :11], noisy[:13, :11]),
        "synthetic identical": (smooth, smooth),
    }
    for index, (name, (a, b)) in enumerate(pairs.items()):
        a_path = os.path.join(directory, f"synthetic{index}_a.png")
        b_path = os.path.join(directory, f"synthetic{index}_b.png")
        io.imsave(a_path, a, check_contrast=False)
        io.imsave(b_path, b, check_contrast=False)
        yield name, a_path, b_path


def rendered_pair(uvr, mesh, directory):
    """Renders `mesh` with the reference and the adaptive integrator; returns the two PNG paths."""
    stem = os.path.join(directory, os.path.splitext(os.path.basename(mesh))[0])
    a_path, b_path, stats_path = stem + "_reference.png", stem + "_full.png", stem + "_reference.json"
    run([uvr, "render", mesh, "--size", SIZE, "--mode", "reference", "-o", a_path, "--stats", stats_path])
    with open(stats_path) as file:
        s1 = json.load(file)["s1"]
    run([uvr, "render", mesh, "--size", SIZE, "--mode", "full", "--s2", repr(S2_FACTOR * s1), "-o", b_path])
    return a_path, b_path


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    uvr, shared = sys.argv[1], sys.argv[2]
    failures, summary = [], []
    with tempfile.TemporaryDirectory(prefix="uvr_compare_") as directory:
        for name, a_path, b_path in synthetic_pairs(directory):
            summary.append(check_pair(uvr, name, a_path, b_path, failures))
        for mesh in MESHES:
            path = os.path.join(shared, mesh)
            if not os.path.exists(path):
                failures.append(f"{path}: missing (shared data)")
                continue
            a_path, b_path = rendered_pair(uvr, path, directory)
            summary.append(check_pair(uvr, os.path.basename(mesh), a_path, b_path, failures))
    print("uvr compare vs scikit-image:")
    print("\n".join(summary))
    if failures:
        print("FAIL:\n  " + "\n  ".join(failures), file=sys.stderr)
        return 1
    print(f"OK: SSIM within {SSIM_TOLERANCE}, PSNR within {PSNR_TOLERANCE_DB} dB")
    return 0


if __name__ == "__main__":
    sys.exit(main())
