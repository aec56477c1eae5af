#!/usr/bin/python3
"""Independent check of a `radar-emu run` output directory.

bus_out.log is read with python-can's candump reader, every frame decoded with canmatrix using
docs/icd/radar_emu_detections.dbc, the lists reassembled, and each decoded signal compared with
detections.json within half the ICD's quantisation step. report.json must hold per-stage
timings for every frame. Exit status 0 only if everything matches.

usage: check_run_outputs.py RUN_DIR DBC_FILE
"""
import json
import math
import sys

import can
import canmatrix.formats


def fail(msg):
    print("FAIL:", msg)
    sys.exit(1)


def slot_signals(sig, slot):
    """The signals of FD slot `slot` ("Range_1" ...), named without the suffix."""
    suffix = f"_{slot}"
    return {k[: -len(suffix)]: v for k, v in sig.items() if k.endswith(suffix)}


def main():
    if len(sys.argv) != 3:
        fail("usage: check_run_outputs.py RUN_DIR DBC_FILE")
    run_dir, dbc_path = sys.argv[1], sys.argv[2]
    db = canmatrix.formats.loadp_flat(dbc_path)
    frames_by_id = {f.arbitration_id.id: f for f in db.frames}
    for needed in (0x708, 0x709, 0x70A, 0x70B, 0x70C):
        if needed not in frames_by_id:
            fail(f"DBC has no message 0x{needed:X}")

    with open(f"{run_dir}/detections.json") as f:
        # Frames marked "sent": false put nothing on the bus (stale_output = "silent").
        expected = [fr for fr in json.load(f)["frames"] if fr.get("sent", True)]
    with open(f"{run_dir}/report.json") as f:
        report = json.load(f)

    for stage in ("input", "scene_update", "trace", "sensor", "output"):
        st = report["stage_timing"].get(stage)
        if st is None or st["count"] != report["frames"]:
            fail(f"report.json: stage {stage} missing or not timed every frame")

    # Reassemble the lists: classic (header 0x708, A 0x709 / B 0x70A per detection) or CAN FD
    # (0x70B header with slots 0-1, 0x70C continuations with SlotCount slots from FirstIndex),
    # every detection as a dict of DBC signal names without the slot suffix.
    lists = []
    current = None
    for msg in can.CanutilsLogReader(f"{run_dir}/bus_out.log"):
        fr = frames_by_id.get(msg.arbitration_id)
        if fr is None:
            fail(f"unexpected identifier 0x{msg.arbitration_id:X} in bus_out.log")
        sig = {k: float(v.phys_value) for k, v in fr.decode(bytes(msg.data)).items()}
        aid = msg.arbitration_id
        if aid in (0x708, 0x70B):
            if (aid == 0x70B) != bool(msg.is_fd):
                fail(f"0x{aid:X} with is_fd={msg.is_fd}")
            current = {"header": sig, "a": {}, "b": {}, "fd": {}}
            lists.append(current)
            if aid == 0x70B:
                count = int(round(sig["DetectionCount"]))
                for slot in range(min(count, 2)):
                    current["fd"][slot] = slot_signals(sig, slot)
        elif current is None:
            fail("detection frame before any header")
        elif aid == 0x70C:
            first, used = int(round(sig["FirstIndex"])), int(round(sig["SlotCount"]))
            for slot in range(used):
                current["fd"][first + slot] = slot_signals(sig, slot)
        else:
            idx = int(round(sig["DetectionIndex"]))
            current["a" if aid == 0x709 else "b"][idx] = sig

    if len(lists) != len(expected):
        fail(f"{len(lists)} lists on the bus, {len(expected)} in detections.json")

    checked = 0
    fd_checked = [0]
    for got, want in zip(lists, expected):
        dets = want["detections"]
        if int(round(got["header"]["DetectionCount"])) != len(dets):
            fail(f"frame {want['frame_counter']}: count mismatch")
        if int(round(got["header"]["FrameCounter"])) != want["frame_counter"]:
            fail(f"frame counter mismatch at {want['frame_counter']}")
        for i, d in enumerate(dets):
            if got["fd"]:
                f = got["fd"].get(i)
                if f is None:
                    fail(f"frame {want['frame_counter']}: FD detection {i} missing on the bus")
                a = b = f
            else:
                a, b = got["a"].get(i), got["b"].get(i)
            if a is None or b is None:
                fail(f"frame {want['frame_counter']}: detection {i} incomplete on the bus")
            pairs = [
                (a["Range"], d["range_m"], 0.01),
                (a["RadialVelocity"], d["radial_velocity_mps"], 0.02),
                (b["Azimuth"], d["azimuth_deg"], 0.01),
                (b["Elevation"], d["elevation_deg"], 0.01),
                (b["Rcs"], d["rcs_dbsm"], 0.01),
                (a["Snr"], min(max(d["snr_db"], 0.0), 127.5), 0.5),
            ]
            if got["fd"]:
                # FD lists carry the one-sigma accuracies (saturated) and the ambiguity flags.
                pairs += [
                    (a["RangeStd"], min(d["range_std_m"], 655.35), 0.01),
                    (a["RadialVelocityStd"], min(d["radial_velocity_std_mps"], 40.95), 0.01),
                    (a["AzimuthStd"], min(d["azimuth_std_deg"], 32.766), 0.002),
                    (a["ElevationStd"], min(d["elevation_std_deg"], 32.766), 0.002),
                ]
                for flag in ("range_ambiguous", "velocity_ambiguous"):
                    name = "RangeAmbiguous" if flag == "range_ambiguous" else "VelocityAmbiguous"
                    if bool(round(a[name])) != bool(d[flag]):
                        fail(f"frame {want['frame_counter']} detection {i}: {name} on the bus "
                             f"differs from detections.json")
                fd_checked[0] += 1
            for bus_value, json_value, step in pairs:
                if not math.isfinite(bus_value) or abs(bus_value - json_value) > step / 2 + 1e-9:
                    fail(f"frame {want['frame_counter']} detection {i}: bus {bus_value} vs "
                         f"json {json_value} (step {step})")
            checked += 1
    if checked == 0:
        fail("no detections to compare")
    kind = f"CAN FD ({fd_checked[0]} with accuracies and flags)" if fd_checked[0] else "classic"
    print(f"ok: {len(lists)} lists, {checked} detections ({kind}) decoded by canmatrix match "
          f"detections.json within ICD quantisation")


if __name__ == "__main__":
    main()
