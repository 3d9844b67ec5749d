//! The authenticated decoder (`gough::proto::auth`): `Verifier::open`, the device's way in for
//! every message. Never a panic, and:
//! 1. arbitrary bytes (the CRC is not checked under `cfg(fuzzing)`) are decoded or refused; a
//!    refusal is counted in exactly one of the verifier's counters and moves no freshness; an
//!    accepted message is one that needs no MAC (the fuzzer cannot forge an AES-CMAC);
//! 2. whatever decodes, sealed by a `Signer` with the device's key, is accepted as the same
//!    message; the same bytes again are stale; the bytes with any one byte changed (the CRC
//!    made right, as an attacker would) are never accepted.
//!
//! 3. with every message authenticated (`Policy::All`): the same arbitrary bytes on a
//!    measurement identifier are accepted only when unsecured and a status request (the one
//!    message the policy lets through); whatever decodes, secured by the device
//!    (`Verifier::seal`, its own counter), is accepted once by a tool's verifier on the
//!    identifier it was sent on, stale the second time, and refused on another identifier or
//!    with any one byte changed.
//!
//! The first input byte picks the MAC length (4..=8) and whether the counter starts near its
//! wrap; the second the byte changed in (2) and (3).
//!
//! Run: `cargo +nightly fuzz run auth_open -- -max_total_time=60`.
#![no_main]

use gough::proto::auth::{self, AuthStatus, Signer, Verifier};
use gough::proto::{crc32, id, AckCode, Command, Key, MacLen, Msg, Policy, MAX_MSG_LEN};
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

    // 3. Every message authenticated: arbitrary bytes on the measurement identifier, then the
    // device's own answers through a tool's verifier.
    let all = |counter: u32| {
        let mut v = Verifier::new(KEY, mac_len, 7).with_policy(Policy::All);
        v.set_counter(counter);
        v
    };
    let mut v = all(start);
    if let Ok(m) = v.open(id::MEASUREMENT, bytes) {
        assert!(
            m == Msg::Command(Command::StatusRequest) && bytes[1] & auth::SECURED == 0,
            "accepted under Policy::All without a MAC: {m:?}"
        );
    }
    let mut device = all(start);
    let mut out = [0u8; MAX_MSG_LEN];
    let sent_on = id::of(msg.msg_type());
    let Ok(n) = device.seal(sent_on, &msg, &mut out) else {
        return;
    };
    let answer = &out[..n];
    assert!(answer[1] & auth::SECURED != 0);
    // The tool continues above the device's counter before this message.
    let mut tool = all(0);
    assert_eq!(
        tool.open(if sent_on == id::RESULT { id::STATUS } else { id::RESULT }, answer)
            .unwrap_err()
            .map(|r| r.code)
            .ok(),
        Some(AckCode::BadMac),
        "another identifier"
    );
    let mut tool = all(0);
    let got = tool.open(sent_on, answer).expect("the device's answer verifies");
    let (mut e1, mut e2) = ([0u8; MAX_MSG_LEN], [0u8; MAX_MSG_LEN]);
    let (n1, n2) = (msg.encode(&mut e1).unwrap(), got.encode(&mut e2).unwrap());
    assert_eq!(e1[..n1], e2[..n2], "the same message");
    assert!(tool.open(sent_on, answer).is_err(), "replayed answer accepted");
    let mut changed = answer.to_vec();
    let i = usize::from(*b) % (n - 4);
    changed[i] ^= 1 << (a % 8);
    let crc = crc32(&changed[..n - 4]).to_le_bytes();
    changed[n - 4..].copy_from_slice(&crc);
    if let Ok(m) = all(0).open(sent_on, &changed) {
        panic!("a changed answer was accepted: {m:?}");
    }
});
