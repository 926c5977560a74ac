#!/usr/bin/env python3
"""Start-up cost of commands: per-run wall time and CPU time (user + system of the child and
what it waited for, from wait4), the cases run in turn so that load falls on all alike.

    bench/startup.py RUNS 'NAME=COMMAND' ['NAME=COMMAND' ...]

COMMAND runs through the shell (set variables in it: PYTHONPATH=... python3 -c 'import tvf');
it must exit 0. Prints the median and the minimum of each (docs/benchmarks.md, "What a
command loads").
"""
import os
import statistics
import subprocess
import sys
import time


def run(command):
    start = time.perf_counter()
    child = subprocess.Popen(command, shell=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    _, status, usage = os.wait4(child.pid, 0)
    wall = time.perf_counter() - start
    if os.waitstatus_to_exitcode(status) != 0:
        sys.exit(f"startup.py: '{command}' exited with status {os.waitstatus_to_exitcode(status)}")
    return wall, usage.ru_utime + usage.ru_stime


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    runs = int(sys.argv[1])
    cases = dict(arg.split("=", 1) for arg in sys.argv[2:])
    walls = {name: [] for name in cases}
    cpus = {name: [] for name in cases}
    for _ in range(runs):
        for name, command in cases.items():
            wall, cpu = run(command)
            walls[name].append(wall)
            cpus[name].append(cpu)
    width = max(len(name) for name in cases)
    for name in cases:
        w, c = walls[name], cpus[name]
        print(f"{name:{width}s}  wall median {1000 * statistics.median(w):7.1f} ms (min {1000 * min(w):6.1f})"
              f"  CPU median {1000 * statistics.median(c):7.1f} ms (min {1000 * min(c):6.1f})  runs {runs}")


if __name__ == "__main__":
    main()
