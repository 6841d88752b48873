"""The CLI's guarantees from Python (issue 30): hostile arrays never crash or hang the interpreter,
no output goes into an input, masks come back in the pixels of the image given, the form of
process() that matches `flowfusion run`, and errors that name the Python argument."""
import hashlib
import shutil
import time
from pathlib import Path

import numpy as np
import pytest

import flowfusion as ff
from conftest import run_app

W, H = 64, 48


@pytest.fixture
def system():
    return ff.System(ff.Camera(50.0, 50.0, 31.5, 23.5, W, H))


def depth():
    return np.ones((H, W), np.float32)


@pytest.mark.parametrize("shape", [(100000, 100000, 3), (1000000, 20000, 3), (80000, 80000, 3)])
def test_huge_broadcast_colour_is_refused_before_any_copy(system, shape):
    rgb = np.broadcast_to(np.zeros(3, np.uint8), shape)
    start = time.perf_counter()
    with pytest.raises(ValueError, match=r"^rgb: shape \(\d+, \d+, 3\) holds more than 67108864 pixels"):
        system.process(rgb, depth(), 0.0)
    assert time.perf_counter() - start < 1.0
    assert system.frames == 0


def test_long_thin_arrays_report_their_true_size(system):
    thin = np.broadcast_to(np.zeros((1, 1), np.uint8), (3_000_000_000, 1))
    with pytest.raises(ValueError, match=r"^rgb: shape \(3000000000, 1\)"):
        system.process(thin, depth(), 0.0)
    big_depth = np.broadcast_to(np.ones((1, 1), np.float32), (H * 1000, W))
    with pytest.raises(ValueError, match=r"^depth: the image is 64x48000 \(WxH\), the camera is 64x48"):
        system.process(np.zeros((H, W, 3), np.uint8), big_depth, 0.0)


def test_broadcast_and_strided_arrays_of_the_right_size_give_the_contiguous_result(synth_seq):
    seq = ff.TumSequence(synth_seq, frames="0:2")
    a = ff.System(seq.camera, T_world_first=seq.initial_pose())
    b = ff.System(seq.camera, T_world_first=seq.initial_pose())
    for f in seq:
        rgb, d = f.rgb, f.depth
        # The same pixels seen through a strided view (every other column) and a Fortran-ordered copy.
        flipped_rgb, fortran_depth = np.repeat(rgb, 2, axis=1)[:, ::2], np.asfortranarray(d)
        assert not flipped_rgb.flags.c_contiguous and not fortran_depth.flags.c_contiguous
        ra = a.process(rgb, d, f.timestamp, depth_timestamp=f.depth_timestamp)
        rb = b.process(flipped_rgb, fortran_depth, f.timestamp, depth_timestamp=f.depth_timestamp)
        np.testing.assert_array_equal(ra.dynamic_mask, rb.dynamic_mask)
    np.testing.assert_array_equal(a.trajectory(), b.trajectory())
    grey = np.broadcast_to(np.uint8(90), (seq.camera.height, seq.camera.width))
    assert b.process(grey, seq[0].depth, 10.0).dynamic_mask.shape == grey.shape


def tree_digest(root):
    """Every file under root with its content's hash: what "the input is untouched" compares."""
    return {str(p.relative_to(root)): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(Path(root).rglob("*")) if p.is_file()}


@pytest.fixture
def own_seq(synth_seq, tmp_path):
    """A copy of the synthetic sequence that a test may try to damage."""
    return Path(shutil.copytree(synth_seq, tmp_path / "seq"))


