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
//! accepted on the message's identifier and at most [`WINDOW`] above the highest it accepted
//! (a replayed, reordered or duplicated message is stale; below, "Freshness per identifier").
//! Having accepted counter `u32::MAX` the device moves to epoch + 1 and counter 0, and so does
//! the [`Signer`]: the counter never wraps within an epoch. The epoch and the highest accepted
//! counter are public (`Status::auth`): a sender that starts reads them and continues.
//!
//! Checked in order by [`Verifier::open`]: a device without a key refuses every
//! state-changing (and every secured) message ([`AckCode::NoKey`]); an unsecured state-changing
//! message is refused ([`AckCode::MacMissing`]); a MAC of the wrong length or value is refused
//! ([`AckCode::BadMac`], compared in constant time); then the freshness
//! ([`AckCode::StaleFreshness`]). Each refusal is counted in [`AuthStatus`]; nothing a refused
//! message carried takes effect.
//!
//! **Policy.** What must be secured is provisioned with the key ([`Policy`], in the key
//! [`slot`]), never set from the bus: [`Policy::StateChanging`] (the default) or [`Policy::All`],
//! under which every message the device receives must be secured, measurements too (but the
//! status request, which synchronises a sender's freshness: [`Policy::All`]), and the device
//! secures every message it sends ([`Verifier::seal`], its own transmit counter
//! in the same epoch; the CAN identifier in the MAC keeps the directions apart).
//!
//! **Freshness per identifier.** Messages on different identifiers are reassembled
//! independently, so they may be delivered in another order than they were sent. As SecOC keeps a
//! freshness value per data identifier, the verifier keeps the last accepted counter per
//! identifier ([`FRESHNESS_IDS`]): a counter is fresh when it is above the last one accepted *on
//! its identifier* and at most [`WINDOW`] above the highest accepted on any
//! (`AuthStatus::counter`). A sender keeps one counter for all identifiers (one [`Signer`]), so no
//! two of its messages share a freshness value, and a sender that starts continues above
//! `AuthStatus::counter` on every identifier.

use super::{id, AckCode, Command, Error, Msg, MsgType};
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
/// A counter is fresh when it is above the last accepted one on its identifier and at most this
/// much above the highest accepted on any.
pub const WINDOW: u32 = 1 << 16;

/// The identifiers that keep a freshness counter of their own (module doc): the device's four
/// receive identifiers and its three transmit identifiers. A secured message on any other
/// identifier does not verify ([`AckCode::BadMac`]).
pub const FRESHNESS_IDS: [u16; 7] = [
    id::MEASUREMENT,
    id::CONFIG,
    id::COMPACT,
    id::BATCH,
    id::RESULT,
    id::STATUS,
    id::BATCH_RESULT,
];

/// What a device authenticates, provisioned with its key (the key [`slot`]), never switched from
/// the bus.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Policy {
    /// Only the state-changing messages ([`is_state_changing`]) must be secured; measurements,
    /// status requests and the device's answers go unsecured.
    #[default]
    StateChanging = 0,
    /// Every message the device receives must be secured — but `Command::StatusRequest`, the
    /// freshness synchronisation: a sender learns the epoch and counters from the `Status` it
    /// brings, before it can sign anything — and the device secures every message it sends
    /// (`Forces`, `Estimate`, `CompactResults`, `Status`, `Ack`, `Calibration`).
    All = 1,
}

impl Policy {
    /// The policy of its byte in the key slot (0 or 1).
    pub const fn from_u8(b: u8) -> Option<Policy> {
        match b {
            0 => Some(Policy::StateChanging),
            1 => Some(Policy::All),
            _ => None,
        }
    }

    /// Whether `msg`, received, must be secured under this policy.
    pub const fn requires_mac(self, msg: &Msg) -> bool {
        match self {
            Policy::StateChanging => is_state_changing(msg),
            Policy::All => !matches!(msg, Msg::Command(Command::StatusRequest)),
        }
    }
}

/// The index of identifier `id` in [`FRESHNESS_IDS`].
fn lane(cid: u16) -> Option<usize> {
    FRESHNESS_IDS.iter().position(|&i| i == cid)
}

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
    /// The highest counter accepted in this epoch on any identifier (0: none yet); a sender
    /// continues above it.
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

