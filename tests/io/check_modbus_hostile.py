#!/usr/bin/python3
"""Modbus TCP under hostile clients (docs/icd/modbus.md, "Serving hostile clients").

modbus_table_loop serves the detection table of a 2,000-frame loop (5 ms period) with the
project's ModbusServer, publishing one table per frame as `radar-emu run --modbus-server` does.

1. Baseline: the loop alone; its frames over budget (work longer than the period) are counted.
2. The same loop with 50 concurrent clients: 32 pymodbus clients and one mbpoll loop (Debian's
   python3-pymodbus and mbpoll, independent of the project's code) read the whole table in one
   request, again and again; 17 hostile clients (a third) send malformed MBAP headers (protocol
   id, length field), function-0x03 PDUs of the wrong length, unknown function codes, writes,
   reads outside the table or of a bad quantity, stall half-way through a request (half-open),
   and flood the server with connections. Every hostile client checks the answer it gets
   (exception code, or the connection closed) and counts what it sent.

Checks: every table a good client read is the table of the frame whose counter it carries,
recomputed here from the documented layout (float32 ABCD, struct); no good read failed; the
loop with clients has no more frames over budget than the loop alone; every hostile request
appears in the server's counters, kind by kind, and the counters add up
(requests = replies + malformed_mbap + send_failures).

usage: check_modbus_hostile.py MODBUS_TABLE_LOOP
"""
import json
import logging
import random
import select
import socket
import struct
import subprocess
import sys
import threading
import time

FRAMES = 2000
PERIOD_MS = 5.0
MAX_DET = 5
TABLE = 8 + 22 * MAX_DET + 1  # docs/icd/modbus.md: header, records, trailer (119 <= 125)
REQUEST_TIMEOUT_S = 0.3
GOOD_PYMODBUS = 32
HOSTILE = 17
SEED = 19

LOOP = None


def fail(msg):
    print("FAIL:", msg)
    sys.exit(1)


# ---- the table of frame k, from the documented layout (modbus_table_loop.cpp's header) -------

def f32_regs(v):
    hi, lo = struct.unpack(">HH", struct.pack(">f", v))
    return [hi, lo]


def expected_table(k):
    n = k % (MAX_DET + 1)
    time_ms = int(k * PERIOD_MS)
    regs = [k & 0xFFFF, n, 0x02 if k % 2 else 0, MAX_DET, time_ms >> 16, time_ms & 0xFFFF, 22, 1]
    for i in range(MAX_DET):
        if i < n:
            rec = []
            for v in (100.0 + k + 10.0 * i, 1.5 * (i - 2), 0.5 * i, -20.0 + i, 10.0 + i,
                      (k % 30) - 10.0, 1.0, 0.1, 0.1, 0.2):
                rec += f32_regs(v)
            rec += [1 if i % 2 else 0, 0]
        else:
            rec = [0] * 22
        regs += rec
    regs.append(k & 0xFFFF)
    return regs


# ---- the loop ----------------------------------------------------------------------------------

