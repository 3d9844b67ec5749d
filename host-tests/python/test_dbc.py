"""The DBC files of `gough proto dbc` (classic) and `gough proto dbc --fd`, read by cantools in
strict mode, decode every frame that the host's encoder (the core's segmenter) puts on the bus
for a replay, into the values the host's reassembler decodes from the same frames.

Run by `cargo xtask test-all` in the project's venv:
    GOUGH=target/debug/gough python -m pytest host-tests/python/test_dbc.py
"""
import json
import os
import struct
import subprocess
from pathlib import Path

import cantools
import pytest

ROOT = Path(__file__).resolve().parents[2]
GOUGH = os.environ.get("GOUGH", str(ROOT / "target/debug/gough"))
TIR = ROOT / "host-tests/data/tyres/MagicFormula61_Parameters.tir"
LOG = ROOT / "examples/replay_log.csv"
KEY = ROOT / "firmware/keys/test.key"  # the TEST KEY: the calibrations sent back secured


def gough(*args):
    return subprocess.run([GOUGH, *args], check=True, capture_output=True, text=True).stdout


def load(fd, secure_all=False):
    text = gough("proto", "dbc", *(["--fd"] if fd else []), *(["--secure-all"] if secure_all else []))
    return cantools.database.load_string(text, database_format="dbc", strict=True)


def frames(fd, compact=False, batch=False, secured=False, secure_all=False):
    flags = (["--fd"] if fd else []) + (["--compact"] if compact else []) + (["--batch"] if batch else [])
    flags += ["--key-file", str(KEY)] if secured else []
    flags += ["--secure-all"] if secure_all else []
    out = gough("proto", "frames", "--tir", str(TIR), "--log", str(LOG), *flags)
    return [json.loads(line) for line in out.splitlines()]


WHEELS = ["FrontLeft", "FrontRight", "RearLeft", "RearRight"]


def f32(x):
    """A JSON number (an f32 printed as f64) as the f32 it was."""
    return struct.unpack("<f", struct.pack("<f", x))[0]


def payload(sig, prefix, n_bytes_total):
    """The message bytes of `prefix*` byte signals (little-endian integers of ≤ 8 bytes)."""
    keys = sorted((k for k in sig if k.startswith(prefix)), key=lambda k: int(k.rsplit("_", 1)[1]) if k != prefix else 0)
    out = b""
    for k in keys:
        n = min(8, n_bytes_total - len(out))
        out += int(sig[k]).to_bytes(n, "little")
    return out


# The compact measurement's physical signals: name in the DBC, field, scale.
COMPACT = [("Fz", "fz", 0.5), ("Fy", "fy", 1.0), ("Mz", "mz", 0.1), ("Fx", "fx", 1.0),
           ("vx", "vx", 0.01), ("omega", "omega", 0.01), ("alpha", "alpha", 1e-4),
           ("kappa", "kappa", 1e-4), ("gamma", "gamma", 1e-4)]


@pytest.mark.parametrize("fd,compact,batch,secured,secure_all",
                         [(False, False, False, False, False), (True, False, False, False, False),
                          (False, True, False, False, False), (True, True, False, False, False),
                          (False, False, True, False, False), (True, False, True, False, False),
                          (False, False, False, True, False), (True, False, False, True, False),
                          (False, False, False, True, True), (True, False, False, True, True),
                          (True, True, False, True, True), (True, False, True, True, True)],
                         ids=["classic", "fd", "classic-compact", "fd-compact", "classic-batch",
                              "fd-batch", "classic-secured", "fd-secured", "classic-secure-all",
                              "fd-secure-all", "fd-compact-secure-all", "fd-batch-secure-all"])
