"""Shared fixtures: the module, the `flowfusion` executable, short sequences.

Run from the build tree with PYTHONPATH=build/python (ctest sets it, and FLOWFUSION_APP to the
executable the comparisons with `flowfusion run` use).
"""
import os
import shutil
import subprocess
from pathlib import Path

import pytest

import flowfusion as ff

REPO = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="session")
def app():
    """Path of the `flowfusion` executable; the comparisons with it skip when it is not found."""
    path = os.environ.get("FLOWFUSION_APP") or shutil.which("flowfusion")
    if not path or not os.path.exists(path):
        pytest.skip("the flowfusion executable was not found (set FLOWFUSION_APP)")
    return path


def run_app(app, *args):
    """Runs `flowfusion ARGS...`; returns its stdout and fails the test with its stderr on error."""
    p = subprocess.run([app, *map(str, args)], capture_output=True, text=True)
    assert p.returncode == 0, f"flowfusion {' '.join(map(str, args))} failed:\n{p.stderr}"
    return p.stdout


@pytest.fixture(scope="session")
def synth_seq(tmp_path_factory):
    """A 20-frame 320x240 synthetic sequence with two moving objects and exact ground truth."""
    out = tmp_path_factory.mktemp("synth") / "seq"
    return Path(ff.synth(out, seed=5, frames=20, objects=2, width=320, height=240))


@pytest.fixture(scope="session")
def fr1():
    """The shared TUM fr1/xyz frames, or a skip when they are absent."""
    base = Path(os.environ.get("FLOWFUSION_SHARED_DATA") or REPO.parent / "shared" / "data")
    path = base / "tum" / "fr1_xyz_head300"
    if not (path / "rgb.txt").exists():
        pytest.skip(f"shared data {path} is absent")
    return path
