#!/usr/bin/env python3
"""Time per step of a time series: a movie (`uvr render --time-step A:B`), whose steps on an unchanged grid keep
the acceleration data (VolumeRenderer::setField), against a full load and build of each step (`uvr render
--time-step K`, one process per step). Prints a Markdown table: per step the load, the acceleration update
(setField) or build (build_ms + tf_update_ms), and the frame; medians over the steps after the first.

  bench/movie_steps.py UVR SERIES.pvd [--field NAME] [--steps A:B] [--size WxH] [--backend cpu|cuda] [--runs N]
  bench/movie_steps.py UVR --brain-series MESH.vtu DIR [--count N] ...

--brain-series first writes DIR/brain_K.vtu (K < N, default 4; point field T1 times a wave that moves with K,
the grid unchanged; uncompressed appended .vtu) and DIR/brain.pvd from MESH, with `uvr convert` and numpy, then
times that series.
"""
import argparse
import json
import os
import re
import statistics
import subprocess
import sys
import tempfile


def appended_array(data, header, name, dtype, components=1):
    """The raw appended array `name` of a .vtu as uvr convert writes it (UInt64 byte count, then the values)."""
    import numpy as np
    match = re.search(rf'Name="{name}"[^>]*offset="(\d+)"', header)
    start = data.index(b'<AppendedData encoding="raw">') + len(b'<AppendedData encoding="raw">')
    start = data.index(b"_", start) + 1 + int(match.group(1))
    size = int(np.frombuffer(data, np.uint64, 1, start)[0])
    return start + 8, np.frombuffer(data, dtype, size // np.dtype(dtype).itemsize, start + 8).reshape(-1, components)


def brain_series(uvr, mesh, folder, count):
    import numpy as np
    os.makedirs(folder, exist_ok=True)
    base = os.path.join(folder, "brain_base.vtu")
    subprocess.run([uvr, "convert", mesh, base, "--field", "T1"], check=True, stdout=subprocess.DEVNULL)
    with open(base, "rb") as f:
        data = bytearray(f.read())
    header = data[:data.index(b"<AppendedData")].decode()
    _, points = appended_array(data, header, "Points", np.float32, 3)
    t1_at, t1 = appended_array(data, header, "T1", np.float32)
    t1 = t1[:, 0].astype(np.float64)
    rows = []
    for k in range(count):
        wave = 0.5 + 0.5 * np.sin(points[:, 0].astype(np.float64) / 15.0 + k * np.pi / count)
        data[t1_at:t1_at + 4 * len(t1)] = (t1 * wave).astype("<f4").tobytes()
        with open(os.path.join(folder, f"brain_{k}.vtu"), "wb") as f:
            f.write(data)
        rows.append(f'<DataSet timestep="{k}" file="brain_{k}.vtu"/>')
    os.remove(base)
    pvd = os.path.join(folder, "brain.pvd")
    with open(pvd, "w") as f:
        f.write('<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1"><Collection>\n' +
                "\n".join(rows) + "\n</Collection></VTKFile>\n")
    return pvd


def render(uvr, args):
    with tempfile.TemporaryDirectory() as tmp:
        stats = os.path.join(tmp, "stats.json")
        subprocess.run([uvr, "render", *args, "-o", os.path.join(tmp, "frame.png"), "--stats", stats], check=True,
                       stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                       env={**os.environ, "PATH": "/nonexistent"})  # frames only: no video
        with open(stats) as f:
            return json.load(f)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("uvr")
    parser.add_argument("series", nargs="?")
    parser.add_argument("--brain-series", nargs=2, metavar=("MESH", "DIR"))
    parser.add_argument("--count", type=int, default=4)
    parser.add_argument("--field", default="")
    parser.add_argument("--steps", default="all")
    parser.add_argument("--size", default="512x512")
    parser.add_argument("--backend", default="cpu")
    parser.add_argument("--runs", type=int, default=3)
    a = parser.parse_args()
    series = brain_series(a.uvr, *a.brain_series, a.count) if a.brain_series else a.series
    if not series:
        sys.exit("movie_steps: give SERIES.pvd or --brain-series MESH DIR")
    common = [series, "--size", a.size, "--backend", a.backend] + (["--field", a.field] if a.field else [])

    # Each number the median of --runs runs (the machine may be shared: single runs vary by tens of per cent).
    movies = [render(a.uvr, common + ["--time-step", a.steps]) for _ in range(a.runs)]
    movie = movies[0]
    frames = [{key: (statistics.median(m["frame_stats"][i][key] for m in movies)
                     if isinstance(value, (int, float)) and not isinstance(value, bool) else value)
               for key, value in frame.items()} for i, frame in enumerate(movie["frame_stats"])]
    fresh = []
    same_range = ["--range", repr(movie["range"][0]), repr(movie["range"][1])]  # the movie's, the first step's
    for f in frames:
        runs = [render(a.uvr, common + same_range + ["--time-step", str(f["time_step"])]) for _ in range(a.runs)]
        fresh.append({key: statistics.median(r[key] for r in runs)
                      for key in ("load_ms", "build_ms", "tf_update_ms", "render_ms")})
    print(f"{series}: {movie['cells']} cells, {len(frames)} steps, {a.size}, backend {a.backend}, "
          f"{movie['threads']} threads, medians of {a.runs} runs\n")
    print("| step | load ms (movie / fresh) | movie: setField ms | fresh: build + tf ms | frame ms (movie / fresh) |")
    print("|---:|---:|---:|---:|---:|")
    for f, single in zip(frames, fresh):
        update = f"{f['step_update_ms']:.1f}" if f["acceleration"] == "reused" else f"({f['acceleration']})"
        print(f"| {f['time_step']} | {f['load_ms']:.1f} / {single['load_ms']:.1f} | {update} | "
              f"{single['build_ms'] + single['tf_update_ms']:.1f} | {f['render_ms']:.1f} / {single['render_ms']:.1f} |")
    later = [f for f in frames[1:] if f["acceleration"] == "reused"]
    if later:
        reused = statistics.median(f["load_ms"] + f["step_update_ms"] for f in later)
        full = statistics.median(s["load_ms"] + s["build_ms"] + s["tf_update_ms"] for s in fresh[1:])
        print(f"\nper step, median of steps 1 on: load + setField {reused:.1f} ms, load + build {full:.1f} ms "
              f"({full / reused:.1f}x); setField alone "
              f"{statistics.median(f['step_update_ms'] for f in later):.1f} ms, build alone "
              f"{statistics.median(s['build_ms'] + s['tf_update_ms'] for s in fresh[1:]):.1f} ms")


if __name__ == "__main__":
    main()
