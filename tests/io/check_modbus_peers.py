#!/usr/bin/python3
"""Independent peers for radar-emu's Modbus navigation map (docs/icd/modbus.md).

(a) Starts modbus_nav_server (the project's test server) in three configurations (float32 ABCD,
    float32 CDAB, scaled int32), reads its registers with pymodbus and with mbpoll, decodes them
    here with struct from the ICD's layout, and compares them with the straight line this script
    asked for, evaluated at the sender's own time stamp.
(b) Starts a pymodbus TCP server holding navigation maps this script packs with struct, and
    checks that modbus_nav_read (ModbusClient + NavDecoder) decodes the same values, and rejects
    and counts a NaN and an out-of-range value.

Readiness: the "listening HOST:PORT" line of modbus_nav_server; pymodbus's own "serving" future.

usage: check_modbus_peers.py MODBUS_NAV_SERVER MODBUS_NAV_READ
"""
import asyncio
import json
import logging
import math
import re
import select
import shutil
import struct
import subprocess
import sys
import threading
import time
import types

try:
    import pymodbus.client  # noqa: F401
except ModuleNotFoundError as exc:
    # Debian's python3-pymodbus 3.0 imports serial_asyncio (python3-serial-asyncio, only
    # "Recommends") even for TCP. The checks below use TCP only: stand in for it.
    if exc.name != "serial_asyncio":
        raise
    stub = types.ModuleType("serial_asyncio")

    def _no_serial(*_args, **_kwargs):
        raise RuntimeError("serial_asyncio is not installed")

    stub.create_serial_connection = _no_serial
    sys.modules["serial_asyncio"] = stub
from pymodbus.client import ModbusTcpClient
from pymodbus.datastore import (ModbusSequentialDataBlock, ModbusServerContext,
                                ModbusSlaveContext)
from pymodbus.server.async_io import ModbusTcpServer

# WGS84 (NIMA TR8350.2, table 3.1) and the radii of curvature (sec. 4).
WGS84_A = 6378137.0
WGS84_F = 1.0 / 298.257223563
WGS84_E2 = WGS84_F * (2.0 - WGS84_F)
F32_REL = 2.0 ** -24  # half an ulp of binary32, relative

FAILURES = []


def check(ok, what):
    if not ok:
        FAILURES.append(what)
        print("FAIL:", what)


def near(got, want, tol, what):
    check(got is not None and abs(got - want) <= tol, f"{what}: got {got}, want {want} +- {tol}")


# ---- Register decoding from the ICD (docs/icd/modbus.md) -----------------------------------

def u32(regs, i, order):
    hi, lo = (regs[i], regs[i + 1]) if order == "abcd" else (regs[i + 1], regs[i])
    return (hi << 16) | lo


def i32(regs, i, order):
    return struct.unpack(">i", struct.pack(">I", u32(regs, i, order)))[0]


def f32(regs, i, order):
    return struct.unpack(">f", struct.pack(">I", u32(regs, i, order)))[0]


def f64(regs, i, order):
    words = regs[i:i + 4] if order == "abcd" else list(reversed(regs[i:i + 4]))
    return struct.unpack(">d", struct.pack(">4H", *words))[0]


FIELDS = ["height_m", "true_heading_deg", "pitch_deg", "roll_deg", "vel_east_mps",
          "vel_north_mps", "vel_up_mps"]
SCALED = {"lat_deg": 1e-7, "lon_deg": 1e-7, "height_m": 1e-3, "true_heading_deg": 1e-6,
          "pitch_deg": 1e-6, "roll_deg": 1e-6, "vel_east_mps": 1e-4, "vel_north_mps": 1e-4,
          "vel_up_mps": 1e-4}


def decode_map(regs, order, encoding):
    """The navigation map as a dict of map-unit values (deg, m, m/s)."""
    out = {"counter": regs[0], "status": regs[1], "time_ms": u32(regs, 2, order)}
    if encoding == "float32":
        out["lat_deg"] = f64(regs, 4, order)
        out["lon_deg"] = f64(regs, 8, order)
        for k, name in enumerate(FIELDS):
            out[name] = f32(regs, 12 + 2 * k, order)
    else:
        names = ["lat_deg", "lon_deg"] + FIELDS
        for k, name in enumerate(names):
            out[name] = i32(regs, 4 + 2 * k, order) * SCALED[name]
    return out


