"""Runs a command under a virtual X server again, up to twice, where it lost the server before doing anything
else ("bad X server connection", "cannot open display"): on a loaded machine xvfb-run's server is at times not
yet or no longer reachable, at times three times running on one display. So each retry waits longer and
starts its search for a free display 100 further on (xvfb-run's -n). Any other failure, and the exit status,
pass through unchanged.

Usage: retry_lost_display.py COMMAND [ARGS...]
"""
import subprocess
import sys
import time

LOST = ("bad X server connection", "cannot open display", "Can't open display")


def with_display_search_from(command, offset):
    """`command` with the display number after xvfb-run's -n moved on by `offset`."""
    command = list(command)
    for i in range(len(command) - 1):
        if command[i] == "-n" and command[i + 1].isdigit():
            command[i + 1] = str(int(command[i + 1]) + offset)
            break
    return command


def main():
    for attempt in range(3):
        run = subprocess.run(with_display_search_from(sys.argv[1:], 100 * attempt), capture_output=True, text=True)
        sys.stdout.write(run.stdout)
        sys.stderr.write(run.stderr)
        if run.returncode == 0 or not any(text in run.stdout + run.stderr for text in LOST):
            return run.returncode
        print(f"retry_lost_display: the X server was lost (attempt {attempt + 1})", flush=True)
        if attempt < 2:
            time.sleep(5 * (attempt + 1))
    return run.returncode


if __name__ == "__main__":
    sys.exit(main())
