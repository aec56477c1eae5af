#!/usr/bin/python3
"""Clean stops of `radar-emu run`, end to end through the real binary.

1. SIGINT in the middle of a long run (100,000 frames planned): exit status 130, and every output
   complete and valid for the frames run: report.json says interrupted (SIGINT) with the frame
   count, detections.json and truth.json parse with one entry per frame, frames.csv has a line per
   frame, every candump line of both bus logs parses with python-can, bus_out.log holds one
   detection list per frame with consecutive frame counters and decodes with canmatrix to
   detections.json (check_run_outputs.py), both pictures are PNG files, and a replay of bus_in.log
   for that many frames gives a byte-identical bus_out.log and detections.json.
2. SIGTERM likewise: status 143, report.json says SIGTERM; its stdout and stderr go to one file,
   where the summary table comes whole before the one-line "interrupted after" message.
3. A second signal exits at once: a real-time run at 0.5 Hz sleeps up to 2 s to its next frame
   boundary; a second SIGINT during that sleep ends the process with status 130 before it writes
   report.json.

The moment to signal is read from the outputs themselves (frames.csv grows as frames are written),
never guessed with a sleep.

usage: check_interrupt.py RADAR_EMU DBC WORK_DIR
"""
import filecmp
import json
import os
import shutil
import signal
import subprocess
import sys
import time

import can

# The runway scene from a holding ownship with a cheap radar (scripts/soak.sh's default).
SCENARIO = """name = "interrupt test: runway scene, ownship holding"
[scene]
builtin = "default"
[ownship]
start_enu_m = [0.0, -4000.0, 230.0]
velocity_enu_mps = [0.0, 0.0, 0.0]
[radar]
pulses = 16
target_ray_spacing_m = 0.25
swath_start_m = 3500.0
max_range_m = 5000.0
"""
PLANNED = 100000


def fail(msg):
    print("FAIL:", msg)
    sys.exit(1)


def frames_in_csv(path):
    try:
        with open(path) as f:
            return max(0, sum(1 for line in f if line.endswith("\n")) - 1)
    except FileNotFoundError:
        return 0


def start(exe, args, err_path, merged=False):
    """merged: stdout into the same file as stderr, as a terminal or a `2>&1` log shows them."""
    err = open(err_path, "w")
    return subprocess.Popen([exe, "run", *args], stdout=err if merged else subprocess.DEVNULL,
                            stderr=err)


def wait_until(pred, proc, what, timeout_s=300.0):
    t_end = time.monotonic() + timeout_s
    while time.monotonic() < t_end:
        if pred():
            return
        if proc.poll() is not None:
            fail(f"radar-emu exited ({proc.returncode}) while waiting for {what}")
        time.sleep(0.02)
    proc.kill()
    fail(f"timed out waiting for {what}")


