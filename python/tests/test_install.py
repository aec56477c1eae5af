"""`cmake --install BUILD --prefix P` into a temporary prefix: the binary, the Python module in
the prefix's site-packages, the DBC, the ICDs and the examples are there, and the installed
module imports (and works) from that prefix alone."""
import glob
import os
import subprocess
import sys


def test_install_tree(tmp_path):
    build = os.environ["RADAR_EMU_BUILD_DIR"]
    cmake = os.environ.get("RADAR_EMU_CMAKE", "cmake")
    site_rel = os.environ["RADAR_EMU_PYTHON_INSTALL_DIR"]
    prefix = tmp_path / "prefix"
    p = subprocess.run([cmake, "--install", build, "--prefix", str(prefix)],
                       capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    site = prefix / site_rel
    expected = [
        prefix / "bin" / "radar-emu",
        prefix / "share" / "radar-emu" / "radar_emu_detections.dbc",
        prefix / "share" / "doc" / "radar-emu" / "icd" / "detections.md",
        prefix / "share" / "doc" / "radar-emu" / "icd" / "canaerospace_input.md",
        prefix / "share" / "doc" / "radar-emu" / "icd" / "modbus.md",
        prefix / "share" / "doc" / "radar-emu" / "python.md",
        prefix / "share" / "radar-emu" / "examples" / "faulty_bus.toml",
        prefix / "share" / "radar-emu" / "examples" / "python" / "rcs_sweep.py",
        prefix / "share" / "radar-emu" / "examples" / "python" / "engagement.py",
    ]
    missing = [str(f) for f in expected if not f.is_file()]
    assert not missing, missing
    assert glob.glob(str(site / "radar_emu*.so")), f"no module in {site}"
    assert os.access(prefix / "bin" / "radar-emu", os.X_OK)
    # The installed module alone: a clean environment, run from an unrelated directory.
    env = {"PATH": os.environ.get("PATH", "/usr/bin:/bin"), "PYTHONPATH": str(site)}
    code = ("import radar_emu; print(radar_emu.__file__); "
            "print(len(radar_emu.atten([10e9])))")
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env,
                       cwd=tmp_path)
    assert p.returncode == 0, p.stderr
    assert p.stdout.splitlines()[0].startswith(str(site)) and p.stdout.splitlines()[1] == "1"
    p = subprocess.run([str(prefix / "bin" / "radar-emu"), "--version"], capture_output=True,
                       text=True)
    assert p.returncode == 0 and "radar-emu" in p.stdout


def test_another_interpreter_without_numpy_is_told_which_one_to_use():
    """An interpreter that cannot import NumPy (here the build's own with -S: no site-packages,
    so no Debian NumPy) gets one ImportError naming the interpreter the module was built for,
    not a bare missing-module error from the first array."""
    build_py = os.path.join(os.environ["RADAR_EMU_BUILD_DIR"], "python")
    code = ("import sys; sys.path.insert(0, sys.argv[1])\n"
            "try:\n    import numpy\nexcept ImportError:\n    pass\n"
            "else:\n    sys.exit(77)\n"
            "import radar_emu\n")
    p = subprocess.run([sys.executable, "-S", "-c", code, build_py], capture_output=True,
                       text=True, env={"PATH": os.environ.get("PATH", "/usr/bin:/bin")})
    if p.returncode == 77:
        import pytest
        pytest.skip(f"{sys.executable} -S still imports NumPy: no interpreter without it here")
    assert p.returncode != 0
    last = p.stderr.strip().splitlines()[-1]
    assert last.startswith("ImportError: radar_emu: this interpreter"), p.stderr
    assert "cannot import NumPy" in last and "the module was built for /" in last, last
