#!/usr/bin/env python3
"""An independent client of the gough CAN protocol, on python-can's `slcan` interface.

This is the project's second implementation of the protocol, written from docs/protocol.md's
description (not from the Rust code): framing, CRC-32, postcard bodies. It tests ours.

Run by `cargo xtask test-all` against the firmware under QEMU:
    gough firmware run --no-build --port PORT &
    python test_slcan_client.py --port PORT --gough path/to/gough

It waits until the device answers a measurement with an Estimate (its friction estimators
start with the parameters, at boot), sends measurements, decodes the predicted forces and checks them against
`gough mf eval --precision f32` (the host's f32 run of the same core, with libm: the firmware's
default build runs the `fast` backend, so the check allows 2e-5 of Fz, ten times the measured
difference between the two backends; a misplaced byte is off by far more), decodes the estimate
that follows each; sends the four wheels as one CompactBatch and decodes the CompactResults
against the same samples sent as single-wheel CompactMeasurements; sends a message with a broken CRC and checks the device counted it; then stops
the firmware. Exit code 0 = pass.

Authentication (protocol v5, docs/protocol.md "Security"): every state-changing message
(settings, calibration, stop) is secured with the device key (--key-file, the TEST KEY) by
Python's own AES-CMAC (the `cryptography` package: an implementation independent of the
firmware's RustCrypto one): type | 0x40, then the counter (u32 LE) and the MAC truncated to the
device's length after the body, MAC = CMAC(K, id LE || version || type || body || counter ||
epoch LE). The device must accept those, and refuse an unsigned, a forged and a replayed one
with their own Ack codes, counted in Status.

With --secure-all (the device started with `gough firmware run --secure-all`: every message
authenticated) the client runs a short scenario of its own instead: it signs its measurements
and checks every answer's MAC and freshness with the same independent CMAC (per CAN identifier:
a counter above the last one accepted on that identifier, within 65,536 of the highest); an
unsigned and a forged measurement are refused, counted and not answered; an answer altered on
the way is refused by the client.
"""
import argparse
import csv
import os
import socket
import struct
import subprocess
import sys
import tempfile
import time
import zlib

import can
from cryptography.hazmat.primitives.cmac import CMAC
from cryptography.hazmat.primitives.ciphers import algorithms

PROTO_VERSION = 5
ID_MEASUREMENT, ID_CONFIG, ID_RESULT, ID_STATUS = 0x300, 0x301, 0x310, 0x311
ID_COMPACT, ID_BATCH, ID_BATCH_RESULT = 0x302, 0x303, 0x312
T_MEASUREMENT, T_COMMAND, T_FORCES, T_ESTIMATE, T_STATUS, T_ACK = 0x01, 0x06, 0x81, 0x82, 0x83, 0x84
T_COMPACT, T_BATCH, T_BATCH_RESULTS = 0x07, 0x08, 0x85
T_SETTINGS = 0x05
T_SET_CALIBRATION, T_CALIBRATION = 0x09, 0x86
ACK_OK, ACK_BAD_SETTINGS, ACK_BAD_CALIBRATION = 0, 10, 11
ACK_NO_KEY, ACK_MAC_MISSING, ACK_BAD_MAC, ACK_STALE = 12, 13, 14, 15
SECURED = 0x40  # type bit: a counter and a MAC follow the body
ABSENT = -32768  # compact fields: an absent optional value
CMD_STATUS_REQUEST, CMD_STOP = 1, 2


def varint(b, i):
    """postcard varint (LEB128, unsigned) at b[i:] -> (value, next index)."""
    v, shift = 0, 0
    while True:
        x = b[i]
        i += 1
        v |= (x & 0x7F) << shift
        if x < 0x80:
            return v, i
        shift += 7


def message(mtype, body):
    data = bytes([PROTO_VERSION, mtype]) + body
    return data + struct.pack("<I", zlib.crc32(data))


def read_key(path):
    """A key file: 32 hex digits on one line, '#' comment lines skipped."""
    lines = [l.strip() for l in open(path) if l.strip() and not l.strip().startswith("#")]
    assert len(lines) == 1 and len(lines[0]) == 32, "key file: 32 hex digits"
    return bytes.fromhex(lines[0])