def test_save_and_run_never_write_into_the_input(own_seq):
    before = tree_digest(own_seq)
    seq = ff.TumSequence(own_seq, frames="0:2")
    system = ff.System(seq.camera, T_world_first=seq.initial_pose())
    for f in seq:
        system.process(f)
    attempts = [
        (lambda: system.save(own_seq, overwrite=True, sequence=seq), " is the input sequence"),
        (lambda: system.save(own_seq, overwrite=True), " is the input sequence"),  # known from the frames
        (lambda: system.save(own_seq / "masks", overwrite=True), " lies inside the input sequence"),
        (lambda: system.save(own_seq.parent, overwrite=True), " contains the input sequence"),
        (lambda: ff.run(own_seq, own_seq, overwrite=True), " is the input sequence"),
        (lambda: ff.run(own_seq, own_seq / "out"), " lies inside the input sequence"),
    ]
    for call, relation in attempts:
        with pytest.raises(ValueError, match=relation + r" .*results never go into an input"):
            call()
        assert tree_digest(own_seq) == before
    assert not (own_seq / "out").exists()
    # The refusal leaves the output folder free: a save elsewhere, twice in one process, works.
    out = own_seq.parent / "out"
    system.save(out, sequence=seq, export_map=False)
    system.save(out, overwrite=True, sequence=seq, export_map=False)
    assert (out / "trajectory.txt").is_file()


def distorted_copy(synth_seq, tmp_path):
    """The synthetic sequence with a camera.txt declaring lens distortion (so it is undistorted)."""
    root = Path(shutil.copytree(synth_seq, tmp_path / "distorted"))
    fx, fy, cx, cy, w, h = (root / "camera.txt").read_text().splitlines()[-1].split()
    (root / "camera.txt").write_text(f"{fx} {fy} {cx} {cy} {w} {h} 0.25 -0.3 0.002 0.001 0.05\n")
    return root


def test_masks_come_back_in_the_pixels_of_the_image_given(app, synth_seq, tmp_path):
    root = distorted_copy(synth_seq, tmp_path)
    run_app(app, "run", root, "--out", tmp_path / "cli", "--quiet", "--no-map", "--frames", "0:7")
    written = tmp_path / "cli" / "masks"
    seq = ff.TumSequence(root, frames="0:7")
    assert seq.distortion is not None
    raw_seq = ff.TumSequence(root, frames="0:7", undistort=False)
    c = seq.camera
    distorted = ff.Camera(c.fx, c.fy, c.cx, c.cy, c.width, c.height, distortion=seq.distortion)
    by_frame = ff.System(c, T_world_first=seq.initial_pose())  # frames of the sequence
    by_raw = ff.System(distorted, T_world_first=seq.initial_pose())  # raw images, undistorted by the System
    by_undistorted = ff.System(c, T_world_first=seq.initial_pose())  # the frames' (undistorted) arrays
    moved = 0
    for f, raw in zip(seq, raw_seq):
        r = by_frame.process(f)
        r_raw = by_raw.process(raw.rgb, raw.depth, raw.timestamp, depth_timestamp=raw.depth_timestamp)
        r_und = by_undistorted.process(f.rgb, f.depth, f.timestamp, depth_timestamp=f.depth_timestamp)
        cli = written / f"{f.timestamp:.6f}.png"
        assert cli.is_file()
        np.testing.assert_array_equal(r.dynamic_mask, r_raw.dynamic_mask)
        np.testing.assert_array_equal(r.dynamic_mask, seq.to_raw_pixels(r_und.dynamic_mask))
        moved += int(np.count_nonzero(r.dynamic_mask != r_und.dynamic_mask))
    assert moved > 0, "the distortion moves mask pixels, so the test tells raw from undistorted"
    # The files are the CLI's, byte for byte, from the frames and from the raw arrays.
    for system, name in [(by_frame, "frames"), (by_raw, "raw")]:
        system.save(tmp_path / name, sequence=seq, export_map=False)
        names = sorted(p.name for p in written.iterdir())
        assert names == sorted(p.name for p in (tmp_path / name / "masks").iterdir())
        for n in names:
            assert (tmp_path / name / "masks" / n).read_bytes() == (written / n).read_bytes(), (name, n)
    assert "pixels of the image passed in" in ff.Result.dynamic_mask.__doc__


