#!/usr/bin/python3
"""No silent surprises (issue 18): every subcommand's options walked with bad values, as a table.
Each row of BAD is a command line that must exit non-zero with ONE line on stderr containing the
fragment: an ignored option (given in a mode that does not read it), a value out of its physical
range (the message in the unit the option is given in), conflicting options, unknown or ignored
scenario keys and glTF extras, an output path that cannot be written (refused before any work:
each row would otherwise run for minutes), a mesh past the memory limit (refused with its
estimate). Each row of QUIET runs with -q and must exit 0 with the warning still on stderr and
nothing on stdout (-q silences progress and the summary only). ISSUE32 is the table of every
silent case issue 32 names, each now an error or a line the user sees.
Usage: check_cli_options.py RADAR_EMU SOURCE_DIR WORK_DIR"""
import json
import os
import socket
import subprocess
import sys
import time

from cli_check import check, finish

exe, src, d = sys.argv[1], sys.argv[2], sys.argv[3]
os.makedirs(d, exist_ok=True)


def write(name, text):
    path = os.path.join(d, name)
    with open(path, "w") as f:
        f.write(text)
    return path


def radar_emu(*args):
    return subprocess.run([exe, *args], capture_output=True, text=True, timeout=300)


# Inputs: a trihedral and a small sphere (made by the tool itself; checked in check_rcs_cli.py),
# a plain file where a directory is expected, scenarios, a glTF with an unknown extras key.
mesh = os.path.join(d, "t.stl")
sphere = os.path.join(d, "s.stl")
for args in (["scene", "target", "trihedral-tri", "--a-m", "0.3", "--out", mesh],
             ["scene", "target", "sphere", "--a-m", "0.05", "--out", sphere],
             ["scene", "target", "plate", "--a-m", "1", "--b-m", "1", "--out",
              os.path.join(d, "plate.gltf")]):
    r = radar_emu(*args)
    if r.returncode != 0:
        sys.exit(f"setup failed: {' '.join(args)}: {r.stderr}")
a_file = write("a_file.txt", "not a directory\n")
no_dir = "/nonexistent_radar_emu_dir"
with open(os.path.join(d, "plate.gltf")) as f:
    gltf = json.load(f)
gltf["nodes"][0]["extras"] = {"radar_emu": {"speed_mps": 3}}
extras = write("extras.gltf", json.dumps(gltf))
toml = {
    "both": '[scene]\nbuiltin = "default"\nfile = "x.glb"\n',
    "seed_file": '[scene]\nfile = "x.glb"\nseed = 3\n',
    "extras_scene": f'[scene]\nfile = "{extras}"\n',
    "unknown_key": '[radar]\ncarrier = 9.4e9\n',
    "unknown_table": '[radr]\ncarrier_hz = 9.4e9\n',
    "pattern_file": '[antenna]\npattern = "gaussian"\npattern_file = "p.csv"\n',
    "gain": '[antenna]\ngain_db = 30.0\nefficiency = 0.5\n',
    "os_rank": '[detector]\ncfar = "ca"\nos_rank = 0.75\n',
    "taylor": '[radar]\ntaylor_nbar = 5\n',
    "range": '[radar]\ncarrier_hz = 94.0\n',
    "facet": '[[target]]\nbuiltin = "sphere"\nsize_m = 1.0\nfacet_m = 1e-4\n'
             'position_enu_m = [0, 0, 0]\n',
}
sc = {k: write(k + ".toml", v) for k, v in toml.items()}
log = os.path.join(src, "tests", "data", "replay", "approach_gap.log")
old_log = write("old.log", "(1000000000.000000) can0 137#0102\n")
f10 = ["--freq-hz", "1e10"]
# A port in use, for the live view's --serve (held open until the script ends).
busy = socket.socket()
busy.bind(("127.0.0.1", 0))
busy.listen()
busy_port = busy.getsockname()[1]

