"""The ParaView plugin in pvbatch: LoadPlugin, disk_out_ref shown as "uvr Volume" with a colour map and an
opacity function, a screenshot; SSIM >= 0.99 against `uvr render` of the same view and function. uvr's own
properties (mode, s1) reach the mapper.

Usage: pvbatch test_paraview_plugin.py UVR_BINARY PLUGIN SOURCE_DIR (run by ctest under xvfb-run; ParaView's
Python must be importable: PYTHONPATH names python3-paraview's files where they are unpacked, not installed)
"""
import os
import sys
import tempfile

import uvr_scene

try:
    from paraview import simple
except ImportError:
    print("SKIPPED: ParaView's Python (python3-paraview, or its files unpacked by scripts/setup-debian) is "
          "not found")
    sys.exit(77)


def main():
    uvr, plugin, source = sys.argv[1:4]
    disk = os.path.join(source, "data", "disk_out_ref.vtu")
    simple.LoadPlugin(plugin, remote=False, ns=globals())
    reader = simple.XMLUnstructuredGridReader(FileName=[disk])
    view = simple.CreateRenderView()
    display = uvr_scene.show_uvr_volume(simple, reader, view)

    with tempfile.TemporaryDirectory() as tmp:
        shot = os.path.join(tmp, "paraview.png")
        scene = uvr_scene.save_screenshot(simple, view, shot)
        uvr_scene.check_against_uvr(uvr, disk, scene, shot, "pvbatch")

        # uvr's own properties reach the mapper: a much coarser fixed step changes the picture.
        display.UvrMode = "reference"
        display.UvrS1 = 2.0
        coarse = os.path.join(tmp, "coarse.png")
        uvr_scene.save_screenshot(simple, view, coarse)
        changed = uvr_scene.compare(uvr, shot, coarse)
        print(f"mode reference, s1 2: SSIM {changed:.4f} against the default")
        assert changed < 0.98, "UvrMode and UvrS1 did not change the frame"


if __name__ == "__main__":
    main()
