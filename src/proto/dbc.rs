//! The bus description as a DBC file (`gough proto dbc`, `gough proto dbc --fd`), generated
//! from the tables of this module so it cannot drift from the code.
//!
//! Every frame of the protocol decodes against it, also in strict decoders (cantools: exact
//! data length, a signal set for every value of a multiplexer). Per identifier:
//! - the frame header: `frame_index` (the multiplexer), `last_frame`, `first_frame`, `msg_seq`;
//! - first frames (`frame_index` 0): `msg_len`, `proto_version`, `msg_type` (with its names) and
//!   the message bytes that follow as `first_bytes*` (little-endian integers of ≤ 8 bytes);
//! - continuation frames (`frame_index` 1..=63, an extended-multiplexing range): the message
//!   bytes as `next_bytes*`.
//!
//! Each identifier has one frame length ([`Mtu::frame_len`]): 8 on classic CAN; 64 on CAN FD, 32
//! on [`id::RESULT`] and [`id::COMPACT`], 48 on [`id::BATCH`]. On CAN FD a whole [`super::Forces`],
//! [`super::Estimate`] or [`super::CompactMeasurement`] fits one frame, and postcard puts their
//! fields at fixed offsets (one-byte enums, fixed-width integers, `f32`), so the FD file
//! multiplexes these identifiers' first frames on `msg_type` and gives the bodies as physical
//! signals: `wheel`, `t_us`, `Fx`, `Fy`, `Mz` and `flags` of `Forces`; `wheel`, `t_us`, `mu`,
//! `sigma`, `state` (a value table), `mu_min`, `change` (the change-of-surface flag, 0/1) and
//! `mismatch` (the model-mismatch flag, 0/1) of `Estimate`; the scaled fields of `CompactMeasurement`;
//! and each message's CRC-32; on [`id::BATCH_RESULT`] the four-wheel `CompactResults` (one
//! 64-byte frame): `results_t_us`, per wheel (`FL_`, `FR_`, `RL_`, `RR_`) `Fx`, `Fy`, `Mz`,
//! `mu`, `sigma`, `mu_min` (scaled), `state` (a value table with `NoEstimate`), `change`,
//! `mf_flags`, `present`, `mismatch` (bits of the status byte), and `results_crc`. The four-wheel
//! `CompactBatch` ([`id::BATCH`], two 48-byte frames) has byte signals only.
//! A bus log then shows μ per wheel without gough. On classic CAN
//! these messages span several frames, and only their bytes are signals.

use super::auth::{MacLen, Policy, SECURED, STATE_CHANGING_TYPES};
use super::segmenter::Mtu;
use super::{id, MsgType, PROTO_VERSION};
use core::fmt::{self, Write};

/// Byte offset in a first frame where the message body starts: frame header (3), then the
/// message's version and type bytes.
const BODY: usize = 5;

/// Writes `name` (or `name_0`, `name_1`, ..) signals over bytes `from..to` of a frame, ≤ 8
/// bytes each (little-endian unsigned), multiplexed by `mux`.
fn byte_signals<W: Write>(
    w: &mut W,
    name: &str,
    mux: &str,
    (from, to): (usize, usize),
    rx: &str,
) -> fmt::Result {
    let mut start = from;
    let mut k = 0;
    while start < to {
        let n = (to - start).min(8);
        let max = u64::MAX >> (64 - 8 * n);
        write!(w, " SG_ {name}")?;
        if to - from > 8 {
            write!(w, "_{k}")?;
        }
        writeln!(
            w,
            " {mux} : {}|{}@1+ (1,0) [0|{max}] \"\" {rx}",
            start * 8,
            n * 8
        )?;
        start += n;
        k += 1;
    }
    Ok(())
}

/// How a body field is encoded.
#[derive(Clone, Copy, PartialEq)]
enum Kind {
    /// Unsigned little-endian integer.
    U,
    /// Signed (two's complement) little-endian integer.
    I,
    /// IEEE-754 `f32`, little endian.
    F,
    /// Unsigned bits `start .. start + len` of the byte at the offset.
    Bits(usize, usize),
}

/// One physical signal of a single-frame body on CAN FD: name, byte offset in the body, bytes,
/// encoding, scale (physical value per count), unit, value table. Offsets follow postcard's
/// encoding of the message (checked by `host-tests/python/test_dbc.py` against encoded
/// messages).
type Field = (
    &'static str,
    usize,
    usize,
    Kind,
    f32,
    &'static str,
    &'static [&'static str],
);