/// The receiving end (the device; or a tool checking the device's answers): checks secured
/// messages against its key, [`Policy`] and freshness (per identifier, [`FRESHNESS_IDS`]), and
/// under [`Policy::All`] secures what the device sends ([`Verifier::seal`], its own transmit
/// counter in the same epoch). Keeps the keyed CMAC (the AES round keys and CMAC subkeys: 400
/// bytes on the M4F, computed once in [`Verifier::new`]); its `Debug` does not show them.
#[derive(Clone)]
pub struct Verifier {
    key: Option<(Cmac<Aes128>, MacLen)>,
    policy: Policy,
    /// The last counter accepted on each of [`FRESHNESS_IDS`] in this epoch.
    last: [u32; FRESHNESS_IDS.len()],
    /// The last counter this end secured a message with ([`Verifier::seal`]).
    tx: u32,
    status: AuthStatus,
}

impl fmt::Debug for Verifier {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Verifier")
            .field("key", &self.key.as_ref().map(|_| "..."))
            .field("policy", &self.policy)
            .field("last", &self.last)
            .field("tx", &self.tx)
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
            policy: Policy::StateChanging,
            last: [0; FRESHNESS_IDS.len()],
            tx: 0,
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

    /// The same, under `policy` (provisioned with the key).
    pub fn with_policy(mut self, policy: Policy) -> Verifier {
        self.policy = policy;
        self
    }

    /// What must be secured.
    pub const fn policy(&self) -> Policy {
        self.policy
    }

    /// State and counters.
    pub const fn status(&self) -> &AuthStatus {
        &self.status
    }

    /// The current epoch (it moves on after counter `u32::MAX`: the board stores it then).
    pub const fn epoch(&self) -> u32 {
        self.status.epoch
    }

    /// Sets the last accepted counter on every identifier (tests of the counter wrap; a tool
    /// that starts checking a device's answers from a counter it verified).
    pub fn set_counter(&mut self, counter: u32) {
        self.status.counter = counter;
        self.last = [counter; FRESHNESS_IDS.len()];
    }

    /// Moves to the next epoch (after counter `u32::MAX`, received or sent): every counter back
    /// to 0.
    fn next_epoch(&mut self) {
        self.status.epoch = self.status.epoch.saturating_add(1);
        self.set_counter(0);
        self.tx = 0;
    }

