#!/usr/bin/python3
"""`radar-emu run` on Modbus, end to end, against independent peers (Debian's mbpoll and
python3-pymodbus).

1. Output: `radar-emu run --modbus-server 127.0.0.1:0` serves the detection table
   (docs/icd/modbus.md). After the run it keeps serving the final table; mbpoll and a pymodbus
   client read it, the floats are decoded here with struct from the ICD, and every value must
   equal the last frame of detections.json to float32 precision; mbpoll and pymodbus must agree
   register for register.
2. Input: the ownship state comes from a Modbus navigation server, (a) the project's test server
   (modbus_nav_server) and (b) a pymodbus server whose registers this script updates every 20 ms
   along a straight line it computes itself (WGS84 per NIMA TR8350.2). The radar runs on the wall
   clock (--realtime); every valid frame's ownship position (detections.json "ownship_enu_m", the
   scene's ENU frame) must lie on that line, and advance along it at the line's speed.

usage: check_modbus_run.py RADAR_EMU MODBUS_NAV_SERVER PEERS_DIR WORK_DIR
"""
import json
import logging
import math
import os
import re
import select
import struct
import subprocess
import sys
import threading
import time

EXE = SERVER = WORK = None
A = 6378137.0
F = 1.0 / 298.257223563
E2 = F * (2.0 - F)
# The default scene's anchor (scene/default_scene.hpp): ENU origin of ownship_enu_m.
ANCHOR = (43.6, 1.4, 150.0)


def fail(msg):
    print("FAIL:", msg)
    sys.exit(1)


# ---- WGS84, independent of the C++ code -----------------------------------------------------

def ecef(lat_deg, lon_deg, h):
    lat, lon = math.radians(lat_deg), math.radians(lon_deg)
    n = A / math.sqrt(1 - E2 * math.sin(lat) ** 2)
    return ((n + h) * math.cos(lat) * math.cos(lon), (n + h) * math.cos(lat) * math.sin(lon),
            (n * (1 - E2) + h) * math.sin(lat))


def enu_of(lat_deg, lon_deg, h):
    x0 = ecef(*ANCHOR)
    x = ecef(lat_deg, lon_deg, h)
    d = [x[i] - x0[i] for i in range(3)]
    lat, lon = math.radians(ANCHOR[0]), math.radians(ANCHOR[1])
    e = -math.sin(lon) * d[0] + math.cos(lon) * d[1]
    n = (-math.sin(lat) * math.cos(lon) * d[0] - math.sin(lat) * math.sin(lon) * d[1] +
         math.cos(lat) * d[2])
    u = math.cos(lat) * math.cos(lon) * d[0] + math.cos(lat) * math.sin(lon) * d[1] + \
        math.sin(lat) * d[2]
    return (e, n, u)


def geodetic_of_enu(p):
    """Inverse of enu_of by Newton iteration on the forward map (any exact method will do)."""
    lat, lon, h = ANCHOR[0] + p[1] / 111000.0, ANCHOR[1] + p[0] / 80000.0, ANCHOR[2] + p[2]
    for _ in range(8):
        q = enu_of(lat, lon, h)
        eps = 1e-7
        jac = []
        for k in range(3):
            x = [lat, lon, h]
            x[k] += eps if k < 2 else 1e-3
            qq = enu_of(*x)
            jac.append([(qq[i] - q[i]) / (eps if k < 2 else 1e-3) for i in range(3)])
        r = [p[i] - q[i] for i in range(3)]
        # Solve J dx = r (3x3, columns jac[k]) by Cramer's rule.
        m = [[jac[k][i] for k in range(3)] for i in range(3)]

        def det(mm):
            return (mm[0][0] * (mm[1][1] * mm[2][2] - mm[1][2] * mm[2][1]) -
                    mm[0][1] * (mm[1][0] * mm[2][2] - mm[1][2] * mm[2][0]) +
                    mm[0][2] * (mm[1][0] * mm[2][1] - mm[1][1] * mm[2][0]))
        d0 = det(m)
        dx = []
        for k in range(3):
            mk = [row[:] for row in m]
            for i in range(3):
                mk[i][k] = r[i]
            dx.append(det(mk) / d0)
        lat, lon, h = lat + dx[0], lon + dx[1], h + dx[2]
    return lat, lon, h


# ---- running radar-emu ------------------------------------------------------------------------

def start(args):
    proc = subprocess.Popen(args, stderr=subprocess.PIPE, stdout=subprocess.DEVNULL, text=True)
    return proc


def wait_line(proc, pattern, timeout_s):
    deadline = time.monotonic() + timeout_s
    seen = []
    while time.monotonic() < deadline:
        ready, _, _ = select.select([proc.stderr], [], [], 0.2)
        if ready:
            line = proc.stderr.readline()
            if not line and proc.poll() is not None:
                break
            seen.append(line)
            m = re.search(pattern, line)
            if m:
                return m
    proc.kill()
    fail(f"radar-emu never printed /{pattern}/: {''.join(seen)[-800:]}")


