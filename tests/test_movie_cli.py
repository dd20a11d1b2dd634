#!/usr/bin/env python3
"""Movies from `uvr render`: a series of time steps renders each step as a single-step render of it does, the
steps whose grid is unchanged keeping the acceleration data and a changed grid getting a new renderer; --orbit
frames are plain renders from the turned camera; --camera-path passes through its keyframes at their frames;
the video is made by the ffmpeg on the PATH (a stand-in here) and skipped without one; bad values of each new
option exit 2 naming it.

Usage: test_movie_cli.py UVR_BINARY SHARED_DATA_DIR
"""
import itertools
import json
import math
import os
import stat
import subprocess
import sys
import tempfile

import numpy as np
from PIL import Image

DISK = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "data", "disk_out_ref.vtu")
SIZE = ["--size", "32x24"]
failures = []


def check(condition, message):
    if not condition:
        failures.append(message)
    return condition


def run(uvr, args, expect=0, env=None):
    result = subprocess.run([uvr, *args], capture_output=True, text=True, timeout=300, env=env)
    if result.returncode != expect:
        sys.exit(f"FAIL: uvr {' '.join(args)} exited with {result.returncode}, expected {expect}:\n"
                 f"{result.stderr.strip()}")
    return result


def image(path):
    return np.asarray(Image.open(path).convert("RGB"), dtype=np.int16)


def cube_vtu(path, n, value):
    """n^3 hexahedra over [0, 1]^3 with the point field f = value(x, y, z)."""
    m = n + 1
    points = [(i / n, j / n, k / n) for k in range(m) for j in range(m) for i in range(m)]
    cells = []
    for k in range(n):
        for j in range(n):
            for i in range(n):
                at = lambda a, b, c: (k + c) * m * m + (j + b) * m + i + a
                cells.append([at(0, 0, 0), at(1, 0, 0), at(1, 1, 0), at(0, 1, 0),
                              at(0, 0, 1), at(1, 0, 1), at(1, 1, 1), at(0, 1, 1)])
    text = lambda values: " ".join(repr(v) for v in values)
    with open(path, "w") as f:
        f.write(f"""<?xml version="1.0"?>
<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian">
 <UnstructuredGrid><Piece NumberOfPoints="{len(points)}" NumberOfCells="{len(cells)}">
  <Points><DataArray type="Float32" NumberOfComponents="3" format="ascii">{text(c for p in points for c in p)}</DataArray></Points>
  <Cells>
   <DataArray type="Int64" Name="connectivity" format="ascii">{text(v for c in cells for v in c)}</DataArray>
   <DataArray type="Int64" Name="offsets" format="ascii">{text(range(8, 8 * len(cells) + 1, 8))}</DataArray>
   <DataArray type="UInt8" Name="types" format="ascii">{text([12] * len(cells))}</DataArray>
  </Cells>
  <PointData><DataArray type="Float32" Name="f" format="ascii">{text(value(*p) for p in points)}</DataArray></PointData>
 </Piece></UnstructuredGrid>
</VTKFile>
""")


def series(tmp):
    """Four steps: the same grid with three fields, then another grid of the same bounds (the same camera)."""
    steps = [(5, lambda x, y, z: x * y), (5, lambda x, y, z: 1.0 - z * z),
             (5, lambda x, y, z: 0.5 + 0.5 * math.sin(6.0 * x)), (4, lambda x, y, z: y)]
    rows = []
    for i, (n, value) in enumerate(steps):
        cube_vtu(os.path.join(tmp, f"step{i}.vtu"), n, value)
        rows.append(f'<DataSet timestep="{i * 0.5}" file="step{i}.vtu"/>')
    path = os.path.join(tmp, "series.pvd")
    with open(path, "w") as f:
        f.write('<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1"><Collection>\n' +
                "\n".join(rows) + "\n</Collection></VTKFile>\n")
    return path


def vector(v):
    return ",".join(repr(float(c)) for c in v)


