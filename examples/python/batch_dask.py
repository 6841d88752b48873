#!/usr/bin/env python3
"""Sequences (and a grid of settings) as Dask tasks: one row per (sequence, setting) with ATE, RPE,
mask IoU and milliseconds per frame, written as CSV.

    PYTHONPATH=build/python python3 examples/python/batch_dask.py SEQ [SEQ ...] --out table.csv \\
        [--grid odometry.levels=3,4 ...] [--workers 4 | --scheduler tcp://HOST:8786]

Without --scheduler a LocalCluster of --workers processes runs the tasks; with it the same tasks go to
an existing Dask cluster, whose workers need `import flowfusion` and the sequence folders at the same
paths. Each task is the Python loop of run_sequence.py; sequences without ground truth leave the
metric columns empty.
"""
import argparse
import csv
import itertools
import json
import os
import sys
import tempfile
import time

import flowfusion as ff

COLUMNS = ["sequence", "setting", "frames", "ate_rmse_m", "rpe_translation_rmse_m_per_s",
           "rpe_rotation_rmse_deg_per_s", "mean_iou", "ms_per_frame"]


def parse_value(text):
    """'4' -> 4, 'true' -> True, 'frame_to_model' -> 'frame_to_model' (as --set reads values)."""
    try:
        return json.loads(text)
    except json.JSONDecodeError:
        return text


def settings_grid(grid):
    """['a.b=1,2', 'c.d=x'] -> [{'a.b': 1, 'c.d': 'x'}, {'a.b': 2, 'c.d': 'x'}] (every combination)."""
    axes = []
    for assignment in grid:
        key, _, values = assignment.partition("=")
        axes.append([(key, parse_value(v)) for v in values.split(",")])
    return [dict(combination) for combination in itertools.product(*axes)]


def setting_name(settings):
    return " ".join(f"{key}={json.dumps(value)}" for key, value in settings.items()) or "defaults"


def evaluate(sequence, settings, rpe_delta=1.0, frames=None):
    """One sequence with one setting through the Python loop: the table's row."""
    cfg = ff.Config()
    for key, value in settings.items():
        cfg.set(key, value)
    seq = ff.TumSequence(sequence, frames=frames)
    system = ff.System(seq.camera, cfg, T_world_first=seq.initial_pose())
    start = time.perf_counter()
    for frame in seq:
        system.process(frame)
    ms_per_frame = (time.perf_counter() - start) * 1000.0 / len(seq)
    row = dict.fromkeys(COLUMNS, "")
    row.update(sequence=sequence, setting=setting_name(settings), frames=len(seq), ms_per_frame=ms_per_frame)
    if seq.groundtruth is not None:
        estimate = system.trajectory()
        row["ate_rmse_m"] = ff.eval.ate(seq.groundtruth, estimate)["translation_m"]["rmse"]
        rpe = ff.eval.rpe(seq.groundtruth, estimate, delta=rpe_delta)
        row["rpe_translation_rmse_m_per_s"] = rpe["translation_rmse_m_per_s"]
        row["rpe_rotation_rmse_deg_per_s"] = rpe["rotation_rmse_deg_per_s"]
    if seq.masks_dir is not None:
        with tempfile.TemporaryDirectory() as tmp:
            system.save(tmp, overwrite=True, sequence=seq, export_map=False)
            row["mean_iou"] = ff.eval.seg(seq.masks_dir, os.path.join(tmp, "masks"))["mean_iou"]
    return row


def run_tasks(client, tasks, rpe_delta, frames):
    futures = [client.submit(evaluate, sequence, settings, rpe_delta, frames, pure=False)
               for sequence, settings in tasks]
    return client.gather(futures)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("sequences", nargs="+", help="TUM-layout sequence folders")
    parser.add_argument("--out", required=True, help="CSV file to write")
    parser.add_argument("--grid", action="append", default=[], metavar="KEY=V1,V2",
                        help="a setting and its values to try (repeatable: every combination runs)")
    parser.add_argument("--frames", help="FIRST:LAST frame indices of every sequence")
    parser.add_argument("--rpe-delta", type=float, default=1.0, help="RPE pair spacing, s")
    parser.add_argument("--scheduler", help="address of an existing Dask scheduler (tcp://HOST:8786)")
    parser.add_argument("--workers", type=int, default=2, help="LocalCluster worker processes")
    args = parser.parse_args(argv)

    from dask.distributed import Client, LocalCluster

    tasks = [(os.path.abspath(s), g) for s in args.sequences for g in settings_grid(args.grid)]
    if args.scheduler:
        with Client(args.scheduler) as client:
            rows = run_tasks(client, tasks, args.rpe_delta, args.frames)
    else:
        with LocalCluster(n_workers=args.workers, threads_per_worker=1, dashboard_address=None) as cluster, \
                Client(cluster) as client:
            rows = run_tasks(client, tasks, args.rpe_delta, args.frames)
    with open(args.out, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=COLUMNS)
        writer.writeheader()
        writer.writerows(rows)
    for row in rows:
        print(f"{row['sequence']} [{row['setting']}]: ATE {row['ate_rmse_m']} m, IoU {row['mean_iou']}, "
              f"{row['ms_per_frame']:.1f} ms/frame")
    print(f"wrote {args.out} ({len(rows)} rows)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
