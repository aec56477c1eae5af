#!/usr/bin/python3
"""`radar-emu run --nav-modbus` when the navigation source is unreachable or goes away
(docs/icd/modbus.md, "Lost sources").

1. Unreachable: a port nobody listens on, and the README's own example address
   (tcp:192.0.2.10:502, TEST-NET-1: never routed). The run happens (outputs written), every
   frame is invalid and counted, stderr says why on one line, report.json nav_modbus.link says
   "never_answered", and radar-emu exits with status 3. The connection attempts back off
   (0.2 s doubling to 2 s): over a 3 s run they are at most 6 (a fixed 0.2 s would make 15).
2. Lost and back: the project's navigation server (modbus_nav_server) is killed mid-run and
   restarted on the same port 1.5 s later. The run exits 0; stderr says "lost" and "answers
   again"; report.json counts one outage (nav_modbus.link), the frames the loop ran without a
   source, and invalid frames (flagged OWNSHIP_INVALID in detections.json) between valid ones;
   the source is read again within one retry period (2 s back-off ceiling) of its return.

usage: check_modbus_nav_outage.py RADAR_EMU MODBUS_NAV_SERVER WORK_DIR
"""
import json
import os
import re
import select
import socket
import subprocess
import sys
import time

EXE = SERVER = WORK = None
SCENARIO = None
# A light loop (runway only, 4 beams, 8 pulses: well under a millisecond a frame), so that the
# loop's own physics cannot starve the poller or the server on a small machine: what is
# measured is the navigation link.
LIGHT_TOML = """name = "light loop for the Modbus navigation outage test"
[scene]
builtin = "default"
[antenna]
azimuth_min_deg = -2.0
azimuth_max_deg = 2.0
[radar]
pulses = 8
max_range_m = 3000.0
terrain_ray_spacing_deg = 0.5
"""
RETRY_MAX_S = 2.0  # ModbusClientConfig::reconnect_max_interval_s, as radar-emu sets it
OWNSHIP_INVALID = 0x01  # docs/icd/detections.md status bit


def fail(msg):
    print("FAIL:", msg)
    sys.exit(1)


def free_port():
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    return port


def load(out):
    with open(f"{out}/report.json") as f:
        rep = json.load(f)
    with open(f"{out}/detections.json") as f:
        det = json.load(f)
    return rep, det


def part_unreachable():
    for name, endpoint, frames in (("refused", f"tcp:127.0.0.1:{free_port()}", 60),
                                   ("test-net", "tcp:192.0.2.10:502", 20)):
        out = f"{WORK}/unreachable_{name}"
        p = subprocess.run([EXE, "run", SCENARIO, "--quiet", "--realtime", "--frames", str(frames), "--out",
                            out, "--nav-modbus", endpoint], capture_output=True, text=True,
                           timeout=120)
        if p.returncode != 3:
            fail(f"{endpoint}: exit status {p.returncode}, 3 expected; stderr: {p.stderr.strip()}")
        lines = p.stderr.strip().splitlines()
        warn = [l for l in lines if f"navigation source {endpoint} unreachable" in l]
        err = [l for l in lines if l.startswith(f"radar-emu: error: navigation source {endpoint} "
                                                "never answered")]
        if len(warn) != 1 or len(err) != 1:
            fail(f"{endpoint}: stderr lacks the unreachable warning or the final error: {lines}")
        rep, det = load(out)
        link = rep["nav_modbus"]["link"]
        if rep["frames"] != frames or rep["frames_valid"] != 0 or \
                rep["validity"]["frames_invalid"] != frames:
            fail(f"{endpoint}: frames {rep['frames']} valid {rep['frames_valid']} invalid "
                 f"{rep['validity']['frames_invalid']}")
        if link["state"] != "never_answered" or link["frames_source_down"] != frames or \
                link["outages"] != 0 or link["first_read_s"] != -1:
            fail(f"{endpoint}: link report {link}")
        if any(not (fr["status"] & OWNSHIP_INVALID) for fr in det["frames"]):
            fail(f"{endpoint}: a frame is not flagged OWNSHIP_INVALID")
        # Back-off: attempts at 0, 0.2, 0.6, 1.4, 3.0 s (+ the one at setup) in a 3 s run.
        if name == "refused" and not 2 <= link["connect_failures"] <= 6:
            fail(f"{endpoint}: {link['connect_failures']} connection attempts in 3 s: no back-off")
        print(f"ok: {endpoint} unreachable: exit 3, {frames} invalid frames counted, "
              f"{link['connect_failures']} connection attempts ({link['last_error']}), stderr: "
              f"{warn[0]!r}")


