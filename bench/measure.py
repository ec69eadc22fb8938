#!/usr/bin/env python3
"""Run a command and report its wall time and peak resident memory.

usage: measure.py LABEL -- COMMAND ARGS...
Prints one line: LABEL  wall_s  peak_MB  exit. Uses os.wait4, so the peak is
that of the command's own process.
"""
import os
import sys
import time


def main():
    label = sys.argv[1]
    cmd = sys.argv[sys.argv.index("--") + 1:]
    start = time.monotonic()
    pid = os.fork()
    if pid == 0:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, 1)
        os.execvp(cmd[0], cmd)
    _, status, usage = os.wait4(pid, 0)
    wall = time.monotonic() - start
    code = os.waitstatus_to_exitcode(status)
    print(f"| {label} | {wall:.2f} | {usage.ru_maxrss / 1024:.0f} | {code} |")
    return code


if __name__ == "__main__":
    sys.exit(main())
