#!/usr/bin/python3
"""Fits the fidelity governor's cost model ([governor] in the scenario, loop/governor.hpp) to
the stage times of runs on this machine.

usage: scripts/fit-governor-costs.py RUN_DIR [RUN_DIR ...]

Each RUN_DIR is the --out directory of a `radar-emu run` (its frames.csv). The runs should span
the figures the model counts: e.g. the scenario with [governor] enabled = false (level 0), the
same with [radar] reuse_static_paths = false (every ray traced), and one held at a coarser
level ([governor] max_level = 4 with compute_fraction = 0.01). Frame 0 of each run is left out
(its caches are cold). The model, per frame:

  trace  = trace_ms_per_frame + trace_ns_per_facet x the targets' facets (facet pass)
           + trace_ns_per_ray x rays traced
           + trace_ns_per_kept_return x kept returns
           + terrain_ns_per_patch x max(terrain patches, terrain facets) (the governor's count)
  sensor = sensor_ns_per_cell x cells synthesised + sensor_ns_per_return x the rays' returns
           + sensor_ns_per_unmerged_return x those the sensor did not merge into another
           + sensor_ns_per_terrain_return x the terrain engine's returns

fitted by least squares with non-negative coefficients (numpy.linalg.lstsq, a coefficient that
comes out negative is set to 0 and the rest fitted again). Prints the [governor] lines to paste,
and per run the mean and 99th percentile of measured / predicted for each stage, so the fit can
be judged where it is used.
"""
import csv
import os
import sys

import numpy as np

# "frame": the constant; "terrain": max(terrain_patches, terrain_facets)
TRACE_TERMS = ["frame", "target_facets", "rays", "kept_returns", "terrain"]
TRACE_KEYS = ["trace_ms_per_frame", "trace_ns_per_facet", "trace_ns_per_ray", "trace_ns_per_kept_return",
              "terrain_ns_per_patch"]
SENSOR_TERMS = ["cells_synthesised", "ray_returns", "unmerged_returns", "terrain_returns"]
SENSOR_KEYS = ["sensor_ns_per_cell", "sensor_ns_per_return", "sensor_ns_per_unmerged_return",
               "sensor_ns_per_terrain_return"]


def load(run_dir):
    path = os.path.join(run_dir, "frames.csv")
    with open(path, newline="") as f:
        rows = [r for r in csv.DictReader(f) if r["ownship_valid"] == "1"]
    needed = ["target_facets", "rays", "kept_returns", "terrain_patches", "terrain_facets"]
    needed += ["cells_synthesised", "returns", "terrain_returns", "merged_returns"]
    missing = [k for k in needed if rows and k not in rows[0]]
    if missing:
        sys.exit(f"{path}: no column {missing[0]} (a frames.csv from an older radar-emu?)")
    for r in rows:
        r["terrain"] = max(float(r["terrain_patches"]), float(r["terrain_facets"]))
        r["ray_returns"] = float(r["returns"]) - float(r["terrain_returns"])
        r["unmerged_returns"] = r["ray_returns"] - float(r["merged_returns"])
    return rows[1:]


def fit_nonnegative(x, y):
    """Least squares y ~ x c with c >= 0: negative coefficients dropped and the rest refitted."""
    active = list(range(x.shape[1]))
    c = np.zeros(x.shape[1])
    while active:
        sol, *_ = np.linalg.lstsq(x[:, active], y, rcond=None)
        if (sol >= 0).all():
            c[active] = sol
            break
        active = [a for a, s in zip(active, sol) if s >= 0]
    return c


def main():
    if len(sys.argv) < 2 or sys.argv[1] in ("-h", "--help"):
        print(__doc__)
        return 0 if len(sys.argv) >= 2 else 2
    runs = {d: load(d) for d in sys.argv[1:]}
    rows = [r for rs in runs.values() for r in rs]
    if len(rows) < 10:
        sys.exit("fit-governor-costs: fewer than 10 frames in all: run longer")

    def matrix(rs, terms):  # ns x count -> ms; the constant in ms
        return np.array([[1.0 if t == "frame" else float(r[t]) * 1e-6 for t in terms] for r in rs])

    trace = fit_nonnegative(matrix(rows, TRACE_TERMS), np.array([float(r["trace_ms"]) for r in rows]))
    sensor = fit_nonnegative(matrix(rows, SENSOR_TERMS),
                             np.array([float(r["sensor_ms"]) for r in rows]))
    print(f"# fitted on {len(rows)} frames of {len(runs)} runs ({os.cpu_count()} CPUs)")
    print("[governor]")
    for key, value in zip(TRACE_KEYS + SENSOR_KEYS, list(trace) + list(sensor)):
        print(f"{key} = {value:.2f}" if key.endswith("_ms_per_frame") else f"{key} = {value:.1f}")
    print("\n# measured / predicted per run: mean, p99 (trace, sensor, both)")
    for d, rs in runs.items():
        pt = matrix(rs, TRACE_TERMS) @ trace
        ps = matrix(rs, SENSOR_TERMS) @ sensor
        mt = np.array([float(r["trace_ms"]) for r in rs])
        ms = np.array([float(r["sensor_ms"]) for r in rs])
        ratios = [mt / pt, ms / ps, (mt + ms) / (pt + ps)]
        text = ", ".join(f"{np.mean(q):.2f} {np.percentile(q, 99):.2f}" for q in ratios)
        print(f"# {d}: {len(rs)} frames, predicted {np.mean(pt + ps):.1f} ms a frame: {text}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
