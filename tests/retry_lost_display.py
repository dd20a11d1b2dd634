"""Runs a command under a virtual X server again, up to twice, where it lost the server before doing anything
else ("bad X server connection", "cannot open display"): on a loaded machine xvfb-run's server is at times not
yet or no longer reachable. Any other failure, and the exit status, pass through unchanged.

Usage: retry_lost_display.py COMMAND [ARGS...]
"""
import subprocess
import sys
import time

LOST = ("bad X server connection", "cannot open display", "Can't open display")


def main():
    for attempt in range(3):
        run = subprocess.run(sys.argv[1:], capture_output=True, text=True)
        sys.stdout.write(run.stdout)
        sys.stderr.write(run.stderr)
        if run.returncode == 0 or not any(text in run.stdout + run.stderr for text in LOST):
            return run.returncode
        print(f"retry_lost_display: the X server was lost (attempt {attempt + 1}); running again", flush=True)
        time.sleep(2)
    return run.returncode


if __name__ == "__main__":
    sys.exit(main())
