"""radar_emu.Loop stepped from Python against `radar-emu run` on the same scenario: every
frame's header, ownship position, detections and truth equal to detections.json and truth.json.
Those files print doubles with std::to_chars (shortest round trip), so json.load gives the
exact doubles and the comparison is bit for bit."""
import json
import os

import numpy as np
import pytest

import radar_emu

DETECTION_KEYS = ["range_m", "azimuth_deg", "elevation_deg", "radial_velocity_mps", "snr_db",
                  "rcs_dbsm", "range_std_m", "azimuth_std_deg", "elevation_std_deg",
                  "radial_velocity_std_mps", "range_ambiguous", "velocity_ambiguous"]
TRUTH_KEYS = ["range_m", "azimuth_deg", "elevation_deg", "radial_velocity_mps"]


def json_value(v):
    return float("nan") if v is None else v


def same(a, b):
    return a == b or (isinstance(a, float) and np.isnan(a) and np.isnan(b))


def compare_run(out_dir, frames):
    with open(os.path.join(out_dir, "detections.json")) as f:
        cli_dets = json.load(f)["frames"]
    with open(os.path.join(out_dir, "truth.json")) as f:
        cli_truth = json.load(f)["frames"]
    assert len(cli_dets) == len(frames) == len(cli_truth)
    total = 0
    for k, (fr, cd, ct) in enumerate(zip(frames, cli_dets, cli_truth)):
        assert fr["frame_counter"] == cd["frame_counter"], k
        assert fr["time_s"] == cd["time_s"], k
        assert fr["status"] == cd["status"], k
        assert fr["sent"] == cd.get("sent", True), k
        assert fr["ownship_valid"] == ct["ownship_valid"], k
        if fr["ownship_valid"]:
            assert list(fr["ownship_enu_m"]) == cd["ownship_enu_m"], k
        dets = fr["detections"]
        assert len(dets) == len(cd["detections"]), f"frame {k}"
        for i, d in enumerate(cd["detections"]):
            for key in DETECTION_KEYS:
                assert same(dets[key][i].item(), json_value(d[key])), f"frame {k} det {i} {key}"
            want_id = -1 if d["object_id"] is None else d["object_id"]
            assert dets["object_id"][i] == want_id, f"frame {k} det {i} object_id"
        truth = fr["truth"]
        assert len(truth) == len(ct["objects"]), f"frame {k}"
        for i, o in enumerate(ct["objects"]):
            assert truth["object_id"][i] == o["object_id"]
            for key in TRUTH_KEYS:
                assert truth[key][i] == o[key], f"frame {k} truth {i} {key}"
        total += len(dets)
    return total


def step_all(loop):
    frames = []
    while (f := loop.step()) is not None:
        frames.append(f)
    return frames


def test_default_scenario_matches_run(cli, tmp_path):
    n = 30
    cli("run", "--frames", n, "--out", tmp_path / "cli", "-q")
    loop = radar_emu.Loop(frames=n)
    frames = step_all(loop)
    summary = loop.finish()
    assert summary["frames"] == n and len(frames) == n
    total = compare_run(tmp_path / "cli", frames)
    print(f"default scenario: {n} frames, {total} detections identical to detections.json")
    assert total > 0
    assert summary["detections_total"] == total


def test_scenario_file_with_faults_matches_run(cli, tmp_path, source_dir):
    # A faulty bus (drops, corruption, a stale INS, malformed frames): the stepped loop takes
    # the same seeded faults, so frames with a stale state match too. Its own outputs as well.
    scenario = os.path.join(source_dir, "examples", "faulty_bus.toml")
    n = 60
    cli("run", scenario, "--frames", n, "--out", tmp_path / "cli", "-q")
    loop = radar_emu.Loop(scenario, frames=n, out_dir=str(tmp_path / "py"))
    frames = list(loop)
    loop.finish()
    total = compare_run(tmp_path / "cli", frames)
    print(f"faulty_bus.toml: {n} frames, {total} detections identical")
    with open(tmp_path / "cli" / "detections.json") as a, \
            open(tmp_path / "py" / "detections.json") as b:
        assert a.read() == b.read()
    with open(tmp_path / "cli" / "bus_out.log") as a, open(tmp_path / "py" / "bus_out.log") as b:
        assert a.read() == b.read()


