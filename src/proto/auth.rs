//! Authenticated messages (AUTOSAR SecOC style): who may reconfigure the device.
//!
//! Threat: a node on the bus reads, injects, replays, delays and drops frames, but does not know
//! the device's 16-byte key. Every state-changing message ([`is_state_changing`]: the tyre
//! upload, `Settings`, `SetCalibration`, `Command::Reset` and `Command::Stop`) must then be
//! *secured*: its type byte has bit 6 set ([`SECURED`]) and the body is followed by the
//! transmitted freshness counter (u32 LE) and a MAC truncated to [`MacLen`] (4–8) bytes, inside
//! the CRC-32:
//!
//! `[PROTO_VERSION][type | 0x40][postcard body][counter u32 LE][MAC, 4..=8 bytes][CRC-32 LE]`
//!
//! The MAC is AES-128-CMAC (NIST SP 800-38B, RustCrypto `aes` + `cmac`), left-truncated, over
//! the CAN identifier (2 bytes LE), the message from its version byte through the counter, and
//! the epoch (4 bytes LE): `CMAC(K, id ‖ version ‖ type ‖ body ‖ counter ‖ epoch)`. The
//! freshness value is the 64-bit pair (epoch, counter); only its low half (the counter) is sent
//! (SecOC's truncated freshness value).
//!
//! **Freshness.** The device's *epoch* is a boot counter kept in its non-volatile memory, raised
//! once per boot (so a message of an earlier boot never verifies again) and once per counter
//! wrap; within an epoch the device accepts a counter only if it is above the last one it
//! accepted and at most [`WINDOW`] above it (a replayed, reordered or duplicated message is
//! stale). Having accepted counter `u32::MAX` the device moves to epoch + 1 and counter 0, and so
//! does the [`Signer`]: the counter never wraps within an epoch. The epoch and the last accepted
//! counter are public (`Status::auth`): a sender that starts reads them and continues.
//!
//! Checked in order by [`Verifier::open`]: a device without a key refuses every
//! state-changing (and every secured) message ([`AckCode::NoKey`]); an unsecured state-changing
//! message is refused ([`AckCode::MacMissing`]); a MAC of the wrong length or value is refused
//! ([`AckCode::BadMac`], compared in constant time); then the freshness
//! ([`AckCode::StaleFreshness`]). Each refusal is counted in [`AuthStatus`]; nothing a refused
//! message carried takes effect.

use super::{AckCode, Command, Error, Msg, MsgType};
use aes::Aes128;
use cmac::digest::generic_array::GenericArray;
use cmac::digest::KeyInit;
use cmac::{Cmac, Mac};
use core::fmt;
use postcard::experimental::max_size::MaxSize;
use serde::{Deserialize, Serialize};

/// Bytes of a device key (AES-128).
pub const KEY_LEN: usize = 16;
/// Bit of the header's type byte that marks a secured message (a counter and a MAC follow the
/// body). No [`MsgType`] has it.
pub const SECURED: u8 = 0x40;
/// Bytes of the transmitted freshness counter.
pub const COUNTER_LEN: usize = 4;
/// Shortest MAC \[bytes\].
pub const MAC_LEN_MIN: u8 = 4;
/// Longest MAC \[bytes\].
pub const MAC_LEN_MAX: u8 = 8;
/// Longest trailer (counter + MAC) a secured message adds \[bytes\].
pub const TRAILER_MAX: usize = COUNTER_LEN + MAC_LEN_MAX as usize;
/// A counter is fresh when it is above the last accepted one by at most this much.
pub const WINDOW: u32 = 1 << 16;

/// A device key: 16 bytes. Its `Debug` does not show it.
#[derive(Clone, Copy, PartialEq, Eq)]
pub struct Key([u8; KEY_LEN]);

impl fmt::Debug for Key {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("Key(..)")
    }
}

