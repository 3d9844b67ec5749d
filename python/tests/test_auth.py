"""gough.Signer (the core's auth::Signer from Python) against an independent AES-CMAC
(`cryptography`): the secured layout of docs/protocol.md "Security", the counter and its wrap."""
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
