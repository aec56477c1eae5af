#!/usr/bin/python3
"""MPI scale-out (docs/cluster.md): `mpirun -np N radar-emu rcs|profile ...` writes byte for byte
the files of one process (`radar-emu rcs ...` without mpirun): CSVs, statistics, PNGs, ISAR.
  - rcs over a theta x phi grid of 21 directions (blocks of 11 and 10 cut a theta row), with
    multi-bounce paths (a trihedral), edge terms, --window-deg statistics and a plot, on 2 ranks;
  - the same on 3 ranks, and a 2-direction sweep on 3 ranks (one rank with nothing to do);
  - profile with an ISAR image over a phi sweep, on 2 ranks;
  - sar (pulses split) on three trihedrals and on a grass field with speckle, on 2 ranks;
  - rank 0 alone prints (one summary), and a command that does not split (scene target) is
    refused under mpirun with a one-line error.
Usage: check_mpi_split.py RADAR_EMU MPIEXEC WORK_DIR
MPIEXEC is "none" for a build without MPI: the test is then skipped (exit 77)."""
import filecmp
import json
import os
import subprocess
import sys

from cli_check import check, finish, runner

exe, mpiexec, work = sys.argv[1], sys.argv[2], sys.argv[3]
if mpiexec in ("", "none"):
    print("SKIP: radar-emu was built without MPI (CMake RADAR_EMU_MPI=OFF, or AUTO without "
          "Open MPI: Debian openmpi-bin libopenmpi-dev): nothing to compare")
    sys.exit(77)
os.makedirs(work, exist_ok=True)
run = runner(exe)

# The tests run as root in CI: Open MPI refuses that unless told. --oversubscribe: more ranks
# than cores (the CI machine has 2). --bind-to none: the ranks share the cores with TBB.
env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
           OMPI_MCA_rmaps_base_oversubscribe="1")
# Shared memory between the ranks of this one machine, nothing else; and no cross-memory attach
# (process_vm_readv), which containers without CAP_SYS_PTRACE refuse.
env["OMPI_MCA_btl"] = "self,vader"
env["OMPI_MCA_btl_vader_single_copy_mechanism"] = "none"


def mpirun(ranks, *args):
    cmd = [mpiexec, "--oversubscribe", "--bind-to", "none", "-np", str(ranks), exe, *args]
    return subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=300)


def mpirun_ok(ranks, *args):
    r = mpirun(ranks, *args)
    if r.returncode != 0:
        print(r.stdout, r.stderr)
        sys.exit(f"mpirun -np {ranks} radar-emu {' '.join(args)} exited {r.returncode}")
    return r


def same_files(a_dir, b_dir, names, what):
    for n in names:
        a, b = os.path.join(a_dir, n), os.path.join(b_dir, n)
        check(os.path.getsize(a) > 0, f"{what}: {n} written by one process")
        check(filecmp.cmp(a, b, shallow=False), f"{what}: {n} differs between 1 process and mpirun")


tri = os.path.join(work, "trihedral.obj")
run("scene", "target", "trihedral-square", "--a-m", "0.25", "--out", tri)

# rcs: 3 theta x 7 phi directions, 5 frequencies, 3 bounces, edges on.
rcs_args = ["rcs", "--mesh", tri, "--freq-sweep-hz", "9e9:11e9:5", "--theta-deg", "30:60:3",
            "--phi-deg", "20:70:7", "--pol", "HH,VV,HV", "--window-deg", "20"]
names = ["rcs.csv", "rcs_stats.csv", "rcs.png"]


def rcs_into(d):
    os.makedirs(d, exist_ok=True)
    return [*rcs_args, "--out", os.path.join(d, "rcs.csv"), "--plot", os.path.join(d, "rcs.png")]


one = os.path.join(work, "rcs_1")
r1 = run(*rcs_into(one))
with open(os.path.join(one, "rcs.csv")) as f:
    check(len(f.readlines()) == 1 + 21 * 5, "rcs: 105 rows")