impl Key {
    /// The key of these bytes.
    pub const fn new(bytes: [u8; KEY_LEN]) -> Key {
        Key(bytes)
    }

    /// The key of a key file's text: 32 hexadecimal digits on one line; blank lines and lines
    /// starting with `#` (comments) are skipped. `None` for anything else.
    pub fn from_hex(text: &str) -> Option<Key> {
        let mut lines = text
            .lines()
            .map(str::trim)
            .filter(|l| !l.is_empty() && !l.starts_with('#'));
        let hex = lines.next()?.as_bytes();
        if lines.next().is_some() || hex.len() != 2 * KEY_LEN {
            return None;
        }
        let mut k = [0u8; KEY_LEN];
        for (b, pair) in k.iter_mut().zip(hex.chunks_exact(2)) {
            let digit = |c: u8| {
                char::from(c)
                    .to_digit(16)
                    .and_then(|d| u8::try_from(d).ok())
            };
            *b = digit(*pair.first()?)? << 4 | digit(*pair.get(1)?)?;
        }
        Some(Key(k))
    }

    /// AES-128-CMAC keyed with this key: the AES key schedule and the CMAC subkeys computed
    /// once, cloned for each message ([`tag`]).
    fn keyed(&self) -> Cmac<Aes128> {
        <Cmac<Aes128> as KeyInit>::new(&GenericArray::from(self.0))
    }

    /// The full (16-byte) AES-128-CMAC of `data` (NIST SP 800-38B), for the test vectors.
    pub fn cmac_raw(&self, data: &[u8]) -> [u8; 16] {
        let mut m = self.keyed();
        m.update(data);
        m.finalize().into_bytes().into()
    }
}

/// The length a MAC is truncated to: 4..=8 bytes ([`MAC_LEN_MIN`], [`MAC_LEN_MAX`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct MacLen(u8);

impl MacLen {
    /// 8 bytes (64 bits): a forgery succeeds with probability 2⁻⁶⁴ per try.
    pub const DEFAULT: MacLen = MacLen(MAC_LEN_MAX);
    /// `n` bytes, if 4..=8.
    pub const fn new(n: u8) -> Option<MacLen> {
        if n >= MAC_LEN_MIN && n <= MAC_LEN_MAX {
            Some(MacLen(n))
        } else {
            None
        }
    }
    /// Bytes.
    pub const fn get(self) -> usize {
        self.0 as usize
    }
}

/// The message types that can change the device's state (all on `id::CONFIG`; a `Command` only
/// when `Reset` or `Stop`): the types a secured message may have.
pub const STATE_CHANGING_TYPES: [MsgType; 6] = [
    MsgType::ParamBegin,
    MsgType::ParamChunk,
    MsgType::ParamCommit,
    MsgType::Settings,
    MsgType::Command,
    MsgType::SetCalibration,
];

/// Whether a message changes the device's state (and so must be secured): the tyre upload,
/// `Settings`, `SetCalibration`, `Command::Reset` and `Command::Stop`. Measurements, status
/// requests and the device's answers are not.
pub const fn is_state_changing(msg: &Msg) -> bool {
    matches!(
        msg,
        Msg::ParamBegin(_)
            | Msg::ParamChunk(_)
            | Msg::ParamCommit(_)
            | Msg::Settings(_)
            | Msg::SetCalibration(_)
            | Msg::Command(Command::Reset | Command::Stop)
    )
}

/// The trailer of a secured message, as [`Msg::decode_secured`] finds it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Trailer<'a> {
    /// What the MAC covers (with the identifier before and the epoch after): the message from
    /// its version byte through the counter.
    pub data: &'a [u8],
    /// The transmitted freshness counter.
    pub counter: u32,
    /// The truncated MAC.
    pub mac: &'a [u8],
}

