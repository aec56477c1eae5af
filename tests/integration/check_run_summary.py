#!/usr/bin/python3
"""The summary `radar-emu run` prints says what was seen and how the frames were degraded
(issue 29), checked against the run's own files read independently:

- one row per object in the beam: its frames in the beam counted from truth.json, its detected
  frames <= that, Pd = detected / in beam;
- the false-alarm line over every detection of detections.json;
- where frames.csv has frames above level 0, "N of M frames degraded (levels a-b, est. X dB)"
  with N, a, b counted from frames.csv and X its estimated error at level b;
- a [[target]] placed behind the aircraft (never in the beam) gets a setup warning and a
  "never in the beam" line.

usage: check_run_summary.py RADAR_EMU WORK_DIR
"""
import csv
import json
import os
import re
import subprocess
import sys

FRAMES = 40


def fail(msg):
    print("FAIL:", msg)
    sys.exit(1)


def run(exe, *args):
    p = subprocess.run([exe, "run", *args], capture_output=True, text=True)
    if p.returncode != 0:
        fail(f"radar-emu run {' '.join(args)}: exit {p.returncode}: {p.stderr}")
    return p.stdout, p.stderr


def check_default(exe, out):
    text, _ = run(exe, "--frames", str(FRAMES), "--out", out)
    print(text)
    with open(os.path.join(out, "truth.json")) as f:
        truth = json.load(f)
    in_beam = {}
    for fr in truth["frames"]:
        for o in fr["objects"]:
            in_beam[o["object"]] = in_beam.get(o["object"], 0) + 1
    rows = {}
    for line in text.splitlines():
        m = re.match(r"^    (\S+)\s+(\d+)\s+(\d+)\s+(\d\.\d\d)\s", line)
        if m:
            rows[m.group(1)] = (int(m.group(2)), int(m.group(3)), float(m.group(4)))
    if not in_beam:
        fail("truth.json has no object in the beam")
    for name, n in in_beam.items():
        if name not in rows:
            fail(f"no summary row for {name} (in the beam {n} frames)")
        beam, det, pd = rows[name]
        if beam != n:
            fail(f"{name}: {beam} frames in the beam in the summary, {n} in truth.json")
        if det > beam or abs(pd - det / beam) > 0.0051:
            fail(f"{name}: detected {det} of {beam}, Pd {pd}")
    extra = set(rows) - set(in_beam)
    if extra:
        fail(f"rows for objects never in the beam: {sorted(extra)}")

    with open(os.path.join(out, "detections.json")) as f:
        total = sum(len(fr["detections"]) for fr in json.load(f)["frames"])
    m = re.search(r"^  false alarms (\d+\.\d\d) per frame \((\d+) of (\d+) detections", text,
                  re.M)
    if not m:
        fail("no false-alarm line")
    if int(m.group(3)) != total or abs(float(m.group(1)) - int(m.group(2)) / FRAMES) > 0.0051:
        fail(f"false-alarm line {m.group(0)!r}: {total} detections in detections.json")

    with open(os.path.join(out, "frames.csv")) as f:
        levels = [(int(r["governor_level"]), float(r["governor_estimated_snr_error_db"]))
                  for r in csv.DictReader(f) if r["governor_level"] != ""]
    degraded = [l for l in levels if l[0] > 0]
    if degraded:
        lo, hi = min(l[0] for l in degraded), max(l[0] for l in degraded)
        est = next(e for l, e in degraded if l == hi)
        want = f"  governor    {len(degraded)} of {FRAMES} frames degraded (levels {lo}-{hi}, " \
               f"est. {est:.1f} dB)"
        if want not in text:
            fail(f"expected {want!r}")
    elif "frames degraded" in text:
        fail("a degraded line without a degraded frame in frames.csv")
    print(f"summary: {len(rows)} objects in the beam as truth.json, {total} detections, "
          f"{len(degraded)} degraded frames as frames.csv")


def check_never_in_beam(exe, work):
    toml = os.path.join(work, "behind.toml")
    with open(toml, "w") as f:
        f.write('[[target]]\nname = "behind_the_aircraft"\nbuiltin = "jeep"\n'
                'position_enu_m = [0.0, -9000.0, 5.0]\n')
    text, err = run(exe, toml, "--frames", "5", "--out", os.path.join(work, "behind"))
    if "'behind_the_aircraft' never enters the beam over the planned run" not in err:
        fail(f"no setup warning for the target behind the aircraft: {err!r}")
    if not re.search(r"^  never in the beam: .*behind_the_aircraft", text, re.M):
        fail("no 'never in the beam' line naming it")
    print("setup warning and summary line for a target never in the beam")


def main():
    if len(sys.argv) != 3:
        print(__doc__)
        return 2
    exe, work = sys.argv[1], sys.argv[2]
    os.makedirs(work, exist_ok=True)
    check_default(exe, os.path.join(work, "default"))
    check_never_in_beam(exe, work)
    print("PASS")
    return 0


if __name__ == "__main__":
    sys.exit(main())