def test_series(uvr, tmp):
    pvd = series(tmp)
    common = [pvd, "--range", "0", "1", "--view", "iso", *SIZE]
    singles = []
    for step in range(4):
        out = os.path.join(tmp, f"single{step}.png")
        stats = os.path.join(tmp, f"single{step}.json")
        run(uvr, ["render", *common, "--time-step", str(step), "-o", out, "--stats", stats])
        singles.append(image(out))
        with open(stats) as f:
            single = json.load(f)
        check(single["time_step"] == step and "frame_stats" not in single,
              f"single step {step}: stats time_step {single['time_step']}, keys {sorted(single)}")
    check(all(np.abs(singles[i] - singles[i + 1]).max() > 20 for i in range(3)),
          "the steps' single renders do not differ: the series test would show nothing")

    movie = os.path.join(tmp, "movie.png")
    stats = os.path.join(tmp, "movie.json")
    result = run(uvr, ["render", *common, "--time-step", "0:3", "-o", movie, "--stats", stats],
                 env={**os.environ, "PATH": "/nonexistent"})
    with open(stats) as f:
        movie_stats = json.load(f)
    frames = movie_stats["frame_stats"]
    check([f["time_step"] for f in frames] == [0, 1, 2, 3], f"movie steps {[f['time_step'] for f in frames]}")
    check([f["acceleration"] for f in frames] == ["built", "reused", "reused", "built"],
          f"movie acceleration {[f['acceleration'] for f in frames]}: steps 1 and 2 keep the grid, 3 does not")
    check(result.stderr.count("time step 3") == 1 and "differ" in result.stderr,
          f"the changed grid is not reported once: {result.stderr.strip()}")
    check(movie_stats["frames"] == 4 and movie_stats["time_step"] == 0 and movie_stats["video"] is None,
          f"movie stats: frames {movie_stats['frames']}, time_step {movie_stats['time_step']}, "
          f"video {movie_stats['video']}")
    check(not os.path.exists(movie) and not os.path.exists(os.path.join(tmp, "movie.mp4")),
          "a movie wrote OUT.png or a video without ffmpeg")
    for step in range(4):
        frame = image(os.path.join(tmp, f"movie_{step:04d}.png"))
        # Exact: the reused acceleration data must render as a fresh build does.
        check(np.array_equal(frame, singles[step]),
              f"movie frame {step} differs from the single-step render (max {np.abs(frame - singles[step]).max()})")

    every_other = os.path.join(tmp, "other.json")
    run(uvr, ["render", *common, "--time-step", "all", "-o", os.path.join(tmp, "all.png")])
    run(uvr, ["render", *common, "--time-step", "1:3:2", "-o", os.path.join(tmp, "other.png"),
              "--stats", every_other])
    check(np.array_equal(image(os.path.join(tmp, "all_0002.png")), singles[2]), "--time-step all, frame 2")
    with open(every_other) as f:
        check([f["time_step"] for f in json.load(f)["frame_stats"]] == [1, 3], "--time-step 1:3:2 steps")
    check(np.array_equal(image(os.path.join(tmp, "other_0001.png")), singles[3]), "--time-step 1:3:2, frame 1")


def test_orbit(uvr, tmp):
    plain = os.path.join(tmp, "plain.png")
    run(uvr, ["render", DISK, *SIZE, "-o", plain])
    stats = os.path.join(tmp, "orbit.json")
    run(uvr, ["render", DISK, *SIZE, "--orbit", "40", "--frames", "3", "-o", os.path.join(tmp, "orbit.png"),
              "--stats", stats])
    with open(stats) as f:
        frames = json.load(f)["frame_stats"]
    check(len(frames) == 3 and all(f["acceleration"] == ("built" if i == 0 else "kept")
                                   for i, f in enumerate(frames)), "orbit: 3 frames, one build")
    check(np.array_equal(image(os.path.join(tmp, "orbit_0000.png")), image(plain)), "orbit frame 0 != plain render")
    camera = frames[0]["camera"]
    eye, at, up = (np.array(camera[k], dtype=np.float64) for k in ("eye", "at", "up"))
    axis = up / np.linalg.norm(up)
    for k in (1, 2):
        angle = math.radians(40.0 * k)
        v = eye - at
        turned = at + v * math.cos(angle) + np.cross(axis, v) * math.sin(angle) + axis * axis.dot(v) * (
            1.0 - math.cos(angle))
        expected = os.path.join(tmp, f"turned{k}.png")
        run(uvr, ["render", DISK, *SIZE, "--eye", vector(turned), "--at", vector(at), "--up", vector(up),
                  "--fovy", repr(camera["fovy"]), "-o", expected])
        frame, want = image(os.path.join(tmp, f"orbit_{k:04d}.png")), image(expected)
        # The eye goes through text here: a last-bit difference may move an edge pixel by a level.
        check(np.abs(frame - want).max() <= 2 and np.abs(frame - want).mean() < 0.05,
              f"orbit frame {k} differs from a render from the turned eye (max {np.abs(frame - want).max()})")
        check(np.abs(frame - image(plain)).mean() > 1.0, f"orbit frame {k} looks like frame 0")
    # By default a full turn.
    full = os.path.join(tmp, "full.json")
    run(uvr, ["render", DISK, "--size", "8x8", "--orbit", "90", "-o", os.path.join(tmp, "full.png"), "--stats", full])
    with open(full) as f:
        check(json.load(f)["frames"] == 4, "--orbit 90 does not make 4 frames")


