"""Bad inputs raise the stated exceptions with a message naming the argument, path or setting."""
import numpy as np
import pytest

import flowfusion as ff

W, H = 64, 48


@pytest.fixture
def system():
    return ff.System(ff.Camera(50.0, 50.0, 31.5, 23.5, W, H))


def frame(rgb_dtype=np.uint8, depth_dtype=np.float32, rgb_shape=(H, W, 3), depth_shape=(H, W)):
    return np.zeros(rgb_shape, rgb_dtype), np.ones(depth_shape, depth_dtype)


@pytest.mark.parametrize("kwargs, argument", [
    ({"rgb_dtype": np.float32}, "rgb"),
    ({"rgb_shape": (H, W, 4)}, "rgb"),
    ({"rgb_shape": (W, H, 3)}, "rgb"),
    ({"rgb_shape": (H, W, 3, 1)}, "rgb"),
    ({"depth_dtype": np.int32}, "depth"),
    ({"depth_dtype": np.float64}, "depth"),
    ({"depth_shape": (H, W, 1)}, "depth"),
    ({"depth_shape": (H + 1, W)}, "depth"),
])
def test_wrong_array_raises_value_error_naming_it(system, kwargs, argument):
    rgb, depth = frame(**kwargs)
    with pytest.raises(ValueError, match=f"^{argument}: "):
        system.process(rgb, depth, 0.0)
    assert system.frames == 0


def test_bad_depth_values_and_time_order(system):
    rgb, depth = frame()
    depth[0, 0] = -1.0
    with pytest.raises(ValueError, match="^depth: "):
        system.process(rgb, depth, 0.0)
    depth[0, 0] = np.nan  # no measurement, accepted
    system.process(rgb, depth, 1.0)
    depth[0, 0] = 0.0
    with pytest.raises(ValueError, match="^timestamp: "):
        system.process(rgb, depth, 0.5)
    with pytest.raises(ValueError, match="^depth_scale: "):
        system.process(rgb, depth.astype(np.uint16), 2.0, depth_scale=0.0)
    grey = np.zeros((H, W), np.uint8)
    assert system.process(grey, (depth * 5000).astype(np.uint16), 2.0).dynamic_mask.shape == (H, W)


def test_bad_pose_and_camera():
    cam = ff.Camera(50.0, 50.0, 31.5, 23.5, W, H)
    with pytest.raises(ValueError, match="^T_world_first: "):
        ff.System(cam, T_world_first=np.eye(3))
    with pytest.raises(ValueError, match="^T_world_first: "):
        ff.System(cam, T_world_first=2 * np.eye(4))
    with pytest.raises(ValueError, match="Camera"):
        ff.Camera(-1.0, 50.0, 31.5, 23.5, W, H)
    with pytest.raises(ValueError, match="distortion"):
        ff.Camera(50.0, 50.0, 31.5, 23.5, W, H, distortion=(0.1, 0.2))
    with pytest.raises(ValueError, match="nonsense"):
        ff.Camera.preset("nonsense")


def test_missing_paths_raise_file_not_found(tmp_path):
    missing = tmp_path / "missing"
    for call in [lambda: ff.TumSequence(missing), lambda: ff.Config.load(missing / "config.json"),
                 lambda: ff.eval.ate(missing / "gt.txt", np.zeros((3, 8))),
                 lambda: ff.eval.seg(missing, tmp_path), lambda: ff.run(missing, tmp_path / "out")]:
        with pytest.raises(FileNotFoundError, match="missing"):
            call()


@pytest.mark.parametrize("key, value", [
    ("odometry.no_such_setting", 1),
    ("odometry.levels", 0),
    ("odometry.levels", "four"),
    ("pipeline.tracking", "sideways"),
    ("no_section.levels", 3),
])
def test_bad_setting_raises_value_error_naming_it(key, value):
    cfg = ff.Config()
    before = cfg.to_dict()
    with pytest.raises(ValueError, match=key.split(".")[-1]):
        cfg.set(key, value)
    assert cfg.to_dict() == before


def test_bad_inputs_to_tools(tmp_path):
    gt = np.zeros((5, 8))
    gt[:, 0] = np.arange(5)
    gt[:, 7] = 1.0  # qw: identity rotations
    with pytest.raises(ValueError, match="^est: "):
        ff.eval.ate(gt, gt[:, :7])
    bad = gt.copy()
    bad[2, 7] = 0.0
    with pytest.raises(ValueError, match="^est row 2: quaternion"):
        ff.eval.ate(gt, bad)
    with pytest.raises(ValueError, match="^est row 1: timestamps"):
        ff.eval.ate(gt, gt[::-1])
    with pytest.raises(ValueError, match="no_such_key"):
        ff.synth(tmp_path / "s", frames=2, no_such_key=1)
    with pytest.raises(ValueError, match="frames"):
        ff.TumSequence(tmp_path, frames="3")
