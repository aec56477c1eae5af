#!/usr/bin/python3
"""Progress lines and clean stops of the long offline commands, end to end through the binary.

1. `rcs` on a truck mesh, 3000 directions x 2 frequencies, stderr on a pseudo-terminal: the
   progress line "rcs: P % (D/3000 directions), ..." appears; SIGINT once it has: exit status
   130, one line "radar-emu: rcs: interrupted by SIGINT after N of 3000 directions; ...", and
   rcs.csv holds the header, 2 N data rows (the first N directions at both frequencies, in
   sweep order) and a last line "# incomplete: ... (2N rows)".
2. `rcs` again with SIGTERM: exit status 143, the CSV's mark says SIGTERM.
   `rcs --method mom` (a sphere, 40 frequencies): the estimate line, then SIGINT between
   frequencies keeps all 19 directions at the k frequencies done (19 k rows).
   `profile` likewise (SIGINT): the CSV holds whole profiles of the angles the message counts
   and ends "# incomplete: ... (R rows)" with R its row count.
3. `sar examples/sar_trihedrals.toml` on a pseudo-terminal: the estimate line, the progress line
   in pulses; SIGINT after it began: status 130, the one-line message, sar.json says
   "incomplete": true, "stop_signal": "SIGINT" and pulses_done equals the message's count (below
   the case's pulses), image.tif and image.png are there.
4. Quiet: a short complete `rcs` with stderr a pipe prints no progress line and no "%"; with a
   pseudo-terminal and -q, none either; without -q on a pseudo-terminal the line is there and
   the finished CSV has no incomplete mark.
5. `tradeoff --quick --cases sphere,grazing,iem`, SIGINT during the sphere case: status 130,
   the one line, tradeoff.csv holds the sphere rows only and ends "# incomplete: stopped by
   SIGINT after 1 of 3 cases, before grazing (N rows)" with N its row count. On a terminal its
   progress line "tradeoff: 100 % (1/1 cases)" ends a short run, the case's lines above it.
6. `image examples/ev_radar_94ghz.toml` (200 x 66 pixels) on a pseudo-terminal: the estimate
   line, the progress line in columns; SIGINT once a strip of columns is done: status 130, the
   one line "... after K of 200 columns; ...", image.csv holds the K x 66 pixels of columns
   0..K-1 and ends "# incomplete: stopped by SIGINT after K of 200 columns (R rows)" with R its
   row count, image.json says incomplete, SIGINT, columns_done K.
7. `scene import` of the Olinda DEM at 4 m cells, SIGINT once the progress line passed 20 %:
   status 130, the one line in rows, the glTF is written and marked (`scene info --json` shows
   "incomplete" naming K of T rows of central tiles, K < T), and its central tiles are exactly
   the rows terrain_r00 .. r(K-1). `scene gen terrain` on a terminal: SIGINT during the
   generation leaves the whole scene written (it loads), status 130 and the one line.

The moment to signal is read from the progress line itself, never guessed with a sleep.

usage: check_offline_interrupt.py RADAR_EMU SOURCE_DIR WORK_DIR
"""
import json
import os
import pty
import re
import select
import signal
import subprocess
import sys
import time

import cli_check
from cli_check import check, failures, finish

exe, src, work = sys.argv[1], sys.argv[2], sys.argv[3]
os.makedirs(work, exist_ok=True)
cli_check.verbose = True  # an "ok" line for every check that passes


def run_on_pty(args, signal_when=None, sig=signal.SIGINT, timeout_s=120.0):
    """Runs args with stderr on a pseudo-terminal; sends sig once signal_when(stderr so far)
    holds. Returns (status, stderr text, stdout text)."""
    master, slave = pty.openpty()
    proc = subprocess.Popen(args, cwd=work, stdout=subprocess.PIPE, stderr=slave,
                            stdin=subprocess.DEVNULL)
    # The slave stays open here until the child's output is read: when its last descriptor
    # closes, Linux hangs the terminal up and may drop what the child wrote just before exiting
    # (its final message was lost about once in three runs under load).
    err, sent = b"", False
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        ready, _, _ = select.select([master], [], [], 0.1)
        if ready:
            try:
                chunk = os.read(master, 4096)
            except OSError:  # the child closed its end
                break
            if not chunk:
                break
            err += chunk
        if not sent and signal_when is not None and signal_when(err.decode(errors="replace")):
            proc.send_signal(sig)
            sent = True
        if proc.poll() is not None and not ready:
            break
    if proc.poll() is None:
        proc.kill()
    out = proc.communicate()[0].decode()
    # What the child wrote just before it exited may still wait in the terminal's buffer.
    while select.select([master], [], [], 0.2)[0]:
        try:
            chunk = os.read(master, 4096)
        except OSError:
            break
        if not chunk:
            break
        err += chunk
    os.close(slave)
    os.close(master)
    return proc.returncode, err.decode(errors="replace").replace("\r\n", "\n"), out