class Loop:
    def __init__(self):
        self.proc = subprocess.Popen(
            [LOOP, "--frames", str(FRAMES), "--period-ms", str(PERIOD_MS), "--max-detections",
             str(MAX_DET), "--max-clients", "64", "--request-timeout-s", str(REQUEST_TIMEOUT_S)],
            stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
        line = self.readline(10.0)
        if not line.startswith("listening 127.0.0.1:"):
            fail(f"modbus_table_loop did not report readiness: {line!r}")
        self.port = int(line.split(":")[1])

    def readline(self, timeout_s):
        ready, _, _ = select.select([self.proc.stdout], [], [], timeout_s)
        return self.proc.stdout.readline() if ready else ""

    def go(self):
        self.proc.stdin.write("go\n")
        self.proc.stdin.flush()

    def wait_loop(self):
        line = self.readline(FRAMES * PERIOD_MS / 1000.0 + 60.0)
        if not line.startswith("{"):
            fail(f"modbus_table_loop: no loop summary: {line!r}")
        return json.loads(line)["loop"]

    def finish(self):
        self.proc.stdin.close()
        line = self.readline(10.0)
        self.proc.wait(timeout=10.0)
        if not line.startswith("{"):
            fail(f"modbus_table_loop: no server summary: {line!r}")
        return json.loads(line)["server"]


# ---- good clients ------------------------------------------------------------------------------

class Good(threading.Thread):
    def __init__(self, port, stop, idx):
        super().__init__(daemon=True)
        self.port, self.stop, self.idx = port, stop, idx
        self.reads = 0
        self.frames_seen = set()
        self.errors = []

    def check(self, regs):
        k_low = regs[0]
        # The frame number from the counter and the time stamp (k x 5 ms, k < 65536 here).
        time_ms = (regs[4] << 16) | regs[5]
        k = int(round(time_ms / PERIOD_MS))
        if k & 0xFFFF != k_low:
            k = k_low
        want = expected_table(k)
        if regs != want:
            bad = [i for i in range(TABLE) if regs[i] != want[i]]
            self.errors.append(f"frame {k}: registers {bad[:8]} differ from the ICD's table")
        self.frames_seen.add(k)

    def run(self):
        from pymodbus.client import ModbusTcpClient
        client = ModbusTcpClient("127.0.0.1", port=self.port, timeout=2)
        if not client.connect():
            self.errors.append("cannot connect")
            return
        rnd = random.Random(SEED + self.idx)
        while not self.stop.is_set():
            rr = client.read_holding_registers(0, TABLE, slave=1)
            if rr.isError():
                self.errors.append(f"read failed: {rr}")
                break
            self.reads += 1
            self.check(list(rr.registers))
            time.sleep(rnd.uniform(0.005, 0.02))
        client.close()


class GoodMbpoll(threading.Thread):
    """mbpoll, one process per poll: one 119-register read, printed in hex."""

    def __init__(self, port, stop):
        super().__init__(daemon=True)
        self.port, self.stop = port, stop
        self.reads = 0
        self.frames_seen = set()
        self.errors = []

    def run(self):
        checker = Good(self.port, self.stop, 0)
        while not self.stop.is_set():
            p = subprocess.run(["mbpoll", "-m", "tcp", "-p", str(self.port), "-0", "-1", "-r", "0",
                                "-c", str(TABLE), "-t", "4:hex", "-o", "2", "127.0.0.1"],
                               capture_output=True, text=True, timeout=30)
            if p.returncode != 0:
                self.errors.append(f"mbpoll: {p.stdout[-200:]} {p.stderr[-200:]}")
                break
            regs = {}
            for line in p.stdout.splitlines():
                if line.startswith("["):
                    ref, val = line.split(":")
                    regs[int(ref.strip("[] "))] = int(val.strip(), 16)
            if sorted(regs) != list(range(TABLE)):
                self.errors.append(f"mbpoll printed {len(regs)} registers")
                break
            self.reads += 1
            checker.check([regs[i] for i in range(TABLE)])
            time.sleep(0.05)
        self.errors += checker.errors
        self.frames_seen = checker.frames_seen


# ---- hostile clients ---------------------------------------------------------------------------

def mbap(tid, pdu, protocol=0, length=None, unit=1):
    return struct.pack(">HHHB", tid, protocol, len(pdu) + 1 if length is None else length, unit) + pdu


def recv_exact(s, n, timeout_s=2.0):
    s.settimeout(timeout_s)
    data = b""
    while len(data) < n:
        chunk = s.recv(n - len(data))
        if not chunk:
            return data
        data += chunk
    return data


def expect_closed(s, timeout_s):
    """True if the server closes the connection (EOF or reset) within timeout_s."""
    s.settimeout(timeout_s)
    try:
        return s.recv(1) == b""
    except ConnectionResetError:
        return True
    except socket.timeout:
        return False


class Hostile(threading.Thread):
    KINDS = ["bad_protocol", "bad_mbap_length", "bad_pdu_length", "unknown_function", "write",
             "illegal_address", "illegal_quantity", "half_open", "flood"]

    def __init__(self, port, stop, idx):
        super().__init__(daemon=True)
        self.port, self.stop = port, stop
        self.kind = self.KINDS[idx % len(self.KINDS)]
        self.rnd = random.Random(SEED * 100 + idx)
        self.sent = {}
        self.connections = 0
        self.errors = []

    def connect(self):
        s = socket.create_connection(("127.0.0.1", self.port), timeout=5)
        self.connections += 1
        return s

    def count(self, key):
        self.sent[key] = self.sent.get(key, 0) + 1

    def exception(self, s, pdu, fc, code, key):
        tid = self.rnd.randrange(65536)
        s.sendall(mbap(tid, pdu))
        self.count(key)
        ans = recv_exact(s, 9)
        want = struct.pack(">HHHBBB", tid, 0, 3, 1, fc | 0x80, code)
        if ans != want:
            self.errors.append(f"{self.kind}: answer {ans.hex()} (expected {want.hex()})")

    def run(self):
        s = None
        try:
            while not self.stop.is_set():
                k = self.kind
                if k in ("bad_protocol", "bad_mbap_length"):
                    s = self.connect()
                    if k == "bad_protocol":
                        s.sendall(mbap(1, b"\x03\x00\x00\x00\x01", protocol=self.rnd.randrange(1, 65536)))
                    else:
                        s.sendall(mbap(1, b"\x03\x00\x00\x00\x01",
                                       length=self.rnd.choice([0, 1, 255, 300, 65535])))
                    self.count("malformed_mbap")
                    if not expect_closed(s, 5.0):
                        self.errors.append(f"{k}: connection not closed")
                    s.close()
                    s = None
                    time.sleep(0.02)
                    continue
                if k == "half_open":
                    s = self.connect()
                    s.sendall(mbap(2, b"\x03\x00\x00\x00\x05")[: self.rnd.randrange(1, 11)])
                    self.count("incomplete")
                    if not expect_closed(s, REQUEST_TIMEOUT_S + 5.0):
                        self.errors.append("half-open: connection not closed")
                    s.close()
                    s = None
                    continue
                if k == "flood":
                    for _ in range(10):
                        c = self.connect()
                        c.close()
                    time.sleep(0.01)
                    continue
                if s is None:
                    s = self.connect()
                if k == "bad_pdu_length":
                    extra = bytes(self.rnd.randrange(1, 20))
                    pdu = (b"\x03\x00\x00\x00\x01" + extra) if self.rnd.random() < 0.5 else b"\x03\x00"
                    self.exception(s, pdu, 0x03, 0x03, "bad_length")
                elif k == "unknown_function":
                    fc = self.rnd.choice([0x01, 0x02, 0x04, 0x07, 0x08, 0x0B, 0x11, 0x2B, 0x41, 0x64, 0x7F,
                                          0x83, 0xFF])
                    self.exception(s, bytes([fc]) + bytes(self.rnd.randrange(0, 8)), fc, 0x01,
                                   "unknown_function")
                elif k == "write":
                    fc = self.rnd.choice([0x05, 0x06, 0x0F, 0x10, 0x16, 0x17])
                    self.exception(s, bytes([fc, 0, 0, 0, 1, 2, 0, 7]), fc, 0x01, "refused_writes")
                elif k == "illegal_address":
                    start = self.rnd.randrange(TABLE - 5, 65536)
                    qty = self.rnd.randrange(max(1, TABLE - start + 1), 126) if start < TABLE else \
                        self.rnd.randrange(1, 126)
                    self.exception(s, struct.pack(">BHH", 3, start, qty), 0x03, 0x02, "illegal_address")
                elif k == "illegal_quantity":
                    qty = self.rnd.choice([0, 126, 200, 65535])
                    self.exception(s, struct.pack(">BHH", 3, 0, qty), 0x03, 0x03, "illegal_quantity")
                time.sleep(self.rnd.uniform(0.001, 0.01))
        except Exception as e:  # noqa: BLE001 (reported as a failure below)
            self.errors.append(f"{self.kind}: {e!r}")
        finally:
            if s is not None:
                s.close()


def main():
    global LOOP
    if len(sys.argv) != 2:
        fail("usage: check_modbus_hostile.py MODBUS_TABLE_LOOP")
    LOOP = sys.argv[1]
    logging.getLogger("pymodbus").setLevel(logging.CRITICAL)

    base = Loop()
    base.go()
    alone = base.wait_loop()
    alone_server = base.finish()
    print(f"loop alone: {alone['frames']} frames, {alone['frames_over_budget']} over the "
          f"{PERIOD_MS} ms budget, work max {alone['work_max_us']} us, "
          f"wake-up late by up to {alone['wake_late_max_us']} us")

    loop = Loop()
    stop = threading.Event()
    good = [Good(loop.port, stop, i) for i in range(GOOD_PYMODBUS)] + [GoodMbpoll(loop.port, stop)]
    hostile = [Hostile(loop.port, stop, i) for i in range(HOSTILE)]
    for c in good + hostile:
        c.start()
    time.sleep(0.5)  # every client connected and at work
    loop.go()
    busy = loop.wait_loop()
    stop.set()
    for c in good + hostile:
        c.join(timeout=30)
    server = loop.finish()
    print(f"loop with {len(good)} good and {len(hostile)} hostile clients: {busy['frames']} "
          f"frames, {busy['frames_over_budget']} over budget, work max {busy['work_max_us']} us, "
          f"wake-up late by up to {busy['wake_late_max_us']} us")
    print("server:", json.dumps(server))

    # Good clients: every table correct, no failure, the table advancing.
    reads = 0
    frames = set()
    for c in good:
        if c.errors:
            fail(f"good client: {c.errors[:3]}")
        if c.reads < 10:
            fail(f"good client read only {c.reads} tables")
        reads += c.reads
        frames |= c.frames_seen
    if len(frames) < FRAMES // 10:
        fail(f"the good clients saw only {len(frames)} distinct frames")
    print(f"ok: {len(good)} good clients read {reads} tables of {len(frames)} distinct frames, "
          f"every one equal to the ICD's table of its frame")
    for c in hostile:
        if c.errors:
            fail(f"hostile client ({c.kind}) got unexpected answers: {c.errors[:3]}")

    # The loop: nothing over budget that the loop alone did not have.
    if busy["frames_over_budget"] > alone["frames_over_budget"]:
        fail(f"{busy['frames_over_budget']} frames over budget with clients, "
             f"{alone['frames_over_budget']} without")
    print(f"ok: frames over budget with clients {busy['frames_over_budget']} <= alone "
          f"{alone['frames_over_budget']}")

    # Every hostile request counted, kind by kind.
    sent = {}
    connections = sum(c.connections for c in hostile) + GOOD_PYMODBUS
    for c in hostile:
        for k, v in c.sent.items():
            sent[k] = sent.get(k, 0) + v
    for key in ("malformed_mbap", "bad_length", "unknown_function", "refused_writes",
                "illegal_address", "illegal_quantity", "incomplete"):
        if server[key] != sent.get(key, 0):
            fail(f"server counted {server[key]} {key}, the hostile clients sent {sent.get(key, 0)}")
    if server["send_failures"] != 0 or server["errors"] != 0:
        fail(f"send failures {server['send_failures']}, errors {server['errors']}")
    if server["requests"] != server["replies"] + server["malformed_mbap"] + server["send_failures"]:
        fail("requests != replies + malformed_mbap + send_failures")
    accepted = server["clients_accepted"] + server["clients_refused"]
    mbpoll_connections = next(c.reads for c in good if isinstance(c, GoodMbpoll))
    if accepted < connections + mbpoll_connections:
        fail(f"{accepted} connections counted, at least {connections + mbpoll_connections} made")
    print(f"ok: every hostile request counted: " +
          ", ".join(f"{k} {sent[k]}" for k in sorted(sent)) +
          f"; {server['clients_accepted']} connections accepted, {server['clients_refused']} "
          f"refused, {server['clients_evicted']} evicted, {server['incomplete']} half-open closed")


if __name__ == "__main__":
    main()