/// The device's authentication state and counters, reported in `Status::auth`.
#[derive(Serialize, Deserialize, MaxSize, Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct AuthStatus {
    /// MAC length the device expects \[bytes\]; 0: the device has no key (it refuses every
    /// state-changing message).
    pub mac_len: u8,
    /// The current epoch (boot counter).
    #[serde(with = "postcard::fixint::le")]
    pub epoch: u32,
    /// The last counter accepted in this epoch (0: none yet); a sender continues above it.
    #[serde(with = "postcard::fixint::le")]
    pub counter: u32,
    /// Secured messages accepted.
    pub accepted: u32,
    /// Refused: the device has no key ([`AckCode::NoKey`]).
    pub no_key: u32,
    /// Refused: a state-changing message not secured ([`AckCode::MacMissing`]).
    pub missing: u32,
    /// Refused: a MAC of the wrong length or value ([`AckCode::BadMac`]).
    pub bad_mac: u32,
    /// Refused: a counter not above the last accepted one, or too far above it
    /// ([`AckCode::StaleFreshness`]).
    pub stale: u32,
}

/// A message the [`Verifier`] refused: its type (for the `Ack`) and why.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Refused {
    /// The refused message's type.
    pub of: MsgType,
    /// Why: [`AckCode::NoKey`], [`AckCode::MacMissing`], [`AckCode::BadMac`] or
    /// [`AckCode::StaleFreshness`].
    pub code: AckCode,
}

/// The receiving end (the device): checks secured messages against its key and freshness.
/// Keeps the keyed CMAC (the AES round keys and CMAC subkeys: 400 bytes on the M4F, computed
/// once in [`Verifier::new`]); its `Debug` does not show them.
#[derive(Clone)]
pub struct Verifier {
    key: Option<(Cmac<Aes128>, MacLen)>,
    status: AuthStatus,
}

impl fmt::Debug for Verifier {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Verifier")
            .field("key", &self.key.as_ref().map(|_| "..."))
            .field("status", &self.status)
            .finish()
    }
}

impl Default for Verifier {
    fn default() -> Self {
        Self::without_key()
    }
}

impl Verifier {
    /// A device without a key: every state-changing message is refused ([`AckCode::NoKey`]).
    pub const fn without_key() -> Verifier {
        Verifier {
            key: None,
            status: AuthStatus {
                mac_len: 0,
                epoch: 0,
                counter: 0,
                accepted: 0,
                no_key: 0,
                missing: 0,
                bad_mac: 0,
                stale: 0,
            },
        }
    }

    /// A device with `key`, expecting MACs of `mac_len` bytes, in `epoch` (this boot's value of
    /// the non-volatile boot counter: never one an earlier boot used), no counter accepted yet.
    pub fn new(key: Key, mac_len: MacLen, epoch: u32) -> Verifier {
        let mut v = Verifier::without_key();
        v.key = Some((key.keyed(), mac_len));
        v.status.mac_len = mac_len.0;
        v.status.epoch = epoch;
        v
    }

    /// State and counters.
    pub const fn status(&self) -> &AuthStatus {
        &self.status
    }

    /// The current epoch (it moves on after counter `u32::MAX`: the board stores it then).
    pub const fn epoch(&self) -> u32 {
        self.status.epoch
    }

    /// Sets the last accepted counter (tests of the counter wrap).
    pub fn set_counter(&mut self, counter: u32) {
        self.status.counter = counter;
    }

    /// Decodes the complete encoded message `bytes` received on identifier `id` and checks it
    /// ([`Verifier::check`]): `Ok(msg)` to act on; `Err(Ok(refused))` for a message refused
    /// (counted; answer it with an `Ack` of `refused.code`); `Err(Err(e))` for bytes that do not
    /// decode.
    pub fn open(&mut self, id: u16, bytes: &[u8]) -> Result<Msg, Result<Refused, Error>> {
        let msg = Msg::decode(bytes).map_err(Err)?;
        self.check(id, &msg, bytes).map_err(Ok)?;
        Ok(msg)
    }

