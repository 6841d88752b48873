#!/usr/bin/env python3
"""A TUM-layout sequence through flowfusion from Python: trajectory and masks out, ATE printed.

    PYTHONPATH=build/python python3 examples/python/run_sequence.py SEQUENCE OUT_DIR [--set key=value ...]
"""
import argparse
import json

import flowfusion as ff

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("sequence", help="TUM-layout folder (rgb.txt, depth.txt, rgb/, depth/)")
parser.add_argument("out", help="output folder (trajectory.txt, masks/, map.ply, ...)")
parser.add_argument("--frames", help="FIRST:LAST frame indices (inclusive)")
parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="override a setting")
args = parser.parse_args()

cfg = ff.Config()
for assignment in args.set:
    key, _, text = assignment.partition("=")
    try:
        value = json.loads(text)
    except json.JSONDecodeError:
        value = text  # a bare word, e.g. frame_to_model
    cfg.set(key, value)

seq = ff.TumSequence(args.sequence, frames=args.frames)
system = ff.System(seq.camera, cfg, T_world_first=seq.initial_pose())
for frame in seq:
    # process(frame) is what `flowfusion run` does; a source of one's own passes arrays instead:
    # system.process(rgb, depth, timestamp, depth_timestamp=...) (the depth image's own time).
    result = system.process(frame)
    if not result.tracking_ok:
        print(f"{frame.timestamp:.6f}: tracking lost ({result.message})")
system.save(args.out, sequence=seq)
print(f"{len(seq)} frames, results in {args.out}")
if seq.groundtruth is not None:
    ate = ff.eval.ate(seq.groundtruth, system.trajectory())
    print(f"ATE RMSE {ate['translation_m']['rmse'] * 1000:.1f} mm over {ate['matched_poses']} poses")
