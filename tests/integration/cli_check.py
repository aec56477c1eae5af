"""Shared by the CLI check scripts (check_rcs_cli.py, check_scene_cli.py, ...): run radar-emu and
collect failed checks, so that a script reports every failure before it exits non-zero."""
import subprocess
import sys

failures = []
verbose = False  # a script that sets it also prints a line for each check that passes


def check(cond, what):
    if not cond:
        failures.append(what)
        print("FAIL:", what)
    elif verbose:
        print("ok  ", what)


def runner(exe):
    """A run(*args) for `exe`: exits the script with the command's output when it fails."""
    def run(*args):
        r = subprocess.run([exe, *args], capture_output=True, text=True)
        if r.returncode != 0:
            print(r.stdout, r.stderr)
            sys.exit(f"radar-emu {' '.join(args)} exited {r.returncode}")
        return r
    return run


def write_series(path, values):
    """Writes {x: dB} as the "x dB" lines that `rcs --overlay FILE=LABEL` reads."""
    with open(path, "w") as f:
        f.writelines(f"{a:g} {v:.4f}\n" for a, v in sorted(values.items()))


def finish():
    if failures:
        sys.exit(f"{len(failures)} failure(s)")
    if verbose:
        print("all checks passed")
