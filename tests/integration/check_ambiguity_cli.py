#!/usr/bin/python3
"""radar-emu ambiguity end to end: the measured figures against linear-FM theory, and the
computed cuts against the closed form evaluated here (Richards, Fundamentals of Radar Signal
Processing, 2nd ed., eq. 4.98: |chi| = (1 - |tau|/T) |sinc(pi T (f_d + k tau)(1 - |tau|/T))|)."""
import csv
import json
import math
import subprocess
import sys

exe, out = sys.argv[1], sys.argv[2]


def lfm(tau, fd, t, k):
    a = abs(tau) / t
    if a >= 1.0:
        return 0.0
    x = math.pi * t * (fd + k * tau) * (1.0 - a)
    return abs((1.0 - a) * (1.0 if abs(x) < 1e-12 else math.sin(x) / x))


failures = []


def check(name, got, want, rel):
    ok = abs(got - want) <= rel * abs(want)
    print(f"{'ok  ' if ok else 'FAIL'} {name}: {got:.6g} (theory {want:.6g}, +-{rel:.0%})")
    if not ok:
        failures.append(name)


# A short pulse so that the integral is quick: B = 20 MHz, T = 1 us (B T = 20).
subprocess.run([exe, "ambiguity", "--bandwidth-hz", "20e6", "--pulse-width-s", "1e-6",
                "--out", out + "/single", "-q"], check=True)
s = json.load(open(out + "/single/summary.json"))
b, t = s["bandwidth_hz"], s["pulse_width_s"]
k = b / t
m = s["measured"]
# First null of the compressed pulse: B tau (1 - tau/T) = 1, i.e. 1/B (the Rayleigh resolution
# c/2B) for large B T, 1.056/B at B T = 20.
bt = b * t
x = (bt - math.sqrt(bt * bt - 4.0 * bt)) / 2.0
check("zero-Doppler first null [s]", m["zero_doppler_first_null_s"], x / b, 0.02)
check("zero-delay first null [Hz]", m["zero_delay_first_null_hz"], 1.0 / t, 0.05)
# Range-Doppler coupling: the peak moves by tau = -f_d / k (Richards eqs. 4.105-4.106).
check("ridge delay per Hz of Doppler", m["ridge_delay_per_doppler_s_per_hz"], -1.0 / k, 0.02)
worst = 0.0
with open(out + "/single/cuts.csv") as f:
    for row in csv.DictReader(f):
        v = float(row["value"])
        cf = lfm(v, 0.0, t, k) if row["axis"] == "delay_s" else lfm(0.0, v, t, k)
        worst = max(worst, abs(float(row["computed"]) - cf))
print(f"{'ok  ' if worst < 0.01 else 'FAIL'} cuts vs closed form: worst {worst:.4f}")
if worst >= 0.01:
    failures.append("cuts")

# The coherent train: Doppler resolution 1/(M PRI), ambiguities every PRF.
subprocess.run([exe, "ambiguity", "--train", "--pulses", "16", "--prf-hz", "20e3",
                "--out", out + "/train", "-q"], check=True)
s = json.load(open(out + "/train/summary.json"))
check("train zero-delay first null [Hz]", s["measured"]["zero_delay_first_null_hz"],
      1.0 / (16 * 50e-6), 0.05)
sys.exit(1 if failures else 0)
