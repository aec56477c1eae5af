#!/usr/bin/python3
"""Compares the detections of closed-loop runs frame by frame against a reference run.

usage: scripts/compare-detections.py REF_OUT OTHER_OUT [OTHER_OUT ...]

Each argument is a `radar-emu run --out` directory (its detections.json). In every frame a
detection of the reference is matched to the first unmatched detection of the other run within
4.5 m of range (1.5 range cells of the default radar), 0.5 deg of azimuth and 1.5 m/s of radial
velocity; per other run it prints the detections matched, missed (in the reference only) and
added (in the other run only), and the mean and median |SNR difference| of the matched ones.
Used in docs/performance.md ("Static path reuse") to set a change's effect on the detections
beside that of another, equally valid sampling of the same scene (the ray spacing 3 % finer or
coarser).
"""
import json
import sys


def load(path):
    with open(path + "/detections.json") as f:
        d = json.load(f)
    return {fr["frame_counter"]: fr["detections"] for fr in d["frames"]}


def match(ref, other, dr=4.5, daz=0.5, dv=1.5):
    used, snr = set(), []
    for x in ref:
        for j, y in enumerate(other):
            if j in used:
                continue
            if (abs(x["range_m"] - y["range_m"]) <= dr
                    and abs(x["azimuth_deg"] - y["azimuth_deg"]) <= daz
                    and abs(x["radial_velocity_mps"] - y["radial_velocity_mps"]) <= dv):
                used.add(j)
                snr.append(abs(x["snr_db"] - y["snr_db"]))
                break
    return len(snr), len(ref) - len(snr), len(other) - len(snr), snr


def main(argv):
    if len(argv) < 3:
        sys.stderr.write(__doc__)
        return 2
    ref = load(argv[1])
    for path in argv[2:]:
        other = load(path)
        matched = missed = added = 0
        snr = []
        for frame, dets in ref.items():
            m, mi, ad, s = match(dets, other.get(frame, []))
            matched, missed, added, snr = matched + m, missed + mi, added + ad, snr + s
        for frame, dets in other.items():  # frames the reference does not have
            if frame not in ref:
                added += len(dets)
        snr.sort()
        mean = sum(snr) / len(snr) if snr else float("nan")
        median = snr[len(snr) // 2] if snr else float("nan")
        print(f"{path}: matched {matched}, missed {missed}, added {added}, "
              f"|dSNR| mean {mean:.2f} dB, median {median:.2f} dB")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
