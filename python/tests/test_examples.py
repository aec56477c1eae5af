"""The examples of examples/python run as a user would run them (so that they cannot rot)."""
import os
import subprocess
import sys

import pytest


def run_example(source_dir, name, *args):
    path = os.path.join(source_dir, "examples", "python", name)
    p = subprocess.run([sys.executable, path, *args], capture_output=True, text=True,
                       env=os.environ.copy(), timeout=300)
    assert p.returncode == 0, p.stderr
    return p.stdout


def test_rcs_sweep(source_dir):
    out = run_example(source_dir, "rcs_sweep.py", "--points", "7")
    rows = [l for l in out.splitlines() if l[:8].strip().replace(".", "").isdigit()]
    assert len(rows) == 7, out
    assert "median VV RCS over aspect" in out


def test_engagement(source_dir):
    out = run_example(source_dir, "engagement.py", "--frames", "8")
    assert "8 frames," in out and "8 lists reassembled" in out, out
    # Every frame had an ownship state from the script, so every list got through.
    frames = [l for l in out.splitlines() if l[:5].strip().isdigit()]
    assert len(frames) == 8


@pytest.mark.parametrize("scenario", ["faulty_bus.toml"])
def test_engagement_with_a_scenario_file(source_dir, scenario):
    out = run_example(source_dir, "engagement.py",
                      os.path.join(source_dir, "examples", scenario), "--frames", "4")
    assert "4 frames," in out