def test_toml_text_and_ownship_from_python():
    # The scenario as TOML text; the ownship flown from Python: the frame uses the given
    # position (echoed), and a static object's truth range shrinks by the displacement along
    # the line of sight (geometry, independent of the loop).
    toml = radar_emu.default_scenario_toml().replace("frames = 200", "frames = 5")
    loop = radar_emu.Loop(toml=toml)
    assert loop.frames == 5
    p0 = np.array([0.0, -3000.0, 180.0])
    step_m = np.array([0.0, 50.0, 0.0])
    own = dict(position_enu_m=p0, velocity_enu_mps=[0.0, 70.0, 0.0], heading_deg=0.0,
               pitch_deg=0.0, roll_deg=0.0)
    f0 = loop.step(own)
    own["position_enu_m"] = p0 + step_m
    f1 = loop.step(own)
    for f, p in ((f0, p0), (f1, p0 + step_m)):
        assert f["ownship_valid"] and f["status"] & 0x01 == 0  # not OWNSHIP_INVALID
        assert list(f["ownship_enu_m"]) == list(p)
    assert len(f0["truth"]) > 0
    checked = 0
    for t0 in f0["truth"]:
        t1 = f1["truth"][f1["truth"]["object_id"] == t0["object_id"]]
        if len(t1) == 0 or abs(t0["radial_velocity_mps"] + 70.0 * np.cos(
                np.radians(t0["elevation_deg"])) * np.cos(np.radians(t0["azimuth_deg"]))) > 0.5:
            continue  # left the beam, or a moving object
        # Antenna frame: boresight pitched down by the mount depression; the line of sight's
        # north component is the range rate per metre flown north (far field, to 1 cm).
        los_north = -t0["radial_velocity_mps"] / 70.0
        assert abs((t0["range_m"] - t1["range_m"][0]) - 50.0 * los_north) < 0.01
        checked += 1
    assert checked > 0
    with pytest.raises(ValueError, match="unknown key"):
        loop.step(dict(position_enu_m=p0, speed=3))
    loop.step()
    loop.step()
    loop.step()
    assert loop.step() is None  # five frames
    assert loop.finish()["frames"] == 5


def test_cube_from_python_is_the_clis(cli, tmp_path):
    # Data cubes out (docs/cube.md): Loop(cube=, cube_frames=) writes the file `radar-emu run
    # --cube --cube-frames` writes (every dataset equal), and finish() says what it holds; the
    # scenario's [output] cube does the same; bad values are a ValueError naming the argument.
    h5py = pytest.importorskip("h5py")
    n = 3
    cli("run", "--frames", n, "--out", tmp_path / "cli", "-q", "--cube", tmp_path / "cli.h5",
        "--cube-frames", "1:2")
    loop = radar_emu.Loop(frames=n, cube=str(tmp_path / "py.h5"), cube_frames="1:2")
    assert len(list(loop)) == n
    c = loop.finish()["cube"]
    assert (c["frames_written"], c["first_frame"], c["last_frame"]) == (2, 1, 2)
    assert c["frames_dropped"] == 0 and c["write_errors"] == 0 and c["first_error"] == ""
    toml = radar_emu.default_scenario_toml().replace(
        "[output]\n", f'[output]\ncube = "{tmp_path / "toml.h5"}"\ncube_frames = "1:2"\n', 1)
    loop = radar_emu.Loop(toml=toml, frames=n)
    list(loop)
    assert loop.finish()["cube"]["frames_written"] == 2
    with h5py.File(tmp_path / "cli.h5") as a:
        for other in ("py.h5", "toml.h5"):
            with h5py.File(tmp_path / other) as b:
                assert list(b["frames"][...]) == [1, 2]
                for g in ("frame_000001", "frame_000002"):
                    for ds in ("raw", "image", "detections"):
                        assert np.array_equal(a[g][ds][...], b[g][ds][...]), f"{other} {g}/{ds}"
    no_cube = radar_emu.Loop(frames=1)
    list(no_cube)
    assert no_cube.finish()["cube"] is None
    with pytest.raises(ValueError, match="cube_frames= 5:1': LAST is before FIRST|LAST is before"):
        radar_emu.Loop(frames=n, cube=str(tmp_path / "x.h5"), cube_frames="5:1")
    with pytest.raises(ValueError, match="cube= .*not an HDF5 file name"):
        radar_emu.Loop(frames=n, cube=str(tmp_path / "x.txt"))
    with pytest.raises(ValueError, match="cube_frames= 0:1: needs a cube file"):
        radar_emu.Loop(frames=n, cube_frames="0:1")
