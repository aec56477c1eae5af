#!/usr/bin/env python3
"""Writes the seed corpora of the fuzz harnesses (tests/fuzz/corpus/<name>/), from the formats'
documents (docs/icd/*.md, the glTF 2.0, OBJ and STL formats, RFC 6455 and RFC 9112) and the
harnesses' input layouts (each harness's header comment). Deterministic (random.Random(19));
run it again after a harness's input layout changes:

    tests/fuzz/make_seeds.py [--radar-emu build/app/radar-emu]

With --radar-emu, `radar-emu scene target` adds meshes written by the project's own writers.
"""
import argparse
import base64
import json
import math
import os
import random
import shutil
import struct
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
rng = random.Random(19)


def write(name, fname, data):
    d = os.path.join(HERE, "corpus", name)
    os.makedirs(d, exist_ok=True)
    if isinstance(data, str):
        data = data.encode()
    with open(os.path.join(d, fname), "wb") as f:
        f.write(data)


# ---- CANaerospace (docs/icd/canaerospace_input.md) --------------------------------------------
# Fields in the decoder's order: pitch, roll, heading, lat, lon, height, ve, vn, vu.
FIELD_VALUES = [2.0, -1.5, 93.0, 51.47, -0.46, 300.0, 70.0, 0.5, -3.67]


def canas_frame(pick, node, dtype, code, payload4):
    return bytes([pick, 8, node, dtype, 0, code & 0xFF]) + payload4


def canaerospace_seeds():
    # default configuration, FLOAT for every field, twice (codes +1)
    out = bytearray([0])
    for rep in range(2):
        for k, v in enumerate(FIELD_VALUES):
            out += canas_frame(k, 1, 2, rep, struct.pack(">f", v))
    write("canaerospace", "float_all_fields", out)
    # DOUBLEH/DOUBLEL pairs for latitude and longitude, LONG in 1e-7 deg, clock steps
    out = bytearray([0])
    for k in (3, 4):
        hi, lo = struct.unpack(">II", struct.pack(">d", FIELD_VALUES[k]))
        out += canas_frame(k, 1, 30, 10, struct.pack(">I", hi))
        out += canas_frame(k, 1, 31, 11, struct.pack(">I", lo))
        out += bytes([0x20 | k, 0x03, 0xE8, 8, 1, 3, 0, 12]) + struct.pack(">i", round(FIELD_VALUES[k] * 1e7))
    write("canaerospace", "double_and_long", out)
    # node-ID filter 7: one frame from node 7, one from node 3; NaN, out of range, short,
    # unknown type, extended identifier, ignored identifier
    out = bytearray([1, 7])
    out += canas_frame(0, 7, 2, 1, struct.pack(">f", 1.0))
    out += canas_frame(0, 3, 2, 2, struct.pack(">f", 1.0))
    out += canas_frame(1, 7, 2, 1, struct.pack(">f", float("nan")))
    out += canas_frame(1, 7, 2, 2, struct.pack(">f", 500.0))
    out += bytes([2, 3, 7, 2, 0])
    out += canas_frame(2, 7, 77, 5, b"\0\0\0\0")
    out += bytes([0x1F]) + struct.pack(">I", 0x12345678) + bytes([8]) + bytes(8)
    out += bytes([0x0F]) + struct.pack(">I", 0x123) + bytes([8]) + bytes(8)
    write("canaerospace", "node_filter_and_rejections", out)
    # a configuration from the input: every field LONG/FLOAT/DOUBLE on ids 100.., lsb 1e-6
    # (the lsb is a u64 read big-endian, then bit_cast to double)
    out = bytearray([2])
    for k in range(9):
        out += struct.pack(">HBQ", 100 + k, 0x07, struct.unpack(">Q", struct.pack(">d", 1e-6))[0])
    for k, v in enumerate(FIELD_VALUES):
        out += canas_frame(k, 1, 3, 0, struct.pack(">i", round(v / 1e-6)))
    write("canaerospace", "configured_long", out)


# ---- Detection ICD (docs/icd/detections.md) ---------------------------------------------------
def icd_detections(n):
    dets = []
    for _ in range(n):
        dets.append(dict(r=rng.uniform(50, 20000), v=rng.uniform(-200, 200), snr=rng.uniform(0, 60),
                         az=rng.uniform(-30, 30), el=rng.uniform(-10, 10), rcs=rng.uniform(-20, 40)))
    return dets


