"""The ParaView plugin client-server: a pvserver on localhost, pvpython connected to it
(client_server_session.py). The server alone can open the mesh; the frame, rendered on the server, matches
`uvr render` (SSIM >= 0.99). The server's log shows that it loaded the plugin and rendered. The server is
killed whatever happens; every wait has a timeout.

Usage: python3 test_paraview_client_server.py UVR_BINARY PLUGIN SOURCE_DIR PVSERVER PVPYTHON (run by ctest
under xvfb-run; the server and the client share its display)
"""
import json
import os
import re
import subprocess
import sys
import tempfile
import time

SERVER_START_S = 60
CLIENT_S = 180
SKIPPED = 77


def wait_for_port(server, log_path):
    """The port that the server listens on (it was given port 0: the system picks a free one)."""
    deadline = time.monotonic() + SERVER_START_S
    while time.monotonic() < deadline:
        with open(log_path, errors="replace") as f:
            found = re.search(r"Accepting connection\(s\): \S*:(\d+)", f.read())
        if found:
            return int(found.group(1))
        if server.poll() is not None:
            raise RuntimeError(f"pvserver exited ({server.returncode}) before accepting connections")
        time.sleep(0.2)
    raise RuntimeError(f"pvserver did not accept connections within {SERVER_START_S} s")


def stop(server):
    if server.poll() is None:
        server.terminate()
        try:
            server.wait(timeout=10)
        except subprocess.TimeoutExpired:
            server.kill()
            server.wait(timeout=10)


def main():
    uvr, plugin, source, pvserver, pvpython = sys.argv[1:6]
    data = os.path.join(source, "data")
    session = os.path.join(os.path.dirname(os.path.abspath(__file__)), "client_server_session.py")
    env = dict(os.environ, PARAVIEW_LOG_PLUGIN_VERBOSITY="INFO", PARAVIEW_LOG_RENDERING_VERBOSITY="INFO")
    with tempfile.TemporaryDirectory() as tmp:
        server_log = os.path.join(tmp, "pvserver.log")
        out = os.path.join(tmp, "result.json")
        with open(server_log, "w") as log:
            # The server's working folder is the data's: the client names the mesh relative to it.
            server = subprocess.Popen([pvserver, "--server-port=0", "--force-offscreen-rendering"], cwd=data,
                                      env=env, stdout=log, stderr=subprocess.STDOUT)
        try:
            port = wait_for_port(server, server_log)
            client = subprocess.run([pvpython, "--force-offscreen-rendering", session, str(port), uvr, plugin,
                                     os.path.join(data, "disk_out_ref.vtu"), out], cwd=tmp, timeout=CLIENT_S)
            if client.returncode == SKIPPED:
                return SKIPPED
            assert client.returncode == 0, f"the client failed ({client.returncode})"
            with open(out) as f:
                result = json.load(f)
        except BaseException:
            stop(server)
            print_log(server_log)
            raise
        stop(server)
        with open(server_log, errors="replace") as f:
            server_text = f.read()

    try:
        assert re.search(r"Import status: success\s*-*\s*Importing plugin: \**uvrParaView", server_text), \
            "the server's log does not show uvrParaView loading"
        assert "use_distributed_rendering=1" in server_text, "the server's log shows no server render"
    except AssertionError:
        print(server_text)
        raise
    print(f"client-server: plugins on the server {result['server_plugins']}; rendered on the server "
          f"{result['rendered_on_server']} (remote render threshold {result['remote_render_threshold']} MB): "
          f"SSIM {result['ssim']:.4f}")
    return 0


def print_log(path):
    with open(path, errors="replace") as f:
        print("--- pvserver's log ---\n" + f.read() + "--- end of pvserver's log ---", flush=True)


if __name__ == "__main__":
    sys.exit(main())
