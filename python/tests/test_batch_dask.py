"""examples/python/batch_dask.py on a 2-worker LocalCluster over two short synthetic sequences: its
table matches single runs (`flowfusion run` and `flowfusion eval`) of the same sequences."""
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
    p = subprocess.run([sys.executable, str(REPO / "examples" / "python" / "batch_dask.py"), *sequences,
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
