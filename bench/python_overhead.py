#!/usr/bin/env python3
"""The Python loop's cost per frame against `flowfusion run` on the same frames (a benchmark, not a test).

    PYTHONPATH=build/python python3 bench/python_overhead.py SEQUENCE --app build/apps/flowfusion [--frames 0:59]

Four ways over the same frames, each --repeats times in turn (the best of each is printed, as the
machine's load varies): the executable (wall time from start to exit: loading, the pipeline, the mask
files), ff.run (the same loop in-process), the Python loop (ff.TumSequence frames as NumPy arrays
into System.process, then System.save) and the same loop passing the ff.Frame objects themselves (no
array conversion). The maps are not exported (--no-map) in any of them.
"""
import argparse
import resource
import subprocess
import tempfile
import time

import flowfusion as ff


def cpu_seconds():
    """CPU time of this process (all its threads) and its finished children: less disturbed than the
    wall time by other work on the machine."""
    children = resource.getrusage(resource.RUSAGE_CHILDREN)
    return time.process_time() + children.ru_utime + children.ru_stime


def timed(fn):
    wall, cpu = time.perf_counter(), cpu_seconds()
    fn()
    return time.perf_counter() - wall, cpu_seconds() - cpu


def python_loop(sequence, frames, out, arrays=True):
    seq = ff.TumSequence(sequence, frames=frames)
    system = ff.System(seq.camera, ff.Config(), T_world_first=seq.initial_pose())
    for f in seq:
        if arrays:
            system.process(f.rgb, f.depth, f.timestamp, depth_timestamp=f.depth_timestamp)
        else:
            system.process(f)
    system.save(out, sequence=seq, export_map=False)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("sequence")
    parser.add_argument("--app", required=True, help="the flowfusion executable")
    parser.add_argument("--frames", help="FIRST:LAST")
    parser.add_argument("--repeats", type=int, default=2)
    args = parser.parse_args()
    n = len(ff.TumSequence(args.sequence, frames=args.frames))
    frames = ["--frames", args.frames] if args.frames else []
    ways = {
        "flowfusion run": lambda out: subprocess.run(
            [args.app, "run", args.sequence, "--out", out, "--quiet", "--no-map", *frames], check=True),
        "ff.run": lambda out: ff.run(args.sequence, out, frames=args.frames, export_map=False),
        "Python loop": lambda out: python_loop(args.sequence, args.frames, out),
        "loop of Frames": lambda out: python_loop(args.sequence, args.frames, out, arrays=False),
    }
    times = {name: [] for name in ways}
    names = list(ways)
    for repeat in range(args.repeats):
        with tempfile.TemporaryDirectory() as tmp:
            for i in range(len(names)):  # each repeat starts with the next way: no way always goes first
                name = names[(repeat + i) % len(names)]
                times[name].append(timed(lambda: ways[name](f"{tmp}/{i}")))
    reference = [min(t[k] for t in times["flowfusion run"]) * 1000 / n for k in (0, 1)]
    print(f"{n} frames of {args.sequence}, best of {args.repeats}, ms per frame (against flowfusion run):")
    for name, t in times.items():
        wall, cpu = (min(x[k] for x in t) * 1000 / n for k in (0, 1))
        print(f"  {name:15s} wall {wall:7.1f} ({100 * (wall / reference[0] - 1):+5.1f} %)   "
              f"cpu {cpu:7.1f} ({100 * (cpu / reference[1] - 1):+5.1f} %)")


if __name__ == "__main__":
    main()