const WHEELS: &[&str] = &["FrontLeft", "FrontRight", "RearLeft", "RearRight"];

/// `Forces`' body: wheel (1), t_us (4), Fx, Fy, Mz (f32), flags (u16), then the CRC-32.
const FORCES: [Field; 7] = [
    ("forces_wheel", 0, 1, Kind::U, 1.0, "", WHEELS),
    ("forces_t_us", 1, 4, Kind::U, 1.0, "us", &[]),
    ("Fx", 5, 4, Kind::F, 1.0, "N", &[]),
    ("Fy", 9, 4, Kind::F, 1.0, "N", &[]),
    ("Mz", 13, 4, Kind::F, 1.0, "N.m", &[]),
    ("forces_flags", 17, 2, Kind::U, 1.0, "", &[]),
    ("forces_crc", 19, 4, Kind::U, 1.0, "", &[]),
];

/// `Estimate`'s body: wheel (1), t_us (4), μ, σ (f32), state (1), μ_min (f32), change and
/// mismatch (bools, one byte 0/1 each), then the CRC-32.
const ESTIMATE: [Field; 9] = [
    ("estimate_wheel", 0, 1, Kind::U, 1.0, "", WHEELS),
    ("estimate_t_us", 1, 4, Kind::U, 1.0, "us", &[]),
    ("mu", 5, 4, Kind::F, 1.0, "", &[]),
    ("sigma", 9, 4, Kind::F, 1.0, "", &[]),
    (
        "state",
        13,
        1,
        Kind::U,
        1.0,
        "",
        &["Identifiable", "NotIdentifiable", "Fallback"],
    ),
    ("mu_min", 14, 4, Kind::F, 1.0, "", &[]),
    ("change", 18, 1, Kind::U, 1.0, "", &["NoChange", "Change"]),
    ("mismatch", 19, 1, Kind::U, 1.0, "", MISMATCH),
    ("estimate_crc", 20, 4, Kind::U, 1.0, "", &[]),
];

/// `CompactMeasurement`'s body: wheel (1), t_us (4), then i16 counts (u16 for Fz), then the
/// CRC-32. A count of −32768 marks an absent optional field.
const COMPACT: [Field; 12] = [
    ("wheel", 0, 1, Kind::U, 1.0, "", WHEELS),
    ("t_us", 1, 4, Kind::U, 1.0, "us", &[]),
    ("Fz", 5, 2, Kind::U, 0.5, "N", &[]),
    ("Fy", 7, 2, Kind::I, 1.0, "N", &[]),
    ("Mz", 9, 2, Kind::I, 0.1, "N.m", &[]),
    ("Fx", 11, 2, Kind::I, 1.0, "N", &[]),
    ("vx", 13, 2, Kind::I, 0.01, "m/s", &[]),
    ("omega", 15, 2, Kind::I, 0.01, "rad/s", &[]),
    ("alpha", 17, 2, Kind::I, 1e-4, "rad", &[]),
    ("kappa", 19, 2, Kind::I, 1e-4, "", &[]),
    ("gamma", 21, 2, Kind::I, 1e-4, "rad", &[]),
    ("crc", 23, 4, Kind::U, 1.0, "", &[]),
];

const STATES4: &[&str] = &["Identifiable", "NotIdentifiable", "Fallback", "NoEstimate"];
const CHANGE: &[&str] = &["NoChange", "Change"];
const PRESENT: &[&str] = &["Absent", "Present"];
const MISMATCH: &[&str] = &["Explained", "Mismatch"];