def part_output(peers):
    out = f"{WORK}/modbus_out"
    proc = start([EXE, "run", "--quiet", "--frames", "30", "--out", out,
                  "--modbus-server", "127.0.0.1:0", "--modbus-linger-s", "60"])
    try:
        port = int(wait_line(proc, r"modbus server listening on 127\.0\.0\.1:(\d+)", 120)[1])
        wait_line(proc, r"run complete; serving the final table", 300)
        with open(f"{out}/detections.json") as f:
            last = json.load(f)["frames"][-1]
        # Header with mbpoll (16-bit registers).
        head = peers.mbpoll(port, 0, 8, "4", False)
        if head[0] != last["frame_counter"] or head[1] != len(last["detections"]):
            fail(f"mbpoll header {head} vs last frame {last['frame_counter']} with "
                 f"{len(last['detections'])} detections")
        if head[2] != last["status"] or head[6] != 22 or head[7] != 1:
            fail(f"mbpoll header {head}: status/record length/version")
        n = len(last["detections"])
        if n == 0:
            fail("the last frame has no detections to compare")
        regs_needed = 8 + 22 * n
        # Records with mbpoll as ABCD floats (-B), one request per record.
        from pymodbus.client import ModbusTcpClient
        client = ModbusTcpClient("127.0.0.1", port=port)
        client.connect()
        raw = []
        for ref in range(0, regs_needed, 100):
            rr = client.read_holding_registers(ref, min(100, regs_needed - ref), slave=1)
            if rr.isError():
                fail(f"pymodbus read at {ref}: {rr}")
            raw += rr.registers
        client.close()
        if raw[:8] != [int(head[i]) for i in range(8)]:
            fail(f"pymodbus header {raw[:8]} differs from mbpoll's {head}")
        names = ["range_m", "azimuth_deg", "elevation_deg", "radial_velocity_mps", "snr_db",
                 "rcs_dbsm", "range_std_m", "azimuth_std_deg", "elevation_std_deg",
                 "radial_velocity_std_mps"]
        for i, d in enumerate(last["detections"]):
            base = 8 + 22 * i
            floats = peers.mbpoll(port, base, 10, "4:float", True)
            for k, name in enumerate(names):
                word_hi, word_lo = raw[base + 2 * k], raw[base + 2 * k + 1]
                py = struct.unpack(">f", struct.pack(">HH", word_hi, word_lo))[0]
                want = struct.unpack(">f", struct.pack(">f", d[name]))[0]  # float32 of the double
                if py != want:
                    fail(f"detection {i} {name}: pymodbus {py} vs detections.json {d[name]}")
                mb = floats[base + 2 * k]
                if abs(mb - want) > abs(want) * 5e-6 + 1e-6:  # mbpoll prints 6 significant digits
                    fail(f"detection {i} {name}: mbpoll {mb} vs detections.json {d[name]}")
            flags = raw[base + 20]
            if bool(flags & 1) != d["range_ambiguous"] or bool(flags & 2) != \
                    d["velocity_ambiguous"]:
                fail(f"detection {i}: flags {flags:#x}")
        print(f"ok: mbpoll and pymodbus read the served detection table of frame "
              f"{last['frame_counter']}: {n} detections x 10 float32 fields and flags equal "
              f"detections.json")
    finally:
        proc.kill()
        proc.wait()


def check_follows(out, start_enu, vel_enu, who):
    with open(f"{out}/detections.json") as f:
        frames = json.load(f)["frames"]
    pts = [(fr["time_s"], fr["ownship_enu_m"]) for fr in frames if "ownship_enu_m" in fr]
    if len(pts) < 0.8 * len(frames):
        fail(f"{who}: only {len(pts)} of {len(frames)} frames had a valid ownship state")
    speed = math.sqrt(sum(v * v for v in vel_enu))
    u = [v / speed for v in vel_enu]
    worst = 0.0
    along = []
    for t, p in pts:
        d = [p[i] - start_enu[i] for i in range(3)]
        s = sum(d[i] * u[i] for i in range(3))
        perp = math.sqrt(max(0.0, sum(x * x for x in d) - s * s))
        worst = max(worst, perp)
        along.append((t, s))
    if worst > 0.5:
        fail(f"{who}: ownship {worst:.3f} m off the server's track")
    # Least-squares speed along the track against frame time.
    n = len(along)
    mt = sum(t for t, _ in along) / n
    ms = sum(s for _, s in along) / n
    slope = sum((t - mt) * (s - ms) for t, s in along) / sum((t - mt) ** 2 for t, _ in along)
    if abs(slope / speed - 1.0) > 0.03:
        fail(f"{who}: ownship moves at {slope:.2f} m/s along the track, server {speed:.2f} m/s")
    print(f"ok: ownship follows {who}: {n} valid frames, at most {worst:.3f} m off the track, "
          f"{slope:.2f} m/s along it (server {speed:.2f} m/s)")