def one_message(err, command):
    lines = [l for l in err.split("\n") if l.startswith(f"radar-emu: {command}: interrupted")]
    return lines


# The mesh: the built-in truck (436 triangles) scaled to 1 x 1 x 1 m, fast per direction.
mesh = os.path.join(work, "truck.obj")
subprocess.run([exe, "scene", "target", "truck", "--a-m", "1", "--b-m", "1", "--c-m", "1",
                "--out", mesh], check=True, stdout=subprocess.DEVNULL)
PROGRESS = re.compile(r"rcs: (\d+) % \((\d+)/3000 directions\), [\d.]+ s elapsed")


def rcs_args(out, n="3000", extra=()):
    return [exe, "rcs", "--mesh", mesh, "--freq-sweep-hz", "9e9:10e9:2", "--theta-deg", "90",
            "--phi-deg", f"0:360:{n}", "--out", out, *extra]


def check_partial_csv(path, sig_name, n_done):
    with open(path) as f:
        lines = f.read().splitlines()
    header, rows, marks = lines[0], [l for l in lines[1:] if not l.startswith("#")], \
        [l for l in lines if l.startswith("#")]
    check(header.startswith("freq_hz,theta_deg,phi_deg"), f"{path}: the header")
    check(len(marks) == 1 and lines[-1] == marks[0], f"{path}: one mark, the last line")
    m = re.match(r"# incomplete: stopped by (\w+) after (\d+) of 3000 directions x 2 of 2 "
                 r"frequencies \((\d+) rows\)", marks[0] if marks else "")
    check(m is not None, f"{path}: the mark reads '# incomplete: ...': {marks}")
    if m is None:
        return
    check(m.group(1) == sig_name, f"{path}: the mark names {sig_name}")
    check(int(m.group(2)) == n_done, f"{path}: {m.group(2)} directions, the message's {n_done}")
    check(int(m.group(3)) == len(rows) == 2 * n_done,
          f"{path}: {len(rows)} rows = 2 x {n_done} directions = the mark's {m.group(3)}")
    check(0 < n_done < 3000, f"{path}: stopped mid-sweep ({n_done} directions)")
    # Sweep order: direction d at both frequencies, phi = 360 d / 2999.
    for i, row in enumerate(rows):
        f_hz, _, phi = (float(x) for x in row.split(",")[:3])
        d, k = divmod(i, 2)
        if abs(phi - 360.0 * d / 2999) > 1e-6 or abs(f_hz - (9e9 if k == 0 else 10e9)) > 1:
            check(False, f"{path}: row {i} is direction {d}, frequency {k}: {row[:60]}")
            break


# 1 and 2: rcs stopped by SIGINT, then SIGTERM, after the progress line showed 2 % done.
for sig, sig_name, status in ((signal.SIGINT, "SIGINT", 130), (signal.SIGTERM, "SIGTERM", 143)):
    csv = os.path.join(work, f"rcs_{sig_name}.csv")
    code, err, _ = run_on_pty(
        rcs_args(csv), lambda e: any(int(p[0]) >= 2 for p in PROGRESS.findall(e)), sig)
    check(code == status, f"rcs {sig_name}: exit status {code} (want {status})")
    check(PROGRESS.search(err) is not None, f"rcs {sig_name}: a progress line on the terminal")
    msgs = one_message(err, "rcs")
    check(len(msgs) == 1, f"rcs {sig_name}: one interrupt line: {msgs}")
    m = re.match(rf"radar-emu: rcs: interrupted by {sig_name} after (\d+) of 3000 directions; "
                 rf"the rows done are in {re.escape(csv)}, marked incomplete$", msgs[0] if msgs else "")
    check(m is not None, f"rcs {sig_name}: the message names the count and the file: {msgs}")
    if m is not None:
        check_partial_csv(csv, sig_name, int(m.group(1)))

# 2a: rcs --method mom on a 960-triangle sphere, 40 frequencies: the estimate line, then a stop
# between frequencies keeps every direction at the frequencies done.
sphere = os.path.join(work, "sphere.obj")
subprocess.run([exe, "scene", "target", "sphere", "--a-m", "0.1", "--facet-m", "0.02", "--out",
                sphere], check=True, stdout=subprocess.DEVNULL)