    /// Checks `msg`, decoded from the complete encoded message `bytes` received on identifier
    /// `id` (what a `Reassembler` delivered, and its `last()` bytes): `Ok(())` to act on it,
    /// else why it is refused (counted). Order (module doc): no key, not secured, MAC (its
    /// length and value, constant time), freshness. An unsecured message that does not change
    /// the state passes at no cost.
    pub fn check(&mut self, id: u16, msg: &Msg, bytes: &[u8]) -> Result<(), Refused> {
        let secured = bytes.get(1).is_some_and(|t| t & SECURED != 0);
        if !secured && !is_state_changing(msg) {
            return Ok(());
        }
        let of = msg.msg_type();
        let s = &mut self.status;
        let Some((key, len)) = &self.key else {
            s.no_key = s.no_key.wrapping_add(1);
            return Err(Refused {
                of,
                code: AckCode::NoKey,
            });
        };
        if !secured {
            s.missing = s.missing.wrapping_add(1);
            return Err(Refused {
                of,
                code: AckCode::MacMissing,
            });
        }
        // The trailer where this device's MAC length puts it: [data ‖ counter][MAC][CRC]. A
        // sender with another MAC length gets a MAC that does not verify.
        let end = bytes.len().saturating_sub(4);
        let trailer = end.checked_sub(len.get()).and_then(|m| {
            let counter = bytes.get(m.checked_sub(COUNTER_LEN)?..m)?;
            Some(Trailer {
                data: bytes.get(..m)?,
                counter: u32::from_le_bytes(counter.try_into().ok()?),
                mac: bytes.get(m..end)?,
            })
        });
        let Some(t) = trailer.filter(|t| {
            tag(key, id, t.data, s.epoch)
                .verify_truncated_left(t.mac)
                .is_ok()
        }) else {
            s.bad_mac = s.bad_mac.wrapping_add(1);
            return Err(Refused {
                of,
                code: AckCode::BadMac,
            });
        };
        if t.counter <= s.counter || t.counter.wrapping_sub(s.counter) > WINDOW {
            s.stale = s.stale.wrapping_add(1);
            return Err(Refused {
                of,
                code: AckCode::StaleFreshness,
            });
        }
        s.accepted = s.accepted.wrapping_add(1);
        if t.counter == u32::MAX {
            // The counter never wraps: the next epoch (the board stores it).
            s.epoch = s.epoch.saturating_add(1);
            s.counter = 0;
        } else {
            s.counter = t.counter;
        }
        Ok(())
    }
}

/// The sending end (the owner's tool): secures messages with the next freshness value. Its
/// `Debug` does not show the key.
#[derive(Clone)]
pub struct Signer {
    key: Cmac<Aes128>,
    mac_len: MacLen,
    epoch: u32,
    counter: u32,
}

impl fmt::Debug for Signer {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Signer")
            .field("mac_len", &self.mac_len)
            .field("epoch", &self.epoch)
            .field("counter", &self.counter)
            .finish()
    }
}

impl Signer {
    /// Signs with `key` and MACs of `mac_len` bytes for a device in `epoch` whose last accepted
    /// counter is `counter` (both from its `Status::auth`).
    pub fn new(key: Key, mac_len: MacLen, epoch: u32, counter: u32) -> Signer {
        Signer {
            key: key.keyed(),
            mac_len,
            epoch,
            counter,
        }
    }

    /// The freshness value (epoch, counter) of the last message secured.
    pub const fn freshness(&self) -> (u32, u32) {
        (self.epoch, self.counter)
    }

