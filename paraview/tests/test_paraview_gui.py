"""The ParaView plugin in the paraview GUI: `paraview --script=gui_session.py --exit` loads the plugin and
saves a screenshot of disk_out_ref as "uvr Volume"; SSIM >= 0.99 against `uvr render` of the same view and
function. The GUI exits with 0 whatever its script does: the check is on what the script wrote.

Usage: python3 test_paraview_gui.py UVR_BINARY PLUGIN SOURCE_DIR PARAVIEW (run by ctest under xvfb-run)
"""
import json
import os
import subprocess
import sys
import tempfile

import uvr_scene

GUI_S = 120


def main():
    uvr, plugin, source, paraview = sys.argv[1:5]
    tests = os.path.dirname(os.path.abspath(__file__))
    mesh = os.path.join(source, "data", "disk_out_ref.vtu")
    with tempfile.TemporaryDirectory() as out:
        # The GUI's Python finds uvr_scene through PYTHONPATH: it runs the script from a string.
        path = os.pathsep.join(p for p in (os.environ.get("PYTHONPATH"), tests) if p)
        env = dict(os.environ, PYTHONPATH=path, UVR_TEST_PLUGIN=plugin, UVR_TEST_MESH=mesh, UVR_TEST_OUT=out)
        # --dr: no user settings (a colour palette, a view layout) change the frame.
        script = os.path.join(tests, "gui_session.py")
        gui = subprocess.run([paraview, "--dr", f"--script={script}", "--exit"], env=env, capture_output=True,
                             text=True, timeout=GUI_S)
        print(gui.stdout + gui.stderr, flush=True)
        if "No module named 'paraview'" in gui.stdout + gui.stderr:
            print("SKIPPED: ParaView's Python (python3-paraview, or its files unpacked by scripts/setup-debian) "
                  "is not found")
            return 77
        assert gui.returncode == 0, f"paraview exited with {gui.returncode}"
        scene_path = os.path.join(out, "scene.json")
        assert os.path.exists(scene_path), "the GUI's script did not finish (no scene.json): see its output"
        with open(scene_path) as f:
            scene = json.load(f)
        # The GUI's views draw into Qt widgets through generic render windows; pvpython's are X windows,
        # pvbatch's offscreen ones.
        assert scene["render_window"] == "vtkGenericOpenGLRenderWindow", \
            f"the frame came from a {scene['render_window']}, not from a view of the GUI"
        uvr_scene.check_against_uvr(uvr, mesh, scene, os.path.join(out, "gui.png"), "the paraview GUI")
    return 0


if __name__ == "__main__":
    sys.exit(main())
