"""Many sequences (and a grid of settings) as Dask tasks, one CSV row per (sequence, setting): ATE,
RPE, mask IoU and milliseconds per frame.

    python3 -m flowfusion.batch SEQ [SEQ ...] --out table.csv [--grid odometry.levels=3,4 ...]
        [--frames FIRST:LAST] [--rpe-delta 1.0] [--workers 2 | --scheduler tcp://HOST:8786]

Without --scheduler a LocalCluster of --workers processes runs the tasks; with it the same tasks go
to an existing Dask cluster, whose workers need `import flowfusion` and the sequence folders at the
same paths. Each task is the loop `flowfusion run` makes (System.process(frame) over a TumSequence).
A task that fails gets its row with the reason in the `error` column, and the others still run; a
metric that does not apply (no ground truth or masks, a run not longer than --rpe-delta, too few
poses) is left empty with the reason in `notes`. The CSV is written whole or not at all, after every
task ended; the exit status is 1 when any task failed, 2 for bad arguments, else 0.
"""
import argparse
import csv
import itertools
import json
import logging
import os
import sys
import tempfile
import time

import flowfusion as ff

COLUMNS = ["sequence", "setting", "frames", "ate_rmse_m", "rpe_translation_rmse_m_per_s",
           "rpe_rotation_rmse_deg_per_s", "mean_iou", "ms_per_frame", "notes", "error"]


def parse_value(text):
    """'4' -> 4, 'true' -> True, 'frame_to_model' -> 'frame_to_model' (as Config.set takes values)."""
    try:
        return json.loads(text)
    except json.JSONDecodeError:
        return text


def grid_axis(assignment):
    """'a.b=1,2' -> [('a.b', 1), ('a.b', 2)]; argparse's type for --grid."""
    key, sep, values = assignment.partition("=")
    if not sep or not key or not values or "" in values.split(","):
        raise argparse.ArgumentTypeError(f"'{assignment}': expected KEY=V1[,V2...] (e.g. odometry.levels=3,4)")
    return [(key, parse_value(v)) for v in values.split(",")]


def settings_grid(axes):
    """[[('a.b', 1), ('a.b', 2)], [('c.d', 'x')]] -> [{'a.b': 1, 'c.d': 'x'}, {'a.b': 2, 'c.d': 'x'}]."""
    return [dict(combination) for combination in itertools.product(*axes)]


def setting_name(settings):
    return " ".join(f"{key}={json.dumps(value)}" for key, value in settings.items()) or "defaults"


def config_of(settings):
    """The ff.Config with the settings applied (ValueError naming a bad one)."""
    cfg = ff.Config()
    for key, value in settings.items():
        cfg.set(key, value)
    return cfg


def trajectory_metrics(seq, estimate, rpe_delta, row, notes):
    """ATE and RPE into the row, or the reason each does not apply into notes."""
    if seq.groundtruth is None:
        notes.append("no ground truth: no ATE or RPE")
        return
    try:
        row["ate_rmse_m"] = ff.eval.ate(seq.groundtruth, estimate)["translation_m"]["rmse"]
    except ValueError as e:
        notes.append(f"ATE: {e}")
    span = estimate[-1, 0] - estimate[0, 0] if len(estimate) else 0.0
    if span <= rpe_delta:
        notes.append(f"RPE: the run spans {span:.3f} s, not longer than --rpe-delta {rpe_delta:g} s")
        return
    try:
        rpe = ff.eval.rpe(seq.groundtruth, estimate, delta=rpe_delta)
        row["rpe_translation_rmse_m_per_s"] = rpe["translation_rmse_m_per_s"]
        row["rpe_rotation_rmse_deg_per_s"] = rpe["rotation_rmse_deg_per_s"]
    except ValueError as e:
        notes.append(f"RPE: {e}")


def mask_metrics(seq, system, row, notes):
    """Mean IoU of the run's masks (saved as `flowfusion run` writes them) against the sequence's."""
    if seq.masks_dir is None:
        notes.append("no ground-truth masks: no IoU")
        return
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "run")
        system.save(out, sequence=seq, export_map=False)
        try:
            row["mean_iou"] = ff.eval.seg(seq.masks_dir, os.path.join(out, "masks"))["mean_iou"]
        except ValueError as e:
            notes.append(f"IoU: {e}")


def run_task(sequence, settings, rpe_delta, frames):
    """One sequence with one setting: the row, never an exception (a failure is the row's error)."""
    row = dict.fromkeys(COLUMNS, "")
    row.update(sequence=sequence, setting=setting_name(settings))
    notes = []
    try:
        seq = ff.TumSequence(sequence, frames=frames)
        system = ff.System(seq.camera, config_of(settings), T_world_first=seq.initial_pose())
        start = time.perf_counter()
        for frame in seq:
            system.process(frame)
        row["frames"] = len(seq)
        row["ms_per_frame"] = (time.perf_counter() - start) * 1000.0 / len(seq)
        trajectory_metrics(seq, system.trajectory(), rpe_delta, row, notes)
        mask_metrics(seq, system, row, notes)
    except Exception as e:  # the row reports it; the batch goes on
        row["error"] = f"{type(e).__name__}: {e}"
    row["notes"] = "; ".join(notes)
    return row