for ranks in (2, 3):
    d = os.path.join(work, f"rcs_{ranks}")
    r = mpirun_ok(ranks, *rcs_into(d))
    same_files(one, d, names, f"rcs on {ranks} ranks")
    check(r.stdout.count("wrote ") == 1, f"rcs on {ranks} ranks: one summary (rank 0's)")
    check(f"21 directions over {ranks} ranks" in r.stdout, f"rcs on {ranks} ranks: the split said")
    # The run's totals (rays, paths, edge terms) are those of one process.
    totals = [ln for ln in r.stdout.splitlines() if ln.startswith(("21 directions", "edge terms"))]
    totals_1 = [ln for ln in r1.stdout.splitlines() if ln.startswith(("21 directions", "edge terms"))]
    strip = [t.split(" s: ", 1)[-1] for t in totals]  # without the time
    strip_1 = [t.split(" s: ", 1)[-1] for t in totals_1]
    check(strip == strip_1 and len(strip) == 2, f"rcs on {ranks} ranks: totals {strip} != {strip_1}")

# Fewer directions than ranks: rank 2 has none.
few = ["rcs", "--mesh", tri, "--freq-hz", "10e9", "--theta-deg", "40:50:2", "-q"]
run(*few, "--out", os.path.join(work, "few_1.csv"))
mpirun_ok(3, *few, "--out", os.path.join(work, "few_3.csv"))
check(filecmp.cmp(os.path.join(work, "few_1.csv"), os.path.join(work, "few_3.csv"), shallow=False),
      "rcs, 2 directions on 3 ranks: differs from 1 process")

# profile + ISAR over 15 phi angles.
prof_args = ["profile", "--mesh", tri, "--freq-sweep-hz", "8e9:12e9:64", "--theta-deg", "45",
             "--phi-deg", "30:60:15", "-q"]
pnames = ["profile.csv", "profile_isar.csv", "profile.png", "profile_isar.png"]


def prof_into(d):
    os.makedirs(d, exist_ok=True)
    return [*prof_args, "--out", os.path.join(d, "profile.csv"),
            "--plot", os.path.join(d, "profile.png")]


run(*prof_into(os.path.join(work, "prof_1")))
mpirun_ok(2, *prof_into(os.path.join(work, "prof_2")))
same_files(os.path.join(work, "prof_1"), os.path.join(work, "prof_2"), pnames, "profile on 2 ranks")

# sar: the pulses split (three trihedrals, examples/sar_trihedrals.toml, and a grass field with
# speckle): raw data, image, PNGs and the JSON but its timings equal one process's.
src = os.environ.get("RADAR_EMU_SOURCE_DIR",
                     os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
sar_case = os.path.join(src, "examples", "sar_trihedrals.toml")
with open(sar_case) as f:
    # The split of the clutter, not the clutter, is under test (the targets' split is the case
    # above): the field alone, in coarse cells (10 m) over a quarter of the swath (128 gates).
    field = f.read()
field = field[:field.index("[[scene.target]]")]
field = field.replace('ground_material = "none"', 'ground_material = "grass"\nclutter_cell_m = 10.0')
field = field.replace("\ngates = 512", "\ngates = 128")
field_case = os.path.join(work, "sar_field.toml")
with open(field_case, "w") as f:
    f.write(field)
check(field.count('ground_material = "grass"') == 1 and "\ngates = 128" in field
      and "[[scene.target]]" not in field, "sar: the field case is a field alone, 128 gates")


def sar_json(d):
    with open(os.path.join(d, "sar.json")) as f:
        j = json.load(f)
    j.pop("timing_s", None)
    return j


for tag, case in (("sar", sar_case), ("sar_field", field_case)):
    d1, d2 = os.path.join(work, f"{tag}_1"), os.path.join(work, f"{tag}_2")
    run("sar", case, "--out", d1, "-q")
    mpirun_ok(2, "sar", case, "--out", d2, "-q")
    same_files(d1, d2, ["raw.tif", "image.tif", "image.png"], f"{tag} on 2 ranks")
    check(sar_json(d1) == sar_json(d2), f"{tag} on 2 ranks: sar.json (but timings) differs")

# A command that does not split its work is refused, on every rank, in one line each.
r = mpirun(2, "scene", "target", "plate", "--a-m", "1", "--b-m", "1",
           "--out", os.path.join(work, "plate.obj"))
check(r.returncode != 0, "scene target under mpirun -np 2: refused")
errors = [ln for ln in r.stderr.splitlines() if ln.startswith("radar-emu: error")]
check(len(errors) == 2 and all("only rcs, profile and sar split" in e for e in errors),
      f"scene target under mpirun: one error line a rank, got {errors}")
check(not os.path.exists(os.path.join(work, "plate.obj")), "scene target under mpirun: no file")

finish()
print("mpi split: byte-identical to one process")