/// One wheel's signals of `CompactResults` (12 bytes from `4 + 12 i`): Fx, Fy, Mz (i16),
/// μ, σ (u16), μ_min (u8), status (state bits 0–1, change bit 2, MF flags bit 3, present bit 4,
/// mismatch bit 5).
/// Counts −32768 (i16), 65535 (u16), 255 (u8) mean "not available".
macro_rules! wheel_results {
    ($b:expr, $fx:literal, $fy:literal, $mz:literal, $mu:literal, $sigma:literal, $mu_min:literal,
     $state:literal, $change:literal, $flags:literal, $present:literal, $mismatch:literal) => {
        [
            ($fx, $b, 2, Kind::I, 1.0, "N", &[]),
            ($fy, $b + 2, 2, Kind::I, 1.0, "N", &[]),
            ($mz, $b + 4, 2, Kind::I, 0.1, "N.m", &[]),
            ($mu, $b + 6, 2, Kind::U, 1e-4, "", &[]),
            ($sigma, $b + 8, 2, Kind::U, 1e-4, "", &[]),
            ($mu_min, $b + 10, 1, Kind::U, 0.01, "", &[]),
            ($state, $b + 11, 1, Kind::Bits(0, 2), 1.0, "", STATES4),
            ($change, $b + 11, 1, Kind::Bits(2, 1), 1.0, "", CHANGE),
            ($flags, $b + 11, 1, Kind::Bits(3, 1), 1.0, "", &[]),
            ($present, $b + 11, 1, Kind::Bits(4, 1), 1.0, "", PRESENT),
            ($mismatch, $b + 11, 1, Kind::Bits(5, 1), 1.0, "", MISMATCH),
        ]
    };
}

const RESULTS_FL: [Field; 11] = wheel_results!(
    4,
    "FL_Fx",
    "FL_Fy",
    "FL_Mz",
    "FL_mu",
    "FL_sigma",
    "FL_mu_min",
    "FL_state",
    "FL_change",
    "FL_mf_flags",
    "FL_present",
    "FL_mismatch"
);
const RESULTS_FR: [Field; 11] = wheel_results!(
    16,
    "FR_Fx",
    "FR_Fy",
    "FR_Mz",
    "FR_mu",
    "FR_sigma",
    "FR_mu_min",
    "FR_state",
    "FR_change",
    "FR_mf_flags",
    "FR_present",
    "FR_mismatch"
);
const RESULTS_RL: [Field; 11] = wheel_results!(
    28,
    "RL_Fx",
    "RL_Fy",
    "RL_Mz",
    "RL_mu",
    "RL_sigma",
    "RL_mu_min",
    "RL_state",
    "RL_change",
    "RL_mf_flags",
    "RL_present",
    "RL_mismatch"
);
const RESULTS_RR: [Field; 11] = wheel_results!(
    40,
    "RR_Fx",
    "RR_Fy",
    "RR_Mz",
    "RR_mu",
    "RR_sigma",
    "RR_mu_min",
    "RR_state",
    "RR_change",
    "RR_mf_flags",
    "RR_present",
    "RR_mismatch"
);
/// `CompactResults`' body: t_us (4), the four wheels (12 bytes each), then the CRC-32.
const RESULTS_T: [Field; 2] = [
    ("results_t_us", 0, 4, Kind::U, 1.0, "us", &[]),
    ("results_crc", 52, 4, Kind::U, 1.0, "", &[]),
];

/// The single-frame messages whose bodies are signals on CAN FD, by identifier (a message may
/// have several field tables).
const BODIES: [(u16, MsgType, &[Field]); 8] = [
    (id::COMPACT, MsgType::CompactMeasurement, &COMPACT),
    (id::RESULT, MsgType::Forces, &FORCES),
    (id::RESULT, MsgType::Estimate, &ESTIMATE),
    (id::BATCH_RESULT, MsgType::CompactResults, &RESULTS_T),
    (id::BATCH_RESULT, MsgType::CompactResults, &RESULTS_FL),
    (id::BATCH_RESULT, MsgType::CompactResults, &RESULTS_FR),
    (id::BATCH_RESULT, MsgType::CompactResults, &RESULTS_RL),
    (id::BATCH_RESULT, MsgType::CompactResults, &RESULTS_RR),
];

/// `true` when identifier `cid` has physical signals on a bus of `mtu`.
fn has_bodies(mtu: Mtu, cid: u16) -> bool {
    mtu == Mtu::Fd && BODIES.iter().any(|b| b.0 == cid)
}

/// Writes the DBC text for classic CAN ([`Mtu::Classic`]) or CAN FD ([`Mtu::Fd`]), secured
/// messages with 8-byte MACs ([`write_with`]).
pub fn write<W: Write>(w: &mut W, mtu: Mtu) -> fmt::Result {
    write_with(w, mtu, MacLen::DEFAULT)
}

/// The body length of a secured single-frame message on CAN FD (fixed; `ParamChunk`'s varies),
/// where its freshness counter starts.
const fn fixed_body(t: MsgType) -> Option<usize> {
    match t {
        MsgType::ParamBegin => Some(8),
        MsgType::ParamCommit => Some(4),
        MsgType::Settings => Some(9),
        MsgType::Command => Some(1),
        MsgType::SetCalibration => Some(37),
        _ => None,
    }
}