def run_tasks(client, tasks, rpe_delta, frames):
    """The rows in the tasks' order; a task whose worker died gets its row with the error too."""
    futures = [client.submit(run_task, sequence, settings, rpe_delta, frames, pure=False)
               for sequence, settings in tasks]
    rows = []
    for (sequence, settings), future in zip(tasks, futures):
        try:
            rows.append(future.result())
        except Exception as e:
            row = dict.fromkeys(COLUMNS, "")
            row.update(sequence=sequence, setting=setting_name(settings), error=f"{type(e).__name__}: {e}")
            rows.append(row)
    return rows


def write_csv_atomic(path, rows):
    """The table under a temporary name beside `path`, renamed into place once complete."""
    folder = os.path.dirname(os.path.abspath(path))
    fd, tmp = tempfile.mkstemp(prefix=".batch-", suffix=".csv", dir=folder)
    try:
        with os.fdopen(fd, "w", newline="") as f:
            writer = csv.DictWriter(f, fieldnames=COLUMNS)
            writer.writeheader()
            writer.writerows(rows)
        os.replace(tmp, path)
    except BaseException:
        os.unlink(tmp)
        raise


def check_arguments(parser, args):
    """Refuses what would fail every task or touch an input, before any task starts."""
    if not args.rpe_delta > 0 or args.rpe_delta == float("inf"):
        parser.error(f"--rpe-delta {args.rpe_delta}: must be a positive number of seconds")
    if args.workers < 1:
        parser.error(f"--workers {args.workers}: must be at least 1")
    out = os.path.realpath(args.out)
    if os.path.isdir(out):
        parser.error(f"--out {args.out}: is a folder; give the CSV file to write")
    if not os.path.isdir(os.path.dirname(out)):
        parser.error(f"--out {args.out}: the folder {os.path.dirname(args.out) or '.'} does not exist")
    for sequence in args.sequences:
        if os.path.commonpath([out, os.path.realpath(sequence)]) == os.path.realpath(sequence):
            parser.error(f"--out {args.out}: lies inside the input sequence {sequence}; choose another file")
    for axis in args.grid:
        for key, value in axis:
            try:
                ff.Config().set(key, value)
            except ValueError as e:
                parser.error(f"--grid {key}={json.dumps(value)}: {e}")


def parse_arguments(argv):
    parser = argparse.ArgumentParser(prog="python3 -m flowfusion.batch", description=__doc__.splitlines()[0])
    parser.add_argument("sequences", nargs="+", help="TUM-layout sequence folders")
    parser.add_argument("--out", required=True, help="CSV file to write")
    parser.add_argument("--grid", action="append", default=[], type=grid_axis, metavar="KEY=V1,V2",
                        help="a setting and its values to try (repeatable: every combination runs)")
    parser.add_argument("--frames", help="FIRST:LAST frame indices of every sequence")
    parser.add_argument("--rpe-delta", type=float, default=1.0, help="RPE pair spacing, s (default 1)")
    parser.add_argument("--scheduler", help="address of an existing Dask scheduler (tcp://HOST:8786)")
    parser.add_argument("--workers", type=int, default=2, help="LocalCluster worker processes (default 2)")
    args = parser.parse_args(argv)
    check_arguments(parser, args)
    return args


def compute_rows(args, tasks):
    from dask.distributed import Client, LocalCluster

    if args.scheduler:
        with Client(args.scheduler, timeout="20s") as client:
            return run_tasks(client, tasks, args.rpe_delta, args.frames)
    with LocalCluster(n_workers=args.workers, threads_per_worker=1, dashboard_address=None,
                      silence_logs=logging.ERROR) as cluster, Client(cluster) as client:
        return run_tasks(client, tasks, args.rpe_delta, args.frames)


def main(argv=None):
    args = parse_arguments(argv)
    tasks = [(os.path.abspath(s), g) for s in args.sequences for g in settings_grid(args.grid)]
    try:
        rows = compute_rows(args, tasks)
    except (OSError, TimeoutError) as e:
        print(f"flowfusion.batch: error: the Dask cluster ({args.scheduler or 'local'}): {e}", file=sys.stderr)
        return 2
    write_csv_atomic(args.out, rows)
    for row in rows:
        what = f"error: {row['error']}" if row["error"] else \
            f"ATE {row['ate_rmse_m'] or '-'} m, IoU {row['mean_iou'] or '-'}, {row['ms_per_frame']:.1f} ms/frame"
        print(f"{row['sequence']} [{row['setting']}]: {what}")
    failed = sum(1 for row in rows if row["error"])
    print(f"wrote {args.out} ({len(rows)} rows{f', {failed} failed' if failed else ''})")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
