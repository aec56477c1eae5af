#!/usr/bin/python3
"""The live view (`radar-emu run --serve`) end to end, checked by independent means.

1. `radar-emu run --realtime --serve 127.0.0.1:0 --serve-wait-s 30 --serve-linger-s 30` waits
   for a viewer. This script connects with its own RFC 6455 client (written here from the RFC:
   handshake with a key from a fixed, printed seed, the Sec-WebSocket-Accept checked with
   hashlib, unmasked server frames parsed), which starts the run. It must receive live updates
   (frames counting up, "ended" false) and then the final one ("ended" true), whose detections
   must equal the last frame of detections.json (written by the run's other output path).
2. While the server lingers, headless Chromium (Debian's `chromium`) loads the page and takes a
   screenshot. The PNG is decoded here (zlib + struct, PNG spec filters 0-4) and must hold a
   magenta (#ff00ff) mark at the B-scope pixel of every detection of the last frame of
   detections.json (the page's own B-scope geometry, loop/outputs/live_view_page.cpp, computed here
   from the scenario's field of view read with tomllib), no magenta anywhere else, and a green
   ring around every object of the last frame of truth.json.
3. report.json "live_view" accounts for every update the frame loop published.

The scenario is examples/gltf_targets.toml (3-6 detections in every frame) with the fidelity
governor off, so that what the screenshot must show does not depend on the machine's load.
Skipped (exit 77) when chromium is not installed.
usage: check_live_view.py RADAR_EMU SOURCE_DIR WORK_DIR
"""
import base64
import hashlib
import json
import os
import random
import select
import shutil
import signal
import socket
import struct
import subprocess
import sys
import time
import tomllib
import zlib

SEED = 18
FRAMES = 40
WINDOW = (1320, 720)
# loop/outputs/run_plots.hpp BScopeLayout
W, H, LEFT, RIGHT, TOP, BOTTOM = 900, 700, 70, 20, 40, 50


def fail(msg):
    print("FAIL:", msg)
    sys.exit(1)


def lround(v):
    return int(v + 0.5) if v >= 0 else -int(-v + 0.5)


def read_line(proc, pattern, timeout_s, seen):
    """Reads the process's stderr until a line containing `pattern`; returns it."""
    end = time.monotonic() + timeout_s
    while time.monotonic() < end:
        r, _, _ = select.select([proc.stderr], [], [], 0.5)
        if r:
            line = proc.stderr.readline().decode(errors="replace")
            if not line:
                break
            seen.append(line.rstrip())
            if pattern in line:
                return line
    fail(f"no '{pattern}' on stderr within {timeout_s} s; stderr so far:\n" + "\n".join(seen))


# ---- an RFC 6455 client (sec. 4.1 handshake, sec. 5.2 framing) ----
GUID = "258EAFA5-E914-47DA-95CA-C5AB0DC85B11"


def ws_connect(host, port, rng):
    s = socket.create_connection((host, port), timeout=20)
    key = base64.b64encode(bytes(rng.getrandbits(8) for _ in range(16))).decode()
    s.sendall((f"GET /ws HTTP/1.1\r\nHost: {host}:{port}\r\nUpgrade: websocket\r\n"
               f"Connection: Upgrade\r\nSec-WebSocket-Key: {key}\r\n"
               "Sec-WebSocket-Version: 13\r\n\r\n").encode())
    buf = b""
    while b"\r\n\r\n" not in buf:
        chunk = s.recv(4096)
        if not chunk:
            fail("server closed during the handshake")
        buf += chunk
    head, rest = buf.split(b"\r\n\r\n", 1)
    lines = head.decode().split("\r\n")
    if not lines[0].startswith("HTTP/1.1 101"):
        fail(f"handshake refused: {lines[0]}")
    headers = {k.strip().lower(): v.strip() for k, v in (l.split(":", 1) for l in lines[1:])}
    want = base64.b64encode(hashlib.sha1((key + GUID).encode()).digest()).decode()
    if headers.get("sec-websocket-accept") != want:
        fail(f"Sec-WebSocket-Accept {headers.get('sec-websocket-accept')} != {want}")
    return s, rest


