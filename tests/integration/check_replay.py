#!/usr/bin/python3
"""Record and replay, end to end through the real binary.

1. Determinism: `radar-emu run` records its input (bus_in.log); `radar-emu replay` of that log
   gives a byte-identical bus_out.log and detections.json.
2. Golden log (tests/data/replay/approach_gap.log, see its README): replayed with both stale-output
   policies. Which radar frames must be flagged OWNSHIP_INVALID is computed here from the log's own
   time stamps (the last frame of each ownship identifier at or before each radar frame, against
   the 0.5 s timeout), and how many input frames the decoder must reject is computed from their
   bytes (CANaerospace v1.7 message format); both are compared with the replay's outputs. The
   output log must also decode with canmatrix to detections.json (check_run_outputs.py).

usage: check_replay.py RADAR_EMU GOLDEN_LOG DBC WORK_DIR
"""
import filecmp
import json
import math
import os
import struct
import subprocess
import sys

import can

EPOCH_S = 1767225600
RATE_HZ = 20.0
TIMEOUT_S = 0.5
# The ownship identifiers the default decoder needs (docs/icd/canaerospace_input.md).
OWNSHIP_IDS = (311, 312, 1133, 1036, 1037, 1038, 1130, 1131, 1132)


def fail(msg):
    print("FAIL:", msg)
    sys.exit(1)


def run(*args):
    p = subprocess.run(args, capture_output=True, text=True)
    if p.returncode != 0:
        fail(f"{' '.join(args)} exited {p.returncode}: {p.stderr.strip()}")
    return p.stdout


def classify(msg):
    """'ok' or the reason a CANaerospace v1.7 decoder must reject this frame (ids of interest)."""
    d = bytes(msg.data)
    if msg.arbitration_id not in OWNSHIP_IDS:
        return "ignored"
    if len(d) < 4:
        return "short_frame"
    dtype = d[1]
    if dtype in (2, 30, 31) or (dtype == 3 and msg.arbitration_id in (1036, 1037)):
        if len(d) < 8:
            return "short_frame"
        if dtype == 2:
            (v,) = struct.unpack(">f", d[4:8])
            if not math.isfinite(v):
                return "not_a_number"
            if msg.arbitration_id == 1036 and abs(v) > 90:
                return "out_of_range"
        return "ok"
    if 32 <= dtype:
        return "unknown_data_type"
    return "unsupported_data_type"


def expected_validity(log_path, frames):
    msgs = list(can.CanutilsLogReader(log_path))
    last = {}
    invalid = []
    i = 0
    for k in range(frames):
        t = EPOCH_S + k / RATE_HZ
        while i < len(msgs) and msgs[i].timestamp <= t + 1e-7:
            if classify(msgs[i]) == "ok":
                last[msgs[i].arbitration_id] = msgs[i].timestamp
            i += 1
        stale = any(cid not in last or t - last[cid] > TIMEOUT_S + 1e-7 for cid in OWNSHIP_IDS)
        invalid.append(stale)
    rejected = sum(1 for m in msgs if classify(m) not in ("ok", "ignored"))
    return invalid, rejected


def main():
    if len(sys.argv) != 5:
        fail("usage: check_replay.py RADAR_EMU GOLDEN_LOG DBC WORK_DIR")
    exe, golden, dbc, work = sys.argv[1:]
    os.makedirs(work, exist_ok=True)
    here = os.path.dirname(os.path.abspath(__file__))

    # 1. run -> replay is byte-identical.
    live, rep = f"{work}/live", f"{work}/replayed"
    run(exe, "run", "--quiet", "--frames", "30", "--out", live)
    run(exe, "replay", f"{live}/bus_in.log", "--quiet", "--out", rep)
    for name in ("bus_out.log", "detections.json", "bus_in.log"):
        if not filecmp.cmp(f"{live}/{name}", f"{rep}/{name}", shallow=False):
            fail(f"replay of the recorded input changed {name}")
    print("ok: replay of a 30-frame run reproduces bus_out.log, detections.json and bus_in.log "
          "byte for byte")

    # 2. The golden log, with the two stale-output policies.
    frames = 60
    invalid, rejected = expected_validity(golden, frames)
    n_invalid = sum(invalid)
    if not (5 <= n_invalid <= 20):
        fail(f"golden log should give a stale window, computed {n_invalid} invalid frames")
    for policy in ("flag", "silent"):
        out = f"{work}/golden_{policy}"
        toml = f"{work}/golden_{policy}.toml"
        with open(toml, "w") as f:
            f.write(f'[run]\nstale_output = "{policy}"\n')
        run(exe, "replay", golden, toml, "--quiet", "--frames", str(frames), "--out", out)
        with open(f"{out}/detections.json") as f:
            dets = json.load(f)["frames"]
        with open(f"{out}/report.json") as f:
            report = json.load(f)
        if len(dets) != frames:
            fail(f"{policy}: {len(dets)} frames in detections.json, expected {frames}")
        for k, (fr, stale) in enumerate(zip(dets, invalid)):
            flagged = bool(fr["status"] & 1)
            if flagged != stale:
                fail(f"{policy}: frame {k} (t = {k / RATE_HZ:.2f} s) OWNSHIP_INVALID={flagged}, "
                     f"expected {stale}")
            if stale and fr["detections"]:
                fail(f"{policy}: frame {k} is stale but carries detections")
            sent = fr.get("sent", True)
            if policy == "silent" and sent == stale:
                fail(f"silent: frame {k} sent={sent} with stale={stale}")
            if policy == "flag" and not sent:
                fail(f"flag: frame {k} not sent")
        if report["input"]["rejected"] != rejected:
            fail(f"{policy}: decoder rejected {report['input']['rejected']}, the log holds "
                 f"{rejected} malformed ownship frames")
        if report["validity"]["frames_invalid"] != n_invalid:
            fail(f"{policy}: report frames_invalid {report['validity']['frames_invalid']} != "
                 f"{n_invalid}")
        # The bus carries exactly what detections.json says (lists decoded with canmatrix).
        p = subprocess.run(["/usr/bin/python3", f"{here}/check_run_outputs.py", out, dbc],
                           capture_output=True, text=True)
        if p.returncode != 0:
            fail(f"{policy}: check_run_outputs: {p.stdout.strip()} {p.stderr.strip()}")
        headers = sum(1 for m in can.CanutilsLogReader(f"{out}/bus_out.log")
                      if m.arbitration_id == 0x708)
        want_headers = frames if policy == "flag" else frames - n_invalid
        if headers != want_headers:
            fail(f"{policy}: {headers} list headers on the bus, expected {want_headers}")
        print(f"ok: golden replay, stale_output={policy}: {n_invalid} of {frames} frames stale "
              f"exactly where the log's time stamps say, {rejected} malformed frames rejected, "
              f"{headers} lists on the bus")


if __name__ == "__main__":
    main()
