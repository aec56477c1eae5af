#!/usr/bin/python3
"""`radar-emu run --cube` end to end (docs/cube.md), read with h5py and checked with NumPy.

A short default-scenario run writes a cube file for a few frames. For every detection of every
captured frame, against detections.json of the same frame (what went on the bus):
  * the image: the detection's cell is a local maximum of |cell|^2, and the range and velocity of
    that cell from the file's bin attributes are within one bin of the detection's;
  * the raw samples: the beam's Sigma channel, range-compressed by correlation with the
    reference chirp built from the file's attributes and Doppler-transformed with NumPy, peaks
    within one bin of the detection's cell, with a power over the cell and its neighbours within
    3 dB of the image's
    (strong detections of scene objects, SNR >= 20 dB and 20 dB above the clutter ridge around
    the cell: noise and clutter speckle are drawn anew for the raw samples, so a cell where they
    matter agrees only in distribution).
The same run without --cube writes the same detections.json byte for byte. The scenario's
`[output] cube` and `cube_frames` write the same file as the flags (every dataset and attribute
equal), and the flags win over them. Then the errors: an unwritable path, a bad --cube-frames, a range past the run and one over the
size limit (its estimate printed) are each refused with one line before the run.

usage: check_cube.py RADAR_EMU WORK_DIR
"""
import json
import os
import subprocess
import sys

import h5py
import numpy as np

C = 299792458.0


def fail(msg):
    print("FAIL:", msg)
    sys.exit(1)


def run(exe, args, expect_ok=True):
    p = subprocess.run([exe, "run"] + args, capture_output=True, text=True, timeout=900)
    if expect_ok and p.returncode != 0:
        fail(f"radar-emu run {' '.join(args)} exited {p.returncode}: {p.stderr}")
    return p


def process_raw(f, raw_sum):
    """Sigma channel [pulse][fast] -> image [velocity row][range bin], as docs/cube.md says."""
    fs = f.attrs["sample_rate_hz"]
    t_p = f.attrs["pulse_width_s"]
    k = f.attrs["chirp_rate_hz_per_s"]
    nr = int(f.attrs["range_bins"])
    m = int(f.attrs["pulses"])
    w_r = f["range_window"][...]
    w_d = f["doppler_window"][...]
    n_p = len(w_r)
    x = (np.arange(n_p) + 0.5) / fs - 0.5 * t_p
    h = w_r * np.exp(1j * np.pi * k * x * x)
    # y[l] = sum_i raw[l + i] conj(h[i]), l = 0 .. nr-1, each pulse.
    y = np.empty((m, nr), dtype=complex)
    for p in range(m):
        y[p] = np.correlate(raw_sum[p].astype(complex), h, mode="valid")[:nr]
    z = np.fft.ifft(y * w_d[:, None], axis=0) * m
    z = np.fft.fftshift(z, axes=0)
    return z / np.sqrt(np.sum(w_r**2) * np.sum(w_d**2))


