#!/usr/bin/python3
"""Independent check of the detection ICD's DBC and of the CANaerospace encoding.

Runs icd_vectors, reads its candump logs with python-can, decodes the detection frames with
canmatrix using docs/icd/radar_emu_detections.dbc, and checks each signal against the physical
values within half a quantisation step: the classic lists, and the CAN FD lists ("##" lines,
per-slot signals Range_0 ..) with their accuracies (saturated at the field's maximum) and
ambiguity flags. CANaerospace frames are decoded with Python's struct module from the
specification's layout (big-endian value in bytes 4..7).

usage: check_dbc.py ICD_VECTORS_EXE DBC_FILE WORK_DIR
"""
import json
import struct
import subprocess
import sys

import can
import canmatrix.formats


def fail(msg):
    print("FAIL:", msg)
    sys.exit(1)


def main():
    exe, dbc, work = sys.argv[1:4]
    subprocess.run([exe, work], check=True)
    with open(f"{work}/vectors.json") as f:
        vectors = json.load(f)
    db = canmatrix.formats.loadp_flat(dbc)
    by_id = {fr.arbitration_id.id: fr for fr in db.frames}

    def decode(msg):
        fr = by_id.get(msg.arbitration_id)
        if fr is None:
            fail(f"identifier 0x{msg.arbitration_id:X} not in the DBC")
        return {k: float(v.phys_value) for k, v in fr.decode(bytes(msg.data)).items()}

    lists = []
    for msg in can.CanutilsLogReader(f"{work}/detections.log"):
        s = decode(msg)
        if msg.arbitration_id == 0x708:
            lists.append({"h": s, "a": {}, "b": {}})
        else:
            part = "a" if msg.arbitration_id == 0x709 else "b"
            lists[-1][part][int(s["DetectionIndex"])] = s
            if int(s["FrameCounterLow"]) != int(lists[-1]["h"]["FrameCounter"]) % 256:
                fail("FrameCounterLow does not match the header")
    want_lists = vectors["lists"]
    if len(lists) != len(want_lists):
        fail(f"{len(lists)} lists decoded, {len(want_lists)} written")
    n = 0
    for got, want in zip(lists, want_lists):
        h = got["h"]
        if int(h["FrameCounter"]) != want["frame_counter"] or int(h["TimeMs"]) != want["time_ms"]:
            fail(f"header mismatch {h} vs {want}")
        status = want["status"]
        bits = [int(h[k]) for k in ("StatusOwnshipInvalid", "StatusOverrun", "StatusTruncated",
                                    "StatusDropped", "StatusDegraded")]
        if int(h["Status"]) != status or bits != [(status >> i) & 1 for i in range(5)]:
            fail(f"status mismatch {h} vs {status}")
        if int(h["DetectionCount"]) != len(want["detections"]):
            fail("detection count mismatch")
        for i, d in enumerate(want["detections"]):
            a, b = got["a"][i], got["b"][i]
            for bus, ref, step in ((a["Range"], d["range_m"], 0.01),
                                   (a["RadialVelocity"], d["radial_velocity_mps"], 0.02),
                                   (a["Snr"], d["snr_db"], 0.5),
                                   (b["Azimuth"], d["azimuth_deg"], 0.01),
                                   (b["Elevation"], d["elevation_deg"], 0.01),
                                   (b["Rcs"], d["rcs_dbsm"], 0.01)):
                if abs(bus - ref) > step / 2 + 1e-9:
                    fail(f"list {want['frame_counter']} detection {i}: {bus} vs {ref}")
            n += 1
    if n < 100:
        fail(f"only {n} detections checked")

    nfd = check_fd(work, vectors["fd_lists"], by_id, decode)

    msgs = list(can.CanutilsLogReader(f"{work}/canaerospace.log"))
    pitch = msgs[0]
    if pitch.arbitration_id != 311 or pitch.data[1] != 2 or pitch.dlc != 8:
        fail("pitch frame header")
    if struct.unpack(">f", bytes(pitch.data[4:8]))[0] != vectors["canaerospace"]["pitch_deg"]:
        fail("pitch value")
    hi, lo = msgs[1], msgs[2]
    if (hi.data[1], lo.data[1]) != (30, 31) or (lo.data[3] - hi.data[3]) % 256 != 1:
        fail("DOUBLEH/DOUBLEL types or message codes")
    lat = struct.unpack(">d", bytes(hi.data[4:8]) + bytes(lo.data[4:8]))[0]
    if lat != vectors["canaerospace"]["latitude_deg"]:
        fail(f"latitude {lat}")
    print(f"ok: {len(lists)} lists / {n} detections decoded by canmatrix with the DBC match; "
          f"CAN FD: {len(vectors['fd_lists'])} lists / {nfd} detections match; "
          f"CANaerospace FLOAT and DOUBLE frames match struct")


