"""Map reuse from Python: ff.run(..., map_in=RUN1) and ff.System(..., map_in=RUN1) continue in a
previous run's map as `flowfusion run --map-in` does; a bad map is a ValueError naming the file."""
import json
from pathlib import Path

import numpy as np
import pytest

import flowfusion as ff


@pytest.fixture(scope="module")
def loop_seq(tmp_path_factory):
    """45 frames round the synthetic room's loop at 0.5 m/s: 1.5 s, about 70 degrees, a few keyframes."""
    out = tmp_path_factory.mktemp("map_reuse") / "loop"
    return Path(ff.synth(out, seed=1, frames=45, objects=0, width=320, height=240, camera_path="loop",
                         camera_speed=0.5))


@pytest.fixture(scope="module")
def first_run(loop_seq, tmp_path_factory):
    out = tmp_path_factory.mktemp("map_reuse") / "run1"
    ff.run(loop_seq, out)
    assert (out / "map.ffmap").is_file()
    return out


def test_run_continues_in_the_first_runs_world_frame(loop_seq, first_run, tmp_path):
    result = ff.run(loop_seq, tmp_path / "run2", map_in=first_run)
    summary = json.loads((tmp_path / "run2" / "summary.json").read_text())
    assert summary["map_in"]["localized_at_frame"] == 0
    assert summary["map_in"]["keyframes"] > 0 and result["map_in"]["surfels"] > 0
    # The first run started at the ground truth's pose: the second one's poses stand on the truth.
    gt = ff.TumSequence(loop_seq).groundtruth
    error_m = np.linalg.norm(result["trajectory"][:, 1:4] - gt[: len(result["trajectory"]), 1:4], axis=1)
    assert np.sqrt(np.mean(error_m**2)) < 0.02


def test_system_continues_in_a_saved_map(loop_seq, first_run):
    seq = ff.TumSequence(loop_seq)
    system = ff.System(seq.camera, map_in=first_run / "map.ffmap")
    results = [system.process(f) for f in list(seq)[:3]]
    assert all(r.tracking_ok for r in results), [r.message for r in results]
    assert results[0].message == "localized in the saved map" and results[0].has_pose


def test_bad_map_in_is_a_value_error_naming_the_file(synth_seq, first_run, tmp_path):
    junk = tmp_path / "junk.ffmap"
    junk.write_bytes(b"not a map")
    with pytest.raises(ValueError, match="junk.ffmap: not a flowfusion map file"):
        ff.run(synth_seq, tmp_path / "out", map_in=junk)
    assert not (tmp_path / "out").exists()
    with pytest.raises(ValueError, match="is the --map-in map"):
        ff.run(synth_seq, first_run, map_in=first_run, overwrite=True)
    off = ff.Config()
    off.set("slam.loop_closure", "off")
    with pytest.raises(ValueError, match="needs loop closure"):
        ff.System(ff.TumSequence(synth_seq).camera, config=off, map_in=first_run)