def encode_map(values, counter, status, time_ms, order, encoding):
    """Packs a navigation map from map-unit values, here in Python, from the ICD."""
    def words32(bits):
        hi, lo = bits >> 16, bits & 0xFFFF
        return [hi, lo] if order == "abcd" else [lo, hi]

    regs = [counter, status] + words32(time_ms)
    if encoding == "float32":
        for name in ("lat_deg", "lon_deg"):
            w = list(struct.unpack(">4H", struct.pack(">d", values[name])))
            regs += w if order == "abcd" else list(reversed(w))
        for name in FIELDS:
            regs += words32(struct.unpack(">I", struct.pack(">f", values[name]))[0])
    else:
        for name in ["lat_deg", "lon_deg"] + FIELDS:
            raw = round(values[name] / SCALED[name])
            regs += words32(raw & 0xFFFFFFFF)
    return regs


# ---- (a) our server, independent clients ---------------------------------------------------

TRACK = {"lat_deg": 51.47, "lon_deg": -0.46, "height_m": 300.0, "vel_east_mps": 70.0,
         "vel_north_mps": -12.5, "vel_up_mps": -3.5, "true_heading_deg": 93.5,
         "pitch_deg": -3.0, "roll_deg": 1.25}
DURATION_S = 3.0


def expected_at(t_s):
    """The straight line modbus_nav_server plays (radii of curvature at the start point)."""
    lat0 = math.radians(TRACK["lat_deg"])
    s2 = math.sin(lat0) ** 2
    m = WGS84_A * (1 - WGS84_E2) / (1 - WGS84_E2 * s2) ** 1.5
    n = WGS84_A / math.sqrt(1 - WGS84_E2 * s2)
    h0 = TRACK["height_m"]
    e = dict(TRACK)
    e["lat_deg"] = TRACK["lat_deg"] + math.degrees(TRACK["vel_north_mps"] * t_s / (m + h0))
    e["lon_deg"] = TRACK["lon_deg"] + math.degrees(
        TRACK["vel_east_mps"] * t_s / ((n + h0) * math.cos(lat0)))
    e["height_m"] = h0 + TRACK["vel_up_mps"] * t_s
    return e


def start_server(exe, order, encoding, base):
    args = [exe, "--port", "0", "--order", order, "--encoding", encoding, "--base", str(base),
            "--rate-hz", "50", "--duration-s", str(DURATION_S)]
    for key, opt in (("lat_deg", "--lat-deg"), ("lon_deg", "--lon-deg"),
                     ("height_m", "--height-m"), ("vel_east_mps", "--vel-east-mps"),
                     ("vel_north_mps", "--vel-north-mps"), ("vel_up_mps", "--vel-up-mps"),
                     ("true_heading_deg", "--heading-deg"), ("pitch_deg", "--pitch-deg"),
                     ("roll_deg", "--roll-deg")):
        args += [opt, repr(TRACK[key])]
    proc = subprocess.Popen(args, stdout=subprocess.PIPE, text=True)
    ready, _, _ = select.select([proc.stdout], [], [], 10.0)
    line = proc.stdout.readline() if ready else ""
    match = re.fullmatch(r"listening 127\.0\.0\.1:(\d+)\n", line)
    if not match:
        proc.kill()
        raise SystemExit(f"FAIL: modbus_nav_server did not report readiness: {line!r}")
    return proc, int(match.group(1))


def check_against_track(m, order, encoding, who):
    t_s = m["time_ms"] / 1000.0
    check(0.0 <= t_s <= DURATION_S, f"{who}: time stamp {t_s} s outside the run")
    check(m["status"] == 7, f"{who}: status word {m['status']} != 7 (all valid)")
    want = expected_at(t_s)
    for name, value in want.items():
        if encoding == "float32":
            # lat/lon float64; the rest float32 (half an ulp) of a double-precision track.
            tol = 1e-9 if name in ("lat_deg", "lon_deg") else abs(value) * F32_REL * 1.01 + 1e-9
        else:
            tol = SCALED[name] * 0.5 * 1.001 + 1e-12
        near(m[name], value, tol, f"{who} {order}/{encoding} {name} at t={t_s}")


