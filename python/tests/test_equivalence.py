"""A Python loop over ff.TumSequence with System.process reproduces `flowfusion run`: the same poses
(to 1e-9 against the same loop in C++, ff.run; the same trajectory.txt as the executable) and the
same mask files, with the same configuration. (The maps are not exported here: test_save_eval.py
exports one.)"""
import filecmp
import json

import numpy as np

import flowfusion as ff
from conftest import run_app

SETTINGS = {"pipeline.max_iterations": 4, "odometry.levels": 3}


def python_loop(seq, cfg):
    """Feeds every frame as NumPy arrays, as a user's own source would."""
    system = ff.System(seq.camera, cfg, T_world_first=seq.initial_pose())
    dynamic_pixels = 0
    for f in seq:
        r = system.process(f.rgb, f.depth, f.timestamp, depth_timestamp=f.depth_timestamp)
        assert r.T_world_cam.shape == (4, 4) and r.T_world_cam.dtype == np.float64
        assert r.dynamic_mask.shape == f.depth.shape and r.dynamic_mask.dtype == np.uint8
        assert r.timestamp == f.timestamp
        dynamic_pixels += int(np.count_nonzero(r.dynamic_mask))
    return system, dynamic_pixels


def check_same_as_run(app, path, tmp_path, frames=None):
    cfg = ff.Config()
    for key, value in SETTINGS.items():
        cfg.set(key, value)
    seq = ff.TumSequence(path, frames=frames)
    system, dynamic_pixels = python_loop(seq, cfg)
    ours = tmp_path / "python"
    system.save(ours, sequence=seq, export_map=False)

    reference = ff.run(path, tmp_path / "ff_run", config=cfg, frames=frames, export_map=False)
    assert reference["frames"] == len(seq) == system.frames
    np.testing.assert_allclose(system.trajectory(), reference["trajectory"], rtol=0, atol=1e-9)

    args = ["run", path, "--out", tmp_path / "app", "--quiet", "--no-map"]
    for key, value in SETTINGS.items():
        args += ["--set", f"{key}={value}"]
    if frames:
        args += ["--frames", frames]
    run_app(app, *args)
    theirs = tmp_path / "app"
    assert (ours / "trajectory.txt").read_text() == (theirs / "trajectory.txt").read_text()
    assert json.loads((ours / "config.json").read_text()) == json.loads((theirs / "config.json").read_text())
    names = sorted(p.name for p in (theirs / "masks").iterdir())
    assert len(names) == len(seq)
    assert names == sorted(p.name for p in (ours / "masks").iterdir())
    _, mismatch, errors = filecmp.cmpfiles(ours / "masks", theirs / "masks", names, shallow=False)
    assert not mismatch and not errors
    return dynamic_pixels


def test_synthetic_loop_matches_run(app, synth_seq, tmp_path):
    dynamic_pixels = check_same_as_run(app, synth_seq, tmp_path)
    assert dynamic_pixels > 0  # the moving objects were segmented: the masks compared are not all empty


def test_fr1_loop_matches_run(app, fr1, tmp_path):
    check_same_as_run(app, fr1, tmp_path, frames="0:29")
