#!/usr/bin/env python3
"""The Python loop's cost per frame against `flowfusion run` on the same frames (a benchmark, not a test).

    PYTHONPATH=build/python python3 bench/python_overhead.py SEQUENCE --app build/apps/flowfusion [--frames 0:59]

Three ways over the same frames, each --repeats times in turn (the best of each is printed, as the
machine's load varies): the executable (wall time from start to exit: loading, the pipeline, the mask
files), ff.run (the same loop in-process), and the Python loop (ff.TumSequence frames as NumPy arrays
into System.process, then System.save). The maps are not exported (--no-map) in any of them.
"""
import argparse
import subprocess
import tempfile
import time

import flowfusion as ff


def timed(fn):
    start = time.perf_counter()
    fn()
    return time.perf_counter() - start


def python_loop(sequence, frames, out):
    seq = ff.TumSequence(sequence, frames=frames)
    system = ff.System(seq.camera, ff.Config(), T_world_first=seq.initial_pose())
    for f in seq:
        system.process(f.rgb, f.depth, f.timestamp, depth_timestamp=f.depth_timestamp)
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
    best = {"flowfusion run": [], "ff.run": [], "Python loop": []}
    for _ in range(args.repeats):
        with tempfile.TemporaryDirectory() as tmp:
            cmd = [args.app, "run", args.sequence, "--out", f"{tmp}/app", "--quiet", "--no-map", *frames]
            best["flowfusion run"].append(timed(lambda: subprocess.run(cmd, check=True)))
            best["ff.run"].append(timed(lambda: ff.run(args.sequence, f"{tmp}/ffrun", frames=args.frames,
                                                       export_map=False)))
            best["Python loop"].append(timed(lambda: python_loop(args.sequence, args.frames, f"{tmp}/py")))
    reference = min(best["flowfusion run"]) * 1000 / n
    print(f"{n} frames of {args.sequence}, best of {args.repeats}:")
    for name, seconds in best.items():
        ms = min(seconds) * 1000 / n
        print(f"  {name:15s} {ms:7.1f} ms/frame ({100 * (ms / reference - 1):+.1f} % against flowfusion run)")


if __name__ == "__main__":
    main()