def ws_messages(sock, buf):
    """Yields the text messages the server sends (server frames are never masked)."""
    while True:
        while True:
            if len(buf) >= 2:
                n, hdr = buf[1] & 0x7F, 2
                if n == 126 and len(buf) >= 4:
                    n, hdr = struct.unpack(">H", buf[2:4])[0], 4
                elif n == 127 and len(buf) >= 10:
                    n, hdr = struct.unpack(">Q", buf[2:10])[0], 10
                if (buf[1] & 0x7F) < 126 or hdr > 2:
                    if buf[1] & 0x80:
                        fail("a server frame is masked (RFC 6455 sec. 5.1 forbids it)")
                    if len(buf) >= hdr + n:
                        break
            chunk = sock.recv(65536)
            if not chunk:
                return
            buf += chunk
        opcode, fin = buf[0] & 0x0F, buf[0] & 0x80
        payload, buf = buf[hdr:hdr + n], buf[hdr + n:]
        if not fin:
            fail("fragmented server frame (the server sends whole messages)")
        if opcode == 0x1:
            yield payload.decode()
        elif opcode == 0x8:
            return


# ---- PNG (ISO/IEC 15948): 8-bit RGB or RGBA, not interlaced ----
def read_png(path):
    with open(path, "rb") as f:
        data = f.read()
    if data[:8] != b"\x89PNG\r\n\x1a\n":
        fail(f"{path}: not a PNG")
    pos, idat, ihdr = 8, b"", None
    while pos < len(data):
        n, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + n]
        if kind == b"IHDR":
            ihdr = struct.unpack(">IIBBBBB", body)
        elif kind == b"IDAT":
            idat += body
        pos += 12 + n
    width, height, depth, colour, _, _, interlace = ihdr
    if depth != 8 or colour not in (2, 6) or interlace != 0:
        fail(f"{path}: unsupported PNG (depth {depth}, colour type {colour}, interlace {interlace})")
    bpp = 3 if colour == 2 else 4
    raw = zlib.decompress(idat)
    stride = width * bpp
    rows, prev, pos = [], bytearray(stride), 0
    for _ in range(height):
        ftype, line = raw[pos], bytearray(raw[pos + 1:pos + 1 + stride])
        pos += 1 + stride
        for i in range(stride):
            a = line[i - bpp] if i >= bpp else 0
            b = prev[i]
            c = prev[i - bpp] if i >= bpp else 0
            if ftype == 1:
                line[i] = (line[i] + a) & 0xFF
            elif ftype == 2:
                line[i] = (line[i] + b) & 0xFF
            elif ftype == 3:
                line[i] = (line[i] + (a + b) // 2) & 0xFF
            elif ftype == 4:  # Paeth
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                pred = a if pa <= pb and pa <= pc else (b if pb <= pc else c)
                line[i] = (line[i] + pred) & 0xFF
        rows.append(bytes(line))
        prev = line
    return width, height, lambda x, y: rows[y][x * bpp:x * bpp + 3]


def main():
    exe, src, work = sys.argv[1], sys.argv[2], sys.argv[3]
    example = os.path.join(src, "examples", "gltf_targets.toml")
    chromium = shutil.which("chromium")
    if chromium is None:
        print("SKIPPED: chromium is not installed (Debian package chromium, in "
              "scripts/install-deps.sh): the live view's screenshot test cannot run")
        sys.exit(77)
    os.makedirs(work, exist_ok=True)
    # The example with its scene file by absolute path and the governor off (full fidelity: a
    # loaded machine makes frames late, not coarser).
    with open(example) as f:
        text = f.read()
    scene = 'file = "scene_extras.gltf"'
    if scene not in text:
        fail(f"{example}: no '{scene}' line to point at the example's scene")
    text = text.replace(scene, 'file = "%s"' % os.path.join(src, "examples", "scene_extras.gltf"))
    scenario = os.path.join(work, "gltf_targets_full_fidelity.toml")
    with open(scenario, "w") as f:
        f.write(text + "\n[governor]\nenabled = false\n")
    out = os.path.join(work, "out")
    shot = os.path.join(work, "live_view.png")
    for p in (shot, os.path.join(out, "report.json")):
        if os.path.exists(p):
            os.remove(p)
    print(f"seed {SEED} (WebSocket key)")
    rng = random.Random(SEED)
    scen = tomllib.loads(subprocess.run([exe, "run", "--print-scenario"], capture_output=True,
                                        text=True, check=True).stdout)
    with open(scenario, "rb") as f:
        own = tomllib.load(f)  # its keys override the embedded default's
    for table in ("antenna", "radar"):
        scen[table].update(own.get(table, {}))
    az_min = scen["antenna"]["azimuth_min_deg"]
    az_max = scen["antenna"]["azimuth_max_deg"]
    range_max = scen["radar"]["max_range_m"]

    def pixel_of(az_deg, range_m):
        x = LEFT + lround((az_deg - az_min) / (az_max - az_min) * (W - LEFT - RIGHT - 1))
        y = H - BOTTOM - lround(range_m / range_max * (H - TOP - BOTTOM - 1))
        return x, y

    proc = subprocess.Popen([exe, "run", scenario, "--realtime", "--frames", str(FRAMES), "--serve",
                             "127.0.0.1:0", "--serve-wait-s", "30", "--serve-linger-s", "30",
                             "--out", out, "--quiet"], stderr=subprocess.PIPE)
    seen = []
    try:
        line = read_line(proc, "live view on http://", 60, seen)
        address = line.split("http://", 1)[1].strip().rstrip("/")
        host, port = address.rsplit(":", 1)
        port = int(port)
        # 1. Our client starts the run and watches it.
        sock, rest = ws_connect(host, port, rng)
        live, final = [], None
        for text in ws_messages(sock, rest):
            m = json.loads(text)
            if m["ended"]:
                final = m
                break
            live.append(m)
        sock.close()
        if final is None:
            fail("the server closed before the final update")
        read_line(proc, "live view serving the last frame", 60, seen)
        frames = [m["frames_seen"] for m in live]
        print(f"client: {len(live)} live updates (frames {frames[:3]}...{frames[-3:]}), final "
              f"after frame {final['frames_seen']}")
        if len(live) < 5:
            fail(f"only {len(live)} live updates during a {FRAMES / 20:.0f} s run")
        if any(b <= a for a, b in zip(frames, frames[1:])):
            fail(f"live updates do not count up: {frames}")
        with open(os.path.join(out, "detections.json")) as f:
            det_frames = json.load(f)["frames"]
        with open(os.path.join(out, "truth.json")) as f:
            truth_frames = json.load(f)["frames"]
        if len(det_frames) != FRAMES or final["frames_seen"] != FRAMES:
            fail(f"detections.json has {len(det_frames)} frames, the final update "
                 f"{final['frames_seen']}; expected {FRAMES}")
        last = det_frames[-1]["detections"]
        if not last:
            fail("the last frame has no detections: nothing to look for")
        got = [(d["azimuth_deg"], d["range_m"]) for d in final["detections"]]
        want = [(d["azimuth_deg"], d["range_m"]) for d in last]
        if len(got) != len(want) or any(abs(a - c) > 1e-3 or abs(b - d) > 0.01
                                        for (a, b), (c, d) in zip(got, want)):
            fail(f"final update's detections {got} != detections.json's last frame {want}")

        # 2. Chromium's screenshot of the page. A screenshot without a single magenta pixel is a
        # page not drawn yet (a loaded machine): taken again with a longer virtual-time budget.
        # Any other difference fails at once.
        def magenta_at(px, x, y):
            r_, g_, b_ = px(x, y)
            return r_ > 235 and g_ < 30 and b_ > 235

        for attempt, budget_ms in enumerate((3000, 8000, 15000), 1):
            if os.path.exists(shot):
                os.remove(shot)
            cmd = [chromium, "--headless=new", "--no-sandbox", "--disable-gpu",
                   "--hide-scrollbars", "--no-first-run",
                   f"--user-data-dir={os.path.join(work, 'chromium-profile')}",
                   "--force-device-scale-factor=1", f"--window-size={WINDOW[0]},{WINDOW[1]}",
                   f"--virtual-time-budget={budget_ms}", f"--screenshot={shot}",
                   f"http://{address}/"]
            r = subprocess.run(cmd, capture_output=True, text=True, timeout=90)
            if r.returncode != 0 or not os.path.exists(shot):
                fail(f"chromium failed ({r.returncode}): {r.stderr[-2000:]}")
            width, height, px = read_png(shot)
            if width < W or height < H:
                fail(f"screenshot {width}x{height} smaller than the B-scope {W}x{H}")
            if any(magenta_at(px, x, y) for y in range(H) for x in range(W)):
                break
            print(f"screenshot {attempt} (virtual time {budget_ms} ms): nothing drawn yet")
        else:
            fail("three screenshots without a detection drawn: the page never showed the frame")

        def magenta(x, y):
            return magenta_at(px, x, y)

        expected = [pixel_of(a, r_) for a, r_ in want]
        for (a, r_), (x, y) in zip(want, expected):
            if not any(magenta(x + dx, y + dy) for dx in (-1, 0, 1) for dy in (-1, 0, 1)):
                fail(f"no detection mark at pixel ({x}, {y}) for azimuth {a:.3f} deg, range "
                     f"{r_:.1f} m: pixel is {tuple(px(x, y))}")
        stray, count = [], 0
        for y in range(H):
            for x in range(W):
                if magenta(x, y):
                    count += 1
                    if not any(abs(x - ex) <= 4 and abs(y - ey) <= 4 for ex, ey in expected):
                        stray.append((x, y))
        if stray:
            fail(f"{len(stray)} magenta pixels away from every detection, e.g. {stray[:5]}")
        truth = truth_frames[-1]["objects"]
        missing = []
        for t in truth:
            x, y = pixel_of(t["azimuth_deg"], t["range_m"])
            ring = [(x + dx, y + dy) for dx in range(-12, 13) for dy in range(-12, 13)
                    if 6 <= (dx * dx + dy * dy) ** 0.5 <= 12 and 0 <= x + dx < W and 0 <= y + dy < H]
            if not any(px(u, v)[1] > 170 and px(u, v)[0] < 120 and px(u, v)[2] < 140
                       for u, v in ring):
                missing.append((t["object"], x, y))
        if missing:
            fail(f"no truth ring around {missing[:5]}")
        print(f"screenshot {width}x{height}: {len(want)} detections found where detections.json "
              f"puts them ({count} magenta pixels, none astray), {len(truth)} truth rings")
    finally:
        if proc.poll() is None:
            proc.send_signal(signal.SIGTERM)
        try:
            proc.wait(timeout=30)
        except subprocess.TimeoutExpired:
            proc.kill()
            fail("radar-emu did not stop on SIGTERM while lingering")
    if proc.returncode != 0:
        fail(f"radar-emu exit status {proc.returncode}; stderr:\n" + "\n".join(seen))

    # 3. The report accounts for every update.
    with open(os.path.join(out, "report.json")) as f:
        lv = json.load(f)["live_view"]
    pub, taken, dropped = (lv["view_updates_published"], lv["view_updates_taken"],
                           lv["view_updates_dropped"])
    if pub != FRAMES or not pub - 1 <= taken + dropped <= pub:
        fail(f"report.json live_view: published {pub}, taken {taken}, dropped {dropped}")
    # (taken and the two counts after it are read one by one while the server may take the last
    # frame: one apart at most)
    seen_or_not = lv["view_updates_sent"] + lv["view_updates_unseen"]
    if lv["view_updates_sent"] < len(live) or not taken - 1 <= seen_or_not <= taken:
        fail(f"report.json live_view: sent {lv['view_updates_sent']} unseen "
             f"{lv['view_updates_unseen']} taken {taken} (client saw {len(live)})")
    if lv["server"]["websocket_clients"] < 1 or lv["server"]["bad_handshakes"] != 0:
        fail(f"report.json live_view.server: {lv['server']}")
    print(f"report.json: {pub} published, {taken} taken, {dropped} dropped, "
          f"{lv['view_updates_sent']} sent")
    print("PASS")


if __name__ == "__main__":
    main()