def main():
    if len(sys.argv) != 3:
        fail("usage: check_cube.py RADAR_EMU WORK_DIR")
    exe, work = sys.argv[1], sys.argv[2]
    os.makedirs(work, exist_ok=True)
    out = os.path.join(work, "run")
    cube = os.path.join(work, "cube.h5")
    p = run(exe, ["--frames", "5", "--out", out, "--cube", cube, "--cube-frames", "2:4"])
    if "cube: 3 frames (2..4)" not in p.stdout:
        fail(f"summary has no cube line for frames 2..4:\n{p.stdout}")
    with open(os.path.join(out, "detections.json")) as fh:
        frames = {fr["frame_counter"]: fr for fr in json.load(fh)["frames"]}
    # Capturing changes nothing the radar does: the same run without --cube sends the same lists.
    plain = os.path.join(work, "plain")
    run(exe, ["-q", "--frames", "5", "--out", plain])
    with open(os.path.join(out, "detections.json"), "rb") as a, \
            open(os.path.join(plain, "detections.json"), "rb") as b:
        if a.read() != b.read():
            fail("detections.json differs between the runs with and without --cube")

    checked_image = checked_raw = 0
    with h5py.File(cube, "r") as f:
        if f.attrs["format"] != "radar-emu cube 1":
            fail(f"format {f.attrs['format']!r}")
        if list(f["frames"][...]) != [2, 3, 4] or f.attrs["frames_written"] != 3:
            fail(f"frames {list(f['frames'][...])}")
        r0, dr = f.attrs["range_bin0_m"], f.attrs["range_bin_m"]
        v0, dv = f.attrs["velocity_bin0_mps"], f.attrs["velocity_bin_mps"]
        lam = f.attrs["wavelength_m"]
        if not np.isclose(f.attrs["doppler_bin_hz"], 2 * dv / lam):
            fail("doppler_bin_hz is not 2 velocity_bin_mps / wavelength_m")
        if not np.isclose(dr, C / (2 * f.attrs["sample_rate_hz"])):
            fail("range_bin_m is not c / (2 fs) for the pulsed waveform")
        beam_az = f.attrs["beam_azimuth_rad"]
        nb, nc, m, nf = f["frame_000002/raw"].shape
        if (nb, nc, m, nf) != (len(beam_az), 3, f.attrs["pulses"], f.attrs["fast_samples"]):
            fail(f"raw shape {(nb, nc, m, nf)}")
        for name in ("frame_000002", "frame_000003", "frame_000004"):
            g = f[name]
            idx = int(g.attrs["frame_index"])
            sent = frames[idx]["detections"]
            dets = g["detections"][...]
            image = g["image"][...]
            if image.dtype != np.complex64 or image.shape != (nb, m, f.attrs["range_bins"]):
                fail(f"{name}: image {image.dtype} {image.shape}")
            if len(dets) != len(sent) or len(sent) == 0:
                fail(f"{name}: {len(dets)} detections in the cube, {len(sent)} sent")
            power = np.abs(image) ** 2
            processed = {}
            for d, s in zip(dets, sent):
                b, j, l = int(d["azimuth_cell"]), int(d["doppler_cell"]), int(d["range_cell"])
                if abs(d["range_m"] - s["range_m"]) > 1e-6:
                    fail(f"{name}: detection order differs from detections.json")
                # Image: a local maximum at the cell, its range and velocity within one bin.
                cell = power[b, j, l]
                nbhd = power[b, [(j - 1) % m, j, (j + 1) % m]][:, max(l - 1, 0) : l + 2]
                if cell < nbhd.max():
                    fail(f"{name}: cell ({b},{j},{l}) is not a local maximum of the image")
                rng = r0 + l * dr
                vel = v0 + j * dv
                if abs(rng - s["range_m"]) > dr or abs(vel - s["radial_velocity_mps"]) > dv:
                    fail(f"{name}: cell ({b},{j},{l}) = {rng:.2f} m, {vel:.2f} m/s against "
                         f"{s['range_m']:.2f} m, {s['radial_velocity_mps']:.2f} m/s sent")
                if abs(np.degrees(beam_az[b]) - s["azimuth_deg"]) > 2.0:
                    fail(f"{name}: beam {b} at {np.degrees(beam_az[b]):.1f} deg, detection at "
                         f"{s['azimuth_deg']:.2f} deg")
                checked_image += 1
                # The raw samples draw their own noise and clutter speckle (docs/cube.md): the
                # returns of scene objects agree, clutter-dominated cells only in distribution.
                if s["snr_db"] < 20.0 or int(d["object_id"]) == 0xFFFFFFFF:
                    continue
                # Static objects share the ground's Doppler: their cells sit on the clutter
                # ridge, whose speckle the raw samples draw anew. Compared only where the cell
                # is 20 dB above the ridge around it (the median of the image's power 5 to 15
                # bins away in range, same beam and velocity bin): a clutter amplitude 20 dB
                # down moves the cell's power by more than 3 dB with a probability of about
                # exp(-0.29^2 / 0.01) = 2e-4 (complex Gaussian, |1 + x|^2 < 0.5 needs |x| >= 0.29).
                ridge = np.concatenate([power[b, j, max(l - 15, 0) : max(l - 4, 0)],
                                        power[b, j, l + 5 : l + 16]])
                if ridge.size == 0 or cell < 100.0 * np.median(ridge):
                    continue
                # Raw: NumPy's own processing of the beam's Sigma samples peaks at the cell.
                if b not in processed:
                    processed[b] = np.abs(process_raw(f, g["raw"][b, 0])) ** 2
                pr = processed[b]
                rows = [(j + dj) % m for dj in range(-4, 5)]
                cols = slice(max(l - 4, 0), l + 5)
                win = pr[rows][:, cols]
                pj, pl = np.unravel_index(np.argmax(win), win.shape)
                pj, pl = rows[pj], cols.start + pl
                dj = min((pj - j) % m, (j - pj) % m)
                if abs(pl - l) > 1 or dj > 1:
                    fail(f"{name}: raw samples of beam {b} peak at ({pj},{pl}), detection at "
                         f"({j},{l}) ({s['range_m']:.1f} m, {s['radial_velocity_mps']:.2f} m/s)")
                rng_raw = r0 + pl * dr
                vel_raw = v0 + pj * dv
                if abs(rng_raw - s["range_m"]) > dr or abs(vel_raw - s["radial_velocity_mps"]) > dv:
                    fail(f"{name}: raw peak {rng_raw:.2f} m, {vel_raw:.2f} m/s")
                # Energy over the cell and its eight neighbours: the image merges an object's
                # coherent returns within a merge cell (radar/sensor/sensor.cpp, merge_returns)
                # where the raw samples keep each at its own range, so a spread object's energy
                # can sit one bin over (frame 3's light mast: image -5.7 / 0.0 dB in range bins
                # l - 1 / l, raw -3.3 / -3.2 dB).
                near = [(j - 1) % m, j, (j + 1) % m]
                lo, hi = max(l - 1, 0), l + 2
                ratio_db = 10 * np.log10(pr[near][:, lo:hi].sum() / power[b, near][:, lo:hi].sum())
                if abs(ratio_db) > 3.0:
                    fail(f"{name}: raw power {ratio_db:+.1f} dB from the image's around the cell")
                checked_raw += 1
    if checked_raw < 3:
        fail(f"only {checked_raw} strong detections checked against the raw samples")
    print(f"cube: {checked_image} detections checked on the image, {checked_raw} on the raw samples")

    # Errors before the run, one line each.
    cases = [
        (["--cube", "/nonexistent-dir/x/cube.h5"], "nonexistent-dir"),
        (["--cube", cube, "--cube-frames", "3"], "FIRST:LAST"),
        (["--cube", cube, "--cube-frames", "4:2"], "LAST is before FIRST"),
        (["--frames", "5", "--cube", cube, "--cube-frames", "7:9"], "past the run's 5 frames"),
        (["--frames", "400", "--cube", cube, "--cube-frames", "0:399"], "MiB a frame"),
        (["--cube-frames", "0:3"], "--cube"),
    ]
    for args, fragment in cases:
        p = run(exe, args, expect_ok=False)
        err = p.stderr.strip().splitlines()
        if p.returncode == 0 or not err or fragment not in err[-1]:
            fail(f"radar-emu run {' '.join(args)}: exit {p.returncode}, stderr {p.stderr!r}, "
                 f"expected a line with {fragment!r}")
    print("cube: errors refused before the run")

    # The scenario's [output] cube and cube_frames: the same file as the flags; the flags win.
    def scenario(name, body):
        path = os.path.join(work, name)
        with open(path, "w") as fh:
            fh.write(body)
        return path

    toml = scenario("cube.toml", '[output]\ncube = "toml_cube.h5"\ncube_frames = "2:4"\n')
    toml_cube = os.path.join(work, "toml_cube.h5")  # relative to the scenario file
    if os.path.exists(toml_cube):
        os.remove(toml_cube)
    p = run(exe, [toml, "--frames", "5", "--out", os.path.join(work, "run_toml")])
    if "cube: 3 frames (2..4)" not in p.stdout:
        fail(f"[output] cube: no cube line for frames 2..4:\n{p.stdout}")
    same_file(cube, toml_cube)
    cli_cube = os.path.join(work, "cli_wins.h5")
    os.remove(toml_cube)
    run(exe, [toml, "-q", "--frames", "5", "--out", os.path.join(work, "run_cli"), "--cube",
              cli_cube, "--cube-frames", "3:3"])
    if os.path.exists(toml_cube):
        fail("--cube given, yet the scenario's [output] cube was written too")
    with h5py.File(cli_cube, "r") as f:
        if list(f["frames"][...]) != [3]:
            fail(f"--cube-frames 3:3 over the scenario's 2:4: frames {list(f['frames'][...])}")
    print("cube: [output] cube writes the flags' file; the flags win")
    bad = [
        ('[output]\ncube = "x.txt"\n', [], '[output] cube: "x.txt" is not an HDF5 file name'),
        ('[output]\ncube_frames = "0:3"\n', [], "[output] cube_frames: needs cube"),
        ('[output]\ncube = "c.h5"\ncube_frames = "4:2"\n', [], "LAST is before FIRST"),
        ('[output]\ncube = "c.h5"\ncube_frames = "7:9"\n', ["--frames", "5"],
         "[output] cube_frames starts at frame 7, past the run's 5 frames"),
        ('[output]\ncube = "c.h5"\n', ["--cube-frames", "x"], "FIRST:LAST"),
    ]
    for body, extra, fragment in bad:
        p = run(exe, [scenario("bad.toml", body)] + extra, expect_ok=False)
        err = p.stderr.strip().splitlines()
        if p.returncode == 0 or not err or fragment not in err[-1]:
            fail(f"scenario {body!r} {extra}: exit {p.returncode}, stderr {p.stderr!r}, "
                 f"expected a line with {fragment!r}")
    print("cube: bad [output] cube keys refused before the run")