def check_clean_stop(exe, dbc, work, scenario, sig, sig_name, replay):
    out = os.path.join(work, sig_name.lower())
    err_path = out + ".stderr"
    shutil.rmtree(out, ignore_errors=True)
    # SIGTERM's run writes stdout and stderr to one file: the summary table must come whole
    # before the one-line message (stdout into a file is block-buffered; the message is not).
    merged = not replay
    proc = start(exe, [scenario, "--frames", str(PLANNED), "--out", out], err_path, merged)
    wait_until(lambda: frames_in_csv(os.path.join(out, "frames.csv")) >= 20, proc,
               "20 frames in frames.csv")
    proc.send_signal(sig)
    try:
        rc = proc.wait(timeout=120)
    except subprocess.TimeoutExpired:
        proc.kill()
        fail(f"{sig_name}: the run did not stop")
    if rc != 128 + sig:
        fail(f"{sig_name}: exit status {rc}, expected {128 + sig}: {open(err_path).read()}")

    if merged:
        lines = [ln for ln in open(err_path).read().replace("\r", "\n").split("\n") if ln.strip()]
        table = [i for i, ln in enumerate(lines) if "stage times" in ln]
        if not table or not lines[-1].startswith("radar-emu: interrupted after") or \
                sum("interrupted after" in ln for ln in lines) != 1 or table[0] > len(lines) - 2:
            fail(f"{sig_name}: stdout and stderr in one file: the summary table, then the "
                 f"interrupted line last, expected: {lines[-12:]}")
    with open(os.path.join(out, "report.json")) as f:
        rep = json.load(f)
    n = rep["frames"]
    if not rep["interrupted"] or rep.get("stop_signal") != sig_name:
        fail(f"{sig_name}: report.json interrupted={rep['interrupted']} "
             f"stop_signal={rep.get('stop_signal')}")
    if not 20 <= n < PLANNED or rep["frames_planned"] != PLANNED:
        fail(f"{sig_name}: {n} frames of {rep['frames_planned']} in report.json")
    if not rep["output_stream"]["complete"] or rep["output_stream"]["frames_written"] != n:
        fail(f"{sig_name}: output_stream {rep['output_stream']}")
    for name in ("detections.json", "truth.json"):
        with open(os.path.join(out, name)) as f:
            doc = json.load(f)
        if len(doc["frames"]) != n or doc["frames_dropped"] != 0:
            fail(f"{sig_name}: {name} holds {len(doc['frames'])} frames, report {n}")
        counters = [fr["frame_counter"] for fr in doc["frames"]]
        if counters != list(range(n)):
            fail(f"{sig_name}: {name} frame counters are not 0..{n - 1}")
    if frames_in_csv(os.path.join(out, "frames.csv")) != n:
        fail(f"{sig_name}: frames.csv does not hold {n} frames")
    headers, lines_out = [], 0
    for msg in can.CanutilsLogReader(os.path.join(out, "bus_out.log")):
        lines_out += 1
        if msg.arbitration_id in (0x708, 0x70B):
            headers.append(msg.data[0] | (msg.data[1] << 8))
    if headers != list(range(n)):
        fail(f"{sig_name}: bus_out.log holds {len(headers)} lists for {n} frames")
    lines_in = sum(1 for _ in can.CanutilsLogReader(os.path.join(out, "bus_in.log")))
    if lines_in != rep["bus"]["frames_in"] or lines_in == 0:
        fail(f"{sig_name}: bus_in.log {lines_in} frames, report {rep['bus']['frames_in']}")
    for png in ("detections.png", "timing.png"):
        with open(os.path.join(out, png), "rb") as f:
            if f.read(8) != b"\x89PNG\r\n\x1a\n":
                fail(f"{sig_name}: {png} is not a PNG file")
    here = os.path.dirname(os.path.abspath(__file__))
    p = subprocess.run(["/usr/bin/python3", f"{here}/check_run_outputs.py", out, dbc],
                       capture_output=True, text=True)
    if p.returncode != 0:
        fail(f"{sig_name}: check_run_outputs: {p.stdout.strip()} {p.stderr.strip()}")
    msg = f"{sig_name}: stopped after {n} of {PLANNED} frames, status {rc}; {lines_out} + " \
          f"{lines_in} candump lines parse, {n} lists decode to detections.json"
    if replay:
        rout = out + "_replay"
        shutil.rmtree(rout, ignore_errors=True)
        p = subprocess.run([exe, "replay", os.path.join(out, "bus_in.log"), scenario, "--frames",
                            str(n), "--out", rout, "--quiet"], capture_output=True, text=True)
        if p.returncode != 0:
            fail(f"{sig_name}: replay exited {p.returncode}: {p.stderr.strip()}")
        for name in ("bus_out.log", "detections.json"):
            if not filecmp.cmp(os.path.join(out, name), os.path.join(rout, name), shallow=False):
                fail(f"{sig_name}: replay of bus_in.log: {name} differs")
        msg += "; the replay is byte-identical"
    print(msg)


def check_second_signal(exe, work):
    # 0.5 Hz on the wall clock: after each frame the loop sleeps to the next boundary (~2 s), so
    # the first SIGINT waits for it and a second one, sent meanwhile, must end the process at once.
    scenario = os.path.join(work, "slow.toml")
    with open(scenario, "w") as f:
        f.write(SCENARIO.replace("[scene]", "[run]\nrate_hz = 0.5\n[scene]"))
    out = os.path.join(work, "twice")
    err_path = out + ".stderr"
    shutil.rmtree(out, ignore_errors=True)
    proc = start(exe, [scenario, "--realtime", "--frames", "1000", "--out", out], err_path)
    wait_until(lambda: frames_in_csv(os.path.join(out, "frames.csv")) >= 1, proc,
               "the first frame in frames.csv")
    proc.send_signal(signal.SIGINT)
    wait_until(lambda: "stopping at the next frame boundary" in open(err_path).read(), proc,
               "the first signal's message")
    t0 = time.monotonic()
    proc.send_signal(signal.SIGINT)
    try:
        rc = proc.wait(timeout=30)
    except subprocess.TimeoutExpired:
        proc.kill()
        fail("second SIGINT: the process did not exit")
    err = open(err_path).read()
    if rc != 130:
        fail(f"second SIGINT: exit status {rc}, expected 130: {err}")
    if "interrupted after" in err or os.path.exists(os.path.join(out, "report.json")):
        fail("second SIGINT: the process went on to write its outputs instead of exiting at once")
    print(f"second SIGINT: exit status 130 after {time.monotonic() - t0:.3f} s, "
          "before the frame boundary, no report written")


def main():
    if len(sys.argv) != 4:
        fail("usage: check_interrupt.py RADAR_EMU DBC WORK_DIR")
    exe, dbc, work = sys.argv[1:]
    os.makedirs(work, exist_ok=True)
    scenario = os.path.join(work, "runway.toml")
    with open(scenario, "w") as f:
        f.write(SCENARIO)
    check_clean_stop(exe, dbc, work, scenario, signal.SIGINT, "SIGINT", replay=True)
    check_clean_stop(exe, dbc, work, scenario, signal.SIGTERM, "SIGTERM", replay=False)
    check_second_signal(exe, work)
    print("PASS")


if __name__ == "__main__":
    main()
