#!/usr/bin/python3
"""Weather and the timeline end to end through the real binary.

1. `radar-emu run` in fog (examples/fog_approach.toml) and in rain (a scenario written here):
   the two-way loss at the reference range that report.json says the loop applied equals
   2 R (gas_dry + gas_vapour + rain_v + fog) from the CSV that `radar-emu atten` prints for the
   same carrier and atmosphere, within 0.01 dB (rain: vertical polarisation, which the SBR
   transmits).
2. The fog run's --trace-events file (python json): one complete "X" event per stage per frame,
   durations >= 0, the stages' sum no more than their frame event.
3. timing.png: a PNG of the documented size (1000 x 1280), read from its IHDR chunk."""
import csv
import json
import os
import struct
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from cli_check import check, finish, runner  # noqa: E402

exe, source_dir, out = sys.argv[1], sys.argv[2], sys.argv[3]
run = runner(exe)
os.makedirs(out, exist_ok=True)
frames = 6
stages = ["input", "scene_update", "trace", "sensor", "output"]


def atten_two_way_db(range_m, fog_gm3, rain_mmh, temp_c, rho_gm3, pressure_hpa, carrier_hz):
    csv_path = os.path.join(out, "atten.csv")
    run("atten", "--freq-hz", repr(carrier_hz), "--fog-gm3", repr(fog_gm3), "--rain-mmh",
        repr(rain_mmh), "--temp-c", repr(temp_c), "--rho-gm3", repr(rho_gm3), "--pressure-hpa",
        repr(pressure_hpa), "--out", csv_path, "--quiet")
    with open(csv_path) as f:
        row = next(csv.DictReader(f))
    one_way_db_km = sum(float(row[k]) for k in
                        ("gas_dry_db_km", "gas_vapour_db_km", "rain_v_db_km", "fog_db_km"))
    return 2.0 * range_m * 1e-3 * one_way_db_km


def check_weather(name, scenario, trace_file=None):
    run_dir = os.path.join(out, name)
    args = ["run", scenario, "--quiet", "--frames", str(frames), "--out", run_dir]
    if trace_file:
        args += ["--trace-events", trace_file]
    run(*args)
    with open(os.path.join(run_dir, "report.json")) as f:
        rep = json.load(f)
    w = rep["weather"]
    want = atten_two_way_db(w["reference_range_m"], w["fog_water_gpm3"], w["rain_rate_mmph"],
                            w["temperature_c"], w["humidity_gpm3"], w["pressure_hpa"],
                            w["carrier_hz"])
    got = w["two_way_loss_db_at_reference"]
    print(f"{name}: loop {got:.5f} dB, atten CLI {want:.5f} dB at {w['reference_range_m']} m")
    check(abs(got - want) <= 0.01, f"{name}: loop two-way loss {got} vs atten CLI {want}")
    check(want > 0.5, f"{name}: the loss is large enough to mean something ({want} dB)")
    return run_dir


fog_trace = os.path.join(out, "fog_trace.json")
fog_dir = check_weather("fog", os.path.join(source_dir, "examples", "fog_approach.toml"),
                        fog_trace)
rain_toml = os.path.join(out, "rain.toml")
with open(rain_toml, "w") as f:
    f.write('[weather]\ncondition = "rain"\nrain_rate_mmph = 16.0\nhumidity_gpm3 = 12.0\n'
            'temperature_c = 20.0\npressure_hpa = 1000.0\n')
check_weather("rain", rain_toml)

# The timeline of the fog run.
with open(fog_trace) as f:
    events = json.load(f)["traceEvents"]
by_frame = {}
for e in events:
    check(e["ph"] == "X", f"event {e['name']} is a complete event")
    check(e["dur"] >= 0.0, f"event {e['name']} frame {e['args']['frame']} has dur >= 0")
    by_frame.setdefault(e["args"]["frame"], []).append(e)
check(len(by_frame) == frames, f"{len(by_frame)} frames on the timeline, want {frames}")
for idx, evs in sorted(by_frame.items()):
    names = sorted(e["name"] for e in evs)
    check(names == sorted(stages + ["frame"]), f"frame {idx}: one event per stage, got {names}")
    frame = [e for e in evs if e["name"] == "frame"][0]
    total = sum(e["dur"] for e in evs if e["name"] != "frame")
    check(total <= frame["dur"] + 1e-6, f"frame {idx}: stages {total} us <= frame {frame['dur']} us")

# timing.png: PNG signature, then the IHDR chunk's width and height (big-endian).
with open(os.path.join(fog_dir, "timing.png"), "rb") as f:
    head = f.read(24)
check(head[:8] == b"\x89PNG\r\n\x1a\n", "timing.png is a PNG")
width, height = struct.unpack(">II", head[16:24])
check((width, height) == (1000, 1280), f"timing.png is 1000 x 1280, got {width} x {height}")
finish()
print("weather and timeline: ok")