def le(v, n):
    return int(v).to_bytes(n, "little", signed=False)


def s16(v):
    return int(v) & 0xFFFF


def classic_list(counter, dets, status=0, time_ms=1234):
    frames = [(0, struct.pack("<HBBI", counter, len(dets), status, time_ms))]
    for i, d in enumerate(dets):
        a = bytes([i, counter & 0xFF]) + le(round(d["r"] / 0.01), 3) + le(s16(round(d["v"] / 0.02)), 2) + \
            bytes([round(d["snr"] / 0.5)])
        b = bytes([i, counter & 0xFF]) + le(s16(round(d["az"] / 0.01)), 2) + le(s16(round(d["el"] / 0.01)), 2) + \
            le(s16(round(d["rcs"] / 0.01)), 2)
        frames += [(1, a), (2, b)]
    return frames


def put_bits(buf, bit, width, v):
    for i in range(width):
        byte, b = divmod(bit + i, 8)
        if (v >> i) & 1:
            buf[byte] |= 1 << b
        else:
            buf[byte] &= ~(1 << b) & 0xFF


def fd_slot(d):
    s = bytearray(20)
    put_bits(s, 0, 24, round(d["r"] / 0.01))
    put_bits(s, 24, 16, s16(round(d["v"] / 0.02)))
    put_bits(s, 40, 8, round(d["snr"] / 0.5))
    put_bits(s, 48, 16, s16(round(d["az"] / 0.01)))
    put_bits(s, 64, 16, s16(round(d["el"] / 0.01)))
    put_bits(s, 80, 16, s16(round(d["rcs"] / 0.01)))
    put_bits(s, 96, 16, 150)     # range std 1.5 m
    put_bits(s, 112, 12, 20)     # velocity std 0.2 m/s
    put_bits(s, 124, 14, 100)    # azimuth std 0.2 deg
    put_bits(s, 138, 14, 50)     # elevation std 0.1 deg
    put_bits(s, 152, 1, 1)
    return bytes(s)


def fd_list(counter, dets, status=0, time_ms=99):
    h = bytearray(struct.pack("<HBBI", counter, len(dets), status, time_ms)) + bytearray(40)
    for k in range(min(2, len(dets))):
        h[8 + 20 * k:28 + 20 * k] = fd_slot(dets[k])
    frames = [(0, bytes(h))]
    first = 2
    while first < len(dets):
        chunk = dets[first:first + 3]
        c = bytearray(struct.pack("<HBB", counter, first, len(chunk))) + bytearray(60)
        for k, d in enumerate(chunk):
            c[4 + 20 * k:24 + 20 * k] = fd_slot(d)
        frames.append((1, bytes(c)))
        first += 3
    return frames


def icd_seeds():
    out = bytearray([0])
    for ctl, payload in classic_list(7, icd_detections(3)) + classic_list(8, []) + classic_list(9, icd_detections(1)):
        out += bytes([ctl]) + payload
    write("icd_classic", "three_lists", out)
    out = bytearray([0])
    frames = classic_list(300, icd_detections(4))
    frames = frames[:1] + frames[1:][::-1]  # detection frames in reverse
    for ctl, payload in frames + frames[:2]:  # then a header and an orphan-to-be
        out += bytes([ctl]) + payload
    out += bytes([3, 0x01, 0x23]) + bytes(8)  # a foreign identifier
    write("icd_classic", "reversed_and_foreign", out)
    for name, fd in (("icd_classic", False), ("icd_fd", True)):
        for n in (0, 3, 40):
            data = bytearray([1]) + struct.pack(">HBI", 5, 0, 4242) + bytes([n])
            for _ in range(n):
                for _ in range(10):
                    data += bytes([rng.randrange(13)]) + struct.pack(">I", rng.getrandbits(32))
                data += bytes([rng.randrange(4)])
            data += bytes([rng.randrange(256), rng.randrange(2)])
            write(name, "round_trip_%d" % n, data)
    out = bytearray([0])
    for ctl, payload in fd_list(11, icd_detections(7)) + fd_list(12, icd_detections(1)) + fd_list(13, icd_detections(2)):
        out += bytes([ctl]) + payload
    write("icd_fd", "three_lists", out)
    out = bytearray([0])
    frames = fd_list(14, icd_detections(11))
    for ctl, payload in frames[:1] + frames[1:][::-1]:
        out += bytes([ctl]) + payload
    write("icd_fd", "reversed_continuations", out)