def mbpoll(port, ref, count, kind, big_endian):
    cmd = ["mbpoll", "-m", "tcp", "-p", str(port), "-a", "1", "-0", "-1", "-o", "1",
           "-r", str(ref), "-c", str(count), "-t", kind]
    if big_endian:
        cmd.append("-B")
    cmd.append("127.0.0.1")
    out = subprocess.run(cmd, capture_output=True, text=True, timeout=10)
    values = {}
    for line in out.stdout.splitlines():
        match = re.match(r"\[(\d+)\]:\s+(\S+)", line)
        if match:
            text = match.group(2)
            values[int(match.group(1))] = int(text, 16) if text.startswith("0x") else float(text)
    if out.returncode != 0 or len(values) != count:
        raise SystemExit(f"FAIL: {' '.join(cmd)} -> rc {out.returncode}\n{out.stdout}{out.stderr}")
    return values


def part_a(server_exe):
    configs = [("abcd", "float32", 0), ("cdab", "float32", 100), ("abcd", "scaled", 1000),
               ("cdab", "scaled", 40000)]
    servers = [(cfg, *start_server(server_exe, *cfg)) for cfg in configs]
    try:
        for (order, encoding, base), _proc, port in servers:
            count = 26 if encoding == "float32" else 22
            client = ModbusTcpClient("127.0.0.1", port=port)
            check(client.connect(), f"pymodbus connects to port {port}")
            rr = client.read_holding_registers(base, count, slave=1)
            check(not rr.isError(), f"pymodbus read {order}/{encoding}: {rr}")
            first = decode_map(rr.registers, order, encoding)
            check_against_track(first, order, encoding, "pymodbus")
            # The sender is alive: its update counter and time stamp move on.
            deadline = time.monotonic() + 2.0
            later = first
            while later["counter"] == first["counter"] and time.monotonic() < deadline:
                time.sleep(0.005)
                later = decode_map(client.read_holding_registers(base, count, slave=1).registers,
                                   order, encoding)
            check(later["counter"] != first["counter"] and later["time_ms"] > first["time_ms"],
                  f"update counter/time stamp did not move ({order}/{encoding})")
            check_against_track(later, order, encoding, "pymodbus")
            # Writes are refused: the table is read-only for clients.
            wr = client.write_register(base, 1, slave=1)
            check(wr.isError(), f"write accepted by the read-only table ({order}/{encoding})")
            client.close()

            # mbpoll: the raw registers (hex), decoded here ...
            raw = mbpoll(port, base, count, "4:hex", False)
            regs = [raw[base + i] for i in range(count)]
            check_against_track(decode_map(regs, order, encoding), order, encoding, "mbpoll hex")
            # ... and mbpoll's own decoding of the 32-bit values (-B = ABCD, default = CDAB).
            # mbpoll prints 6 significant digits; the constant fields are exact in 6 digits.
            want = expected_at(0.0)
            first_field = 12 if encoding == "float32" else 8
            kind = "4:float" if encoding == "float32" else "4:int"
            vals = mbpoll(port, base + first_field, 7, kind, order == "abcd")
            for k, name in enumerate(FIELDS):
                if name == "height_m":
                    continue  # changes with time
                got = vals[base + first_field + 2 * k]
                if encoding == "scaled":
                    got *= SCALED[name]
                near(got, want[name], abs(want[name]) * 5e-6 + 1e-9,
                     f"mbpoll {kind} {order} {name}")
    finally:
        for _cfg, proc, _port in servers:
            try:
                rc = proc.wait(timeout=DURATION_S + 10)
                check(rc == 0, f"modbus_nav_server exited with {rc}")
            except subprocess.TimeoutExpired:
                proc.kill()
                check(False, "modbus_nav_server did not exit after its run time")


# ---- (b) independent server, our client --------------------------------------------------

class PymodbusServer:
    """pymodbus ModbusTcpServer on 127.0.0.1, ephemeral port, in a thread."""

    def __init__(self, size):
        self.store = ModbusSlaveContext(hr=ModbusSequentialDataBlock(0, [0] * size),
                                        zero_mode=True)
        context = ModbusServerContext(slaves=self.store, single=True)
        self.ready = threading.Event()
        self.port = None
        self.thread = threading.Thread(target=self._run, args=(context,), daemon=True)
        self.thread.start()
        if not self.ready.wait(10.0):
            raise SystemExit("FAIL: pymodbus server did not start")

    def _run(self, context):
        self.loop = asyncio.new_event_loop()
        asyncio.set_event_loop(self.loop)
        self.server = ModbusTcpServer(context, address=("127.0.0.1", 0), loop=self.loop)

        async def main():
            task = asyncio.ensure_future(self.server.serve_forever())
            await self.server.serving
            self.port = self.server.server.sockets[0].getsockname()[1]
            self.ready.set()
            try:
                await task
            except asyncio.CancelledError:
                pass

        self.loop.run_until_complete(main())

    def set(self, base, regs):
        self.store.setValues(3, base, regs)

    def stop(self):
        future = asyncio.run_coroutine_threadsafe(self.server.shutdown(), self.loop)
        try:
            future.result(timeout=5.0)
        except Exception:  # noqa: BLE001 (best effort; the thread is a daemon)
            pass