BAD = [
    # unknown options, everywhere
    (["run", "--frobnicate"], "The following argument was not expected: --frobnicate"),
    (["rcs", "--mesh", mesh, *f10, "--no-such-option", "1"], "not expected: 1 --no-such-option"),
    (["scene", "target", "box", "--radius-m", "1", "--out", os.path.join(d, "b.stl")],
     "not expected: 1 --radius-m"),
    # run
    (["run", "--rt-priority", "5"], "--rt-priority requires --realtime"),
    (["run", "--lock-memory"], "--lock-memory requires --realtime"),
    (["run", "--cpu", "1"], "--cpu requires --realtime"),
    (["run", "--realtime", "--cpu", "5000"], "--cpu: Value 5000 not in range 0 to 1023"),
    (["run", "--realtime", "--rt-priority", "0"], "--rt-priority: Value 0 not in range 1 to 99"),
    (["run", "--modbus-linger-s", "5"], "--modbus-linger-s requires --modbus-server"),
    (["run", "--modbus-server", ":0", "--modbus-linger-s", "-1"],
     "--modbus-linger-s: -1 is outside [0, 86400] s"),
    # the live view (run --serve)
    (["run", "--serve", "127.0.0.1:99999"],
     "--serve: '127.0.0.1:99999': expected HOST:PORT, :PORT or PORT with a port 0-65535"),
    (["run", "--serve-wait-s", "5"], "--serve-wait-s requires --serve"),
    (["run", "--serve-linger-s", "5"], "--serve-linger-s requires --serve"),
    (["run", "--serve", ":0", "--serve-wait-s", "-1"], "--serve-wait-s: -1 is outside [0, 86400] s"),
    (["run", "--frames", "1000000", "--serve", f"127.0.0.1:{busy_port}"],
     f"--serve 127.0.0.1:{busy_port}: cannot listen: Address already in use"),
    (["run", "--print-scenario", "--frames", "3"], "excludes --print-scenario"),
    (["run", "--print-scenario", "--out", d], "excludes --print-scenario"),
    (["run", "--frames", "0"], "--frames: Value 0 not in range"),
    (["run", "--frames", "1000000", "--out", a_file + "/out"], "cannot create the output directory"),
    (["run", "--frames", "1000000", "--trace-events", no_dir + "/t.json"],
     "t.json: cannot open for writing: directory " + no_dir + " does not exist"),
    # the scenario: unknown keys and tables, keys a mode does not read, values out of range
    (["run", sc["both"]], "both.toml: [scene] file: builtin and file exclude each other"),
    (["run", sc["seed_file"]], "seed_file.toml: [scene] seed: seeds a built-in scene, not a file"),
    (["run", sc["unknown_key"]], "unknown_key.toml: [radar] carrier: unknown key (known: waveform, "),
    (["run", sc["unknown_table"]], "unknown_table.toml: radr: unknown table (known: name, run, "),
    (["run", sc["pattern_file"]], "[antenna] pattern_file: is read with pattern = \"table\" only"),
    (["run", sc["gain"]], "[antenna] efficiency: unused when gain_db is given"),
    (["run", sc["os_rank"]], "[detector] os_rank: is read with cfar = \"os\" only"),
    (["run", sc["taylor"]], "[radar] taylor_nbar: is read with a \"taylor\" range_window"),
    (["run", sc["range"]], "[radar] carrier_hz: 94 is outside [1e+08, 1e+12]"),
    (["run", sc["facet"]], "facet.toml: [[target]] #1 facet_m: a sphere with 0.0001 m facets "
     "would have "
     "about 3.95e+09 triangles (about 829 GB of memory), over the limit of 2e+07 triangles"),
    # glTF extras: the key and the node
    (["run", sc["extras_scene"]], "node 0 extras radar_emu: unknown key 'speed_mps'"),
    (["scene", "info", extras], "node 0 extras radar_emu: unknown key 'speed_mps'"),
    # replay
    (["replay", log, "--frames", "0"], "--frames: Value 0 not in range"),
    (["replay", log, "--out", a_file + "/replay"], "cannot create the output directory"),
    (["replay", os.path.join(d, "nope.log")], "nope.log"),
    # scene target: dimensions a kind does not read, ranges, the memory limit, the output
    (["scene", "target", "sphere", "--a-m", "1", "--facet-m", "1e-4", "--out",
      os.path.join(d, "big.glb")],
     "a sphere would have about 3.95e+09 triangles (about 829 GB of memory), over the limit of "
     "2e+07 triangles (raise it with --max-triangles"),
    (["scene", "target", "sphere", "--a-m", "1", "--facet-m", "0.01", "--max-triangles", "1000",
      "--out",
      os.path.join(d, "s.glb")], "over the limit of 1e+03 triangles"),
    (["scene", "target", "sphere", "--max-triangles", "0", "--out", os.path.join(d, "s.glb")],
     "--max-triangles: 0 is outside [1, 1.4e+09] triangles"),
    (["scene", "target", "sphere", "--b-m", "2", "--out", os.path.join(d, "s.glb")],
     "--b-m: a sphere takes --a-m only"),
    (["scene", "target", "plate", "--c-m", "2", "--out", os.path.join(d, "p.glb")],
     "--c-m: a plate takes --a-m and --b-m only"),
    (["scene", "target", "box", "--a-m", "0", "--out", os.path.join(d, "b.glb")],
     "--a-m: 0 is outside (0, 100000] m"),
    (["scene", "target", "box", "--facet-m", "-1", "--out", os.path.join(d, "b.glb")],
     "--facet-m: -1 is outside [0, 100000] m"),
    (["scene", "target", "box", "--out", os.path.join(d, "b.ply")],
     "b.ply: cannot write a '.ply' file (expected .glb, .gltf, .obj, .stl)"),
    (["scene", "target", "box", "--out", no_dir + "/b.stl"], "cannot open for writing"),
    (["scene", "target", "cone", "--out", os.path.join(d, "c.stl")], "unknown target 'cone'"),
    # scene gen / preview
    (["scene", "gen", "terrain", "--out", os.path.join(d, "t.obj")], "cannot write a '.obj' file"),
    (["scene", "gen", "terrain", "--out", no_dir + "/t.glb"], "does not exist"),
    (["scene", "preview", extras, "--fov-deg", "0", "--out", os.path.join(d, "v.png")],
     "--fov-deg: 0 is outside (0, 180) deg"),
    (["scene", "preview", extras, "--fov-deg", "180", "--out", os.path.join(d, "v.png")],
     "--fov-deg: 180 is outside (0, 180) deg"),
    (["scene", "preview", extras, "--width", "0", "--out", os.path.join(d, "v.png")],
     "--width: Value 0 not in range 1 to 16384"),
    (["scene", "preview", extras, "--out", os.path.join(d, "v.jpg")],
     "v.jpg: cannot write a '.jpg' file (expected .png)"),
    (["scene", "preview", extras, "--out", no_dir + "/v.png"], "cannot open for writing"),
    # rcs
    (["rcs", "--mesh", mesh, *f10, "--theta-deg", "200"], "--theta-deg: 200 is outside [-180, 180] deg"),
    (["rcs", "--mesh", mesh, *f10, "--theta-deg", "0:200:3"],
     "--theta-deg: 200 (in 0:200:3) is outside [-180, 180] deg"),
    (["rcs", "--mesh", mesh, *f10, "--phi-deg", "400"], "--phi-deg: 400 is outside [-360, 360] deg"),
    (["rcs", "--mesh", mesh, *f10, "--bistatic-theta-deg", "200", "--bistatic-phi-deg", "0"],
     "--bistatic-theta-deg: 200 is outside [0, 180] deg"),
    (["rcs", "--mesh", mesh, *f10, "--bistatic-theta-deg", "20"],
     "--bistatic-theta-deg requires --bistatic-phi-deg"),
    (["rcs", "--mesh", mesh, "--freq-hz", "-1"], "--freq-hz: -1 is outside (0, 1e+15] Hz"),
    (["rcs", "--mesh", mesh, *f10, "--freq-sweep-hz", "9e9:1e10:3"], "excludes"),
    (["rcs", "--mesh", mesh, *f10, "--scale", "0"], "--scale: 0 is outside (0, 1e+06]"),
    (["rcs", "--mesh", mesh, *f10, "--plot", os.path.join(d, "x.jpg")],
     "x.jpg: cannot write a '.jpg' file (expected .png)"),
    (["rcs", "--mesh", mesh, "--freq-sweep-hz", "9e9:1e10:3", "--theta-deg", "0:10:3", "--plot",
      os.path.join(d, "m.png"), "--overlay", mesh + "=ref"],
     "--overlay: curves go on a plot of one swept dimension"),
    (["rcs", "--mesh", mesh, *f10, "--theta-deg", "0:90:901", "--out", no_dir + "/a.csv"],
     "a.csv: cannot open for writing: directory " + no_dir + " does not exist"),
    (["rcs", "--mesh", mesh, *f10, "--out", d], "cannot open for writing: it is a directory"),
    # A full disk (/dev/full) shows only when the buffered CSV is flushed: a failed write.
    (["rcs", "--mesh", sphere, *f10, "--out", "/dev/full"], "/dev/full: write failed"),
    (["rcs", "--mesh", mesh, *f10, "--stats-out", os.path.join(d, "st.csv")],
     "--stats-out requires --window-deg"),
    (["rcs", "--mesh", mesh, *f10, "--window-deg", "10"],
     "--window-deg: needs a sweep in theta or phi"),
    (["rcs", "--mesh", mesh, *f10, "--window-deg", "0"], "--window-deg: 0 is outside (0, 360] deg"),
    (["rcs", "--mesh", mesh, *f10, "--bounces", "1", "--rays-per-wavelength", "8"],
     "--rays-per-wavelength: not used with --bounces 1"),
    (["rcs", "--mesh", mesh, *f10, "--rays-per-wavelength", "0"],
     "--rays-per-wavelength: 0 is outside (0, 1000] rays a wavelength"),
    # profile
    (["profile", "--mesh", mesh, "--freq-sweep-hz", "9e9:1e10:8", "--isar-out",
      os.path.join(d, "i.csv")], "--isar-out: an ISAR image needs a sweep in theta or phi"),
    (["profile", "--mesh", mesh, "--freq-sweep-hz", "9e9:1e10:8", "--isar-plot",
      os.path.join(d, "i.png")], "--isar-plot: an ISAR image needs a sweep in theta or phi"),
    (["profile", "--mesh", mesh, "--freq-sweep-hz", "9e9:1e10:8", "--oversample", "0"],
     "--oversample: Value 0 not in range 1 to 64"),
    (["profile", "--mesh", mesh, "--freq-sweep-hz", "9e9:1e10:8", "--dynamic-range-db", "0"],
     "--dynamic-range-db: 0 is outside (0, 400] dB"),
    (["profile", "--mesh", mesh, "--freq-sweep-hz", "9e9:1e10:8", "--plot",
      os.path.join(d, "p.svg")], "cannot write a '.svg' file"),
    (["profile", "--mesh", mesh, "--freq-sweep-hz", "9e9:1e10:8", "--out", no_dir + "/p.csv"],
     "cannot open for writing"),
    (["profile", "--mesh", sphere, "--freq-sweep-hz", "1.1e10:1.2e10:8", "--out", "/dev/full"],
     "/dev/full: write failed"),
    # ambiguity
    (["ambiguity", "--prf-hz", "1e3", "--out", os.path.join(d, "amb")], "--prf-hz requires --train"),
    (["ambiguity", "--pulses", "8", "--out", os.path.join(d, "amb")], "--pulses requires --train"),
    (["ambiguity", "--train", "--delay-span", "2", "--out", os.path.join(d, "amb")], "excludes"),
    (["ambiguity", "--points", "3"], "--points: Value 3 not in range 11 to 2001"),
    (["ambiguity", "--bandwidth-hz", "0"], "--bandwidth-hz: 0 is outside [1000, 1e+10] Hz"),
    (["ambiguity", "--pulse-width-s", "2"], "--pulse-width-s: 2 is outside [1e-10, 1] s"),
    (["ambiguity", "--out", a_file + "/amb"], "cannot create the output directory"),
    (["ambiguity", os.path.join(d, "nope.toml")], "nope.toml"),
    # atten
    (["atten", "--freq-hz", "0.5e9"], "--freq-hz: 5e+08 is outside [1e+09, 1e+12] Hz"),
    (["atten", "--freq-hz", "1e9:2e12:3"], "(in 1e9:2e12:3) is outside [1e+09, 1e+12] Hz"),
    (["atten", "--freq-hz", "1e10", "--rain-mmh", "-3"], "--rain-mmh: -3 is outside [0, 500] mm/h"),
    (["sigma0", "--material", "grass", "--model", "empirical", "--freq-hz", "94e9"],
     "use --model total at --freq-hz 9.4e+10"),
    (["atten", "--freq-hz", "1e10", "--out-of-leaf"], "--out-of-leaf requires --veg-depth-m"),
    (["atten", "--freq-hz", "1e10", "--pressure-hpa", "-5"],
     "--pressure-hpa: -5 is outside [0, 1100] hPa"),
    (["atten", "--freq-hz", "1e10", "--temp-c", "200"], "--temp-c: 200 is outside [-100, 60] C"),
    (["atten", "--freq-hz", "1e10", "--rho-gm3", "-1"], "--rho-gm3: -1 is outside [0, 130] g/m^3"),
    (["atten", "--freq-hz", "1e10", "--fog-gm3", "9"], "--fog-gm3: 9 is outside [0, 5] g/m^3"),
    (["atten", "--freq-hz", "1e10", "--plot", os.path.join(d, "a.png")],
     "--plot: needs a frequency sweep"),
    (["atten", "--freq-hz", "1e10:2e10:3", "--plot", os.path.join(d, "a.jpg")],
     "cannot write a '.jpg' file"),
    (["atten", "--freq-hz", "1e10", "--out", no_dir + "/a.csv"], "cannot open for writing"),
    (["atten", "--freq-hz", "1e10", "--out", "/dev/full"], "/dev/full: write failed"),
    # image (the EV image of examples/ev_radar_94ghz.toml)
    (["image", "--looks", "0"], "--looks: Value 0 not in range 1 to 1000"),
    (["image", "--time-s", "-1"], "--time-s: -1 is outside [0, 1e+06] s"),
    (["image", "--optical-scale", "0"], "--optical-scale: Value 0 not in range 1 to 16"),
    (["image", "--seed", "-3"], "--seed: '-3' is not a whole number"),
    (["image", "--out", a_file + "/img"], "cannot create the output directory"),
    (["image", os.path.join(d, "nope.toml")], "nope.toml"),
    (["image", os.path.join(src, "examples", "ev_radar_94ghz.toml"), "--time-s", "100",
      "--out", os.path.join(d, "img")], "--time-s: the ownship at t = 100 s is at height -137.0 m"),
    # sigma0
    (["sigma0", "--material", "grass", "--corr", "xpower", "--freq-hz", "1e10"],
     "--material excludes --corr"),
    (["sigma0", "--material", "grass", "--eps-r", "4,0.1", "--freq-hz", "1e10"],
     "--material excludes --eps-r"),
    (["sigma0", "--eps-r", "4,0.1", "--rms-height-m", "0.001", "--corr-length-m", "0.01",
      "--x-power", "2", "--freq-hz", "1e10"], "--x-power requires --corr"),
    (["sigma0", "--eps-r", "4,0.1", "--rms-height-m", "0.001", "--corr-length-m", "0.01",
      "--corr", "gaussian", "--x-power", "2", "--freq-hz", "1e10"],
     "--x-power: used with --corr xpower only"),
    (["sigma0", "--eps-r", "4,0.1", "--rms-height-m", "0.001", "--corr-length-m", "0.01",
      "--corr", "xpower", "--x-power", "1", "--freq-hz", "1e10"], "--x-power: 1 is outside (1, 20]"),
    (["sigma0", "--eps-r", "4,0.1", "--rms-height-m", "0.001", "--corr-length-m", "0.01",
      "--corr", "cosine", "--freq-hz", "1e10"], "--corr: cosine not in"),
    (["sigma0", "--material", "grass", "--phi-s-deg", "30", "--freq-hz", "1e10"],
     "--phi-s-deg requires --theta-s-deg"),
    (["sigma0", "--material", "grass", "--freq-hz", "0"], "--freq-hz: 0 is outside (0, 1e+15] Hz"),
    (["sigma0", "--material", "grass", "--freq-hz", "1e10", "--plot", os.path.join(d, "s.gif")],
     "cannot write a '.gif' file"),
    (["sigma0", "--material", "grass", "--freq-hz", "1e10", "--out", no_dir + "/s.csv"],
     "cannot open for writing"),
    (["sigma0", "--material", "grass", "--freq-hz", "1e10", "--out", "/dev/full"],
     "/dev/full: write failed"),
    # tradeoff
    (["tradeoff", "--out", a_file + "/to"], "cannot create the output directory"),
    (["tradeoff", "--cases", "sphere,cone", "--out", os.path.join(d, "to")], "cone"),
    # sar (issue 17): bad TOML keys and values refused before any pulse is made
    (["sar", write("sar_key.toml", "[radar]\ncarrier = 35e9\n"), "--out", os.path.join(d, "sr")],
     "[radar] carrier: unknown key"),
    (["sar", write("sar_table.toml", "[radr]\n"), "--out", os.path.join(d, "sr")], "radr"),
    (["sar", write("sar_bw.toml", "[radar]\nbandwidth_hz = 0\n"), "--out",
      os.path.join(d, "sr")],
     "sar_bw.toml: [radar] bandwidth_hz: 0 is outside [100000, 1e+10]"),
    (["sar", write("sar_prf.toml", "[radar]\nprf_hz = 10.0\n"), "--out", os.path.join(d, "sr")],
     "prf_hz: pulses every 10"),
    (["sar", write("sar_inc.toml", "[antenna]\nincidence_deg = 95\n"), "--out",
      os.path.join(d, "sr")], "sar_inc.toml: [antenna] incidence_deg: 95 is outside [5, 85]"),
    (["sar", write("sar_syn.toml", "[processing]\nsynthetic_beamwidth_deg = 0.001\n"), "--out",
      os.path.join(d, "sr")], "wider than the antenna's azimuth beamwidth"),
    (["sar", write("sar_taper.toml", "[processing]\ntaper = \"hann\"\n"), "--out",
      os.path.join(d, "sr")],
     "sar_taper.toml: [processing] taper: unknown value \"hann\" (known: none, hamming)"),
    (["sar", write("sar_mat.toml", "[scene]\nground_material = \"lava\"\n"), "--out",
      os.path.join(d, "sr")],
     "sar_mat.toml: [scene] ground_material: unknown value \"lava\" (known: none, "),
    (["sar", write("sar_kind.toml", "[[scene.target]]\nkind = \"cone\"\n"), "--out",
      os.path.join(d, "sr")], "kind: unknown"),
    (["sar", os.path.join(d, "no_such_case.toml")], "no_such_case.toml"),
    (["sar", write("sar_ok.toml", ""), "--out", a_file + "/sar"],
     "cannot create the output directory"),
]