class Signer:
    """The owner's end of the authentication: the device's epoch and last accepted counter
    come from its Status; each secured message takes the next counter."""

    def __init__(self, key, mac_len, epoch, counter):
        self.key, self.mac_len, self.epoch, self.counter = key, mac_len, epoch, counter

    def seal(self, cid, mtype, body):
        self.counter += 1
        data = bytes([PROTO_VERSION, mtype | SECURED]) + body + struct.pack("<I", self.counter)
        c = CMAC(algorithms.AES(self.key))
        c.update(struct.pack("<H", cid) + data + struct.pack("<I", self.epoch))
        data += c.finalize()[:self.mac_len]
        if self.counter == 0xFFFFFFFF:  # the device moves to the next epoch after this one
            self.epoch, self.counter = self.epoch + 1, 0
        return data + struct.pack("<I", zlib.crc32(data))


def frames(msg, seq):
    """Segment: first frame [0x80|last, seq, len] + 5 bytes; then [last|index, seq] + 6 bytes."""
    out = [msg[:5]]
    rest = msg[5:]
    while rest:
        out.append(rest[:6])
        rest = rest[6:]
    res = []
    for k, chunk in enumerate(out):
        last = 0x40 if k == len(out) - 1 else 0
        if k == 0:
            res.append(bytes([0x80 | last, seq, len(msg)]) + chunk)
        else:
            res.append(bytes([last | k, seq]) + chunk)
    return res


def measurement(wheel, t_us, fz, fy, mz, vx, alpha, kappa):
    opt = lambda x: b"\x00" if x is None else b"\x01" + struct.pack("<f", x)
    body = bytes([wheel]) + struct.pack("<Ifff", t_us, fz, fy, mz)
    for x in (None, vx, None, None, alpha, kappa, None):  # fx vx omega delta alpha kappa gamma
        body += opt(x)
    return message(T_MEASUREMENT, body)


def compact_fields(fz, fy, mz, fx, vx, omega, alpha, kappa, gamma):
    """A compact measurement's scaled fields (docs/protocol.md): Fz u16 0.5 N, Fy/Fx i16 N,
    Mz i16 0.1 N m, vx/omega i16 0.01, alpha/kappa/gamma i16 1e-4; None -> -32768."""
    c = lambda x, unit: ABSENT if x is None else int(round(x / unit))
    return struct.pack("<Hhhhhhhhh", int(round(fz / 0.5)), c(fy, 1), c(mz, 0.1), c(fx, 1),
                       c(vx, 0.01), c(omega, 0.01), c(alpha, 1e-4), c(kappa, 1e-4), c(gamma, 1e-4))


def compact_measurement(wheel, t_us, fields):
    return message(T_COMPACT, bytes([wheel]) + struct.pack("<I", t_us) + fields)


def batch(t_us, wheels):
    """CompactBatch: t_us u32 LE, present mask u8, then four wheels' 18-byte compact fields
    (zeros for a wheel not present). `wheels`: {index: fields}."""
    body = struct.pack("<IB", t_us, sum(1 << w for w in wheels))
    for w in range(4):
        body += wheels.get(w, bytes(18))
    return message(T_BATCH, body)


def decode_batch_results(b):
    """CompactResults: t_us u32 LE, then per wheel Fx, Fy i16 [N], Mz i16 [0.1 N m], mu, sigma
    u16 [1e-4], mu_min u8 [0.01], status u8 (state bits 0-1, change bit 2, MF flags bit 3,
    present bit 4); -32768 / 65535 / 255: not available."""
    assert len(b) == 4 + 4 * 12, "results body length"
    (t_us,) = struct.unpack("<I", b[:4])
    wheels = []
    for w in range(4):
        fx, fy, mz, mu, sigma, mu_min, status = struct.unpack("<hhhHHBB", b[4 + 12 * w:16 + 12 * w])
        na = lambda v, n, unit: None if v == n else v * unit
        wheels.append(dict(fx=na(fx, -32768, 1.0), fy=na(fy, -32768, 1.0), mz=na(mz, -32768, 0.1),
                           mu=na(mu, 65535, 1e-4), sigma=na(sigma, 65535, 1e-4),
                           mu_min=na(mu_min, 255, 0.01), state=status & 3,
                           change=bool(status & 4), mf_flags=bool(status & 8),
                           present=bool(status & 16)))
    return t_us, wheels