def part_input_project_server():
    # A straight line 4 km short of the default runway (scene ENU ~ (0, -4000, 230)), 70 m/s
    # north, 3.67 m/s down, as the project's test server plays it.
    start_enu = (0.0, -4000.0, 230.0)
    lat0, lon0, h0 = geodetic_of_enu(start_enu)
    vel = (0.0, 70.0, -3.67)
    args = [SERVER, "--port", "0", "--rate-hz", "50", "--duration-s", "30",
            "--lat-deg", repr(lat0), "--lon-deg", repr(lon0), "--height-m", repr(h0),
            "--vel-east-mps", "0", "--vel-north-mps", "70", "--vel-up-mps", "-3.67",
            "--heading-deg", "0", "--pitch-deg", "2", "--roll-deg", "0"]
    srv = subprocess.Popen(args, stdout=subprocess.PIPE, text=True)
    try:
        ready, _, _ = select.select([srv.stdout], [], [], 10.0)
        line = srv.stdout.readline() if ready else ""
        m = re.fullmatch(r"listening 127\.0\.0\.1:(\d+)\n", line)
        if not m:
            fail(f"modbus_nav_server did not report readiness: {line!r}")
        out = f"{WORK}/nav_project"
        p = subprocess.run([EXE, "run", "--quiet", "--realtime", "--frames", "40", "--out", out,
                            "--nav-modbus", f"tcp:127.0.0.1:{m[1]}"],
                           capture_output=True, text=True, timeout=120)
        if p.returncode != 0:
            fail(f"radar-emu run --nav-modbus: {p.stderr.strip()}")
        # The server's line: its start point and ENU velocity in its local frame at the start,
        # which at 4 km from the anchor differs from the anchor's ENU by ~6e-4 rad: rotate the
        # velocity by comparing two points 1 s apart, computed here from the server's formula.
        lat1, lon1, h1 = server_position_at(lat0, lon0, h0, vel, 1.0)
        p0, p1 = enu_of(lat0, lon0, h0), enu_of(lat1, lon1, h1)
        check_follows(out, p0, [p1[i] - p0[i] for i in range(3)], "the project's nav server")
    finally:
        srv.kill()
        srv.wait()


def server_position_at(lat0, lon0, h0, vel, t_s):
    """modbus_nav_server's straight line (radii of curvature at the start, docs/icd/modbus.md)."""
    lat = math.radians(lat0)
    s2 = math.sin(lat) ** 2
    m = A * (1 - E2) / (1 - E2 * s2) ** 1.5
    n = A / math.sqrt(1 - E2 * s2)
    return (lat0 + math.degrees(vel[1] * t_s / (m + h0)),
            lon0 + math.degrees(vel[0] * t_s / ((n + h0) * math.cos(lat))), h0 + vel[2] * t_s)


def part_input_pymodbus(peers):
    # This script is the navigation device: every 20 ms it writes the map (float32, ABCD) of a
    # straight line it computes in the scene's ENU frame, converted to WGS84 here.
    start_enu = (300.0, -3500.0, 200.0)
    vel = (-20.0, 60.0, -2.0)
    server = peers.PymodbusServer(64)
    stop = threading.Event()
    t0 = time.monotonic()

    def device():
        counter = 0
        while not stop.is_set():
            t = time.monotonic() - t0
            p = [start_enu[i] + vel[i] * t for i in range(3)]
            lat, lon, h = geodetic_of_enu(p)
            values = {"lat_deg": lat, "lon_deg": lon, "height_m": h,
                      "true_heading_deg": math.degrees(math.atan2(vel[0], vel[1])) % 360.0,
                      "pitch_deg": 0.0, "roll_deg": 0.0, "vel_east_mps": vel[0],
                      "vel_north_mps": vel[1], "vel_up_mps": vel[2]}
            counter = (counter + 1) & 0xFFFF
            server.set(0, peers.encode_map(values, counter, 7, int(t * 1000), "abcd", "float32"))
            time.sleep(0.02)

    thread = threading.Thread(target=device, daemon=True)
    thread.start()
    try:
        out = f"{WORK}/nav_pymodbus"
        p = subprocess.run([EXE, "run", "--quiet", "--realtime", "--frames", "40", "--out", out,
                            "--nav-modbus", f"tcp:127.0.0.1:{server.port}"],
                           capture_output=True, text=True, timeout=120)
        if p.returncode != 0:
            fail(f"radar-emu run --nav-modbus (pymodbus): {p.stderr.strip()}")
        # The velocity the device sends is in the local frame at the aircraft; the line it moves
        # on is the ENU line above, exactly.
        check_follows(out, start_enu, vel, "a pymodbus server")
    finally:
        stop.set()
        thread.join()
        server.stop()


def main():
    global EXE, SERVER, WORK
    if len(sys.argv) != 5:
        fail("usage: check_modbus_run.py RADAR_EMU MODBUS_NAV_SERVER PEERS_DIR WORK_DIR")
    EXE, SERVER, peers_dir, WORK = sys.argv[1:]
    os.makedirs(WORK, exist_ok=True)
    sys.path.insert(0, peers_dir)
    import check_modbus_peers as peers  # the ICD's packing and the pymodbus server helper
    logging.getLogger("pymodbus").setLevel(logging.CRITICAL)
    part_output(peers)
    part_input_project_server()
    part_input_pymodbus(peers)


if __name__ == "__main__":
    main()