mom_csv = os.path.join(work, "mom.csv")
code, err, _ = run_on_pty(
    [exe, "rcs", "--mesh", sphere, "--method", "mom", "--freq-sweep-hz", "1e9:3e9:40",
     "--theta-deg", "0:180:19", "--out", mom_csv],
    lambda e: re.search(r"rcs: \d+ % \([2-9]/40 frequencies\)", e) is not None)
check(code == 130, f"rcs mom: exit status {code} (want 130)")
check(re.search(r"rcs: estimate: method of moments, \d+ unknowns: matrix \d+ MB, fill \+ LU "
                r"about [\d.]+ s a frequency", err) is not None, "rcs mom: the estimate line")
msgs = one_message(err, "rcs")
m = re.match(r"radar-emu: rcs: interrupted by SIGINT after (\d+) of 40 frequencies; ",
             msgs[0] if len(msgs) == 1 else "")
check(m is not None, f"rcs mom: one message with the frequencies: {msgs}")
with open(mom_csv) as f:
    lines = f.read().splitlines()
rows = [l for l in lines[1:] if not l.startswith("#")]
if m is not None:
    k = int(m.group(1))
    check(lines[-1] == f"# incomplete: stopped by SIGINT after 19 of 19 directions x {k} of 40 "
          f"frequencies ({19 * k} rows)" and len(rows) == 19 * k and 2 <= k < 40,
          f"mom.csv: 19 directions x {k} frequencies = {len(rows)} rows: {lines[-1]}")
    check(len({r.split(",")[0] for r in rows}) == k, "mom.csv: the first k frequencies")

# 2b: profile, stopped by SIGINT mid-sweep: the profiles of the angles done, each whole.
prof = os.path.join(work, "profile.csv")
code, err, _ = run_on_pty(
    [exe, "profile", "--mesh", mesh, "--freq-sweep-hz", "9e9:11e9:64", "--theta-deg", "90",
     "--phi-deg", "0:360:3000", "--out", prof],
    lambda e: re.search(r"profile: ([2-9]|\d\d) % \(\d+/3000 angles\)", e) is not None)
check(code == 130, f"profile: exit status {code} (want 130)")
msgs = one_message(err, "profile")
m = re.match(r"radar-emu: profile: interrupted by SIGINT after (\d+) of 3000 angles; ",
             msgs[0] if len(msgs) == 1 else "")
check(m is not None, f"profile: one message with the angles: {msgs}")
with open(prof) as f:
    lines = f.read().splitlines()
rows = [l for l in lines[1:] if not l.startswith("#")]
mark = re.match(r"# incomplete: stopped by SIGINT after (\d+) of 3000 angles \((\d+) rows\)$",
                lines[-1])
check(mark is not None and int(mark.group(2)) == len(rows), f"profile.csv: the mark: {lines[-1]}")
if m is not None and mark is not None:
    n = int(m.group(1))
    angles = {tuple(r.split(",")[:2]) for r in rows}
    check(int(mark.group(1)) == n == len(angles) and 0 < n < 3000 and len(rows) % n == 0,
          f"profile.csv: {len(angles)} angles, {len(rows)} rows, the message's {n}")

# 3: sar on the three trihedrals.
sar_out = os.path.join(work, "sar_int")
code, err, _ = run_on_pty(
    [exe, "sar", os.path.join(src, "examples", "sar_trihedrals.toml"), "--out", sar_out],
    lambda e: re.search(r"sar: ([1-9]\d*) % \(\d+/\d+ pulses\)", e) is not None)
if code == 1 and "built without it" in err:  # sar needs GDAL's GeoTIFF writer
    print("skip sar: this radar-emu was built without GDAL")
    sys.exit(1 if failures else 0)
check(code == 130, f"sar: exit status {code} (want 130)")
check(re.search(r"sar: estimate: \d+ pulses x \d+ samples, image \d+ x \d+: memory about", err)
      is not None, "sar: the estimate before the raw data")
msgs = one_message(err, "sar")
check(len(msgs) == 1, f"sar: one interrupt line: {msgs}")
m = re.match(r"radar-emu: sar: interrupted by SIGINT after (\d+) of (\d+) pulses; ",
             msgs[0] if msgs else "")
check(m is not None, f"sar: the message names the pulses: {msgs}")
with open(os.path.join(sar_out, "sar.json")) as f:
    meta = json.load(f)