# ---- candump (can-utils `candump -L`) ----------------------------------------------------------
def candump_seeds():
    src = os.path.join(ROOT, "tests", "data", "replay", "approach_gap.log")
    with open(src) as f:
        lines = f.read().splitlines()[:40]
    write("candump", "approach_gap_head", "\n".join(lines) + "\n")
    write("candump", "kinds",
          "(1700000000.123456) can0 123#DEADBEEF\n"
          "(1700000000.123457) vcan1 1ABCDEF0#00\n"
          "(0.000001) can0 7FF#\n"
          "(1700000000.123458) can0 70B##1" + "00" * 48 + "\n"
          "(1700000000.123459) can0 70C##3" + "AB" * 64 + "\n"
          "(1700000000.123460) can0 123#R\n"
          "(1700000000.12346) can0 123#00\r\n"
          "(1700000000.123461) interface_name_ 123#0011223344556677\n")


# ---- Modbus maps (docs/icd/modbus.md) ---------------------------------------------------------
def regs_of(fmt, value, cdab):
    raw = struct.pack(">" + fmt, value)
    regs = [struct.unpack(">H", raw[i:i + 2])[0] for i in range(0, len(raw), 2)]
    return regs[::-1] if cdab else regs


def nav_image(counter, status, time_ms, scaled, cdab, vals):
    regs = [counter & 0xFFFF, status] + regs_of("I", time_ms, cdab)
    lat, lon, h, hdg, pitch, roll, ve, vn, vu = vals
    if scaled:
        scales = [1e-7, 1e-7, 1e-3, 1e-6, 1e-6, 1e-6, 1e-4, 1e-4, 1e-4]
        for v, s in zip(vals, scales):
            regs += regs_of("i", round(v / s), cdab)
    else:
        regs += regs_of("d", lat, cdab) + regs_of("d", lon, cdab)
        for v in (h, hdg, pitch, roll, ve, vn, vu):
            regs += regs_of("f", v, cdab)
    return regs


def modbus_seeds():
    vals = [51.47, -0.46, 300.0, 93.0, 2.0, -1.5, 70.0, 0.5, -3.67]
    for mode in range(4):
        scaled, cdab = bool(mode & 1), bool(mode & 2)
        out = bytearray([mode])
        for k in range(4):
            v = list(vals)
            v[6] += k
            status = 0x0007 if k != 2 else 0x0005
            regs = nav_image(k + (1 if k == 3 else 0), status, 1000 * k, scaled, cdab, v)
            out += bytes([0xFF]) + struct.pack(">H", 20) + b"".join(struct.pack(">H", r) for r in regs)
        out += bytes([3]) + struct.pack(">H", 20) + bytes(30)  # a wrong-size image
        write("modbus_nav", "images_mode%d" % mode, out)
    # out of range and NaN values
    v = list(vals)
    v[0] = 95.0
    v[3] = float("nan")
    regs = nav_image(1, 7, 5, False, False, v)
    write("modbus_nav", "rejections", bytes([0, 0xFF, 0, 1]) + b"".join(struct.pack(">H", r) for r in regs))

    # detection table: decode mode with a well-formed table
    for order in (0, 1):
        n = 4
        regs = [77, 2, 0x02, n] + regs_of("I", 123456, order) + [22, 1]
        for i in range(n):
            rec = []
            if i < 2:
                for v in (1500.0 + i, 3.5, -1.0, -50.0, 20.0, 10.0, 1.5, 0.2, 0.1, 0.3):
                    rec += regs_of("f", v, order)
                rec += [i & 3, 0]
            else:
                rec = [0] * 22
            regs += rec
        regs.append(77)
        data = bytes([order]) + struct.pack(">H", 100) + bytes([n, 1]) + b"".join(struct.pack(">H", r) for r in regs)
        write("modbus_table", "table_order%d" % order, data)
    # round trip
    data = bytearray([2]) + struct.pack(">H", 0) + bytes([8]) + struct.pack(">HBI", 9, 0, 777) + bytes([5])
    for _ in range(5 * 10):
        data += bytes([rng.randrange(200)]) + struct.pack(">I", rng.getrandbits(32))
    data += bytes([1, 0])
    write("modbus_table", "round_trip", data)