/// The configuration identifier's first frames on CAN FD, multiplexed on `msg_type`: each
/// plain type's message bytes as `<Type>_bytes*`; each secured type (`<Type>Secured`, type |
/// 0x40) with a fixed body: `<Type>Secured_body*`, then `<Type>Secured_freshness` (the counter),
/// `<Type>Secured_mac` (`mac_len` bytes) and `<Type>Secured_crc`; a secured `ParamChunk` (its
/// body's length varies, so do the trailer's offsets) as bytes.
fn config_fd<W: Write>(
    w: &mut W,
    len: usize,
    mac_len: MacLen,
    rx: &str,
    muxes: &mut Muxes,
) -> fmt::Result {
    for t in MsgType::ALL.iter().filter(|t| id::of(**t) == id::CONFIG) {
        let mut name = Name::new();
        let _ = write!(name, "{}_bytes", t.name());
        muxed_bytes(w, &name, *t as u8, (BODY, len), rx, muxes)?;
    }
    for t in STATE_CHANGING_TYPES {
        let st = t as u8 | SECURED;
        let mut name = Name::new();
        let Some(b) = fixed_body(t) else {
            let _ = write!(name, "{}Secured_bytes", t.name());
            muxed_bytes(w, &name, st, (BODY, len), rx, muxes)?;
            continue;
        };
        let _ = write!(name, "{}Secured_body", t.name());
        muxed_bytes(w, &name, st, (BODY, BODY + b), rx, muxes)?;
        let m = mac_len.get();
        for (what, off, n) in [
            ("freshness", BODY + b, 4),
            ("mac", BODY + b + 4, m),
            ("crc", BODY + b + 4 + m, 4),
        ] {
            name.clear();
            let _ = write!(name, "{}Secured_{what}", t.name());
            let max = u64::MAX >> (64 - 8 * n);
            writeln!(
                w,
                " SG_ {name} m{st} : {}|{}@1+ (1,0) [0|{max}] \"\" {rx}",
                off * 8,
                n * 8
            )?;
            let _ = muxes.push((name.clone(), st));
        }
    }
    Ok(())
}

/// A signal's name.
type Name = heapless::String<40>;
/// Signals multiplexed on `msg_type`, with its value.
type Muxes = heapless::Vec<(Name, u8), 192>;

/// [`byte_signals`] multiplexed on `msg_type` = `t`; records their names in `muxes`.
fn muxed_bytes<W: Write>(
    w: &mut W,
    name: &str,
    t: u8,
    (from, to): (usize, usize),
    rx: &str,
    muxes: &mut Muxes,
) -> fmt::Result {
    let mut mux = heapless::String::<8>::new();
    let _ = write!(mux, "m{t}");
    byte_signals(w, name, &mux, (from, to), rx)?;
    for k in 0..(to - from).div_ceil(8) {
        let mut n = Name::new();
        let _ = n.push_str(name);
        if to - from > 8 {
            let _ = write!(n, "_{k}");
        }
        let _ = muxes.push((n, t));
    }
    Ok(())
}

/// Writes the DBC text for classic CAN ([`Mtu::Classic`]) or CAN FD ([`Mtu::Fd`]), for secured
/// messages with MACs of `mac_len` bytes: on CAN FD their freshness counter and MAC are signals
/// of their own (on the configuration identifier, multiplexed on `msg_type`); on classic CAN they are bytes
/// of the message, as every body is.
pub fn write_with<W: Write>(w: &mut W, mtu: Mtu, mac_len: MacLen) -> fmt::Result {
    write_policy(w, mtu, mac_len, Policy::StateChanging)
}

/// The message types of identifier `cid` that may come secured under `policy`.
fn secured_types(cid: u16, policy: Policy) -> impl Iterator<Item = MsgType> {
    MsgType::ALL.into_iter().filter(move |t| {
        id::of(*t) == cid && (policy == Policy::All || STATE_CHANGING_TYPES.iter().any(|s| s == t))
    })
}