class AnswerVerifier:
    """Checks the device's secured answers (--secure-all): MAC = CMAC(K, id LE || data up to the
    counter || epoch LE), left `mac_len` bytes; the counter above the last accepted on its
    identifier and at most 65,536 above the highest accepted on any."""

    def __init__(self, key, mac_len, epoch, counter):
        self.key, self.mac_len, self.epoch = key, mac_len, epoch
        self.base, self.last, self.high = counter, {}, counter
        self.refused = 0

    def open(self, cid, data):
        """`data`: the message without its CRC. Returns (type, body) or None (refused)."""
        if data[1] & SECURED == 0 or len(data) < 2 + 4 + self.mac_len:
            self.refused += 1
            return None
        signed, mac = data[:-self.mac_len], data[-self.mac_len:]
        c = CMAC(algorithms.AES(self.key))
        c.update(struct.pack("<H", cid) + signed + struct.pack("<I", self.epoch))
        (counter,) = struct.unpack("<I", signed[-4:])
        if c.finalize()[:self.mac_len] != mac:
            self.refused += 1
            return None
        if counter <= self.last.get(cid, self.base) or counter > self.high + 65536:
            self.refused += 1
            return None
        self.last[cid] = counter
        self.high = max(self.high, counter)
        return data[1] & ~SECURED, signed[2:-4]


class Receiver:
    def __init__(self, bus, verifier=None):
        self.bus = bus
        self.partial = {}
        self.verifier = verifier

    def recv(self, timeout=10.0, calibration=False):
        """The next message from the device, as (type, body). The calibration reports the
        device sends on its own, once a second per wheel, are passed over unless asked for
        (`calibration`): they may come between a request and its answer."""
        end = time.time() + timeout
        while time.time() < end:
            f = self.bus.recv(timeout=max(0.01, end - time.time()))
            if f is None or f.arbitration_id not in (ID_RESULT, ID_STATUS, ID_BATCH_RESULT):
                continue
            d = bytes(f.data)
            first, last, seq = d[0] & 0x80, d[0] & 0x40, d[1]
            if first:
                self.partial[f.arbitration_id] = [d[2], seq, bytearray(d[3:])]
            else:
                p = self.partial.get(f.arbitration_id)
                if p is None or p[1] != seq:
                    raise AssertionError("frame out of order")
                p[2] += d[2:]
            if last:
                total, _, buf = self.partial.pop(f.arbitration_id)
                buf = bytes(buf[:total])
                data, crc = buf[:-4], struct.unpack("<I", buf[-4:])[0]
                assert zlib.crc32(data) == crc, "bad CRC from the device"
                assert data[0] == PROTO_VERSION
                mtype, body = data[1], data[2:]
                if self.verifier is not None:
                    opened = self.verifier.open(f.arbitration_id, data)
                    if opened is None:
                        print(f"note: answer on {f.arbitration_id:#x} refused (MAC or freshness)")
                        continue
                    mtype, body = opened
                if mtype == T_CALIBRATION and not calibration:
                    continue
                return mtype, body
        raise AssertionError("timed out waiting for the device")

    def until(self, want, **kw):
        """The body of the next message of type `want` (the others before it passed over)."""
        while True:
            t, body = self.recv(**kw)
            if t == want:
                return body


class Sender:
    """Messages onto the bus, each identifier's frames numbered in turn; `sent` counts them
    (the device's `messages` counter, for the messages that arrive whole)."""

    def __init__(self, bus):
        self.bus = bus
        self.seq = {}
        self.sent = 0

    def frames(self, cid, frames_):
        for fr in frames_:
            self.bus.send(can.Message(arbitration_id=cid, data=fr, is_extended_id=False))

    def __call__(self, cid, msg):
        n = self.seq.get(cid, 0)
        self.frames(cid, frames(msg, n % 256))
        self.seq[cid] = n + 1
        self.sent += 1