def start_server(port):
    args = [SERVER, "--port", str(port), "--rate-hz", "50", "--duration-s", "60",
            "--lat-deg", "43.56", "--lon-deg", "1.40", "--height-m", "400",
            "--vel-north-mps", "70", "--heading-deg", "0"]
    srv = subprocess.Popen(args, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    ready, _, _ = select.select([srv.stdout], [], [], 10.0)
    line = srv.stdout.readline() if ready else ""
    if not re.fullmatch(rf"listening 127\.0\.0\.1:{port}\n", line):
        srv.kill()
        fail(f"modbus_nav_server did not listen on {port}: {line!r}")
    return srv


def part_lost_and_back():
    port = free_port()
    srv = start_server(port)
    out = f"{WORK}/lost"
    frames = 200  # 10 s at 20 Hz
    radar = subprocess.Popen([EXE, "run", SCENARIO, "--quiet", "--realtime", "--frames", str(frames),
                              "--out", out, "--nav-modbus", f"tcp:127.0.0.1:{port}"],
                             stderr=subprocess.PIPE, stdout=subprocess.DEVNULL, text=True)
    try:
        time.sleep(4.0)
        srv.kill()
        srv.wait()
        t_down = time.monotonic()
        time.sleep(1.5)
        srv = start_server(port)
        down_s = time.monotonic() - t_down
        _, err = radar.communicate(timeout=120)
    finally:
        srv.kill()
        srv.wait()
        if radar.poll() is None:
            radar.kill()
    if radar.returncode != 0:
        fail(f"lost and back: exit status {radar.returncode}; stderr: {err.strip()}")
    lost = [l for l in err.splitlines() if "navigation source" in l and " lost " in l]
    back = [l for l in err.splitlines() if "navigation source" in l and "answers again" in l]
    rep, det = load(out)
    link = rep["nav_modbus"]["link"]
    # One outage: the server's absence (a machine loaded enough to miss three 0.1 s answers
    # in a row would add short ones: each is reported and counted the same way).
    if link["state"] != "up" or link["outages"] < 1 or len(lost) != link["outages"] or \
            len(back) != link["outages"]:
        fail(f"stderr should say lost and back once per counted outage ({link}): {err.strip()}")
    # The outage as the poller saw it: from the first failed read to the first good one. It
    # cannot be shorter than the server's absence, and ends within one retry period of its
    # return (plus a poll period and the server's start).
    outage = link["longest_outage_s"]
    if not down_s - 0.1 <= outage <= down_s + RETRY_MAX_S + 0.5:
        fail(f"outage {outage:.2f} s for a server away {down_s:.2f} s (retry period "
             f"{RETRY_MAX_S} s)")
    # Frames: valid, then a run of invalid ones (flagged), then valid again; counted. On a loaded
    # machine the first frame (or few) can come before the poller's first answer: flagged
    # invalid as they should be, they are the start-up, not the outage, and left out below.
    flags = [bool(fr["status"] & OWNSHIP_INVALID) for fr in det["frames"]]
    startup = flags.index(False) if False in flags else len(flags)
    if startup > 5:
        fail(f"{startup} invalid frames before the source's first answer: {flags}")
    outage_flags = flags[startup:]
    first_bad = outage_flags.index(True) if True in outage_flags else -1
    if first_bad <= 0 or all(outage_flags[first_bad:]) or rep["frames_valid"] + \
            rep["validity"]["frames_invalid"] != rep["frames"]:
        fail(f"expected valid frames, a flagged gap, then valid frames: {flags}")
    gap = sum(outage_flags)
    rate = rep["rate_hz"]
    state_timeout = rep["validity"]["state_timeout_s"]
    if startup + gap != rep["validity"]["frames_invalid"]:
        fail(f"{startup} + {gap} flagged frames, report says "
             f"{rep['validity']['frames_invalid']} invalid")
    # Invalid from state_timeout after the last good read to the first good read again: the
    # frames' own times (a loaded machine skips periods, so counts alone would not tell).
    times = [fr["time_s"] for fr, bad in zip(det["frames"][startup:], outage_flags) if bad]
    span = times[-1] - times[0] + 1.0 / rate
    if abs(span - (outage - state_timeout)) > 0.3:
        fail(f"invalid frames span {span:.2f} s, expected about {outage - state_timeout:.2f} s "
             f"(outage {outage:.2f} s less the {state_timeout} s state time-out)")
    # Frames run without a source: at least the invalid ones, at most the outages' time.
    down_frames = link["frames_source_down"]
    if not gap <= down_frames <= link["outage_s_total"] * rate + 2 * link["outages"]:
        fail(f"{down_frames} frames without a source: {gap} invalid, outages "
             f"{link['outage_s_total']:.2f} s at {rate} Hz")
    print(f"ok: source away {down_s:.2f} s: outage {outage:.2f} s as read, {down_frames} frames "
          f"without a source, {gap} frames flagged invalid, exit 0; stderr: {lost[0]!r} / "
          f"{back[0]!r}")


def main():
    global EXE, SERVER, WORK
    if len(sys.argv) != 4:
        fail("usage: check_modbus_nav_outage.py RADAR_EMU MODBUS_NAV_SERVER WORK_DIR")
    EXE, SERVER, WORK = sys.argv[1:]
    os.makedirs(WORK, exist_ok=True)
    global SCENARIO
    SCENARIO = f"{WORK}/light.toml"
    with open(SCENARIO, "w") as f:
        f.write(LIGHT_TOML)
    part_unreachable()
    part_lost_and_back()


if __name__ == "__main__":
    main()