def test_camera_path(uvr, tmp):
    # Binary fractions: the file and --eye give the same floats.
    keys = [{"eye": [0.0, 0.0, 40.0], "at": [0.0, 0.0, 0.0], "up": [0.0, 1.0, 0.0], "fovy": 30.0},
            {"eye": [30.0, 5.0, 20.0], "at": [0.5, 0.0, 0.25], "up": [0.0, 1.0, 0.0], "fovy": 40.0},
            {"eye": [0.0, 30.0, 25.0], "at": [0.0, 0.5, 0.0], "up": [0.0, 0.0, 1.0], "fovy": 25.0}]
    for numbered, frames, at_frames in ((False, 7, [0, 3, 6]), (True, None, [0, 2, 5])):
        path = os.path.join(tmp, "path.json")
        with open(path, "w") as f:
            json.dump([dict(k, frame=n) for k, n in zip(keys, at_frames)] if numbered else keys, f)
        out = os.path.join(tmp, "path.png")
        stats = os.path.join(tmp, "path_stats.json")
        run(uvr, ["render", DISK, *SIZE, "--camera-path", path, "-o", out, "--stats", stats] +
            (["--frames", str(frames)] if frames else []))
        with open(stats) as f:
            count = json.load(f)["frames"]
        check(count == at_frames[-1] + 1, f"camera path (numbered {numbered}): {count} frames")
        for key, n in zip(keys, at_frames):
            expected = os.path.join(tmp, "key.png")
            run(uvr, ["render", DISK, *SIZE, "--eye", vector(key["eye"]), "--at", vector(key["at"]),
                      "--up", vector(key["up"]), "--fovy", repr(key["fovy"]), "-o", expected])
            check(np.array_equal(image(os.path.join(tmp, f"path_{n:04d}.png")), image(expected)),
                  f"camera path (numbered {numbered}): frame {n} is not keyframe {at_frames.index(n)}'s view")
        between = image(os.path.join(tmp, f"path_{at_frames[1] - 1:04d}.png"))
        check(not np.array_equal(between, image(os.path.join(tmp, f"path_{at_frames[1]:04d}.png"))) and
              not np.array_equal(between, image(os.path.join(tmp, "path_0000.png"))),
              f"camera path (numbered {numbered}): the frame between keyframes 0 and 1 is one of them")


def fake_ffmpeg(folder, status):
    """An ffmpeg that notes its arguments and writes its last one (or fails with `status`)."""
    os.makedirs(folder, exist_ok=True)
    path = os.path.join(folder, "ffmpeg")
    with open(path, "w") as f:
        f.write(f"""#!/bin/sh
printf '%s\\n' "$@" > "{folder}/args"
[ {status} -eq 0 ] || exit {status}
for last; do :; done
echo video > "$last"
""")
    os.chmod(path, os.stat(path).st_mode | stat.S_IXUSR)
    return folder


def test_video(uvr, tmp):
    folder = fake_ffmpeg(os.path.join(tmp, "bin"), 0)
    out = os.path.join(tmp, "v%d.png")  # a '%' the pattern must escape
    stats = os.path.join(tmp, "v.json")
    # A frame past the movie's, left by an earlier one, stays out of the video.
    Image.new("RGB", (8, 8)).save(os.path.join(tmp, "v%d_0003.png"))
    run(uvr, ["render", DISK, "--size", "8x8", "--orbit", "120", "--fps", "12", "-o", out, "--stats", stats,
              "--heatmap", os.path.join(tmp, "heat.png")],
        env={**os.environ, "PATH": folder + os.pathsep + os.environ["PATH"]})
    check(all(os.path.exists(os.path.join(tmp, f"heat_{k:04d}.png")) for k in range(3)), "movie heat maps")
    with open(os.path.join(folder, "args")) as f:
        args = f.read().split("\n")
    video = os.path.join(tmp, "v%d.mp4")
    check(os.path.exists(video), "no OUT.mp4 from ffmpeg")
    check(args[args.index("-framerate") + 1] == "12" and args[args.index("-frames:v") + 1] == "3" and
          args[args.index("-i") + 1] == os.path.join(tmp, "v%%d_%04d.png"), f"ffmpeg arguments: {args}")
    with open(stats) as f:
        check(json.load(f)["video"] == video, "stats: video")
    failing = fake_ffmpeg(os.path.join(tmp, "failing"), 3)
    result = run(uvr, ["render", DISK, "--size", "8x8", "--orbit", "120", "-o", os.path.join(tmp, "w.png")], 1,
                 env={**os.environ, "PATH": failing})
    check("ffmpeg" in result.stderr and not os.path.exists(os.path.join(tmp, "w.mp4")) and
          os.path.exists(os.path.join(tmp, "w_0002.png")), f"a failing ffmpeg: {result.stderr.strip()}")
    # One image has no frame rate: --fps there is said to do nothing, not silently dropped.
    result = run(uvr, ["render", DISK, "--size", "8x8", "--fps", "12", "-o", os.path.join(tmp, "one.png")])
    check("--fps" in result.stderr and "movie" in result.stderr, f"--fps on one image: {result.stderr.strip()}")