def decode_forces(b):
    wheel = b[0]
    t_us, fx, fy, mz, flags = struct.unpack("<IfffH", b[1:19])
    assert len(b) == 19
    return wheel, t_us, fx, fy, mz, flags


def decode_estimate(b):
    """wheel u8, t_us u32 LE, mu f32, sigma f32, state varint, mu_min f32, change bool (v2),
    mismatch bool (v4)."""
    wheel = b[0]
    t_us, mu, sigma = struct.unpack("<Iff", b[1:13])
    state, i = varint(b, 13)
    (mu_min,) = struct.unpack("<f", b[i:i + 4])
    change = b[i + 4]
    assert change in (0, 1), f"change byte {change}"
    assert b[i + 5] in (0, 1), f"mismatch byte {b[i + 5]}"
    assert i + 6 == len(b), "estimate body length"
    return wheel, t_us, mu, sigma, state, mu_min, bool(change)


def decode_status(b):
    fw = tuple(b[0:3])
    proto = b[3]
    source, i = varint(b, 4)
    (param_hash,) = struct.unpack("<I", b[i:i + 4])
    i += 4
    vals = []
    for _ in range(1 + 10 + 4):  # uptime, 10 counters, link, eval, tx, stack
        v, i = varint(b, i)
        vals.append(v)
    # v5: auth: mac_len u8, epoch and counter u32 LE, then 5 counters
    mac_len, epoch, counter = struct.unpack("<BII", b[i:i + 9])
    i += 9
    for _ in range(5):  # accepted, no_key, missing, bad_mac, stale
        v, i = varint(b, i)
        vals.append(v)
    assert i == len(b), "status body length"
    names = ["uptime_ms", "frames", "messages", "duplicates", "truncated", "bad_header",
             "bad_crc", "out_of_order", "overflow", "timeout", "decode",
             "link_errors", "eval_errors", "tx_messages", "stack_peak",
             "auth_accepted", "auth_no_key", "auth_missing", "auth_bad_mac", "auth_stale"]
    s = dict(zip(names, vals))
    s.update(firmware=fw, proto=proto, source=source, param_hash=param_hash,
             mac_len=mac_len, epoch=epoch, counter=counter)
    return s