check(meta.get("incomplete") is True and meta.get("stop_signal") == "SIGINT",
      "sar.json: incomplete, SIGINT")
if m is not None:
    done, total = int(m.group(1)), int(m.group(2))
    check(meta.get("pulses_done") == done and 0 < done < total == meta["platform"]["pulses"],
          f"sar.json: pulses_done {meta.get('pulses_done')} = the message's {done} of {total}")
for name in ("image.tif", "image.png"):
    check(os.path.getsize(os.path.join(sar_out, name)) > 0, f"sar: {name} written")

# 4: quiet when stderr is not a terminal, or with -q; complete runs carry no mark.
short = os.path.join(work, "rcs_short.csv")
p = subprocess.run(rcs_args(short, "300"), cwd=work, capture_output=True, text=True)
check(p.returncode == 0, f"rcs to a pipe: exit status {p.returncode}")
check(re.search(r"rcs: \d+ %", p.stderr) is None and "directions)" not in p.stderr,
      f"rcs to a pipe: no progress line: {p.stderr[:200]!r}")
with open(short) as f:
    text = f.read()
check("#" not in text and len(text.splitlines()) == 601, "rcs complete: 600 rows, no mark")
code, err, _ = run_on_pty(rcs_args(short, "300", ["-q"]))
check(code == 0 and "directions)" not in err, f"rcs -q on a terminal: no progress line: {err!r}")
code, err, _ = run_on_pty(rcs_args(short, "300"))
check(code == 0 and "rcs: 100 % (300/300 directions)" in err,
      "rcs on a terminal: the progress line reaches 100 %")

# 5: tradeoff, stopped between cases (stderr a file: its per-knob lines, no progress line).
tq = os.path.join(work, "tradeoff")
err_path = os.path.join(work, "tradeoff.err")
with open(err_path, "w") as err_file:
    proc = subprocess.Popen([exe, "tradeoff", "--quick", "--cases", "sphere,grazing,iem",
                             "--out", tq], cwd=work, stdout=subprocess.DEVNULL, stderr=err_file)
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and proc.poll() is None:
        with open(err_path) as f:
            if "sphere ka" in f.read():
                proc.send_signal(signal.SIGINT)
                break
        time.sleep(0.05)
    proc.wait(timeout=120)
with open(err_path) as f:
    err = f.read()
check(proc.returncode == 130, f"tradeoff: exit status {proc.returncode} (want 130)")
msgs = one_message(err, "tradeoff")
check(len(msgs) == 1 and msgs[0].startswith(
    "radar-emu: tradeoff: interrupted by SIGINT after 1 of 3 cases; "), f"tradeoff: {msgs}")
with open(os.path.join(tq, "tradeoff.csv")) as f:
    lines = f.read().splitlines()
rows = [l for l in lines[1:] if not l.startswith("#")]
m = re.match(r"# incomplete: stopped by SIGINT after 1 of 3 cases, before grazing \((\d+) rows\)$",
             lines[-1])
check(m is not None and int(m.group(1)) == len(rows) > 0,
      f"tradeoff.csv: the mark counts its {len(rows)} rows: {lines[-1]}")
check(all(r.startswith("sphere,") for r in rows), "tradeoff.csv: the sphere case's rows only")

# 5a: tradeoff's progress line on a terminal, the case's lines printed above it.
code, err, _ = run_on_pty([exe, "tradeoff", "--quick", "--cases", "iem", "--out",
                           os.path.join(work, "tradeoff_pty")])
check(code == 0 and "tradeoff: 100 % (1/1 cases)" in err,
      f"tradeoff on a terminal: the progress line reaches 100 %: {err[-300:]!r}")
# Each case line starts a line of its own (the progress line blanked by "\r...\r" before it)
# and ends one, the progress line drawn again below it.
check(re.search(r"\r {10,}\r  iem \S+ ks [\d.]+: IEM [^\r\n]*\n\rtradeoff: \d+ %", err)
      is not None, "tradeoff on a terminal: the case's lines above the progress line")

# 6: image, stopped between strips of columns.
img_out = os.path.join(work, "image_int")
code, err, _ = run_on_pty(
    [exe, "image", os.path.join(src, "examples", "ev_radar_94ghz.toml"), "--out", img_out],
    lambda e: re.search(r"image: ([1-9]\d*) % \(\d+/200 columns\)", e) is not None)