    /// Encodes `msg`, sent on identifier `id`, into `out`; returns the length. Under
    /// [`Policy::All`] with a key it is secured with this end's next transmit counter in the
    /// current epoch (after `u32::MAX` the epoch moves on, as on receipt: the board stores it);
    /// otherwise plain ([`Msg::encode`]). [`Error::Overflow`] if `out` is too short (a buffer of
    /// [`super::MAX_MSG_LEN`] never is).
    pub fn seal(&mut self, id: u16, msg: &Msg, out: &mut [u8]) -> Result<usize, Error> {
        let (Policy::All, Some((key, len))) = (self.policy, &self.key) else {
            return msg.encode(out);
        };
        let counter = self.tx.saturating_add(1);
        let n = seal_into(key, *len, self.status.epoch, counter, id, msg, out)?;
        if counter == u32::MAX {
            self.next_epoch();
        } else {
            self.tx = counter;
        }
        Ok(n)
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
    /// length and value, constant time), freshness on its identifier. An unsecured message the
    /// [`Policy`] does not require secured passes at no cost.
    pub fn check(&mut self, id: u16, msg: &Msg, bytes: &[u8]) -> Result<(), Refused> {
        let secured = bytes.get(1).is_some_and(|t| t & SECURED != 0);
        if !secured && !self.policy.requires_mac(msg) {
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
        let lane = lane(id);
        let Some((t, last)) = trailer
            .filter(|t| {
                tag(key, id, t.data, s.epoch)
                    .verify_truncated_left(t.mac)
                    .is_ok()
            })
            .zip(lane.and_then(|i| self.last.get_mut(i)))
        else {
            s.bad_mac = s.bad_mac.wrapping_add(1);
            return Err(Refused {
                of,
                code: AckCode::BadMac,
            });
        };
        if t.counter <= *last || t.counter > s.counter.saturating_add(WINDOW) {
            s.stale = s.stale.wrapping_add(1);
            return Err(Refused {
                of,
                code: AckCode::StaleFreshness,
            });
        }
        s.accepted = s.accepted.wrapping_add(1);
        *last = t.counter;
        s.counter = s.counter.max(t.counter);
        if t.counter == u32::MAX {
            // The counter never wraps: the next epoch (the board stores it).
            self.next_epoch();
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
        let counter = self.counter.saturating_add(1);
        let n = seal_into(&self.key, self.mac_len, self.epoch, counter, id, msg, out)?;
        if counter == u32::MAX {
            self.epoch = self.epoch.saturating_add(1);
            self.counter = 0;
        } else {
            self.counter = counter;
        }
        Ok(n)
    }
}

/// Encodes `msg`, sent on identifier `id`, secured with freshness (`epoch`, `counter`) into
/// `out`; returns the length.
fn seal_into(
    key: &Cmac<Aes128>,
    mac_len: MacLen,
    epoch: u32,
    counter: u32,
    id: u16,
    msg: &Msg,
    out: &mut [u8],
) -> Result<usize, Error> {
    let n = msg.encode(out)?;
    let body_end = n.checked_sub(4).ok_or(Error::Overflow)?;
    let data_end = body_end.saturating_add(COUNTER_LEN);
    let mac_end = data_end.saturating_add(mac_len.get());
    let total = mac_end.saturating_add(4);
    if out.len() < total {
        return Err(Error::Overflow);
    }
    if let Some(t) = out.get_mut(1) {
        *t |= SECURED;
    }
    put(out, body_end, &counter.to_le_bytes())?;
    let data = out.get(..data_end).ok_or(Error::Overflow)?;
    let t = tag(key, id, data, epoch).finalize().into_bytes();
    put(out, data_end, t.get(..mac_len.get()).unwrap_or(&[]))?;
    let crc = super::crc32(out.get(..mac_end).ok_or(Error::Overflow)?);
    put(out, mac_end, &crc.to_le_bytes())?;
    Ok(total)
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
/// `"GKEY"`, the format, the MAC length, the [`Policy`] byte (format 2; 0 in format 1), a zero
/// byte, the key, CRC-32 of the 24 bytes before. Format 1 (no policy byte) is
/// [`Policy::StateChanging`]. Erased flash (0xFF) or zeros: no key.
pub mod slot {
    use super::{Key, MacLen, Policy};

    /// Bytes of a slot.
    pub const LEN: usize = 28;
    const MAGIC: [u8; 4] = *b"GKEY";
    /// The format [`encode`] writes.
    pub const FORMAT: u8 = 2;

    /// The slot (format 2) that provisions `key` with MACs of `mac_len` bytes under `policy`.
    pub fn encode(key: &Key, mac_len: MacLen, policy: Policy) -> [u8; LEN] {
        let mut s = [0u8; LEN];
        let (body, crc) = s.split_at_mut(24);
        let (head, k) = body.split_at_mut(8);
        let [m0, m1, m2, m3] = MAGIC;
        head.copy_from_slice(&[m0, m1, m2, m3, FORMAT, mac_len.0, policy as u8, 0]);
        k.copy_from_slice(&key.0);
        crc.copy_from_slice(&super::super::crc32(body).to_le_bytes());
        s
    }

    /// The key, MAC length and policy of a slot (format 1: [`Policy::StateChanging`]), or
    /// `None` (empty, damaged, an unknown format or policy).
    pub fn decode(s: &[u8; LEN]) -> Option<(Key, MacLen, Policy)> {
        let (body, crc) = s.split_at_checked(24)?;
        if body.get(..4)? != MAGIC || super::super::crc32(body).to_le_bytes() != *crc {
            return None;
        }
        let policy = match (*body.get(4)?, *body.get(6)?) {
            (1, _) => Policy::StateChanging,
            (2, p) => Policy::from_u8(p)?,
            _ => return None,
        };
        let mac_len = MacLen::new(*body.get(5)?)?;
        Some((Key(body.get(8..24)?.try_into().ok()?), mac_len, policy))
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
        let six = MacLen::new(6).unwrap();
        for p in [Policy::StateChanging, Policy::All] {
            assert_eq!(slot::decode(&slot::encode(&k, six, p)), Some((k, six, p)));
        }
        let s = slot::encode(&k, six, Policy::All);
        // A format-1 slot (issue 59's, no policy byte) is state-changing only.
        let mut v1 = slot::encode(&k, six, Policy::StateChanging);
        v1[4] = 1;
        let c = crate::proto::crc32(&v1[..24]).to_le_bytes();
        v1[24..].copy_from_slice(&c);
        assert_eq!(slot::decode(&v1), Some((k, six, Policy::StateChanging)));
        // An unknown policy or format is no key.
        for (at, b) in [(6, 2u8), (4, 3)] {
            let mut d = s;
            d[at] = b;
            let c = crate::proto::crc32(&d[..24]).to_le_bytes();
            d[24..].copy_from_slice(&c);
            assert_eq!(slot::decode(&d), None, "byte {at} = {b}");
        }
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

    fn measurement(i: u8) -> Msg {
        Msg::Measurement(Measurement {
            wheel: Wheel::FrontLeft,
            t_us: u32::from(i) * 1000,
            fz: 4000.0,
            kappa: Some(0.01 * f32::from(i)),
            ..Measurement::default()
        })
    }

    fn plain(m: &Msg) -> std::vec::Vec<u8> {
        let mut buf = [0u8; MAX_MSG_LEN];
        let n = m.encode(&mut buf).unwrap();
        buf[..n].to_vec()
    }

    #[test]
    fn secure_all_accepts_secured_measurements_and_refuses_unsecured_forged_and_replayed_ones() {
        let key = Key::new([0x33; 16]);
        let mut v = Verifier::new(key, MacLen::DEFAULT, 2).with_policy(Policy::All);
        let mut s = Signer::new(key, MacLen::DEFAULT, 2, 0);
        let status_req = Msg::Command(Command::StatusRequest);
        let batch = Msg::CompactBatch(crate::proto::CompactBatch::default());
        let compact = Msg::CompactMeasurement(crate::proto::CompactMeasurement::default());
        // Secured: accepted on each receive identifier, exactly the message sent.
        for m in [measurement(1), compact, batch, status_req] {
            let b = sealed(&mut s, &m);
            assert_eq!(v.open(id::of(m.msg_type()), &b), Ok(m), "{m:?}");
            // Unsecured: refused under the policy (but the status request: the freshness
            // synchronisation), accepted without it.
            let p = plain(&m);
            if m == status_req {
                assert_eq!(v.open(id::CONFIG, &p), Ok(m));
            } else {
                let r = v.open(id::of(m.msg_type()), &p).unwrap_err().unwrap();
                assert_eq!(r.code, AckCode::MacMissing, "{m:?}");
            }
            let mut lax = Verifier::new(key, MacLen::DEFAULT, 2);
            assert_eq!(lax.open(id::of(m.msg_type()), &p), Ok(m));
        }
        assert_eq!((v.status().accepted, v.status().missing), (4, 3));
        // Forged (a MAC bit flipped, the CRC made right) and replayed measurements.
        let good = sealed(&mut s, &measurement(2));
        let mut forged = good.clone();
        let n = forged.len();
        forged[n - 5] ^= 0x80;
        let c = crate::proto::crc32(&forged[..n - 4]).to_le_bytes();
        forged[n - 4..].copy_from_slice(&c);
        let refuse = |v: &mut Verifier, b: &[u8]| v.open(id::MEASUREMENT, b).unwrap_err().unwrap();
        assert_eq!(refuse(&mut v, &forged).code, AckCode::BadMac);
        assert_eq!(v.open(id::MEASUREMENT, &good), Ok(measurement(2)));
        assert_eq!(refuse(&mut v, &good).code, AckCode::StaleFreshness);
        // Sent on another identifier than it was signed for: the identifier is in the MAC.
        let other = sealed(&mut s, &measurement(3));
        assert_eq!(
            v.open(id::COMPACT, &other).unwrap_err().unwrap().code,
            AckCode::BadMac
        );
        // An identifier without a freshness counter of its own: never verifies.
        assert_eq!(
            v.open(0x123, &other).unwrap_err().unwrap().code,
            AckCode::BadMac
        );
        let st = *v.status();
        assert_eq!(
            (st.accepted, st.missing, st.bad_mac, st.stale),
            (5, 3, 3, 1)
        );
    }

    #[test]
    fn freshness_is_per_identifier_so_interleaved_delivery_is_accepted() {
        let key = Key::new([0x44; 16]);
        let mut v = Verifier::new(key, MacLen::DEFAULT, 1).with_policy(Policy::All);
        let mut s = Signer::new(key, MacLen::DEFAULT, 1, 0);
        // Sent: measurement (1), settings (2), compact batch (3), measurement (4). Delivered in
        // another order between identifiers (each reassembled on its own), in order within one.
        let m1 = sealed(&mut s, &measurement(1));
        let cfg = sealed(&mut s, &settings());
        let batch = Msg::CompactBatch(crate::proto::CompactBatch::default());
        let b3 = sealed(&mut s, &batch);
        let m4 = sealed(&mut s, &measurement(4));
        assert!(v.open(id::CONFIG, &cfg).is_ok());
        assert!(v.open(id::BATCH, &b3).is_ok());
        assert_eq!(v.open(id::MEASUREMENT, &m1), Ok(measurement(1)));
        assert_eq!(v.open(id::MEASUREMENT, &m4), Ok(measurement(4)));
        assert_eq!((v.status().accepted, v.status().counter), (4, 4));
        // Within one identifier the order still counts: the first measurement again is stale.
        assert_eq!(
            v.open(id::MEASUREMENT, &m1).unwrap_err().unwrap().code,
            AckCode::StaleFreshness
        );
        // The window is from the highest counter accepted on any identifier.
        let mut far = Signer::new(key, MacLen::DEFAULT, 1, 4 + WINDOW);
        let f = sealed(&mut far, &measurement(5));
        assert_eq!(
            v.open(id::MEASUREMENT, &f).unwrap_err().unwrap().code,
            AckCode::StaleFreshness
        );
        let mut edge = Signer::new(key, MacLen::DEFAULT, 1, 3 + WINDOW);
        assert!(v
            .open(
                id::COMPACT,
                &sealed(&mut edge, &Msg::CompactMeasurement(Default::default()))
            )
            .is_ok());
    }

    #[test]
    fn the_device_signs_its_answers_and_a_tool_verifies_them() {
        let key = Key::new([0x55; 16]);
        let mut dev = Verifier::new(key, MacLen::new(6).unwrap(), 8).with_policy(Policy::All);
        let forces = Msg::Forces(crate::proto::Forces::default());
        let ack = Msg::Ack(crate::proto::Ack {
            of: MsgType::Settings as u8,
            seq: 3,
            code: AckCode::Ok,
        });
        let mut out = [0u8; MAX_MSG_LEN];
        let mut answers = std::vec::Vec::new();
        for m in [&forces, &ack, &forces] {
            let n = dev.seal(id::of(m.msg_type()), m, &mut out).unwrap();
            answers.push((id::of(m.msg_type()), out[..n].to_vec()));
        }
        // Secured: type bit, counter 1, 2, 3 (the device's own transmit counter) in epoch 8.
        let (_, t) = Msg::decode_secured(&answers[2].1).unwrap();
        assert_eq!(
            (answers[2].1[1] & SECURED, t.unwrap().counter),
            (SECURED, 3)
        );
        // Receiving did not move the transmit counter, nor the reverse.
        assert_eq!(dev.status().counter, 0);
        let mut tool = Verifier::new(key, MacLen::new(6).unwrap(), 8).with_policy(Policy::All);
        for (cid, b) in &answers {
            assert!(tool.open(*cid, b).is_ok());
        }
        // Replayed, forged, from another epoch, unsigned, or taken for a request: refused.
        assert_eq!(
            tool.open(id::RESULT, &answers[0].1)
                .unwrap_err()
                .unwrap()
                .code,
            AckCode::StaleFreshness
        );
        let mut forged = answers[2].1.clone();
        forged[3] ^= 1;
        let n = forged.len();
        let c = crate::proto::crc32(&forged[..n - 4]).to_le_bytes();
        forged[n - 4..].copy_from_slice(&c);
        assert_eq!(
            tool.open(id::RESULT, &forged).unwrap_err().unwrap().code,
            AckCode::BadMac
        );
        let mut old = Verifier::new(key, MacLen::new(6).unwrap(), 7).with_policy(Policy::All);
        let n = old.seal(id::RESULT, &forces, &mut out).unwrap();
        let mut t2 = Verifier::new(key, MacLen::new(6).unwrap(), 8).with_policy(Policy::All);
        assert_eq!(
            t2.open(id::RESULT, &out[..n]).unwrap_err().unwrap().code,
            AckCode::BadMac
        );
        assert_eq!(
            t2.open(id::RESULT, &plain(&forces))
                .unwrap_err()
                .unwrap()
                .code,
            AckCode::MacMissing
        );
        // The device's answer replayed to it as a request: another identifier in the MAC.
        let (_, fb) = &answers[0];
        assert_eq!(
            dev.open(id::MEASUREMENT, fb).unwrap_err().unwrap().code,
            AckCode::BadMac
        );
        // Without the policy the device sends plain messages.
        let mut lax = Verifier::new(key, MacLen::new(6).unwrap(), 8);
        let n = lax.seal(id::RESULT, &forces, &mut out).unwrap();
        assert_eq!(out[..n], plain(&forces)[..]);
        // The transmit counter never wraps: after u32::MAX the device's epoch moves on.
        dev.tx = u32::MAX - 1;
        dev.seal(id::RESULT, &forces, &mut out).unwrap();
        assert_eq!((dev.epoch(), dev.tx, dev.status().counter), (9, 0, 0));
    }
}