def f32(x):
    return struct.unpack("<f", struct.pack("<f", x))[0]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--port", type=int, required=True)
    ap.add_argument("--gough", required=True, help="path of the gough binary (expected values)")
    ap.add_argument("--tir", required=True)
    ap.add_argument("--key-file", required=True, help="the device key (the TEST KEY)")
    ap.add_argument("--secure-all", action="store_true",
                    help="the device authenticates every message (8-byte MACs): the short scenario")
    a = ap.parse_args()
    key = read_key(a.key_file)
    if a.secure_all:
        return secure_all(a, key)

    cases = [  # wheel, fz, alpha, kappa, vx
        (0, 6752.0, 0.04, 0.05, 16.6),
        (1, 4000.0, -0.1, 0.0, 20.0),
        (2, 9000.0, 0.02, -0.15, 10.0),
        (3, 3000.0, 0.2, 0.1, 30.0),
    ]
    with tempfile.TemporaryDirectory() as d:
        inp, out = os.path.join(d, "in.csv"), os.path.join(d, "out.csv")
        with open(inp, "w") as f:
            f.write("in_Fz,in_kappa,in_alpha,in_gamma,in_phit,in_Vx,in_P\n")
            # The firmware mounts each wheel on its side (FL, RL left; the bundled file's tyre
            # is a right-hand one): a left wheel is the file's tyre mirrored — evaluated at −α
            # (γ is 0), Fy and Mz negated — which is what `mf::eval` does when it mirrors.
            for w, fz, al, ka, vx in cases:
                al = -al if w % 2 == 0 else al
                f.write(f"{f32(fz)!r},{f32(ka)!r},{f32(al)!r},0,0,{f32(vx)!r},0\n")
        subprocess.run([a.gough, "mf", "eval", "--tir", a.tir, "--input", inp, "--output", out,
                        "--precision", "f32"], check=True, capture_output=True)
        with open(out) as f:
            expected = [(f32(float(r["Fx"])), f32(float(r["Fy"])), f32(float(r["Mz"])))
                        for r in csv.DictReader(f)]
            expected = [(fx, -fy, -mz) if c[0] % 2 == 0 else (fx, fy, mz)
                        for c, (fx, fy, mz) in zip(cases, expected)]

    bus, nodelay = connect(a.port)
    print(f"note: TCP_NODELAY {'set' if nodelay else 'not available (frames may be delayed)'}")
    rx = Receiver(bus)
    fails = 0
    send = Sender(bus)

    try:
        # Wait until the device is up and a measurement gets an Estimate (the estimators start
        # with the bundled parameters at boot). (No Vx: the steady-state path, so wheel 0's
        # filter starts afresh with case 0.)
        ready = False
        for _ in range(100):
            send(ID_MEASUREMENT, measurement(0, 0, 5000.0, 0.0, 0.0, None, 0.0, None))
            send(ID_CONFIG, message(T_COMMAND, bytes([CMD_STATUS_REQUEST])))
            while True:
                t, body = rx.recv()
                ready |= t == T_ESTIMATE
                if t == T_STATUS:
                    break
            if ready:
                break
            time.sleep(0.1)
        print(f"{'ok  ' if ready else 'FAIL'} the device's estimator is up")
        fails += not ready
        st = decode_status(body)
        signer = Signer(key, st["mac_len"], st["epoch"], st["counter"])
        ok = 4 <= st["mac_len"] <= 8
        print(f"{'ok  ' if ok else 'FAIL'} the device has a key: MAC {st['mac_len']} bytes, "
              f"epoch {st['epoch']}, counter {st['counter']}")
        fails += not ok

        def ack(cid, msg):
            send(cid, msg)
            return rx.until(T_ACK)

        for k, (w, fz, al, ka, vx) in enumerate(cases):
            send(ID_MEASUREMENT, measurement(w, 1000 * (k + 1), fz, -1000.0, 10.0, vx, al, ka))
            while True:
                t, body = rx.recv()
                # Skip a late answer to a readiness probe (wheel 0, t_us 0): the device may
                # answer the status request before the measurement sent just ahead of it.
                if t == T_FORCES and decode_forces(body)[:2] != (0, 0):
                    break
            wheel, t_us, fx, fy, mz, flags = decode_forces(body)
            ex = expected[k]
            tol = 2e-5 * fz
            ok = ((wheel, t_us) == (w, 1000 * (k + 1)) and abs(fx - ex[0]) <= tol
                  and abs(fy - ex[1]) <= tol and abs(mz - ex[2]) <= tol * 0.4)
            print(f"{'ok  ' if ok else 'FAIL'} wheel {wheel} Fz {fz}: Fx {fx:.7g} Fy {fy:.7g} Mz {mz:.7g} "
                  f"(gough mf eval f32: {ex[0]:.7g} {ex[1]:.7g} {ex[2]:.7g})")
            fails += not ok
            t, body = rx.recv()
            ok = t == T_ESTIMATE
            if ok:
                ew, et, mu, sigma, state, mu_min, change = decode_estimate(body)
                ok = ((ew, et) == (w, t_us) and state in (0, 1, 2) and 0 < mu < 3 and 0 < sigma < 3
                      and 0 < mu_min < 3)
                print(f"{'ok  ' if ok else 'FAIL'} estimate wheel {ew} t_us {et}: mu {mu:.3g} sigma {sigma:.3g} "
                      f"state {('identifiable', 'not_identifiable', 'fallback')[state] if state < 3 else state} "
                      f"mu_min {mu_min:.3g} change {int(change)}")
            else:
                print(f"FAIL expected an Estimate after the forces, got type {t:#x}")
            fails += not ok

        # The four wheels in one batch, answered by one CompactResults; then the same samples
        # as single-wheel compact measurements (the same scaled values, so the same input to the
        # pipeline), each answered by Forces + Estimate. No Vx: the steady-state path, so the
        # forces do not depend on the order. The estimators have seen one sample more for the
        # singles, so the estimates are compared loosely.
        T_B = 50_000
        fields = {w: compact_fields(fz, -1000.0, 10.0, None, None, None, al, ka, None)
                  for w, fz, al, ka, _ in cases}
        send(ID_BATCH, batch(T_B, fields))
        body = rx.until(T_BATCH_RESULTS)
        bt, bw = decode_batch_results(body)
        ok = bt == T_B and all(w["present"] for w in bw)
        print(f"{'ok  ' if ok else 'FAIL'} batch of four wheels answered by one results message, t_us {bt}")
        fails += not ok
        for w, *_ in cases:
            send(ID_COMPACT, compact_measurement(w, T_B, fields[w]))
            t, body = rx.recv()
            if t != T_FORCES:
                print(f"FAIL wheel {w}: expected Forces, got type {t:#x}")
                fails += 1
                continue
            _, ft, fx, fy, mz, flags = decode_forces(body)
            t, body = rx.recv()
            est = decode_estimate(body) if t == T_ESTIMATE else None
            r = bw[w]
            ok = (ft == T_B and r["fx"] is not None and abs(r["fx"] - fx) <= 0.5 + 1e-3
                  and abs(r["fy"] - fy) <= 0.5 + 1e-3 and abs(r["mz"] - mz) <= 0.05 + 1e-4
                  and r["mf_flags"] == (flags != 0))
            if est is None:
                ok = False
            else:
                _, _, mu, sigma, state, mu_min, change = est
                ok = ok and r["mu"] is not None and abs(r["mu"] - mu) <= 0.1 and r["state"] in (0, 1, 2)
                ok = ok and r["mu_min"] is not None and r["mu_min"] <= mu_min + 0.1
            print(f"{'ok  ' if ok else 'FAIL'} batch wheel {w}: Fx {r['fx']} Fy {r['fy']} Mz {r['mz']} "
                  f"mu {r['mu']} sigma {r['sigma']} mu_min {r['mu_min']} state {r['state']} | single: "
                  f"Fx {fx:.7g} Fy {fy:.7g} Mz {mz:.7g}" + (f" mu {est[2]:.4g} sigma {est[3]:.4g} "
                  f"mu_min {est[5]:.3g} state {est[4]}" if est else " no estimate"))
            fails += not ok

        # Settings (v3: limits bool, fallback_mu f32, wheelbase f32): a wheelbase starts the
        # front-to-rear preview; a negative one is refused; back to none.
        for wheelbase, want in ((2.9, ACK_OK), (-2.9, ACK_BAD_SETTINGS), (0.0, ACK_OK)):
            body = ack(ID_CONFIG, signer.seal(ID_CONFIG, T_SETTINGS,
                                              bytes([1]) + struct.pack("<ff", 0.3, wheelbase)))
            of, _, code = body[0], body[1], body[2]
            ok = of == T_SETTINGS and code == want and len(body) == 3
            print(f"{'ok  ' if ok else 'FAIL'} settings with wheelbase {wheelbase} m: ack code {code} "
                  f"(expected {want})")
            fails += not ok

        # The calibration (v4): the device reports each running wheel's about once a second
        # (wheel u8, 4 values f32, 4 sigma f32, batches u32 LE); a SetCalibration is taken
        # (Ack Ok), one with a scale that is not positive refused (BadCalibration, code 11).
        reported = None
        deadline = time.time() + 5.0
        while reported is None and time.time() < deadline:
            send(ID_CONFIG, message(T_COMMAND, bytes([CMD_STATUS_REQUEST])))
            while True:
                t, body = rx.recv(calibration=True)
                if t == T_CALIBRATION:
                    reported = body
                if t == T_STATUS:
                    break
            time.sleep(0.1)
        ok = reported is not None and len(reported) == 37 and reported[0] < 4
        if ok:
            vals = struct.unpack("<8f", reported[1:33])
            ok = all(v > 0 for v in vals[:2]) and vals[3] > 0 and all(s >= 0 for s in vals[4:])
        print(f"{'ok  ' if ok else 'FAIL'} calibration reported: {reported.hex() if reported else None}")
        fails += not ok
        good = bytes([1]) + struct.pack("<8fI", 1.02, 0.99, 0.0005, 1.05, 0.02, 0.05, 0.001, 0.03, 7)
        bad = bytes([1]) + struct.pack("<8fI", -1.0, 0.99, 0.0005, 1.05, 0.02, 0.05, 0.001, 0.03, 7)
        for body_, want in ((good, ACK_OK), (bad, ACK_BAD_CALIBRATION)):
            body = ack(ID_CONFIG, signer.seal(ID_CONFIG, T_SET_CALIBRATION, body_))
            ok = body[0] == T_SET_CALIBRATION and body[2] == want and len(body) == 3
            print(f"{'ok  ' if ok else 'FAIL'} set calibration: ack code {body[2]} (expected {want})")
            fails += not ok

        # Unsigned, forged (a MAC byte flipped, the CRC made right), replayed: each refused with
        # its own code, and nothing changes.
        settings = bytes([1]) + struct.pack("<ff", 0.3, 2.5)
        replayed = signer.seal(ID_CONFIG, T_SETTINGS, settings)
        forged = bytearray(signer.seal(ID_CONFIG, T_SETTINGS, settings))
        forged[-5] ^= 1
        forged[-4:] = struct.pack("<I", zlib.crc32(bytes(forged[:-4])))
        for what, msg, want in (("accepted", replayed, ACK_OK),
                                ("unsigned", message(T_SETTINGS, settings), ACK_MAC_MISSING),
                                ("forged", bytes(forged), ACK_BAD_MAC),
                                ("replayed", replayed, ACK_STALE)):
            body = ack(ID_CONFIG, msg)
            ok = body[0] == T_SETTINGS and body[2] == want
            print(f"{'ok  ' if ok else 'FAIL'} settings {what}: ack code {body[2]} (expected {want})")
            fails += not ok

        # A damaged message: the device must drop it and count it.
        bad = bytearray(measurement(0, 99, 1.0, 1.0, 1.0, 1.0, 0.0, 0.0))
        bad[-1] ^= 0xFF
        send.frames(ID_MEASUREMENT, frames(bytes(bad), 200))
        send(ID_CONFIG, message(T_COMMAND, bytes([CMD_STATUS_REQUEST])))
        body = rx.until(T_STATUS)
        s = decode_status(body)
        ok = (s["bad_crc"] == 1 and s["messages"] == send.sent and s["proto"] == PROTO_VERSION
              and (s["auth_accepted"], s["auth_missing"], s["auth_bad_mac"], s["auth_stale"],
                   s["auth_no_key"]) == (6, 1, 1, 1, 0)
              # the forged message took the signer's last counter; the device never accepted it
              and (s["epoch"], s["counter"]) == (signer.epoch, signer.counter - 1))
        print(f"{'ok  ' if ok else 'FAIL'} status: {s}")
        fails += not ok

        send(ID_CONFIG, signer.seal(ID_CONFIG, T_COMMAND, bytes([CMD_STOP])))
        body = rx.until(T_STATUS)
    finally:
        bus.shutdown()
    print(f"python-can client: {fails} failed")
    return 1 if fails else 0