def test_every_frame_decodes_to_the_hosts_values(fd, compact, batch, secured, secure_all):
    db = load(fd, secure_all)
    msgs = frames(fd, compact, batch, secured, secure_all)
    assert len(msgs) > (150 if batch else 500)
    seen = set()
    for m in msgs:
        dbm = db.get_message_by_frame_id(m["id"])
        assert dbm.is_fd == fd
        got = b""
        for k, h in enumerate(m["frames"]):
            data = bytes.fromhex(h)
            assert len(data) == dbm.length
            sig = dbm.decode(data)  # strict: exact length, every multiplexer value known
            assert sig["frame_index"] == k
            assert sig["first_frame"] == (k == 0)
            assert sig["last_frame"] == (k == len(m["frames"]) - 1)
            if k == 0:
                assert sig["msg_len"] == len(m["encoded"]) // 2
                assert sig["proto_version"] == 5
                assert str(sig["msg_type"]) == m["type"]
                sec = f"{m['type']}_bytes"  # a secured type's first frame on CAN FD
                if any(s.startswith("first_bytes") or s.startswith(sec) for s in sig):
                    raw = dbm.decode(data, decode_choices=False)
                    got = bytes([raw["proto_version"], raw["msg_type"]])
                    pre = "first_bytes" if any(s.startswith("first_bytes") for s in sig) else sec
                    got += payload(raw, pre, dbm.length - 5)
                else:  # FD results: the body as physical signals, checked below
                    got = data[3:]
            else:
                got += payload(sig, "next_bytes", dbm.length - 2)
            seen.add((m["type"], k > 0))
        if m["type"] in ("Calibration", "SetCalibration", "SetCalibrationSecured"):
            # 37 body bytes at fixed offsets: wheel, 4 + 4 f32, batches u32 LE.
            body = bytes.fromhex(m["encoded"])[2:2 + 37]
            want = m["msg"]
            assert len(body) == 37
            assert WHEELS[body[0]] == want["wheel"]
            vals = struct.unpack("<8f", body[1:33])
            assert list(vals) == [f32(x) for x in want["value"] + want["sigma"]]
            assert int.from_bytes(body[33:37], "little") == want["batches"]
        if m["type"].endswith("Secured"):
            # Every secured message: the counter (u32 LE) and the 8-byte MAC between the body
            # and the CRC, in the bytes the DBC's signals carried.
            enc = bytes.fromhex(m["encoded"])
            assert enc[1] & 0x40 and got[1] == enc[1]
            assert int.from_bytes(got[len(enc) - 16:len(enc) - 12], "little") == m["secured"]["counter"]
            assert got[len(enc) - 12:len(enc) - 4].hex() == m["secured"]["mac"]
            seen.add(("Secured", m["id"]))
        if m["type"] == "SetCalibrationSecured":
            # Secured (type | 0x40): counter u32 LE and the 8-byte MAC after the body; on CAN FD
            # signals of their own.
            enc = bytes.fromhex(m["encoded"])
            assert enc[1] & 0x40 and len(enc) == 2 + 37 + 4 + 8 + 4
            assert int.from_bytes(enc[39:43], "little") == m["secured"]["counter"]
            assert enc[43:51].hex() == m["secured"]["mac"]
            if fd:
                sig = dbm.decode(bytes.fromhex(m["frames"][0]))
                pre = m["type"]
                assert sig[f"{pre}_freshness"] == m["secured"]["counter"]
                assert sig[f"{pre}_mac"] == int.from_bytes(enc[43:51], "little")
                assert sig[f"{pre}_crc"] == int.from_bytes(enc[-4:], "little")
                seen.add(("SecuredPhysical", False))
        # The byte signals carry the message exactly (what the host encoded and decoded).
        assert got[: len(m["encoded"]) // 2] == bytes.fromhex(m["encoded"])
        if fd and m["type"] in ("Forces", "Estimate"):
            sig = dbm.decode(bytes.fromhex(m["frames"][0]))
            want = m["msg"]
            pre = m["type"].lower()
            assert str(sig[f"{pre}_wheel"]) == want["wheel"]
            assert sig[f"{pre}_t_us"] == want["t_us"]
            if m["type"] == "Forces":
                for s, f in (("Fx", "fx"), ("Fy", "fy"), ("Mz", "mz")):
                    assert sig[s] == f32(want[f]), (s, sig[s], want[f])
                assert sig["forces_flags"] == want["flags"]
            else:
                assert sig["mu"] == f32(want["mu"])
                assert sig["sigma"] == f32(want["sigma"])
                assert str(sig["state"]) == want["state"]
                assert sig["mu_min"] == f32(want["mu_min"])
                raw = dbm.decode(bytes.fromhex(m["frames"][0]), decode_choices=False)
                assert raw["change"] == int(want["change"])
                assert raw["mismatch"] == int(want["mismatch"])
            enc = bytes.fromhex(m["encoded"])
            assert sig[f"{pre}_crc"] == int.from_bytes(enc[-4:], "little")
        if fd and m["type"] == "CompactMeasurement":
            data = bytes.fromhex(m["frames"][0])
            sig = dbm.decode(data)
            raw = dbm.decode(data, scaling=False)
            want = m["msg"]
            assert str(sig["wheel"]) == want["wheel"]
            assert sig["t_us"] == want["t_us"]
            for s, f, scale in COMPACT:
                assert raw[s] == want[f], (s, raw[s], want[f])
                assert sig[s] == pytest.approx(want[f] * scale, rel=1e-12, abs=1e-12)
            seen.add(("CompactPhysical", False))
        if fd and m["type"] == "CompactResults":
            data = bytes.fromhex(m["frames"][0])
            assert len(m["frames"]) == 1 and len(data) == 64
            sig = dbm.decode(data)
            raw = dbm.decode(data, scaling=False, decode_choices=False)
            want = m["msg"]
            assert sig["results_t_us"] == want["t_us"]
            enc = bytes.fromhex(m["encoded"])
            assert sig["results_crc"] == int.from_bytes(enc[-4:], "little")
            for w, name in zip(want["wheels"], ("FL", "FR", "RL", "RR")):
                for s, scale in (("Fx", 1.0), ("Fy", 1.0), ("Mz", 0.1), ("mu", 1e-4),
                                 ("sigma", 1e-4), ("mu_min", 0.01)):
                    assert raw[f"{name}_{s}"] == w[s.lower() if s != "mu_min" else s]
                    assert sig[f"{name}_{s}"] == pytest.approx(raw[f"{name}_{s}"] * scale, rel=1e-9)
                st = w["status"]
                assert raw[f"{name}_state"] == st & 3
                assert raw[f"{name}_change"] == (st >> 2) & 1
                assert raw[f"{name}_mf_flags"] == (st >> 3) & 1
                assert raw[f"{name}_present"] == (st >> 4) & 1
                assert raw[f"{name}_mismatch"] == (st >> 5) & 1
                if st & 16:
                    assert str(sig[f"{name}_present"]) == "Present"
                    seen.add(("ResultsPhysical", str(sig[f"{name}_state"])))
    # What the replay puts on the bus: measurements, forces, estimates; continuation frames
    # on classic CAN.
    kinds = {t for t, _ in seen}
    if secure_all:
        # Every identifier's messages came secured, measurements and answers too.
        ids = {k for t, k in seen if t == "Secured"}
        assert ids == {m["id"] for m in msgs} and all(m["type"].endswith("Secured") for m in msgs)
        assert len(ids) >= 2, ids
        return
    if batch:
        assert {"CompactBatch", "CompactResults"} == kinds - {"ResultsPhysical"}
        assert ("CompactBatch", True) in seen  # two frames (FD) or 14 (classic)
        if fd:
            states = {k for t, k in seen if t == "ResultsPhysical"}
            assert len(states) >= 2, states
        return
    meas = "CompactMeasurement" if compact else "Measurement"
    set_cal = "SetCalibrationSecured" if secured else "SetCalibration"
    assert {meas, "Forces", "Estimate", "Calibration", set_cal} <= kinds
    if secured and fd:
        assert ("SecuredPhysical", False) in seen
    if not fd:
        assert (meas, True) in seen and ("Estimate", True) in seen
    if fd and compact:
        assert ("CompactPhysical", False) in seen


def test_fd_estimate_states_are_named():
    db = load(True)
    states = {str(m["msg"]["state"]) for m in frames(True) if m["type"] == "Estimate"}
    assert len(states) >= 2, states
    choices = {str(v) for v in db.get_message_by_name("GOUGH_RESULT").get_signal_by_name("state").choices.values()}
    assert choices == {"Identifiable", "NotIdentifiable", "Fallback"}
    change = db.get_message_by_name("GOUGH_RESULT").get_signal_by_name("change")
    assert {str(v) for v in change.choices.values()} == {"NoChange", "Change"}
