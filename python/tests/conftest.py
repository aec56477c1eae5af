"""Shared fixtures of the radar_emu tests: the CLI binary and the source tree, from the
environment ctest sets (python/tests/CMakeLists.txt)."""
import os
import subprocess

import pytest


@pytest.fixture(scope="session")
def cli():
    """Runs `radar-emu ARGS...` (RADAR_EMU_CLI) and fails the test on a non-zero exit."""
    exe = os.environ.get("RADAR_EMU_CLI")
    if not exe:
        pytest.fail("RADAR_EMU_CLI is not set (run the tests through ctest)")

    def run(*args):
        p = subprocess.run([exe, *map(str, args)], capture_output=True, text=True)
        assert p.returncode == 0, f"radar-emu {' '.join(map(str, args))}: {p.stderr}"
        return p.stdout

    return run


@pytest.fixture(scope="session")
def source_dir():
    return os.environ.get("RADAR_EMU_SOURCE_DIR",
                          os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))