    /// Encodes `msg`, to be sent on identifier `id`, secured with the next counter into `out`;
    /// returns the length. [`Error::Overflow`] if `out` is too short (a buffer of
    /// [`super::MAX_MSG_LEN`] never is). After counter `u32::MAX` the signer moves to the next
    /// epoch, as the device does.
    pub fn seal(&mut self, id: u16, msg: &Msg, out: &mut [u8]) -> Result<usize, Error> {
        let n = msg.encode(out)?;
        let body_end = n.checked_sub(4).ok_or(Error::Overflow)?;
        let counter = self.counter.saturating_add(1);
        let data_end = body_end.saturating_add(COUNTER_LEN);
        let mac_end = data_end.saturating_add(self.mac_len.get());
        let total = mac_end.saturating_add(4);
        if out.len() < total {
            return Err(Error::Overflow);
        }
        if let Some(t) = out.get_mut(1) {
            *t |= SECURED;
        }
        put(out, body_end, &counter.to_le_bytes())?;
        let data = out.get(..data_end).ok_or(Error::Overflow)?;
        let t = tag(&self.key, id, data, self.epoch).finalize().into_bytes();
        put(out, data_end, t.get(..self.mac_len.get()).unwrap_or(&[]))?;
        let crc = super::crc32(out.get(..mac_end).ok_or(Error::Overflow)?);
        put(out, mac_end, &crc.to_le_bytes())?;
        if counter == u32::MAX {
            self.epoch = self.epoch.saturating_add(1);
            self.counter = 0;
        } else {
            self.counter = counter;
        }
        Ok(total)
    }
}

/// The CMAC of `id ‖ data ‖ epoch` under a keyed CMAC, not finalised.
fn tag(keyed: &Cmac<Aes128>, id: u16, data: &[u8], epoch: u32) -> Cmac<Aes128> {
    let mut m = keyed.clone();
    m.update(&id.to_le_bytes());
    m.update(data);
    m.update(&epoch.to_le_bytes());
    m
}

fn put(out: &mut [u8], at: usize, bytes: &[u8]) -> Result<(), Error> {
    out.get_mut(at..at.saturating_add(bytes.len()))
        .ok_or(Error::Overflow)?
        .copy_from_slice(bytes);
    Ok(())
}

/// The key slot a device is provisioned with at flash time (never sent on the bus): 28 bytes,
/// `"GKEY"`, format 1, the MAC length, 2 zero bytes, the key, CRC-32 of the 24 bytes before.
/// Erased flash (0xFF) or zeros: no key.
pub mod slot {
    use super::{Key, MacLen};

    /// Bytes of a slot.
    pub const LEN: usize = 28;
    const MAGIC: [u8; 4] = *b"GKEY";

    /// The slot that provisions `key` with MACs of `mac_len` bytes.
    pub fn encode(key: &Key, mac_len: MacLen) -> [u8; LEN] {
        let mut s = [0u8; LEN];
        let (body, crc) = s.split_at_mut(24);
        let (head, k) = body.split_at_mut(8);
        head.copy_from_slice(&[MAGIC[0], MAGIC[1], MAGIC[2], MAGIC[3], 1, mac_len.0, 0, 0]);
        k.copy_from_slice(&key.0);
        crc.copy_from_slice(&super::super::crc32(body).to_le_bytes());
        s
    }