# (command line, fragment of the warning that -q must keep on stderr).
QUIET = [
    (["rcs", "--mesh", sphere, "--freq-hz", "1e9", "-q", "--out", os.path.join(d, "q.csv")],
     "radar-emu: warning: the target is only ka = 1.05"),
    (["profile", "--mesh", sphere, "--freq-sweep-hz", "1e10:2e10:3", "-q", "--out",
      os.path.join(d, "qp.csv")], "radar-emu: warning: the unambiguous range window"),
    (["sigma0", "--material", "grass", "--freq-hz", "35e9", "-q", "--out",
      os.path.join(d, "qs.csv")], "radar-emu: warning: rows with valid=0 leave a model's domain"),
    (["replay", old_log, "--frames", "1", "-q", "--out", os.path.join(d, "qr")],
     "radar-emu replay: warning: log starts at 1000000000.000000 s"),
]

# Issue 32's silent surprises, each now a clear error (exit non-zero, the fragment in the one
# "radar-emu: error:" line; an estimate line may come before it) or a line the user sees
# (exit 0, the fragment on stdout or stderr). Rows: (the case as the issue names it, command
# line, extra environment, "error" | "stdout" | "stderr", fragment).
with open(os.path.join(d, "plate.gltf")) as f:
    incomplete = json.load(f)