check(code == 130, f"image: exit status {code} (want 130)")
check(re.search(r"image: estimate: 200 x 66 pixels, 10 looks, \d+ strips of \d+ columns, "
                r"optical 800 x 264: memory about [\d.]+ [kMG]B, about", err) is not None,
      "image: the estimate before the work")
msgs = one_message(err, "image")
m = re.match(r"radar-emu: image: interrupted by SIGINT after (\d+) of 200 columns; the columns "
             r"done are in .*image.csv, marked incomplete", msgs[0] if len(msgs) == 1 else "")
check(m is not None, f"image: one message with the columns: {msgs}")
with open(os.path.join(img_out, "image.csv")) as f:
    lines = f.read().splitlines()
rows = [l for l in lines[1:] if not l.startswith("#")]
mark = re.match(r"# incomplete: stopped by SIGINT after (\d+) of 200 columns \((\d+) rows\)$",
                lines[-1])
check(mark is not None and int(mark.group(2)) == len(rows), f"image.csv: the mark: {lines[-1]}")
if m is not None and mark is not None:
    k = int(m.group(1))
    columns = {int(r.split(",")[1]) for r in rows}
    check(int(mark.group(1)) == k and 0 < k < 200 and len(rows) == 66 * k and
          columns == set(range(k)), f"image.csv: {len(rows)} rows = 66 x {k} columns 0..{k - 1}")
    with open(os.path.join(img_out, "image.json")) as f:
        meta = json.load(f)
    check(meta.get("incomplete") is True and meta.get("stop_signal") == "SIGINT" and
          meta.get("columns_done") == k, "image.json: incomplete, SIGINT, columns_done")

# 7: scene import, stopped while sampling heights; scene gen stopped while generating.
geo = os.path.join(src, "examples", "geodata")
glb = os.path.join(work, "olinda_int.glb")
PROG = re.compile(r"scene import: (\d+) % \(\d+/\d+ rows\)")
code, err, _ = run_on_pty(
    [exe, "scene", "import", "--dem", os.path.join(geo, "olinda_dem_utm25s.tif"), "--osm",
     os.path.join(geo, "olinda_airstrip.osm"), "--anchor=-8.005,-34.878", "--central",
     "4000,4000", "--cell-m", "4", "--surround-m", "7500", "--surround-cell-m", "45", "--out", glb],
    lambda e: any(int(p) >= 20 for p in PROG.findall(e)))
if code == 1 and "built without GDAL" in err:
    print("skip scene import: this radar-emu was built without GDAL and PROJ")
else:
    check(code == 130, f"scene import: exit status {code} (want 130): {err[-300:]!r}")
    msgs = one_message(err, "scene import")
    check(len(msgs) == 1 and re.match(r"radar-emu: scene import: interrupted by SIGINT after "
                                      r"\d+ of \d+ rows; the tiles done are in ", msgs[0]),
          f"scene import: one message: {msgs}")
    info = subprocess.run([exe, "scene", "info", "--json", glb], capture_output=True, text=True)
    check(info.returncode == 0, f"scene info of the partial scene: {info.stderr}")
    meta = json.loads(info.stdout) if info.returncode == 0 else {}
    m = re.match(r"import stopped by SIGINT: central (\d+) of (\d+) rows of tiles",
                 meta.get("incomplete", ""))
    check(m is not None, f"scene info: the incomplete mark: {meta.get('incomplete')!r}")
    if m is not None:
        k, total = int(m.group(1)), int(m.group(2))
        with open(glb, "rb") as f:
            blob = f.read()
        tile_rows = {int(x) for x in re.findall(rb"terrain_r(\d\d)_c\d\d_lod0", blob)}
        check(k < total and tile_rows == set(range(k)),
              f"scene import: central tiles of rows 0..{k - 1} only ({sorted(tile_rows)[-3:]}), "
              f"{k} of {total}")
gen = os.path.join(work, "terrain_int.glb")
code, err, _ = run_on_pty([exe, "scene", "gen", "terrain", "--out", gen],
                          lambda e: "scene gen: 0 % (0/2 stages)" in e)
info = subprocess.run([exe, "scene", "info", "--json", gen], capture_output=True, text=True)
check(info.returncode == 0 and "incomplete" not in json.loads(info.stdout or "{}"),
      "scene gen: the scene written is whole and loads")
if code == 0:
    print("note: scene gen ended before the signal arrived (a fast machine); only the whole "
          "scene was checked")
else:
    msgs = one_message(err, "scene gen")
    check(code == 130 and len(msgs) == 1 and "the scene was generated whole and is written to"
          in msgs[0], f"scene gen: status {code}, one message: {msgs}")

finish()