# ---- scenario TOML ---------------------------------------------------------------------------
def scenario_seeds(radar_emu):
    ex = os.path.join(ROOT, "examples")
    for f in sorted(os.listdir(ex)):
        # sar_*.toml are `radar-emu sar` cases (the sar_case harness), not scenarios.
        if f.endswith(".toml") and not f.startswith("sar"):
            shutil.copy(os.path.join(ex, f), os.path.join(HERE, "corpus", "scenario_toml", f))
    if radar_emu:
        text = subprocess.run([radar_emu, "run", "--print-scenario"], check=True,
                              capture_output=True).stdout
        write("scenario_toml", "default.toml", text)
    write("scenario_toml", "small.toml", '[run]\nframes = 5\nrate_hz = 10.0\n')
    write("scenario_toml", "bad_key.toml", '[run]\nframez = 5\n')


# ---- websocket (io/websocket.hpp; RFC 6455, RFC 9112) ---------------------------------------
# Input: mode byte (even: a request then frames; odd: frames only), limit byte (% 5 picks
# max_payload_bytes: 0, 125, 126, 8192, 65536), then the client's bytes.
def ws_frame(op, payload, mask=b"\x37\xfa\x21\x3d", fin=True, masked=True):
    n = len(payload)
    b0 = (0x80 if fin else 0) | op
    m = 0x80 if masked else 0
    if n < 126:
        h = bytes([b0, m | n])
    elif n <= 0xFFFF:
        h = bytes([b0, m | 126]) + struct.pack(">H", n)
    else:
        h = bytes([b0, m | 127]) + struct.pack(">Q", n)
    if not masked:
        return h + payload
    return h + mask + bytes(c ^ mask[i % 4] for i, c in enumerate(payload))


def websocket_seeds():
    hs = ("GET /ws HTTP/1.1\r\nHost: localhost:8080\r\nUpgrade: websocket\r\n"
          "Connection: keep-alive, Upgrade\r\nSec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\n"
          "Sec-WebSocket-Version: 13\r\n\r\n").encode()
    # RFC 6455 sec. 5.7: a masked "Hello" (its example bytes), then ping, pong, binary, close
    frames = ws_frame(1, b"Hello") + ws_frame(9, b"Hello") + ws_frame(0xA, b"") + \
        ws_frame(2, bytes(range(200))) + ws_frame(1, b"Hel", fin=False) + ws_frame(0, b"lo") + \
        ws_frame(8, struct.pack(">H", 1000) + b"bye")
    write("websocket", "handshake_and_frames", bytes([0, 3]) + hs + frames)
    write("websocket", "handshake_partial_frame", bytes([0, 3]) + hs + ws_frame(1, b"x" * 300)[:50])
    reqs = {
        "page": "GET / HTTP/1.1\r\nHost: x\r\n\r\n",
        "index_query": "GET /index.html?a=1 HTTP/1.0\r\n\r\n",
        "not_found": "GET /nope HTTP/1.1\r\nHost: x\r\n\r\n",
        "post": "POST /ws HTTP/1.1\r\nHost: x\r\nContent-Length: 0\r\n\r\n",
        "wrong_version": "GET /ws HTTP/1.1\r\nHost: x\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
                         "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 8\r\n\r\n",
        "bad_key": "GET /ws?x HTTP/1.1\r\nhost: x\r\nUPGRADE: WebSocket\r\nconnection: upgrade\r\n"
                   "sec-websocket-key: short==\r\nsec-websocket-version: 13\r\n\r\n",
        "no_host": "GET /ws HTTP/1.1\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
                   "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n\r\n",
        "malformed": "HELLO\r\nHost: x\r\n\r\n",
        "no_blank_line": "GET / HTTP/1.1\r\nHost: x\r\n",
    }
    for name, text in reqs.items():
        write("websocket", "request_" + name, bytes([0, 3]) + text.encode())
    # frames only: the RFC's unmasked "Hello" (a protocol error from a client), 16- and 64-bit
    # lengths, a reserved opcode, a control frame over 125 bytes, a frame over the limit
    write("websocket", "frames_unmasked", bytes([1, 3]) + ws_frame(1, b"Hello", masked=False))
    write("websocket", "frames_lengths", bytes([1, 4]) + ws_frame(2, bytes(300)) + ws_frame(2, bytes(70000))[:2000])
    write("websocket", "frames_reserved_opcode", bytes([1, 3]) + ws_frame(1, b"ok") + ws_frame(3, b"?"))
    write("websocket", "frames_long_ping", bytes([1, 3]) + ws_frame(9, bytes(126)))
    write("websocket", "frames_too_big", bytes([1, 1]) + ws_frame(1, bytes(126)))