def part_b(read_exe):
    server = PymodbusServer(600)
    values = {"lat_deg": 47.123456789012, "lon_deg": -122.987654321098, "height_m": 1234.5,
              "true_heading_deg": 359.5, "pitch_deg": -7.25, "roll_deg": 12.0,
              "vel_east_mps": -55.5, "vel_north_mps": 33.25, "vel_up_mps": 2.0}
    bad = dict(values, height_m=float("nan"), pitch_deg=95.0)
    cases = [  # (name, base, order, encoding, values, status, expect decode, nulls)
        ("float32 abcd", 0, "abcd", "float32", values, 7, "accepted", set()),
        ("float32 cdab", 100, "cdab", "float32", values, 7, "accepted", set()),
        ("scaled abcd", 200, "abcd", "scaled", values, 7, "accepted", set()),
        ("scaled cdab", 300, "cdab", "scaled", values, 7, "accepted", set()),
        ("nan and range", 400, "abcd", "float32", bad, 7, "partial", {"height_m", "pitch_deg"}),
        ("position only", 500, "abcd", "float32", values, 1, "partial",
         {"true_heading_deg", "pitch_deg", "roll_deg", "vel_east_mps", "vel_north_mps",
          "vel_up_mps"}),
    ]
    for name, base, order, encoding, vals, status, _, _ in cases:
        server.set(base, encode_map(vals, 0x1234, status, 987654, order, encoding))
    json_names = {"lat_deg": "latitude_rad", "lon_deg": "longitude_rad", "height_m": "height_m",
                  "true_heading_deg": "true_heading_rad", "pitch_deg": "pitch_rad",
                  "roll_deg": "roll_rad", "vel_east_mps": "vel_east_mps",
                  "vel_north_mps": "vel_north_mps", "vel_up_mps": "vel_up_mps"}
    try:
        for name, base, order, encoding, vals, status, want_decode, nulls in cases:
            out = subprocess.run([read_exe, f"tcp:127.0.0.1:{server.port}", "--base", str(base),
                                  "--order", order, "--encoding", encoding],
                                 capture_output=True, text=True, timeout=10)
            if out.returncode != 0:
                check(False, f"{name}: modbus_nav_read rc {out.returncode}: {out.stderr}")
                continue
            got = json.loads(out.stdout)
            check(got["decode"] == want_decode, f"{name}: decode {got['decode']}")
            check(got["update_counter"] == 0x1234 and got["time_ms"] == 987654 and
                  got["status"] == status, f"{name}: header {got}")
            for key, json_name in json_names.items():
                value = got["fields"][json_name]
                if key in nulls:
                    check(value is None, f"{name}: {json_name} should be rejected, got {value}")
                    continue
                want = vals[key]
                if encoding == "float32" and key not in ("lat_deg", "lon_deg"):
                    want = struct.unpack(">f", struct.pack(">f", want))[0]  # as sent
                if encoding == "scaled":
                    want = round(want / SCALED[key]) * SCALED[key]
                angle = key.endswith("_deg")
                if angle:
                    want = math.radians(want)
                near(value, want, abs(want) * 1e-15 + 1e-15, f"{name}: {json_name}")
            if name == "nan and range":
                check(got["counters"]["not_a_number"] == 1 and
                      got["counters"]["out_of_range"] == 1, f"{name}: counters {got['counters']}")
            if name == "position only":
                check(got["counters"]["flagged_invalid"] == 6, f"{name}: {got['counters']}")
    finally:
        server.stop()


def main():
    server_exe, read_exe = sys.argv[1:3]
    logging.getLogger("pymodbus").setLevel(logging.CRITICAL)  # shutdown chatter
    if shutil.which("mbpoll") is None:
        raise SystemExit("FAIL: mbpoll not installed (Debian package mbpoll)")
    part_a(server_exe)
    part_b(read_exe)
    if FAILURES:
        print(f"{len(FAILURES)} check(s) failed")
        sys.exit(1)
    print("modbus peers: pymodbus and mbpoll agree with the navigation map")


if __name__ == "__main__":
    main()