def same_file(a, b):
    """Every group, dataset and attribute of cube file `a` equals `b`'s (but the scenario name)."""
    with h5py.File(a, "r") as fa, h5py.File(b, "r") as fb:
        def attrs_equal(x, y, where):
            if set(x.attrs) != set(y.attrs):
                fail(f"{where}: attributes {sorted(x.attrs)} against {sorted(y.attrs)}")
            for k in x.attrs:
                if k == "scenario":
                    continue
                if not np.array_equal(np.asarray(x.attrs[k]), np.asarray(y.attrs[k])):
                    fail(f"{where}: attribute {k} {x.attrs[k]!r} against {y.attrs[k]!r}")

        attrs_equal(fa, fb, "/")
        if sorted(fa.keys()) != sorted(fb.keys()):
            fail(f"groups {sorted(fa.keys())} against {sorted(fb.keys())}")
        for name in fa:
            if isinstance(fa[name], h5py.Dataset):
                if not np.array_equal(fa[name][...], fb[name][...]):
                    fail(f"/{name} differs between {a} and {b}")
                continue
            attrs_equal(fa[name], fb[name], name)
            for ds in fa[name]:
                if not np.array_equal(fa[name][ds][...], fb[name][ds][...]):
                    fail(f"/{name}/{ds} differs between {a} and {b}")


if __name__ == "__main__":
    main()