# ---- sar case TOML (tools/sar.hpp; examples/sar_seed.toml documents the keys) ----------
def sar_case_seeds():
    ex = os.path.join(ROOT, "examples")
    for f in sorted(os.listdir(ex)):
        if f.startswith("sar") and f.endswith(".toml"):
            shutil.copy(os.path.join(ex, f), os.path.join(HERE, "corpus", "sar_case", f))
    write("sar_case", "empty_tables.toml", "[radar]\n[platform]\n[antenna]\n[processing]\n[scene]\n")
    write("sar_case", "targets.toml",
          '[platform]\nlook = "left"\nheading_deg = -45.0\n[processing]\ntaper = "hamming"\n'
          '[scene]\nground_material = "none"\n'
          '[[scene.target]]\nkind = "trihedral-tri"\na_m = 0.5\nposition_m = [10.0, -20.0, 0.0]\n'
          '[[scene.target]]\nname = "car"\nkind = "box"\na_m = 4.0\nb_m = 2.0\nc_m = 1.5\n'
          'velocity_mps = [0.0, 10.0, 0.0]\nheading_deg = 90.0\n')
    write("sar_case", "bad_value.toml", "[radar]\ncarrier_hz = 1e20\n")
    write("sar_case", "bad_table.toml", "[radr]\n")
    write("sar_case", "nadir.toml", "[processing]\ngates = 65536\n")


# ---- meshes ----------------------------------------------------------------------------------
CUBE_V = [(x, y, z) for x in (0, 1) for y in (0, 1) for z in (0, 1)]
CUBE_F = [(1, 3, 4, 2), (5, 6, 8, 7), (1, 2, 6, 5), (3, 7, 8, 4), (1, 5, 7, 3), (2, 4, 8, 6)]