    /// The key and MAC length of a slot, or `None` (empty, damaged, another format).
    pub fn decode(s: &[u8; LEN]) -> Option<(Key, MacLen)> {
        let (body, crc) = s.split_at_checked(24)?;
        if body.get(..5)? != [MAGIC[0], MAGIC[1], MAGIC[2], MAGIC[3], 1]
            || super::super::crc32(body).to_le_bytes() != *crc
        {
            return None;
        }
        let mac_len = MacLen::new(*body.get(5)?)?;
        Some((Key(body.get(8..24)?.try_into().ok()?), mac_len))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::proto::{
        id, Bytes, Measurement, ParamChunk, Settings, Wheel, MAX_MSG_LEN, PROTO_VERSION,
    };

    fn hex(s: &str) -> std::vec::Vec<u8> {
        (0..s.len())
            .step_by(2)
            .map(|i| u8::from_str_radix(&s[i..i + 2], 16).unwrap())
            .collect()
    }

    const NIST_KEY: &str = "2b7e151628aed2a6abf7158809cf4f3c";

    /// NIST SP 800-38B, appendix D.1 (AES-128): the four examples.
    #[test]
    fn cmac_matches_the_nist_sp_800_38b_vectors() {
        let key = Key::from_hex(NIST_KEY).unwrap();
        let msg = hex(concat!(
            "6bc1bee22e409f96e93d7e117393172a",
            "ae2d8a571e03ac9c9eb76fac45af8e51",
            "30c81c46a35ce411e5fbc1191a0a52ef",
            "f69f2445df4f9b17ad2b417be66c3710"
        ));
        for (len, tag) in [
            (0, "bb1d6929e95937287fa37d129b756746"),
            (16, "070a16b46b4d4144f79bdd9dd04a287c"),
            (40, "dfa66747de9ae63030ca32611497c827"),
            (64, "51f0bebf7e3b9d92fc49741779363cfe"),
        ] {
            assert_eq!(key.cmac_raw(&msg[..len]).to_vec(), hex(tag), "Mlen {len}");
        }
    }

    #[test]
    fn key_files_parse_32_hex_digits_and_comments_only() {
        let k = Key::from_hex("# TEST KEY\n\n2B7E151628aed2a6abf7158809cf4f3c\n").unwrap();
        assert_eq!(k, Key::from_hex(NIST_KEY).unwrap());
        for bad in [
            "",
            "2b7e151628aed2a6abf7158809cf4f3",
            "2b7e151628aed2a6abf7158809cf4f3c0",
            "2b7e151628aed2a6abf7158809cf4fxx",
            "2b7e151628aed2a6abf7158809cf4f3c\n2b7e151628aed2a6abf7158809cf4f3c",
        ] {
            assert_eq!(Key::from_hex(bad), None, "{bad:?}");
        }
        assert_eq!(std::format!("{k:?}"), "Key(..)");
    }

    #[test]
    fn the_key_slot_round_trips_and_an_empty_or_damaged_one_is_no_key() {
        let k = Key::new([7; 16]);
        let s = slot::encode(&k, MacLen::new(6).unwrap());
        assert_eq!(slot::decode(&s), Some((k, MacLen::new(6).unwrap())));
        assert_eq!(slot::decode(&[0; slot::LEN]), None);
        assert_eq!(slot::decode(&[0xff; slot::LEN]), None);
        for i in 0..slot::LEN {
            let mut d = s;
            d[i] ^= 1;
            assert_eq!(slot::decode(&d), None, "byte {i}");
        }
        assert_eq!(MacLen::new(3), None);
        assert_eq!(MacLen::new(9), None);
    }

    fn settings() -> Msg {
        Msg::Settings(Settings {
            wheelbase: 2.9,
            ..Settings::default()
        })
    }

    fn sealed(s: &mut Signer, m: &Msg) -> std::vec::Vec<u8> {
        let mut buf = [0u8; MAX_MSG_LEN];
        let n = s.seal(id::of(m.msg_type()), m, &mut buf).unwrap();
        buf[..n].to_vec()
    }

    fn refused(v: &mut Verifier, b: &[u8]) -> AckCode {
        v.open(id::CONFIG, b).unwrap_err().unwrap().code
    }

    #[test]
    fn a_sealed_message_has_the_documented_layout_and_opens() {
        let key = Key::from_hex(NIST_KEY).unwrap();
        let mut s = Signer::new(key, MacLen::DEFAULT, 3, 41);
        let b = sealed(&mut s, &settings());
        let mut plain = [0u8; MAX_MSG_LEN];
        let n = settings().encode(&mut plain).unwrap();
        assert_eq!(b.len(), n + 12);
        assert_eq!(b[0], PROTO_VERSION);
        assert_eq!(b[1], MsgType::Settings as u8 | SECURED);
        assert_eq!(b[2..n - 4], plain[2..n - 4]);
        assert_eq!(b[n - 4..n], 42u32.to_le_bytes());
        // The MAC: CMAC(K, id LE ‖ version ‖ type ‖ body ‖ counter ‖ epoch LE), left 8 bytes.
        let mut input = id::CONFIG.to_le_bytes().to_vec();
        input.extend_from_slice(&b[..n]);
        input.extend_from_slice(&3u32.to_le_bytes());
        assert_eq!(b[n..n + 8], key.cmac_raw(&input)[..8]);
        assert_eq!(
            u32::from_le_bytes(b[n + 8..].try_into().unwrap()),
            crate::proto::crc32(&b[..n + 8])
        );
        let mut v = Verifier::new(key, MacLen::DEFAULT, 3);
        v.set_counter(41);
        assert_eq!(v.open(id::CONFIG, &b), Ok(settings()));
        assert_eq!((v.status().accepted, v.status().counter), (1, 42));
        assert_eq!(s.freshness(), (3, 42));
        // Any decoder still reads the message itself.
        assert_eq!(Msg::decode(&b), Ok(settings()));
    }

    #[test]
    fn forged_mac_wrong_key_no_key_missing_mac_and_truncation_are_refused_and_counted() {
        let key = Key::from_hex(NIST_KEY).unwrap();
        let mut v = Verifier::new(key, MacLen::DEFAULT, 1);
        let good = sealed(&mut Signer::new(key, MacLen::DEFAULT, 1, 0), &settings());
        // Forged: a MAC byte changed (the CRC made right again, as an attacker would).
        let mut forged = good.clone();
        let n = forged.len();
        forged[n - 5] ^= 0x01;
        let c = crate::proto::crc32(&forged[..n - 4]).to_le_bytes();
        forged[n - 4..].copy_from_slice(&c);
        assert_eq!(refused(&mut v, &forged), AckCode::BadMac);
        // Another key.
        let other = sealed(
            &mut Signer::new(Key::new([1; 16]), MacLen::DEFAULT, 1, 0),
            &settings(),
        );
        assert_eq!(refused(&mut v, &other), AckCode::BadMac);
        // Another MAC length (the device expects 8 bytes).
        let short = sealed(
            &mut Signer::new(key, MacLen::new(4).unwrap(), 1, 0),
            &settings(),
        );
        assert_eq!(refused(&mut v, &short), AckCode::BadMac);
        // The body changed under the MAC (a wheelbase of 0 for 2.9).
        let mut body = good.clone();
        body[7..11].copy_from_slice(&0f32.to_le_bytes());
        let c = crate::proto::crc32(&body[..n - 4]).to_le_bytes();
        body[n - 4..].copy_from_slice(&c);
        assert_eq!(refused(&mut v, &body), AckCode::BadMac);
        // The epoch is in the MAC: a message of another epoch does not verify.
        let old = sealed(&mut Signer::new(key, MacLen::DEFAULT, 0, 0), &settings());
        assert_eq!(refused(&mut v, &old), AckCode::BadMac);
        // Not secured.
        let mut plain = [0u8; MAX_MSG_LEN];
        let p = settings().encode(&mut plain).unwrap();
        assert_eq!(refused(&mut v, &plain[..p]), AckCode::MacMissing);
        // Truncated: the trailer cut short (MAC of 3 bytes) does not even decode.
        let mut cut = good[..n - 4 - 5].to_vec();
        let c = crate::proto::crc32(&cut).to_le_bytes();
        cut.extend_from_slice(&c);
        assert_eq!(v.open(id::CONFIG, &cut), Err(Err(Error::Decode)));
        let st = *v.status();
        assert_eq!(
            (st.bad_mac, st.missing, st.stale, st.accepted, st.counter),
            (5, 1, 0, 0, 0)
        );
        // The good one still goes through: nothing earlier was lost.
        assert_eq!(v.open(id::CONFIG, &good), Ok(settings()));
        // No key: refused whether secured or not; measurements still pass.
        let mut none = Verifier::without_key();
        assert_eq!(refused(&mut none, &good), AckCode::NoKey);
        assert_eq!(refused(&mut none, &plain[..p]), AckCode::NoKey);
        assert_eq!(none.status().no_key, 2);
        let m = Msg::Measurement(Measurement {
            wheel: Wheel::FrontLeft,
            fz: 4000.0,
            ..Measurement::default()
        });
        let k = m.encode(&mut plain).unwrap();
        assert_eq!(none.open(id::MEASUREMENT, &plain[..k]), Ok(m));
        // A status request needs no MAC either.
        let k = Msg::Command(Command::StatusRequest)
            .encode(&mut plain)
            .unwrap();
        assert!(none.open(id::CONFIG, &plain[..k]).is_ok());
        // Reset and Stop do.
        for c in [Command::Reset, Command::Stop] {
            let k = Msg::Command(c).encode(&mut plain).unwrap();
            assert_eq!(refused(&mut v, &plain[..k]), AckCode::MacMissing);
        }
    }

    #[test]
    fn replayed_reordered_and_far_ahead_counters_are_stale() {
        let key = Key::new([0x7e; 16]);
        let mut s = Signer::new(key, MacLen::DEFAULT, 9, 0);
        let mut v = Verifier::new(key, MacLen::DEFAULT, 9);
        let chunk = |i: u8| {
            Msg::ParamChunk(ParamChunk {
                offset: u32::from(i) * 48,
                data: Bytes::new(&[i; 48]).unwrap(),
            })
        };
        let msgs: std::vec::Vec<_> = (0..3).map(|i| sealed(&mut s, &chunk(i))).collect();
        // Reordered: the second before the first; the first is then stale.
        assert!(v.open(id::CONFIG, &msgs[1]).is_ok());
        assert_eq!(refused(&mut v, &msgs[0]), AckCode::StaleFreshness);
        // Replayed.
        assert_eq!(refused(&mut v, &msgs[1]), AckCode::StaleFreshness);
        assert!(v.open(id::CONFIG, &msgs[2]).is_ok());
        assert_eq!(refused(&mut v, &msgs[2]), AckCode::StaleFreshness);
        // Beyond the window.
        let mut far = Signer::new(key, MacLen::DEFAULT, 9, 3 + WINDOW);
        assert_eq!(
            refused(&mut v, &sealed(&mut far, &settings())),
            AckCode::StaleFreshness
        );
        let mut edge = Signer::new(key, MacLen::DEFAULT, 9, 2 + WINDOW);
        assert!(v.open(id::CONFIG, &sealed(&mut edge, &settings())).is_ok());
        assert_eq!((v.status().stale, v.status().accepted), (4, 3));
    }

    #[test]
    fn the_counter_never_wraps_both_ends_move_to_the_next_epoch() {
        let key = Key::new([0x7e; 16]);
        let mut s = Signer::new(key, MacLen::new(4).unwrap(), 5, u32::MAX - 2);
        let mut v = Verifier::new(key, MacLen::new(4).unwrap(), 5);
        v.set_counter(u32::MAX - 2);
        let a = sealed(&mut s, &settings()); // MAX - 1
        let b = sealed(&mut s, &settings()); // MAX: then epoch 6, counter 0
        assert_eq!(s.freshness(), (6, 0));
        let c = sealed(&mut s, &settings()); // epoch 6, counter 1
        for m in [&a, &b, &c] {
            assert!(v.open(id::CONFIG, m).is_ok());
        }
        assert_eq!((v.epoch(), v.status().counter), (6, 1));
        // The messages of the old epoch, replayed: their MACs do not verify in the new one.
        assert_eq!(refused(&mut v, &a), AckCode::BadMac);
        assert_eq!(refused(&mut v, &b), AckCode::BadMac);
        assert_eq!(refused(&mut v, &c), AckCode::StaleFreshness);
    }
}
