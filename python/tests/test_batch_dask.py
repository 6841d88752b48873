"""`python3 -m flowfusion.batch` (and examples/python/batch_dask.py, which calls it) on a 2-worker
LocalCluster: its table matches single runs (`flowfusion run` and `flowfusion eval`) of the same
sequences, and a bad or short sequence costs only its own row."""
import csv
import json
import os
import subprocess
import sys

import pytest

import flowfusion as ff
from conftest import REPO, run_app

pytest.importorskip("dask.distributed")


def test_batch_table_matches_single_runs(app, tmp_path):
    sequences = [ff.synth(tmp_path / f"seq{seed}", seed=seed, frames=12, objects=1, width=320, height=240)
                 for seed in (4, 5)]
    table = tmp_path / "table.csv"
    p = subprocess.run([sys.executable, "-m", "flowfusion.batch", *sequences,
                        "--out", str(table), "--workers", "2", "--rpe-delta", "0.2",
                        "--grid", "pipeline.max_iterations=4"],
                       capture_output=True, text=True, env=os.environ.copy(), timeout=300)
    assert p.returncode == 0, p.stderr
    rows = {row["sequence"]: row for row in csv.DictReader(table.open())}
    assert len(rows) == 2
    for sequence in sequences:
        row = rows[os.path.abspath(sequence)]
        assert row["setting"] == "pipeline.max_iterations=4" and int(row["frames"]) == 12
        out = tmp_path / ("run_" + os.path.basename(sequence))
        run_app(app, "run", sequence, "--out", out, "--quiet", "--no-map", "--set", "pipeline.max_iterations=4")
        gt = os.path.join(sequence, "groundtruth.txt")
        ate = json.loads(run_app(app, "eval", "ate", gt, out / "trajectory.txt", "--json"))
        rpe = json.loads(run_app(app, "eval", "rpe", gt, out / "trajectory.txt", "--delta", "0.2", "--json"))
        seg = json.loads(run_app(app, "eval", "seg", os.path.join(sequence, "masks"), out / "masks", "--json"))
        # trajectory.txt holds 7 decimals, the task's trajectory full precision
        assert float(row["ate_rmse_m"]) == pytest.approx(ate["translation_m"]["rmse"], abs=1e-6)
        assert float(row["rpe_translation_rmse_m_per_s"]) == pytest.approx(rpe["translation_rmse_m_per_s"], abs=1e-5)
        assert float(row["rpe_rotation_rmse_deg_per_s"]) == pytest.approx(rpe["rotation_rmse_deg_per_s"], abs=1e-3)
        assert float(row["mean_iou"]) == seg["mean_iou"]
        assert float(row["ms_per_frame"]) > 0


def test_a_failed_or_short_sequence_gets_its_row_and_a_non_zero_exit(tmp_path):
    good = ff.synth(tmp_path / "good", seed=4, frames=12, objects=1, width=160, height=120)
    short = ff.synth(tmp_path / "short", seed=5, frames=4, objects=1, width=160, height=120)  # 0.1 s < 1 s
    missing = str(tmp_path / "missing")
    table = tmp_path / "table.csv"
    p = subprocess.run([sys.executable, str(REPO / "examples" / "python" / "batch_dask.py"), good, missing, short,
                        "--out", str(table), "--workers", "2"],
                       capture_output=True, text=True, env=os.environ.copy(), timeout=300)
    assert p.returncode == 1, p.stdout + p.stderr
    assert "Traceback" not in p.stderr, p.stderr
    assert "3 rows, 1 failed" in p.stdout
    rows = {row["sequence"]: row for row in csv.DictReader(table.open())}
    assert len(rows) == 3
    ok, bad, brief = rows[os.path.abspath(good)], rows[missing], rows[os.path.abspath(short)]
    assert ok["error"] == "" and int(ok["frames"]) == 12 and float(ok["ate_rmse_m"]) < 0.05
    assert ok["rpe_translation_rmse_m_per_s"] == "" and "not longer than --rpe-delta" in ok["notes"]  # 0.37 s run
    assert bad["error"].startswith("MissingPathError") and missing in bad["error"] and bad["frames"] == ""
    assert brief["error"] == "" and int(brief["frames"]) == 4 and brief["ate_rmse_m"] != ""
    assert brief["rpe_translation_rmse_m_per_s"] == "" and float(brief["mean_iou"]) >= 0
    assert not list(tmp_path.glob(".batch-*")), "no temporary CSV left"


@pytest.mark.parametrize("args, message", [
    (["--grid", "odometry.levels"], "expected KEY=V1"),
    (["--grid", "odometry.nope=1,2"], "nope"),
    (["--rpe-delta", "0"], "--rpe-delta"),
])
def test_bad_arguments_are_refused_before_any_task(tmp_path, args, message):
    table = tmp_path / "table.csv"
    p = subprocess.run([sys.executable, "-m", "flowfusion.batch", str(tmp_path / "seq"), "--out", str(table), *args],
                       capture_output=True, text=True, env=os.environ.copy(), timeout=60)
    assert p.returncode == 2 and message in p.stderr, p.stderr
    assert not table.exists()
