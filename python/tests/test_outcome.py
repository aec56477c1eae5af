"""The outcome per target from Python (radar_emu.Loop.finish()["targets"], docs/outcome.md)
against what the stepped frames themselves say: frames in the beam counted from each frame's
truth, detected frames and false alarms from each frame's association, and the range error's
mean and spread recomputed from the associated detections; and equal to report.json of
`radar-emu run` on the same frames."""
import json

import numpy as np

import radar_emu


def test_outcome_matches_the_frames_and_the_cli(cli, tmp_path):
    n = 30
    cli("run", "--frames", n, "--out", tmp_path / "cli", "-q")
    loop = radar_emu.Loop(frames=n)
    frames = list(loop)
    summary = loop.finish()
    targets = {t["object_id"]: t for t in summary["targets"]}
    assert summary["frames_scored"] == n

    in_beam, detected, false_alarms, on_objects = {}, {}, 0, 0
    errors = {}  # object id -> range errors of its associated detections, per frame
    for f in frames:
        truth, dets, assoc = f["truth"], f["detections"], f["association"]
        assert len(assoc) == len(dets)
        for oid in truth["object_id"]:
            in_beam[int(oid)] = in_beam.get(int(oid), 0) + 1
        false_alarms += int(np.sum(assoc < 0))
        on_objects += int(np.sum((assoc < 0) & (dets["object_id"] >= 0)))
        per_object = {}
        for i, j in enumerate(assoc):
            if j < 0:
                continue
            oid = int(truth["object_id"][j])
            per_object.setdefault(oid, []).append(dets["range_m"][i] - truth["range_m"][j])
        for oid, errs in per_object.items():
            detected[oid] = detected.get(oid, 0) + 1
            errors.setdefault(oid, []).append(errs)

    checked = 0
    assert summary["false_alarms"] == false_alarms
    assert summary["false_alarms_on_objects"] == on_objects
    assert abs(summary["false_alarms_per_frame"] - false_alarms / n) < 1e-12
    for oid, t in targets.items():
        assert t["frames_in_beam"] == in_beam.get(oid, 0), t["object"]
        assert t["frames_detected"] == detected.get(oid, 0), t["object"]
        if t["frames_in_beam"]:
            assert abs(t["pd"] - t["frames_detected"] / t["frames_in_beam"]) < 1e-12
        # One associated detection a frame: its error is the object's; mean and sample std.
        per_frame = errors.get(oid, [])
        if len(per_frame) >= 2 and all(len(e) == 1 for e in per_frame):
            e = np.array([x[0] for x in per_frame])
            assert abs(t["range_error_m"]["mean"] - e.mean()) < 1e-9, t["object"]
            assert abs(t["range_error_m"]["std"] - e.std(ddof=1)) < 1e-9, t["object"]
            checked += 1
    assert checked > 0

    with open(tmp_path / "cli" / "report.json") as f:
        rep = json.load(f)["outcome"]
    assert rep["false_alarms"] == summary["false_alarms"]
    assert [(t["object"], t["frames_in_beam"], t["frames_detected"]) for t in rep["targets"]] == \
        [(t["object"], t["frames_in_beam"], t["frames_detected"]) for t in summary["targets"]]