def test_process_frame_is_the_form_that_matches_run(synth_seq, tmp_path):
    # Depth images 10 ms after the colour ones, as TUM's are apart.
    root = Path(shutil.copytree(synth_seq, tmp_path / "late_depth"))
    lines = (root / "depth.txt").read_text().splitlines()
    shifted = [ln if ln.startswith("#") else f"{float(ln.split()[0]) + 0.01:.6f} {ln.split()[1]}" for ln in lines]
    (root / "depth.txt").write_text("\n".join(shifted) + "\n")
    cfg = ff.Config()
    cfg.set("pipeline.max_iterations", 3)
    reference = ff.run(root, tmp_path / "run", config=cfg, frames="0:7", export_map=False)["trajectory"]
    seq = ff.TumSequence(root, frames="0:7")
    by_frame = ff.System(seq.camera, cfg, T_world_first=seq.initial_pose())
    by_arrays = ff.System(seq.camera, cfg, T_world_first=seq.initial_pose())
    for f in seq:
        assert f.depth_timestamp == pytest.approx(f.timestamp + 0.01, abs=1e-9)
        by_frame.process(f)
        by_arrays.process(f.rgb, f.depth, f.timestamp, depth_timestamp=f.depth_timestamp)
    np.testing.assert_allclose(by_frame.trajectory(), reference, rtol=0, atol=1e-9)
    np.testing.assert_allclose(by_arrays.trajectory(), reference, rtol=0, atol=1e-9)
    docs = " ".join(o.__doc__ for o in ff.System.process.__overloads__) if hasattr(ff.System.process, "__overloads__") \
        else ff.System.process.__doc__
    assert "depth_timestamp=frame.depth_timestamp" in docs and "process(frame)" in docs
    assert "matches `flowfusion run`" in ff.Frame.__doc__


def test_arguments_of_the_wrong_type_or_value_name_the_python_argument(system, synth_seq):
    rgb = np.zeros((H, W, 3), np.uint8)
    with pytest.raises(TypeError, match="^depth_timestamp: expected None or a number"):
        system.process(rgb, depth(), 0.0, depth_timestamp="x")
    for bad in [float("nan"), float("inf")]:
        with pytest.raises(ValueError, match="^depth_timestamp: must be finite"):
            system.process(rgb, depth(), 0.0, depth_timestamp=bad)
    assert system.frames == 0
    system.process(rgb, depth(), 0.0, depth_timestamp=np.float64(0.01))  # NumPy numbers are numbers
    for scale in [0.0, float("inf"), float("nan"), 1e-30]:
        with pytest.raises(ValueError, match="^depth_scale: "):
            system.process(rgb, (depth() * 5000).astype(np.uint16), 1.0, depth_scale=scale)
    with pytest.raises(TypeError, match="^frames: expected None or a 'FIRST:LAST' string"):
        ff.TumSequence(synth_seq, frames=(2, 4))
    with pytest.raises(TypeError, match="^camera: "):
        ff.TumSequence(synth_seq, camera=3)


@pytest.mark.parametrize("call, names, flag", [
    (lambda s: ff.TumSequence(s, frames="5:999"), "frames 5:999", "--frames"),
    (lambda s: ff.TumSequence(s, frames="x"), "frames 'x'", "--frames"),
    (lambda s: ff.eval.rpe(ff.TumSequence(s).groundtruth, ff.TumSequence(s).groundtruth, delta=100.0),
     "delta: 100 s", "--delta"),
    (lambda s: ff.eval.ate(ff.TumSequence(s).groundtruth, ff.TumSequence(s).groundtruth, max_diff=-1.0),
     "max_diff: ", "--max-diff"),
    (lambda s: ff.eval.ate(ff.TumSequence(s).groundtruth, ff.TumSequence(s).groundtruth, offset=float("nan")),
     "offset: ", "--offset"),
    (lambda s: ff.TumSequence(s, depth_scale=1e9), "depth_scale: ", "--depth-scale"),
])
def test_errors_name_python_arguments_not_command_line_flags(synth_seq, call, names, flag):
    with pytest.raises(ValueError) as error:
        call(synth_seq)
    assert names in str(error.value) and flag not in str(error.value)
