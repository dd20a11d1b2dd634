#!/usr/bin/env python3
"""`mpirun -np 2` and `-np 4` against a single process: the same image (SSIM >= 0.999) in every mode, on a
tet brain, disk_out_ref (hexahedra) and a mixed-element mesh, from outside the mesh, inside it and along the
first split plane; and a rank that cannot open its file ends every rank with status 2.

Usage: mpi_render_check.py UVR_BINARY MPIEXEC SOURCE_DIR SHARED_DATA_DIR
"""
import json
import os
import subprocess
import sys
import tempfile

MODES = ("reference", "skip", "adaptive", "full")
SIZE = "96x96"
ENV = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
           OMPI_MCA_rmaps_base_oversubscribe="1")


def run(command, expect=0, timeout=300):
    result = subprocess.run(command, capture_output=True, text=True, env=ENV, timeout=timeout)
    if result.returncode != expect:
        sys.exit(f"FAIL: {' '.join(command)} exited with {result.returncode}, expected {expect}:\n"
                 f"{result.stdout.strip()}\n{result.stderr.strip()}")
    return result


def main():
    uvr, mpiexec, source, shared = sys.argv[1:5]
    mpirun = lambda ranks: [mpiexec, "--oversubscribe", "-np", str(ranks)]
    with tempfile.TemporaryDirectory() as tmp:
        out = lambda name: os.path.join(tmp, name)
        brain = out("brain.umesh")
        run([uvr, "gen", os.path.join(shared, "source", "ch2better.nii.gz"), "--cells", "60000", "-o", brain])
        meshes = {"brain": brain, "disk": os.path.join(source, "data", "disk_out_ref.vtu"),
                  "mixed": os.path.join(source, "tests", "data", "gmsh", "mixed_41_binary.msh")}
        worst = 1.0
        for name, mesh in meshes.items():
            # The first split plane, which 2 and 4 ranks share: a view that looks along it.
            stats_path = out(f"{name}_regions.json")
            run(mpirun(2) + [uvr, "render", mesh, "--size", "8x8", "-o", out("probe.png"), "--stats", stats_path])
            with open(stats_path) as f:
                stats = json.load(f)
            if stats["ranks"] != 2 or len(stats["rank_render_ms"]) != 2:
                sys.exit(f"FAIL: {name}: ranks {stats['ranks']}, rank_render_ms {stats['rank_render_ms']}")
            if not stats["composite_bytes"] > 0 or not stats["composite_ms"] >= 0:
                sys.exit(f"FAIL: {name}: composite_bytes {stats['composite_bytes']}")
            low, high = stats["rank_regions"]
            axis = next(a for a in range(3) if high[a] > low[a] and low[a + 3] < high[a + 3])
            split = low[axis + 3]
            bounds = [min(low[a], high[a]) for a in range(3)] + [max(low[a + 3], high[a + 3]) for a in range(3)]
            center = [(bounds[a] + bounds[a + 3]) / 2 for a in range(3)]
            extent = max(bounds[a + 3] - bounds[a] for a in range(3))
            across = (axis + 1) % 3  # the plane holds this axis: the view looks along it
            eye = list(center)
            eye[axis] = split
            eye[across] = bounds[across + 3] + 1.5 * extent
            at = list(eye)
            at[across] = center[across]
            up = [0.0, 0.0, 0.0]
            up[3 - axis - across] = 1.0
            inside_at = list(center)
            inside_at[across] += extent
            views = {
                "outside": ["--view", "iso"],
                "inside": ["--eye", ",".join(map(str, center)), "--at", ",".join(map(str, inside_at))],
                "plane": ["--eye", ",".join(map(str, eye)), "--at", ",".join(map(str, at)),
                          "--up", ",".join(map(str, up))],
            }
            for view, options in views.items():
                for mode in MODES:
                    command = [uvr, "render", mesh, "--mode", mode, "--size", SIZE] + options
                    single = out("single.png")
                    run(command + ["-o", single])
                    for ranks in (2, 4):
                        image = out(f"ranks{ranks}.png")
                        run(mpirun(ranks) + command + ["-o", image])
                        ssim = json.loads(run([uvr, "compare", single, image, "--json"]).stdout)["ssim"]
                        worst = min(worst, ssim)
                        if ssim < 0.999:
                            sys.exit(f"FAIL: {name} {view} {mode}, {ranks} ranks: SSIM {ssim:.6f} < 0.999")
        print(f"all modes, views and meshes match the single process; worst SSIM {worst:.6f}")

        # Rank 1 cannot open its file: every rank ends, with status 2 and that rank's message.
        missing = out("missing.vtu")
        result = subprocess.run([mpiexec, "--oversubscribe", "-np", "1", uvr, "render", meshes["mixed"],
                                 "--size", SIZE, "-o", out("x.png"), ":", "-np", "1", uvr, "render", missing,
                                 "--size", SIZE, "-o", out("x.png")],
                                capture_output=True, text=True, env=ENV, timeout=120)
        if result.returncode != 2 or "rank 1" not in result.stderr or "missing.vtu" not in result.stderr:
            sys.exit(f"FAIL: a rank without its file: status {result.returncode}:\n{result.stderr}")
        if os.path.exists(out("x.png")):
            sys.exit("FAIL: an image was written although a rank failed")


if __name__ == "__main__":
    main()