incomplete["scenes"][0].setdefault("extras", {}).setdefault("radar_emu", {})["incomplete"] = \
    "import stopped by SIGINT: test"
incomplete_glb = write("incomplete.gltf", json.dumps(incomplete))
sc32 = {k: write(k + ".toml", v) for k, v in {
    "timeline": '[radar]\npulses = 6250\n',
    "cube": '[run]\nrate_hz = 2.0\n[radar]\npulses = 512\n',
    "truck": '[[target]]\nbuiltin = "truck"\nposition_enu_m = [60.0, 150.0, 0.0]\n',
    "incomplete": f'[scene]\nfile = "{incomplete_glb}"\n',
}.items()}
small = {"RADAR_EMU_MAX_MEMORY_MIB": "100"}
ISSUE32 = [
    ("a radar timeline of 5 s per 50 ms frame was accepted and ran (7 GB)",
     ["run", sc32["timeline"], "--frames", "1"], {}, "error",
     "timeline.toml: [radar] pulses: the radar timeline, 16 beam positions x 6250 pulses x 0.05 ms "
     "PRI = 5 s, is longer than the frame period 1 / [run] rate_hz 20 Hz = 50 ms"),
    ("the sensor's cube allocated whatever its size",
     ["run", sc32["cube"], "--frames", "1"], small, "error",
     "cube.toml: [radar] pulses: the sensor needs about 492 MB of memory (16 beam positions x "
     "1502 range bins x 512 pulses, about 40 B a cell for the range-Doppler maps and the CFAR), "
     "over the limit of 105 MB (RADAR_EMU_MAX_MEMORY_MIB=100; set it higher to allow more)"),
    ("the EV image's looks allocated whatever their size",
     ["image", "--out", os.path.join(d, "im32")], small, "error",
     "image: the EV image needs about 162 MB of memory (16 x 8 pixels, 10 looks"),
    ("the MoM matrix allocated whatever its size",
     ["rcs", "--mesh", sphere, "--method", "mom", "--freq-hz", "1e9", "--out",
      os.path.join(d, "mom32.csv")], {"RADAR_EMU_MAX_MEMORY_MIB": "1"}, "error",
     "--method mom: the method of moments needs about 33 MB of memory (1440 unknowns"),
    ("a SAR run's raw data allocated whatever its size",
     ["sar", write("sar32.toml", ""), "--out", os.path.join(d, "sar32")],
     {"RADAR_EMU_MAX_MEMORY_MIB": "1"}, "error",
     "sar: needs about 882 MB of memory (4021 pulses x 830 samples, image 1017 x 535)"),
    ("a memory limit that is not a number",
     ["image", "--out", os.path.join(d, "im32")], {"RADAR_EMU_MAX_MEMORY_MIB": "lots"}, "error",
     "RADAR_EMU_MAX_MEMORY_MIB: 'lots' is not a number of MiB > 0"),
    ("scene target made a canonical shape of a size nobody gave",
     ["scene", "target", "sphere", "--out", os.path.join(d, "s32.stl")], {}, "error",
     "--a-m: a sphere has no default size: give --a-m [radius] in metres"),
    ("scene target truck wrote a 1 x 1 x 1 m truck and did not say its size",
     ["scene", "target", "truck", "--out", os.path.join(d, "truck32.glb")], {}, "stdout",
     "truck32.glb: truck 8 x 2.5 x 3.4 m [length, width, height], 436 triangles"),
    ("[[target]] builtin = \"truck\" did not say its size",
     ["run", sc32["truck"], "--frames", "1"], {}, "stdout",
     "target target_1: truck 8 x 2.5 x 3.4 m [length, width, height]"),
    ("a long command silent until its end (sar ran 3 minutes with nothing on stderr)",
     ["image", "--out", os.path.join(d, "im32")], {}, "stderr",
     "image: estimate: 16 x 8 pixels, 10 looks, 2 strips of 8 columns, optical 64 x 32: memory "
     "about 162 MB"),
    ("a scene whose import was stopped loaded as if whole",
     ["run", sc32["incomplete"], "--frames", "1"], {}, "stderr",
     "radar-emu: warning: " + incomplete_glb + ": an incomplete scene database (import stopped "
     "by SIGINT: test)"),
    ("a scene of metal alone with the default terrain engine failed with 'the scene has no "
     "terrain' (it now runs without terrain clutter and says so)",
     ["run", sc32["incomplete"], "--frames", "1"], {}, "stderr",
     "radar-emu: warning: terrain engine: the scene has no terrain: no static non-structure "
     "triangle of a material with a sigma0 (materials: metal (no sigma0)): no terrain clutter"),
    ("scene info of a stopped import",
     ["scene", "info", incomplete_glb], {}, "stdout",
     "  INCOMPLETE        import stopped by SIGINT: test"),
]

