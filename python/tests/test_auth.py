"""gough.Signer (the core's auth::Signer from Python) against an independent AES-CMAC
(`cryptography`): the secured layout of docs/protocol.md "Security", the counter and its wrap;
gough.Verifier (the core's auth::Verifier) on answers secured by that independent CMAC."""
import struct
import zlib
from pathlib import Path

import pytest
from cryptography.hazmat.primitives.cmac import CMAC
from cryptography.hazmat.primitives.ciphers import algorithms

import gough

ROOT = Path(__file__).resolve().parents[2]
ID_CONFIG = 0x301


def settings(wheelbase):
    data = bytes([5, 0x05, 1]) + struct.pack("<ff", 0.3, wheelbase)
    return data + struct.pack("<I", zlib.crc32(data))


def cmac(key, data):
    c = CMAC(algorithms.AES(key))
    c.update(data)
    return c.finalize()


def test_a_sealed_message_is_the_documented_layout_with_an_independent_mac():
    key = gough.read_key(ROOT / "firmware/keys/test.key")
    s = gough.Signer(key, epoch=3, counter=41, mac_len=6)
    plain = settings(2.9)
    out = s.seal(ID_CONFIG, plain)
    n = len(plain) - 4
    assert out[0] == 5 and out[1] == 0x45 and out[2:n] == plain[2:n]
    assert struct.unpack("<I", out[n:n + 4])[0] == 42
    mac = cmac(key, struct.pack("<H", ID_CONFIG) + out[:n + 4] + struct.pack("<I", 3))[:6]
    assert out[n + 4:n + 10] == mac
    assert struct.unpack("<I", out[-4:])[0] == zlib.crc32(out[:-4]) and len(out) == n + 14
    assert (s.epoch, s.counter) == (3, 42)
    assert s.seal(ID_CONFIG, plain)[n:n + 4] == struct.pack("<I", 43)


def test_the_counter_never_wraps_and_bad_input_is_refused():
    s = gough.Signer(bytes(16), epoch=7, counter=2**32 - 2)
    s.seal(ID_CONFIG, settings(0.0))
    assert (s.epoch, s.counter) == (8, 0)
    with pytest.raises(ValueError):
        s.seal(ID_CONFIG, settings(0.0)[:-1])  # not a message (CRC)
    with pytest.raises(ValueError):
        gough.Signer(bytes(15), epoch=1)
    with pytest.raises(ValueError):
        gough.Signer(bytes(16), epoch=1, mac_len=9).seal(ID_CONFIG, settings(0.0))


ID_RESULT, ID_STATUS = 0x310, 0x311


def forces(t_us):
    data = bytes([5, 0x81, 1]) + struct.pack("<IfffH", t_us, -812.5, 2310.25, -40.5, 0)
    return data + struct.pack("<I", zlib.crc32(data))


def device_seal(key, cid, plain, epoch, counter, mac_len=8):
    """A device's secured answer, by `cryptography` alone (the layout of docs/protocol.md)."""
    data = bytes([plain[0], plain[1] | 0x40]) + plain[2:-4] + struct.pack("<I", counter)
    data += cmac(key, struct.pack("<H", cid) + data + struct.pack("<I", epoch))[:mac_len]
    return data + struct.pack("<I", zlib.crc32(data))


def test_the_verifier_checks_answers_secured_by_an_independent_cmac():
    key = gough.read_key(ROOT / "firmware/keys/test.key")
    v = gough.Verifier(key, epoch=2, counter=10)
    a = device_seal(key, ID_RESULT, forces(1), 2, 11)
    assert v.open(ID_RESULT, a) == forces(1)
    # Per identifier: an Ack with counter 13 on 0x311 delivered before forces 12 on 0x310.
    ack = bytes([5, 0x84, 5, 0, 0])
    ack += struct.pack("<I", zlib.crc32(ack))
    assert v.open(ID_STATUS, device_seal(key, ID_STATUS, ack, 2, 13)) == ack
    assert v.open(ID_RESULT, device_seal(key, ID_RESULT, forces(2), 2, 12)) == forces(2)
    for msg, cid, code in (
        (a, ID_RESULT, "StaleFreshness"),  # replayed
        (device_seal(key, ID_RESULT, forces(3), 1, 14), ID_RESULT, "BadMac"),  # old epoch
        (device_seal(bytes(16), ID_RESULT, forces(3), 2, 14), ID_RESULT, "BadMac"),  # other key
        (device_seal(key, ID_RESULT, forces(3), 2, 14), ID_STATUS, "BadMac"),  # other id
        (device_seal(key, ID_RESULT, forces(3), 2, 14, mac_len=4), ID_RESULT, "BadMac"),
        (forces(3), ID_RESULT, "MacMissing"),  # unsigned
        (device_seal(key, ID_RESULT, forces(3), 2, 14 + 65536), ID_RESULT, "StaleFreshness"),
    ):
        with pytest.raises(gough.Refused) as e:
            v.open(cid, msg)
        assert e.value.code == code
    altered = bytearray(device_seal(key, ID_RESULT, forces(4), 2, 14))
    altered[4] ^= 1
    altered[-4:] = struct.pack("<I", zlib.crc32(bytes(altered[:-4])))
    with pytest.raises(gough.Refused):
        v.open(ID_RESULT, bytes(altered))
    assert v.counts() == dict(accepted=3, missing=1, bad_mac=5, stale=2, epoch=2, counter=13)
    assert v.open(ID_RESULT, device_seal(key, ID_RESULT, forces(4), 2, 14)) == forces(4)
    with pytest.raises(ValueError):
        v.open(ID_RESULT, a[:-1])  # not a message (CRC)
