//! The authenticated decoder (`gough::proto::auth`): `Verifier::open`, the device's way in for
//! every message. Never a panic, and:
//! 1. arbitrary bytes (the CRC is not checked under `cfg(fuzzing)`) are decoded or refused; a
//!    refusal is counted in exactly one of the verifier's counters and moves no freshness; an
//!    accepted message is one that needs no MAC (the fuzzer cannot forge an AES-CMAC);
//! 2. whatever decodes, sealed by a `Signer` with the device's key, is accepted as the same
//!    message; the same bytes again are stale; the bytes with any one byte changed (the CRC
//!    made right, as an attacker would) are never accepted.
//!
//! The first input byte picks the MAC length (4..=8) and whether the counter starts near its
//! wrap; the second the byte changed in (2).
//!
//! Run: `cargo +nightly fuzz run auth_open -- -max_total_time=60`.
#![no_main]

use gough::proto::auth::{self, AuthStatus, Signer, Verifier};
use gough::proto::{crc32, id, Key, MacLen, Msg, MAX_MSG_LEN};
use libfuzzer_sys::fuzz_target;

const KEY: Key = Key::new(*b"gough fuzz key!!");

fn refusals(s: &AuthStatus) -> u32 {
    s.no_key + s.missing + s.bad_mac + s.stale
}

fuzz_target!(|data: &[u8]| {
    let [a, b, bytes @ ..] = data else { return };
    let mac_len = MacLen::new(4 + a % 5).unwrap();
    let start = if a & 0x80 != 0 {
        u32::MAX - 1
    } else {
        u32::from(*b)
    };
    let cid = id::CONFIG;

    // 1. Arbitrary bytes.
    let mut v = Verifier::new(KEY, mac_len, 7);
    v.set_counter(start);
    let before = *v.status();
    match v.open(cid, bytes) {
        Ok(m) => {
            assert!(!auth::is_state_changing(&m) && bytes[1] & auth::SECURED == 0);
            assert_eq!(*v.status(), before);
        }
        Err(Ok(_)) => {
            assert_eq!(refusals(v.status()), refusals(&before) + 1);
            assert_eq!((v.epoch(), v.status().counter), (7, start));
        }
        Err(Err(_)) => assert_eq!(*v.status(), before),
    }

    // 2. Sealed by the owner: accepted once, then stale; one byte changed: never accepted.
    let Ok(msg) = Msg::decode(bytes) else { return };
    let mut signer = Signer::new(KEY, mac_len, 7, start);
    let mut buf = [0u8; MAX_MSG_LEN];
    let Ok(n) = signer.seal(cid, &msg, &mut buf) else {
        return;
    };
    let sealed = &buf[..n];
    let mut v = Verifier::new(KEY, mac_len, 7);
    v.set_counter(start);
    let got = v
        .open(cid, sealed)
        .expect("the owner's message is accepted");
    let (mut e1, mut e2) = ([0u8; MAX_MSG_LEN], [0u8; MAX_MSG_LEN]);
    let (n1, n2) = (msg.encode(&mut e1).unwrap(), got.encode(&mut e2).unwrap());
    assert_eq!(e1[..n1], e2[..n2], "the same message");
    assert_eq!(v.status().accepted, 1);
    if start == u32::MAX - 1 {
        // Counter u32::MAX accepted: both ends move to the next epoch.
        assert_eq!((v.epoch(), v.status().counter), (8, 0));
        assert_eq!(signer.freshness(), (8, 0));
    }
    assert_eq!(
        v.open(cid, sealed).unwrap_err().map(|r| r.code).ok(),
        Some(if start == u32::MAX - 1 {
            gough::proto::AckCode::BadMac
        } else {
            gough::proto::AckCode::StaleFreshness
        })
    );
    let mut v = Verifier::new(KEY, mac_len, 7);
    v.set_counter(start);
    let mut changed = sealed.to_vec();
    let i = usize::from(*b) % (n - 4);
    changed[i] ^= 1 << (a % 8);
    let crc = crc32(&changed[..n - 4]).to_le_bytes();
    changed[n - 4..].copy_from_slice(&crc);
    if let Ok(m) = v.open(cid, &changed) {
        // Only by leaving the MAC out of play: the secured bit cleared on a message that needs
        // none (it then decodes only if nothing follows the body, which it does not).
        panic!("a changed secured message was accepted: {m:?}");
    }
});
