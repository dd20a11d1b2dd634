"""The script that test_paraview_gui.py gives to the paraview GUI (--script): loads the plugin, shows
disk_out_ref as "uvr Volume" in the GUI's render view and saves a screenshot and its scene. The GUI passes no
arguments to a script: they come in the environment (UVR_TEST_PLUGIN, UVR_TEST_MESH, UVR_TEST_OUT).
"""
import json
import os
import sys

# As in pvpython: ParaView's own modules, unpacked rather than installed, ahead of the system's VTK modules.
sys.path[:0] = [p for p in os.environ.get("PYTHONPATH", "").split(os.pathsep) if p]

import uvr_scene  # noqa: E402
from paraview import simple  # noqa: E402


def main():
    out = os.environ["UVR_TEST_OUT"]
    simple.LoadPlugin(os.environ["UVR_TEST_PLUGIN"], remote=False, ns=globals())
    reader = simple.XMLUnstructuredGridReader(FileName=[os.environ["UVR_TEST_MESH"]])
    view = simple.GetActiveViewOrCreate("RenderView")
    uvr_scene.show_uvr_volume(simple, reader, view)
    scene = uvr_scene.save_screenshot(simple, view, os.path.join(out, "gui.png"))
    scene["render_window"] = view.GetRenderWindow().GetClassName()
    with open(os.path.join(out, "scene.json"), "w") as f:
        json.dump(scene, f)


main()
