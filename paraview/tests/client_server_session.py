"""The client of test_paraview_client_server.py, run by pvpython: connects to the pvserver at localhost:PORT,
loads the plugin on both sides, opens disk_out_ref on the server (a path relative to the server's working
folder, which this process cannot open), shows it as "uvr Volume" rendered on the server and checks the
screenshot against `uvr render`. The view keeps its Remote Render Threshold (20 MB, far above the mesh):
the frame is rendered on the server all the same, as ParaView's volume representations require.

Usage: pvpython client_server_session.py PORT UVR_BINARY PLUGIN MESH OUT_JSON (MESH: the server's file, for
uvr render here; OUT_JSON: what the driver reads back)
"""
import json
import os
import sys

# pvpython puts the folder of the system's VTK modules (python3-vtk9's vtkmodules, where installed) ahead of
# PYTHONPATH; ParaView's own modules, unpacked rather than installed, must come first.
sys.path[:0] = [p for p in os.environ.get("PYTHONPATH", "").split(os.pathsep) if p]

import uvr_scene  # noqa: E402

try:
    from paraview import servermanager, simple
except ImportError:
    print("SKIPPED: ParaView's Python (python3-paraview, or its files unpacked by scripts/setup-debian) is "
          "not found")
    sys.exit(77)

SERVER_MESH = "disk_out_ref.vtu"


def remote_plugins():
    manager = servermanager.vtkSMProxyManager.GetProxyManager().GetPluginManager()
    info = manager.GetRemoteInformation(servermanager.ActiveConnection.Session)
    return [info.GetPluginName(i) for i in range(info.GetNumberOfPlugins()) if info.GetPluginLoaded(i)]


def main():
    port, uvr, plugin, mesh, out = sys.argv[1:6]
    simple.Connect("localhost", int(port))
    assert servermanager.ActiveConnection.IsRemote(), "the session is not connected to a server"
    simple.LoadPlugin(plugin, remote=True, ns=globals())
    simple.LoadPlugin(plugin, remote=False, ns=globals())
    loaded = remote_plugins()
    assert "uvrParaView" in loaded, f"the server has not loaded uvrParaView: {loaded}"

    assert not os.path.exists(SERVER_MESH), f"{SERVER_MESH} must be the server's file alone"
    reader = simple.XMLUnstructuredGridReader(FileName=[SERVER_MESH])
    view = simple.CreateRenderView()
    uvr_scene.show_uvr_volume(simple, reader, view)
    scene = uvr_scene.save_screenshot(simple, view, "server.png")
    rendered_on_server = bool(view.GetClientSideObject().GetUseDistributedRenderingForRender())
    assert rendered_on_server, "the client rendered the frame, not the server"
    ssim = uvr_scene.check_against_uvr(uvr, mesh, scene, "server.png", "pvpython connected to pvserver")
    result = {"server_plugins": loaded, "rendered_on_server": rendered_on_server, "ssim": ssim,
              "remote_render_threshold": view.RemoteRenderThreshold}
    with open(out, "w") as f:
        json.dump(result, f)


if __name__ == "__main__":
    main()