/// As [`write_with`], for a device provisioned with `policy`: under [`Policy::All`] every
/// identifier's types come secured too (type | 0x40, `<Type>Secured` in the `msg_type` value
/// tables). Their counter and MAC follow a body whose end is not at a fixed offset of a frame
/// (a `Measurement`'s length varies; the other secured messages span frames, a
/// `CompactMeasurement`, `Forces`, `Estimate` or `CompactResults` spilling into a second CAN
/// FD frame): they are message bytes (`first_bytes*`, `next_bytes*`; on CAN FD the first frames
/// of the identifiers with physical signals carry `<Type>Secured_bytes*`), to be found at the
/// end of the message, before its CRC.
pub fn write_policy<W: Write>(w: &mut W, mtu: Mtu, mac_len: MacLen, policy: Policy) -> fmt::Result {
    let fd = mtu == Mtu::Fd;
    let mut muxes = Muxes::new();
    writeln!(w, "VERSION \"gough-proto-{PROTO_VERSION}\"")?;
    writeln!(w)?;
    writeln!(w, "NS_ :")?;
    writeln!(
        w,
        "\tBA_DEF_\n\tBA_DEF_DEF_\n\tBA_\n\tSIG_VALTYPE_\n\tSG_MUL_VAL_"
    )?;
    writeln!(w)?;
    writeln!(w, "BS_:")?;
    writeln!(w)?;
    writeln!(w, "BU_: HOST GOUGH")?;
    for (cid, name, dir) in id::ALL {
        let (tx, rx) = if dir == "host to device" {
            ("HOST", "GOUGH")
        } else {
            ("GOUGH", "HOST")
        };
        let len = mtu.frame_len(cid);
        let signals = has_bodies(mtu, cid) || (fd && cid == id::CONFIG);
        writeln!(w)?;
        writeln!(w, "BO_ {cid} {name}: {len} {tx}")?;
        writeln!(w, " SG_ frame_index M : 0|6@1+ (1,0) [0|63] \"\" {rx}")?;
        writeln!(w, " SG_ last_frame : 6|1@1+ (1,0) [0|1] \"\" {rx}")?;
        writeln!(w, " SG_ first_frame : 7|1@1+ (1,0) [0|1] \"\" {rx}")?;
        writeln!(w, " SG_ msg_seq : 8|8@1+ (1,0) [0|255] \"\" {rx}")?;
        writeln!(w, " SG_ msg_len m0 : 16|8@1+ (1,0) [6|255] \"byte\" {rx}")?;
        writeln!(w, " SG_ proto_version m0 : 24|8@1+ (1,0) [0|255] \"\" {rx}")?;
        if signals {
            writeln!(w, " SG_ msg_type m0M : 32|8@1+ (1,0) [0|255] \"\" {rx}")?;
            if cid == id::CONFIG {
                config_fd(w, len, mac_len, rx, &mut muxes)?;
            } else if policy == Policy::All {
                for t in secured_types(cid, policy) {
                    let mut name = Name::new();
                    let _ = write!(name, "{}Secured_bytes", t.name());
                    muxed_bytes(w, &name, t as u8 | SECURED, (BODY, len), rx, &mut muxes)?;
                }
            }
            for (_, t, fields) in BODIES.iter().filter(|b| b.0 == cid) {
                for (name, off, n, kind, scale, unit, _) in fields.iter() {
                    let sign = if matches!(kind, Kind::I | Kind::F) {
                        '-'
                    } else {
                        '+'
                    };
                    let (start, bits) = match kind {
                        Kind::Bits(b, l) => ((BODY + off) * 8 + b, *l),
                        _ => ((BODY + off) * 8, n * 8),
                    };
                    writeln!(
                        w,
                        " SG_ {name} m{} : {start}|{bits}@1{sign} ({scale},0) [0|0] \"{unit}\" {rx}",
                        *t as u8,
                    )?;
                }
            }
        } else {
            writeln!(w, " SG_ msg_type m0 : 32|8@1+ (1,0) [0|255] \"\" {rx}")?;
            byte_signals(w, "first_bytes", "m0", (BODY, len), rx)?;
        }
        byte_signals(w, "next_bytes", "m1", (2, len), rx)?;
    }
    writeln!(w)?;
    for (cid, _, dir) in id::ALL {
        write!(
            w,
            "CM_ BO_ {cid} \"gough protocol v{PROTO_VERSION}, {dir}: segmented messages (header, postcard body, CRC-32). Carries:"
        )?;
        for t in MsgType::ALL.iter().filter(|t| id::of(**t) == cid) {
            write!(w, " {}", t.name())?;
        }
        if policy == Policy::All {
            write!(
                w,
                ". Every message secured (type | 0x40; the device provisioned to authenticate every message): counter (u32 LE) and AES-128-CMAC truncated to {} bytes after the body, before the CRC-32",
                mac_len.get()
            )?;
        } else if cid == id::CONFIG {
            write!(
                w,
                ". Secured (type | 0x40: upload, settings, calibration, reset, stop): counter (u32 LE) and AES-128-CMAC truncated to {} bytes after the body, before the CRC-32",
                mac_len.get()
            )?;
        }
        writeln!(w, "\";")?;
    }
    if fd {
        writeln!(w, "BA_DEF_ BO_ \"VFrameFormat\" ENUM \"StandardCAN\",\"ExtendedCAN\",\"reserved\",\"J1939PG\",\"reserved\",\"reserved\",\"reserved\",\"reserved\",\"reserved\",\"reserved\",\"reserved\",\"reserved\",\"reserved\",\"reserved\",\"StandardCAN_FD\",\"ExtendedCAN_FD\";")?;
        writeln!(w, "BA_DEF_ BO_ \"CANFD_BRS\" ENUM \"0\",\"1\";")?;
        writeln!(w, "BA_DEF_ \"BusType\" STRING ;")?;
        writeln!(w, "BA_DEF_DEF_ \"VFrameFormat\" \"StandardCAN\";")?;
        writeln!(w, "BA_DEF_DEF_ \"CANFD_BRS\" \"1\";")?;
        writeln!(w, "BA_DEF_DEF_ \"BusType\" \"CAN FD\";")?;
        writeln!(w, "BA_ \"BusType\" \"CAN FD\";")?;
        for (cid, _, _) in id::ALL {
            writeln!(w, "BA_ \"VFrameFormat\" BO_ {cid} 14;")?;
            writeln!(w, "BA_ \"CANFD_BRS\" BO_ {cid} 1;")?;
        }
    }
    for (cid, _, _) in id::ALL {
        write!(w, "VAL_ {cid} msg_type")?;
        for t in MsgType::ALL.iter().filter(|t| id::of(**t) == cid) {
            write!(w, " {} \"{}\"", *t as u8, t.name())?;
        }
        for t in secured_types(cid, policy) {
            write!(w, " {} \"{}Secured\"", t as u8 | SECURED, t.name())?;
        }
        writeln!(w, " ;")?;
    }
    if fd {
        for (cid, _, fields) in BODIES {
            for (name, .., table) in fields.iter().filter(|f| !f.6.is_empty()) {
                write!(w, "VAL_ {cid} {name}")?;
                for (i, v) in table.iter().enumerate() {
                    write!(w, " {i} \"{v}\"")?;
                }
                writeln!(w, " ;")?;
            }
        }
        for (cid, _, fields) in BODIES {
            for (name, ..) in fields.iter().filter(|f| f.3 == Kind::F) {
                writeln!(w, "SIG_VALTYPE_ {cid} {name} : 1;")?;
            }
        }
    }
    for (cid, _, _) in id::ALL {
        let len = mtu.frame_len(cid);
        let n = (len - 2).div_ceil(8);
        for k in 0..n {
            write!(w, "SG_MUL_VAL_ {cid} next_bytes")?;
            if n > 1 {
                write!(w, "_{k}")?;
            }
            writeln!(w, " frame_index 1-63;")?;
        }
        if has_bodies(mtu, cid) || (fd && cid == id::CONFIG) {
            // Two multiplexers: every multiplexed signal names its multiplexer here.
            for name in ["msg_len", "proto_version", "msg_type"] {
                writeln!(w, "SG_MUL_VAL_ {cid} {name} frame_index 0-0;")?;
            }
            for (_, t, fields) in BODIES.iter().filter(|b| b.0 == cid) {
                for (name, ..) in fields.iter() {
                    writeln!(w, "SG_MUL_VAL_ {cid} {name} msg_type {0}-{0};", *t as u8)?;
                }
            }
            {
                for (name, t) in muxes
                    .iter()
                    .filter(|(_, t)| MsgType::from_u8(t & !SECURED).map(id::of) == Some(cid))
                {
                    writeln!(w, "SG_MUL_VAL_ {cid} {name} msg_type {t}-{t};")?;
                }
            }
        }
    }
    Ok(())
}
