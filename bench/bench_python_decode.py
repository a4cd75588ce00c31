#!/usr/bin/env python3
"""Times isowave.decode() (the Python module) against the library's decode in C++ on the same file, in one run.

The target (issue #36): the Python decode at 100% returns its arrays within 1.2x the C++ decode's time. Both sides do
the same work: read and decode the file, synthesize the fine control points and build the fine control mesh
(bench_codec --decode-only FILE PERCENT, "with the fine control mesh"); Python also wraps the buffers as NumPy arrays
(no copy). Best of five each, in fresh processes, taking turns (--rounds, default 3): the C++ bench (whose malloc keeps freed memory
for reuse, as the CLI's does), Python as it comes, and Python after isowave.keep_freed_memory_for_reuse().

usage: PYTHONPATH=build/python /usr/bin/python3 bench/bench_python_decode.py FILE.isw [PERCENT] [--rounds N]
       [--bench-codec PATH]
"""
import argparse
import os
import re
import subprocess
import sys
import time


def cpp_seconds(bench_codec, path, percent):
    out = subprocess.run([bench_codec, "--decode-only", path, str(percent)], check=True, capture_output=True,
                         text=True).stdout
    return float(re.search(r"with the fine control mesh: ([0-9.]+) s", out).group(1))


def python_seconds(path, percent, keep_memory):
    command = [sys.executable, os.path.abspath(__file__), path, str(percent), "--worker"]
    out = subprocess.run(command + (["--keep-freed-memory"] if keep_memory else []), check=True, capture_output=True,
                         text=True).stdout
    return float(out.split()[-1])


def worker(path, percent, keep_memory, runs=5):
    import isowave
    if keep_memory:
        isowave.keep_freed_memory_for_reuse()
    best = float("inf")
    for _ in range(runs):
        start = time.perf_counter()
        vertices, faces = isowave.decode(path, percent=percent)
        best = min(best, time.perf_counter() - start)
        del vertices, faces
    print(best)


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("file")
    parser.add_argument("percent", nargs="?", type=float, default=100.0)
    parser.add_argument("--bench-codec", default=os.path.join(here, "..", "build", "bench", "bench_codec"))
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("--keep-freed-memory", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.worker:
        return worker(args.file, args.percent, args.keep_freed_memory)
    sides = {"C++ decode with the control mesh": lambda: cpp_seconds(args.bench_codec, args.file, args.percent),
             "isowave.decode()": lambda: python_seconds(args.file, args.percent, False),
             "isowave.decode(), memory kept": lambda: python_seconds(args.file, args.percent, True)}
    times = {name: [] for name in sides}
    for _ in range(args.rounds):
        for name, measure in sides.items():
            times[name].append(measure())
    cpp = min(times["C++ decode with the control mesh"])
    print(f"{args.file} at {args.percent:g}%, best of 5 per round, {args.rounds} rounds:")
    for name, rounds in times.items():
        print(f"  {name:34s} best {min(rounds):.3f} s (rounds {', '.join(f'{t:.3f}' for t in rounds)}), "
              f"{min(rounds) / cpp:.3f}x C++")
    print("target: Python <= 1.2x C++")


if __name__ == "__main__":
    main()
