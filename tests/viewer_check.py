#!/usr/bin/env python3
"""Checks `uvr view` without a person: a script turns, pans and zooms the camera, edits the transfer function
and takes screenshots under Xvfb; the image region of each screenshot must match `uvr render` of the same
view (SSIM >= 0.99 by `uvr compare`), and the camera must have moved as the script says.

Usage: viewer_check.py UVR_BINARY SOURCE_DIR (run by ctest when the viewer is built and xvfb-run exists)
"""
import json
import math
import os
import subprocess
import sys
import tempfile

import numpy as np
from skimage import io

SIZE = (200, 160)
MIN_SSIM = 0.99
SCRIPT = """# turn, pan and zoom, then a new preset, range and opacity
orbit 30 20
pan 0.05 -0.03
zoom 1.25
mode adaptive
preset Viridis (matplotlib)
range 400 850
opacity 400 0 600 0.3 850 0.9
screenshot edited
heatmap on
screenshot heatmap
heatmap off
view iso
screenshot iso
"""


# In sanitizer builds LeakSanitizer exits with this status (LSAN_OPTIONS in tests/CMakeLists.txt), so that its
# report can be read: leaks that the X11 and OpenGL stack or the sanitizer runtimes leave are not uvr's, and
# their stacks do not always name a module that a suppression could match (a library unloaded at exit).
LEAK_EXIT = 23


def leaks_in_uvr(report, uvr, source):
    """Whether a LeakSanitizer report holds a stack with a frame in uvr's binary or sources."""
    return any(uvr in line or source in line or " uvr::" in line
               for line in report.splitlines() if line.lstrip().startswith("#"))


def run(command, uvr=None, source=None):
    result = subprocess.run(command, capture_output=True, text=True)
    if result.returncode == LEAK_EXIT and uvr and "LeakSanitizer" in result.stderr and \
            not leaks_in_uvr(result.stderr, uvr, source):
        return result.stdout
    if result.returncode != 0:
        sys.exit(f"FAIL: {' '.join(command)} exited with {result.returncode}:\n{result.stderr.strip()}")
    return result.stdout


def main():
    uvr, source = sys.argv[1], sys.argv[2]
    mesh = os.path.join(source, "data", "disk_out_ref.vtu")
    failures = []
    with tempfile.TemporaryDirectory() as tmp:
        script = os.path.join(tmp, "view.txt")
        with open(script, "w") as f:
            f.write(SCRIPT)
        prefix = os.path.join(tmp, "shot")
        run(["xvfb-run", "-a", "-s", "-screen 0 1024x768x24", uvr, "view", mesh, "--field", "Temp", "--size",
             f"{SIZE[0]}x{SIZE[1]}", "--script", script, "--screenshot", prefix], os.path.realpath(uvr),
            os.path.realpath(source))

        # The starting camera, from `uvr render`'s defaults: the viewer must have moved away from it.
        info = json.loads(run([uvr, "info", mesh, "--json"]))
        b = info["bounds"]
        center = np.array([(b[0] + b[1]) / 2, (b[2] + b[3]) / 2, (b[4] + b[5]) / 2])
        radius = 0.5 * math.dist((b[0], b[2], b[4]), (b[1], b[3], b[5]))
        start_distance = radius / math.sin(math.radians(15))

        for name in ("edited", "heatmap", "iso"):
            view = json.load(open(f"{prefix}-{name}.json"))
            cam = view["camera"]
            eye, at = np.array(cam["eye"]), np.array(cam["at"])
            distance = np.linalg.norm(eye - at)
            # Statistics as everywhere: the full-resolution frame follows its preview, which took the transfer
            # function's update, so it waited for none; the build is the renderer's, once.
            stats = view["stats"]
            if stats["tf_update_ms"] != 0 or not stats["build_ms"] > 0:
                failures.append(f"{name}: tf_update_ms {stats['tf_update_ms']}, build_ms {stats['build_ms']}")
            if name == "iso":
                # The named view, framed as the reset camera: from +x+y+z at the reset camera's distance.
                direction = (eye - at) / distance
                if np.abs(direction - 1 / math.sqrt(3)).max() > 1e-5 or np.linalg.norm(at - center) > 1e-4 * radius \
                        or abs(distance - start_distance) > 1e-3 * start_distance:
                    failures.append(f"iso: eye {eye}, at {at}: not the iso view of the reset camera")
            elif abs(distance - start_distance / 1.25) > 1e-3 * start_distance:
                failures.append(f"{name}: eye distance {distance}, expected {start_distance / 1.25} after zoom")
            # Orbit 30 deg about +y and 20 deg about the right axis: the view direction turned by
            # acos(cos 30 cos 20) from -z.
            turned = math.degrees(math.acos(np.dot((eye - at) / distance, (0, 0, 1))))
            expected = math.degrees(math.acos(math.cos(math.radians(30)) * math.cos(math.radians(20))))
            if name != "iso" and abs(turned - expected) > 0.05:
                failures.append(f"{name}: view turned {turned:.3f} deg, expected {expected:.3f}")
            if name != "iso" and np.linalg.norm(at - center) < 0.01 * radius:
                failures.append(f"{name}: pan did not move the focal point")

            reference, heatmap = os.path.join(tmp, f"{name}-ref.png"), os.path.join(tmp, f"{name}-heat.png")
            vec = lambda v: ",".join(repr(x) for x in v)
            run([uvr, "render", mesh, "--field", "Temp", "--tf", f"{prefix}-{name}-tf.json", "--range",
                 repr(view["range"][0]), repr(view["range"][1]), "--mode", view["mode"], "--s1", repr(view["s1"]),
                 "--s2", repr(view["s2"]), "--p", repr(view["p"]), "--unit", repr(view["unit"]), "--eye",
                 vec(cam["eye"]), "--at", vec(cam["at"]), "--up", vec(cam["up"]), "--fovy", repr(cam["fovy"]),
                 "--size", f"{SIZE[0]}x{SIZE[1]}", "-o", reference, "--heatmap", heatmap])
            expected_image = heatmap if view["heatmap"] else reference

            x, y, w, h = view["image_region"]
            window = io.imread(f"{prefix}-{name}.png")[:, :, :3]
            region = os.path.join(tmp, f"{name}-region.png")
            io.imsave(region, window[y:y + h, x:x + w], check_contrast=False)
            for label, path in (("window region", region), ("saved frame", f"{prefix}-{name}-frame.png")):
                ssim = json.loads(run([uvr, "compare", path, expected_image, "--json"]))["ssim"]
                print(f"{name}: {label} vs uvr render: SSIM {ssim:.5f}")
                if ssim < MIN_SSIM:
                    failures.append(f"{name}: {label} SSIM {ssim:.5f} < {MIN_SSIM}")
    if failures:
        sys.exit("FAIL:\n" + "\n".join(failures))
    print("viewer_check: OK")


if __name__ == "__main__":
    main()