def connect(port):
    """The firmware's SLCAN bridge at `port` (retried while it starts), and whether Nagle's
    algorithm could be turned off.

    Each frame is one small socket write: with Nagle's algorithm on (pyserial's socket:// does
    not turn it off), the second frame of a message waits for the ACK of the first, which the
    peer may delay by 40 ms or more — beyond the device's 50 ms between the frames of one
    message (FRAME_TIMEOUT_MS), and the message is dropped as timed out. A CAN adapter would
    send the frames back to back; so does the host's own client (`set_nodelay`)."""
    bus = None
    for _ in range(100):
        try:
            bus = can.Bus(interface="slcan", channel=f"socket://127.0.0.1:{port}", sleep_after_open=0)
            break
        except Exception:
            time.sleep(0.1)
    assert bus is not None, "cannot connect to the firmware"
    sock = getattr(getattr(bus, "serialPortOrig", None), "_socket", None)
    if sock is not None:
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    return bus, sock is not None


def secure_all(a, key, mac_len=8):
    """The device provisioned with --secure-all: measurements signed, every answer checked."""
    bus, _ = connect(a.port)
    fails = 0
    send = Sender(bus)

    def check(ok, what):
        nonlocal fails
        print(f"{'ok  ' if ok else 'FAIL'} secure-all: {what}")
        fails += not ok

    try:
        # The status request is the one message the device takes unsigned (it synchronises the
        # freshness); its Status comes signed: checked from the counter it carries.
        raw = Receiver(bus)
        send(ID_CONFIG, message(T_COMMAND, bytes([CMD_STATUS_REQUEST])))
        body = raw.until(T_STATUS | SECURED)
        data = bytes([PROTO_VERSION, T_STATUS | SECURED]) + body
        (c0,) = struct.unpack("<I", data[-mac_len - 4:-mac_len])
        st = decode_status(body[:-mac_len - 4])
        v = AnswerVerifier(key, mac_len, st["epoch"], c0 - 1)
        check(v.open(ID_STATUS, data) is not None and st["mac_len"] == mac_len,
              f"the device's Status is signed and verifies (epoch {st['epoch']}, its counter {c0})")
        signer = Signer(key, mac_len, st["epoch"], st["counter"])
        rx = Receiver(bus, v)

        def forces_t():
            """The next Forces' t_us; only Estimates may come before it (no Ack: a refused
            measurement is not answered)."""
            while True:
                t, body = rx.recv()
                if t == T_FORCES:
                    return decode_forces(body)[1]
                assert t == T_ESTIMATE, f"unexpected answer type {t:#x}"

        meas = lambda t_us: measurement(1, t_us, 4000.0, -1000.0, 10.0, 20.0, 0.02, 0.01)
        sealed = lambda t_us: signer.seal(ID_MEASUREMENT, T_MEASUREMENT, meas(t_us)[2:-4])
        send(ID_MEASUREMENT, sealed(1))
        check(forces_t() == 1, "a signed measurement is answered by signed forces")
        forged = bytearray(sealed(101))
        forged[-5] ^= 1
        forged[-4:] = struct.pack("<I", zlib.crc32(bytes(forged[:-4])))
        send(ID_MEASUREMENT, meas(100))  # unsigned
        send(ID_MEASUREMENT, bytes(forged))
        send(ID_MEASUREMENT, sealed(2))
        check(forces_t() == 2, "an unsigned and a forged measurement are not answered")
        # An answer altered on the way (a body byte, the CRC made right) is refused here.
        before = v.refused
        send(ID_MEASUREMENT, sealed(3))
        while True:
            f = bus.recv(timeout=10.0)
            assert f is not None, "timed out"
            if f.arbitration_id == ID_RESULT:
                break
        # The first frame of the forces: alter it, then let the verifier judge the message.
        d = bytearray(f.data)
        d[5] ^= 0x10
        total = d[2]
        buf = bytearray(d[3:])
        while len(buf) < total:
            g = bus.recv(timeout=10.0)
            if g is not None and g.arbitration_id == ID_RESULT:
                buf += bytes(g.data)[2:]
        buf = bytes(buf[:total])
        check(v.open(ID_RESULT, buf[:-4]) is None and v.refused == before + 1,
              "an altered answer is refused by the client")
        send(ID_CONFIG, signer.seal(ID_CONFIG, T_COMMAND, bytes([CMD_STATUS_REQUEST])))
        body = rx.until(T_STATUS)
        s = decode_status(body)
        check((s["auth_missing"], s["auth_bad_mac"], s["auth_stale"]) == (1, 1, 0)
              and v.refused == 1,
              f"the device counted them (missing {s['auth_missing']}, bad MAC {s['auth_bad_mac']}); "
              f"answers verified, {v.refused} refused (the altered one)")
        send(ID_CONFIG, signer.seal(ID_CONFIG, T_COMMAND, bytes([CMD_STOP])))
        body = rx.until(T_STATUS)
    finally:
        bus.shutdown()
    print(f"python-can client (secure-all): {fails} failed")
    return 1 if fails else 0


if __name__ == "__main__":
    sys.exit(main())