# (signal, JSON key, quantisation step, largest value the field carries or None)
FD_SIGNALS = (("Range", "range_m", 0.01, None),
              ("RadialVelocity", "radial_velocity_mps", 0.02, None),
              ("Snr", "snr_db", 0.5, None),
              ("Azimuth", "azimuth_deg", 0.01, None),
              ("Elevation", "elevation_deg", 0.01, None),
              ("Rcs", "rcs_dbsm", 0.01, None),
              ("RangeStd", "range_std_m", 0.01, 655.35),
              ("RadialVelocityStd", "radial_velocity_std_mps", 0.01, 40.95),
              ("AzimuthStd", "azimuth_std_deg", 0.002, 32.766),
              ("ElevationStd", "elevation_std_deg", 0.002, 32.766))


def check_fd(work, want_lists, by_id, decode):
    """Decodes the CAN FD log with the DBC; returns the number of detections checked."""
    for fid, size in ((0x70B, 48), (0x70C, 64)):
        if not by_id[fid].is_fd or by_id[fid].size != size:
            fail(f"DBC: 0x{fid:X} is not a {size}-byte CAN FD message")
    lists = []
    for msg in can.CanutilsLogReader(f"{work}/detections_fd.log"):
        if not msg.is_fd or not msg.bitrate_switch:
            fail(f"0x{msg.arbitration_id:X}: not read as CAN FD with BRS")
        if len(msg.data) != by_id[msg.arbitration_id].size:
            fail(f"0x{msg.arbitration_id:X}: {len(msg.data)} bytes")
        s = decode(msg)
        if msg.arbitration_id == 0x70B:
            count = int(s["DetectionCount"])
            lists.append({"h": s, "d": {k: (s, k) for k in range(min(count, 2))}})
        elif msg.arbitration_id == 0x70C:
            cur = lists[-1]
            count = int(cur["h"]["DetectionCount"])
            first, slots = int(s["FirstIndex"]), int(s["SlotCount"])
            if int(s["FrameCounter"]) != int(cur["h"]["FrameCounter"]):
                fail("FD FrameCounter does not match the header")
            if (first - 2) % 3 != 0 or slots != min(3, count - first):
                fail(f"FD FirstIndex {first} / SlotCount {slots} for {count} detections")
            for k in range(slots):
                if first + k in cur["d"]:
                    fail(f"FD detection {first + k} twice")
                cur["d"][first + k] = (s, k)
        else:
            fail(f"unexpected identifier 0x{msg.arbitration_id:X} in the FD log")
    if len(lists) != len(want_lists):
        fail(f"FD: {len(lists)} lists decoded, {len(want_lists)} written")
    n = 0
    for got, want in zip(lists, want_lists):
        h = got["h"]
        if (int(h["FrameCounter"]) != want["frame_counter"] or int(h["TimeMs"]) != want["time_ms"]
                or int(h["Status"]) != want["status"]):
            fail(f"FD header mismatch {h} vs {want}")
        if int(h["DetectionCount"]) != len(want["detections"]) or \
                len(got["d"]) != len(want["detections"]):
            fail("FD detection count mismatch")
        for i, d in enumerate(want["detections"]):
            s, k = got["d"][i]
            for name, key, step, top in FD_SIGNALS:
                ref = d[key] if top is None else min(d[key], top)
                bus = s[f"{name}_{k}"]
                if abs(bus - ref) > step / 2 + 1e-9:
                    fail(f"FD list {want['frame_counter']} detection {i} {name}: {bus} vs {ref}")
            for name, key in (("RangeAmbiguous", "range_ambiguous"),
                              ("VelocityAmbiguous", "velocity_ambiguous")):
                if int(s[f"{name}_{k}"]) != int(d[key]):
                    fail(f"FD list {want['frame_counter']} detection {i} {name}")
            n += 1
    if n < 1000:
        fail(f"FD: only {n} detections checked")
    return n


if __name__ == "__main__":
    main()
