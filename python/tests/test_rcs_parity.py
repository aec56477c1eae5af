"""radar_emu.rcs / Target.rcs against `radar-emu rcs` on the same mesh: every CSV cell equal.

The CSV prints freq/theta/phi with %.10g, rcs_P_dbsm with %.6f, re_P / im_P with %.9e and the
counters as integers (tools/rcs.cpp); the module returns full doubles. So each value
the module returns is printed here with the CSV's own format and the two texts must be
identical: bit for bit to the CSV's printed precision (the CSV holds no more)."""
import csv
import os

import numpy as np
import pytest

import radar_emu

FORMATS = {"freq_hz": "%.10g", "theta_deg": "%.10g", "phi_deg": "%.10g"}


def csv_format(column):
    if column in FORMATS:
        return FORMATS[column]
    if column.startswith("rcs_"):
        return "%.6f"
    if column.startswith(("re_", "im_")):
        return "%.9e"
    return "%d"


def assert_same_as_csv(array, path):
    with open(path, newline="") as f:
        reader = csv.reader(f)
        header = next(reader)
        rows = list(reader)
    assert list(array.dtype.names) == header
    assert len(rows) == len(array)
    mismatches = []
    for i, row in enumerate(rows):
        for column, text in zip(header, row):
            mine = csv_format(column) % array[column][i]
            if mine != text:
                mismatches.append(f"row {i} {column}: python {mine} cli {text}")
    assert not mismatches, "\n".join(mismatches[:20])
    return len(rows) * len(header)


def run_both(cli, tmp_path, mesh, cli_args, **kwargs):
    out = tmp_path / "cli.csv"
    cli("rcs", "--mesh", mesh, *cli_args, "--out", out, "-q")
    array = radar_emu.rcs(mesh, **kwargs)
    cells = assert_same_as_csv(array, out)
    print(f"{os.path.basename(mesh)}: {len(array)} rows, {cells} CSV cells identical")
    return array


def test_plate_monostatic_and_bistatic(cli, tmp_path):
    mesh = tmp_path / "plate.obj"
    cli("scene", "target", "plate", "--a-m", "0.5", "--b-m", "0.3", "--out", mesh)
    array = run_both(cli, tmp_path, str(mesh),
                     ["--freq-sweep-hz", "8e9:12e9:5", "--theta-deg", "0:60:31", "--phi-deg", "0",
                      "--pol", "HH,VV,HV,VH", "--bounces", "1"],
                     freq_hz="8e9:12e9:5", theta_deg="0:60:31", phi_deg=0.0,
                     pol="HH,VV,HV,VH", bounces=1)
    # Broadside at 10 GHz: the closed form 4 pi (ab)^2 / lambda^2 (physics.md), to 0.05 dB.
    lam = 299792458.0 / 10e9
    expected = 10 * np.log10(4 * np.pi * (0.5 * 0.3) ** 2 / lam ** 2)
    row = array[(array["theta_deg"] == 0) & (array["freq_hz"] == 10e9)]
    assert abs(row["rcs_VV_dbsm"][0] - expected) < 0.05
    # Bistatic: receiver fixed at theta 20 deg, phi 180 deg; the arguments given as arrays.
    out = tmp_path / "bistatic.csv"
    cli("rcs", "--mesh", mesh, "--freq-hz", "10e9", "--theta-deg", "0:40:9", "--phi-deg", "0",
        "--bistatic-theta-deg", "20", "--bistatic-phi-deg", "180", "--bounces", "1",
        "--out", out, "-q")
    target = radar_emu.Target(str(mesh), bounces=1)
    bistatic = target.rcs(10e9, theta_deg=np.linspace(0, 40, 9), phi_deg=[0.0],
                          bistatic_theta_deg=20.0, bistatic_phi_deg=180.0)
    assert_same_as_csv(bistatic, out)


def test_vehicle_multibounce(cli, tmp_path):
    mesh = tmp_path / "vehicle.obj"
    cli("scene", "target", "vehicle", "--a-m", "7", "--b-m", "3.5", "--c-m", "2.5", "--out", mesh)
    array = run_both(cli, tmp_path, str(mesh),
                     ["--freq-sweep-hz", "2e9:10e9:3", "--theta-deg", "80:90:3", "--phi-deg",
                      "0:90:4", "--pol", "HH,VV,HV", "--bounces", "4"],
                     freq_hz="2e9:10e9:3", theta_deg="80:90:3", phi_deg="0:90:4",
                     pol="HH,VV,HV", bounces=4)
    assert len(array) == 3 * 4 * 3
    assert array["tubes_cut_off"].max() > 0 or array["facets_lit"].min() > 0


def test_no_edges(cli, tmp_path):
    # edges=False against --no-edges, and the default (edges on) against the CLI's default, on a
    # plate: its four rims are open-sheet boundaries, so the edge terms change the sidelobes.
    mesh = tmp_path / "plate.obj"
    cli("scene", "target", "plate", "--a-m", "0.4", "--b-m", "0.25", "--out", mesh)
    args = ["--freq-sweep-hz", "9e9:11e9:3", "--theta-deg", "-40:40:17", "--phi-deg", "0:90:2",
            "--pol", "HH,VV,HV", "--bounces", "1"]
    kwargs = dict(freq_hz="9e9:11e9:3", theta_deg="-40:40:17", phi_deg="0:90:2",
                  pol="HH,VV,HV", bounces=1)
    off = run_both(cli, tmp_path, str(mesh), args + ["--no-edges"], edges=False, **kwargs)
    on = run_both(cli, tmp_path, str(mesh), args, **kwargs)
    assert not off["edges"].any() and off["edges_used"].max() == 0
    assert on["edges"].all() and on["edges_used"].min() > 0
    assert np.abs(on["rcs_VV_dbsm"] - off["rcs_VV_dbsm"]).max() > 0.1
    # A turn angle other than the default, and its check (named as the Python argument).
    target = radar_emu.Target(str(mesh), bounces=1, edge_turn_deg=10.0)
    assert target.edges and target.edge_count == 4
    with pytest.raises(ValueError, match="edge_turn_deg must be in"):
        radar_emu.Target(str(mesh), edge_turn_deg=180.0)
    with pytest.raises(ValueError, match="bounces must be in"):
        radar_emu.rcs(str(mesh), 1e9, bounces=0)


def test_scaled_mesh_and_bad_input(cli, tmp_path):
    mesh = tmp_path / "dihedral_mm.stl"
    cli("scene", "target", "dihedral", "--a-m", "400", "--b-m", "300", "--out", mesh)
    run_both(cli, tmp_path, str(mesh),
             ["--freq-hz", "9.4e9", "--theta-deg", "-30:30:13", "--scale", "0.001", "--bounces", "2"],
             freq_hz=9.4e9, theta_deg="-30:30:13", scale=0.001, bounces=2)
    with pytest.raises(ValueError, match="theta_deg"):
        radar_emu.rcs(str(mesh), 1e9, theta_deg="0:10")
    with pytest.raises(ValueError, match="HX"):
        radar_emu.rcs(str(mesh), 1e9, pol="HX")
    with pytest.raises(ValueError, match="unknown mesh format"):
        radar_emu.rcs(str(tmp_path / "x.ply"), 1e9)
