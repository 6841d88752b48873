"""The API of issue 18: cameras, configurations, sequences, results, docstrings."""
import inspect

import numpy as np

import flowfusion as ff


def test_camera_preset_and_values():
    cam = ff.Camera.preset("fr1")
    assert (cam.width, cam.height) == (640, 480) and cam.fx == 517.3 and cam.distortion is not None
    cam = ff.Camera(500.0, 501.0, 319.5, 239.5, 640, 480)
    assert cam.distortion is None
    np.testing.assert_array_equal(cam.K, [[500, 0, 319.5], [0, 501, 239.5], [0, 0, 1]])


def test_config_set_get_round_trip(tmp_path):
    cfg = ff.Config()
    assert cfg.get("odometry.levels") == ff.Config().to_dict()["odometry"]["levels"]
    cfg.set("odometry.levels", np.int64(3))
    cfg.set("pipeline.tracking", "frame_to_model")
    assert cfg.get("odometry.levels") == 3 and cfg.to_dict()["pipeline"]["tracking"] == "frame_to_model"
    cfg.save(tmp_path / "c.json")
    assert ff.Config.load(tmp_path / "c.json").to_dict() == cfg.to_dict()


def test_sequence_frames_and_ground_truth(synth_seq):
    seq = ff.TumSequence(synth_seq)
    assert len(seq) == 20 and seq.camera.width == 320 and seq.distortion is None
    f = seq[0]
    assert f.rgb.shape == (240, 320, 3) and f.rgb.dtype == np.uint8
    assert f.depth.shape == (240, 320) and f.depth.dtype == np.float32
    assert seq[-1].timestamp == seq[19].timestamp > f.timestamp
    assert seq.groundtruth.shape == (20, 8) and seq.masks_dir is not None
    T = seq.initial_pose()
    t, q = seq.groundtruth[0, 1:4], seq.groundtruth[0, 4:8]
    np.testing.assert_allclose(T[:3, 3], t, atol=1e-12)
    assert sum(1 for _ in seq) == 20
    part = ff.TumSequence(synth_seq, frames="5:9")
    assert len(part) == 5 and part[0].timestamp == seq[5].timestamp
    assert np.array_equal(part.to_raw_pixels(np.full((240, 320), 255, np.uint8)), np.full((240, 320), 255))
    assert np.linalg.norm(q) > 0


def test_result_and_trajectory(synth_seq):
    seq = ff.TumSequence(synth_seq, frames="0:2")
    system = ff.System(seq.camera, ff.Config(), T_world_first=seq.initial_pose())
    for f in seq:
        r = system.process(f.rgb, (f.depth * 5000).round().astype(np.uint16), f.timestamp)
        assert r.tracking_ok and isinstance(r.message, str)
    traj = system.trajectory()
    assert traj.shape == (3, 8) and traj.dtype == np.float64
    np.testing.assert_allclose(np.linalg.norm(traj[:, 4:], axis=1), 1.0, atol=1e-9)
    np.testing.assert_allclose(r.T_world_cam[:3, 3], traj[-1, 1:4], atol=1e-12)
    assert set(system.timings()["median_ms"]) >= {"odometry", "flow"}


def test_cluster_log_explains_the_scores(synth_seq, tmp_path):
    seq = ff.TumSequence(synth_seq, frames="0:3")
    cfg = ff.Config()
    cfg.set("pipeline.cluster_log", True)
    system = ff.System(seq.camera, cfg, T_world_first=seq.initial_pose())
    results = [system.process(f.rgb, (f.depth * 5000).round().astype(np.uint16), f.timestamp) for f in seq]
    assert results[0].clusters is None  # the first frame is not scored
    c = results[-1].clusters
    labels = c["labels"]
    assert labels.shape == results[-1].scores.shape and labels.dtype == np.int32
    n = len(c["b"])
    assert n == labels.max() + 1 and all(len(c[k]) == n for k in ("pixels", "r_F_px", "delta", "moving"))
    np.testing.assert_array_equal(np.bincount(labels[labels >= 0], minlength=n), c["pixels"])
    # Each pixel's score is its cluster's.
    inside = labels >= 0
    np.testing.assert_allclose(results[-1].scores[inside], c["b"][labels[inside]], atol=1e-6)
    written = ff.run(synth_seq, tmp_path / "run", config=cfg, frames="0:3", export_map=False)["written"]
    assert any(w.endswith("clusters/") for w in written)
    assert len(list((tmp_path / "run" / "clusters").glob("*.csv"))) == 3  # as `flowfusion run --cluster-log`
    plain = ff.System(seq.camera, ff.Config(), T_world_first=seq.initial_pose())
    assert plain.process(seq[0].rgb, (seq[0].depth * 5000).round().astype(np.uint16), seq[0].timestamp).clusters is None


def test_every_public_name_has_a_docstring():
    for name, obj in vars(ff).items():
        if name.startswith("_") or not (inspect.isclass(obj) or callable(obj)):
            continue
        assert obj.__doc__, name
        if inspect.isclass(obj):
            for member, value in vars(obj).items():
                if not member.startswith("_"):
                    assert getattr(value, "__doc__", None), f"{name}.{member}"
    for name in ["ate", "rpe", "seg"]:
        assert getattr(ff.eval, name).__doc__
    assert "process" in ff.System.__doc__ or "process(" in ff.System.process.__doc__