def mesh_seeds(radar_emu):
    obj = "# cube\nmtllib x.mtl\no cube\n" + "".join("v %g %g %g\n" % v for v in CUBE_V)
    obj += "vt 0 0\nvn 0 0 1\nusemtl metal\n"
    obj += "".join("f %d %d %d %d\n" % f for f in CUBE_F[:3])
    obj += "usemtl concrete\n" + "".join("f %d/1 %d/1/1 %d//1 %d\n" % f for f in CUBE_F[3:])
    write("obj", "cube.obj", obj)
    write("obj", "relative.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\nv 0 0 0\nf 1 2 4\n")
    tris = []
    for f in CUBE_F:
        a, b, c, d = (CUBE_V[i - 1] for i in f)
        tris += [(a, b, c), (a, c, d)]
    ascii_stl = "solid cube\n"
    for t in tris:
        ascii_stl += " facet normal 0 0 0\n  outer loop\n" + "".join("   vertex %g %g %g\n" % v for v in t)
        ascii_stl += "  endloop\n endfacet\n"
    write("stl", "cube_ascii.stl", ascii_stl + "endsolid cube\n")
    binary = bytearray(b"solid but binary".ljust(80, b" ")) + struct.pack("<I", len(tris))
    for t in tris:
        binary += struct.pack("<3f", 0, 0, 0) + b"".join(struct.pack("<3f", *v) for v in t) + b"\0\0"
    write("stl", "cube_binary.stl", binary)

    # glTF: one triangle (data: URI), a node with radar_emu extras; the same as GLB.
    pos = struct.pack("<9f", 0, 0, 0, 1, 0, 0, 0, 1, 0)
    idx = struct.pack("<3H", 0, 1, 2) + b"\0\0"
    buf = pos + idx

    def gltf_doc(uri):
        doc = {
            "asset": {"version": "2.0"},
            "scene": 0,
            "scenes": [{"nodes": [0, 1], "extras": {"radar_emu": {"anchor_deg_m": [51.4, -0.4, 20]}}}],
            "nodes": [
                {"name": "plate", "mesh": 0, "translation": [1, 2, 3],
                 "extras": {"radar_emu": {"area": "central", "lod_group": 2, "lod_level": 1, "lod_facet_m": 0.5}}},
                {"name": "mover", "mesh": 0, "rotation": [0, 0.7071068, 0, 0.7071068],
                 "extras": {"radar_emu": {"trajectory": {"waypoints_m": [[0, 0, 0], [100, 0, 0], [100, 100, 0]],
                                                         "speed_mps": 10, "turn_radius_m": 20}}}},
            ],
            "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "material": 0, "mode": 4}]}],
            "materials": [{"name": "metal", "extras": {"radar_emu": {"radar_material": "metal"}}}],
            "accessors": [
                {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                 "min": [0, 0, 0], "max": [1, 1, 0]},
                {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"},
            ],
            "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36},
                            {"buffer": 0, "byteOffset": 36, "byteLength": 6}],
            "buffers": [{"byteLength": len(buf)}],
        }
        if uri:
            doc["buffers"][0]["uri"] = uri
        return doc

    write("gltf", "triangle.gltf",
          json.dumps(gltf_doc("data:application/octet-stream;base64," + base64.b64encode(buf).decode())))
    js = json.dumps(gltf_doc(None)).encode()
    js += b" " * (-len(js) % 4)
    glb = struct.pack("<III", 0x46546C67, 2, 12 + 8 + len(js) + 8 + len(buf)) + \
        struct.pack("<II", len(js), 0x4E4F534A) + js + struct.pack("<II", len(buf), 0x004E4942) + buf
    write("gltf", "triangle.glb", glb)
    moving = gltf_doc("data:application/octet-stream;base64," + base64.b64encode(buf).decode())
    moving["nodes"][1]["extras"] = {"radar_emu": {"velocity_mps": [5, 0, 0], "start_position_m": [0, 10, 0]}}
    moving["nodes"][0]["children"] = [1]
    moving["scenes"][0]["nodes"] = [0]
    write("gltf", "children_moving.gltf", json.dumps(moving))

    if radar_emu:
        tmp = tempfile.mkdtemp()
        try:
            for kind, ext, args in (("plate", "glb", ["--a-m", "1", "--b-m", "1"]),
                                    ("dihedral", "gltf", []), ("box", "obj", []), ("trihedral-tri", "stl", [])):
                out = os.path.join(tmp, kind + "." + ext)
                subprocess.run([radar_emu, "scene", "target", kind, "--out", out] + args, check=True,
                               capture_output=True)
                with open(out, "rb") as f:
                    data = f.read()
                name = {"glb": "gltf", "gltf": "gltf"}.get(ext, ext)
                if len(data) <= 16384:
                    write(name, "written_" + kind + "." + ext, data)
        finally:
            shutil.rmtree(tmp)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--radar-emu", default=os.path.join(ROOT, "build", "emulator", "radar-emu"))
    a = ap.parse_args()
    radar_emu = a.radar_emu if os.path.exists(a.radar_emu) else None
    if radar_emu is None:
        print("make_seeds: no radar-emu executable: skipping the seeds it writes", file=sys.stderr)
    os.makedirs(os.path.join(HERE, "corpus", "scenario_toml"), exist_ok=True)
    os.makedirs(os.path.join(HERE, "corpus", "sar_case"), exist_ok=True)
    canaerospace_seeds()
    icd_seeds()
    candump_seeds()
    modbus_seeds()
    scenario_seeds(radar_emu)
    mesh_seeds(radar_emu)
    websocket_seeds()
    sar_case_seeds()


if __name__ == "__main__":
    main()