for case, args, env, kind, fragment in ISSUE32:
    r = subprocess.run([exe, *args], capture_output=True, text=True, timeout=300,
                       env={**os.environ, **env})
    what = f"{case}: radar-emu {' '.join(args)}"
    if kind == "error":
        errors = [l for l in r.stderr.splitlines() if l.startswith("radar-emu: error:")]
        check(r.returncode != 0, f"{what}: exited 0")
        check(len(errors) == 1 and fragment in errors[0],
              f"{what}: one error line with {fragment!r}: {r.stderr!r}")
    else:
        check(r.returncode == 0, f"{what}: exited {r.returncode}: {r.stderr[-300:]!r}")
        text = r.stdout if kind == "stdout" else r.stderr
        check(fragment in text, f"{what}: {kind} lacks {fragment!r}: {text[-400:]!r}")

for args, fragment in BAD:
    t0 = time.monotonic()
    r = radar_emu(*args)
    what = "radar-emu " + " ".join(args)
    lines = [line for line in r.stderr.splitlines() if line.strip()]
    check(r.returncode != 0, f"{what}: exited 0")
    check(len(lines) == 1, f"{what}: {len(lines)} lines on stderr, not one: {r.stderr!r}")
    check(fragment in r.stderr, f"{what}: stderr {r.stderr!r} lacks {fragment!r}")
    # Refused before any work: a bad option costs no computation.
    check(time.monotonic() - t0 < 10.0, f"{what}: took {time.monotonic() - t0:.1f} s to refuse")

for args, fragment in QUIET:
    r = radar_emu(*args)
    what = "radar-emu " + " ".join(args)
    check(r.returncode == 0, f"{what}: exited {r.returncode}: {r.stderr}")
    check(fragment in r.stderr, f"{what}: -q hid the warning {fragment!r}: stderr {r.stderr!r}")
    check(r.stdout == "", f"{what}: -q printed on stdout: {r.stdout!r}")

print(f"{len(BAD)} bad command lines refused, {len(QUIET)} warnings kept under -q, "
      f"{len(ISSUE32)} silent cases of issue 32 now said")
finish()