def test_errors(uvr, tmp):
    pvd = os.path.join(tmp, "series.pvd")
    out = os.path.join(tmp, "bad.png")
    render = ["render", pvd, *SIZE, "-o", out]

    numbers = itertools.count()

    def path_file(content):
        """A keyframe file of its own: the cases run after all are listed."""
        path = os.path.join(tmp, f"path{next(numbers)}.json")
        with open(path, "w") as f:
            f.write(content)
        return path

    cases = [(render + ["--time-step", v], "--time-step")
             for v in ["1:0", "0:2:0", "a:b", "0:", ":2", "1:2:3:4", "0:9", "all:1", "-1:2", "0x1"]]
    cases += [(render + ["--orbit", v], "--orbit") for v in ["0", "nan", "inf", "400", "abc"]]
    cases += [(render + ["--fps", v], "--fps") for v in ["0", "1.5", "abc", "1000"]]
    cases += [(render + ["--time-step", "0:1", "--frames", "3"], "--frames"),
              (render + ["--orbit", "10", "--camera-path", path_file('[{"eye": [1, 2, 3]}]')], "--orbit")]
    bad_paths = ["", "{", "[]", "{}", "[1]", '[{"eye": [1, 2]}]', '[{"eye": [1, 2, "x"]}]', '[{"fovy": 200}]',
                 '[{"frame": 0}, {}]', '[{"frame": 1}]', '[{"frame": 0}, {"frame": 0}]', '[{"look": [1, 2, 3]}]',
                 '[{"frame": 1.5}]']
    cases += [(render + ["--camera-path", path_file(text)], "--camera-path") for text in bad_paths]
    cases += [(render + ["--camera-path", os.path.join(tmp, "missing.json")], "--camera-path"),
              (render + ["--camera-path", path_file('[{"frame": 0}, {"frame": 4}]'), "--frames", "3"],
               "--camera-path"),
              (render + ["--camera-path", path_file('[{}, {}, {}]'), "--frames", "2"], "--camera-path"),
              # The view-up turns through zero half-way.
              (render + ["--camera-path", path_file('[{"eye": [0, 0, 9], "up": [0, 1, 0]}, '
                                                    '{"eye": [0, 0, 9], "up": [0, -1, 0]}]'), "--frames", "3"],
               "--camera-path")]
    for args, named in cases:
        result = subprocess.run([uvr, *args], capture_output=True, text=True, timeout=300)
        label = "uvr " + " ".join(a.replace(tmp, "TMP") for a in args)
        lines = result.stderr.strip().splitlines()
        if check(result.returncode == 2, f"{label}: exit {result.returncode}, expected 2: {result.stderr.strip()}"):
            check(lines and lines[-1].startswith("uvr: error: ") and named in lines[-1],
                  f"{label}: the message does not name {named}: {result.stderr.strip()}")
        check(not any(name.startswith("bad") and name.endswith(".png") for name in os.listdir(tmp)),
              f"{label}: left a frame behind")


def main():
    uvr = sys.argv[1]
    with tempfile.TemporaryDirectory() as tmp:
        test_series(uvr, tmp)
        test_orbit(uvr, tmp)
        test_camera_path(uvr, tmp)
        test_video(uvr, tmp)
        test_errors(uvr, tmp)
    if failures:
        sys.exit("FAIL:\n  " + "\n  ".join(failures))
    print("movie CLI: ok")


if __name__ == "__main__":
    main()
