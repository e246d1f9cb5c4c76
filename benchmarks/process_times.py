"""Whole-process timer: wall time (start to exit) and peak RSS of commands as a user runs them.

    python3 benchmarks/process_times.py --repeat 5 --json times.json \\
        --run floor "build-bench/benchmarks/torch_floor" \\
        --run generate "build-bench/apps/nec generate 'a person waves' --skeleton 01_01.bvh -o g.bvh --force"

Each --run NAME COMMAND (COMMAND split like a shell line, run without a shell) runs once unmeasured (the file
cache warms), then --repeat times, the commands taking turns so that a slow moment of the machine falls on all of
them. A command that exits non-zero stops the script with its output. Prints a Markdown table: the median wall
time, the fastest and slowest run, and the largest peak RSS; --json writes every run.
"""
import argparse
import json
import os
import shlex
import statistics
import subprocess
import sys
import time


def run_once(argv):
    """(seconds from start to exit, peak RSS in MiB) of one run; exits on failure."""
    start = time.perf_counter()
    process = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
    output = process.stdout.read()
    _, status, usage = os.wait4(process.pid, 0)
    seconds = time.perf_counter() - start
    process.returncode = os.waitstatus_to_exitcode(status)
    if process.returncode != 0:
        sys.stdout.write(output.decode(errors="replace"))
        raise SystemExit(f"process_times.py: '{shlex.join(argv)}' exited with {process.returncode}")
    return seconds, usage.ru_maxrss / 1024.0


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--run", nargs=2, action="append", metavar=("NAME", "COMMAND"), required=True)
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--json", help="write every run here")
    args = parser.parse_args()
    commands = [(name, shlex.split(line)) for name, line in args.run]
    for _, argv in commands:
        run_once(argv)
    runs = {name: [] for name, _ in commands}
    for _ in range(args.repeat):
        for name, argv in commands:
            runs[name].append(run_once(argv))
    print(f"\n| whole process, median of {args.repeat} (fastest - slowest) | s | peak RSS, MiB |\n|---|---:|---:|")
    for name, _ in commands:
        seconds = [s for s, _ in runs[name]]
        print(f"| {name} | {statistics.median(seconds):.2f} ({min(seconds):.2f} - {max(seconds):.2f}) | "
              f"{max(m for _, m in runs[name]):.0f} |")
    print()
    if args.json:
        with open(args.json, "w") as f:
            json.dump({name: [{"seconds": s, "peak_rss_MiB": m} for s, m in rows] for name, rows in runs.items()},
                      f, indent=1)


if __name__ == "__main__":
    main()
