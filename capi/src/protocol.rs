//! The CAN protocol (`gough::proto`): messages to and from C structs, encoding into frames,
//! reassembly of received frames.

use crate::*;

/// `gough_msg_t::kind`: no message (`gough_rx_feed`: not complete yet).
pub const GOUGH_MSG_NONE: u32 = 0;
/// Host → device: a measurement (`gough_msg_t::measurement`).
pub const GOUGH_MSG_MEASUREMENT: u32 = 1;
/// Host → device: start a parameter upload (`param_len`, `param_hash`).
pub const GOUGH_MSG_PARAM_BEGIN: u32 = 2;
/// Host → device: a chunk of `.tir` text (`param_offset`, `chunk_len`, `chunk`).
pub const GOUGH_MSG_PARAM_CHUNK: u32 = 3;
/// Host → device: end of the upload (`param_hash`).
pub const GOUGH_MSG_PARAM_COMMIT: u32 = 4;
/// Host → device: settings (`settings`).
pub const GOUGH_MSG_SETTINGS: u32 = 5;
/// Host → device: a command (`command`: 0 reset, 1 status request, 2 stop).
pub const GOUGH_MSG_COMMAND: u32 = 6;
/// Device → host: predicted forces (`wheel`, `t_us`, `forces`).
pub const GOUGH_MSG_FORCES: u32 = 7;
/// Device → host: a friction estimate (`wheel`, `t_us`, `estimate`).
pub const GOUGH_MSG_ESTIMATE: u32 = 8;
/// Device → host: a status report (received only: its fields are not carried here).
pub const GOUGH_MSG_STATUS: u32 = 9;
/// Device → host: an acknowledgement (`ack_of`, `ack_seq`, `ack_code`, `ack_line`).
pub const GOUGH_MSG_ACK: u32 = 10;
/// A complete message the C API does not map (the four-wheel `CompactBatch` and
/// `CompactResults`, protocol types 0x08 and 0x85): only `kind` is set.
pub const GOUGH_MSG_OTHER: u32 = 11;
/// Device → host: a wheel's calibration (`wheel`, `calibration`), reported at a low rate.
pub const GOUGH_MSG_CALIBRATION: u32 = 12;
/// Host → device: start a wheel's estimator from a calibration (`wheel`, `calibration`);
/// acknowledged (code 11: refused).
pub const GOUGH_MSG_SET_CALIBRATION: u32 = 13;
/// Bytes of `.tir` text in one parameter chunk, at most.
pub const GOUGH_CHUNK_LEN: usize = 48;
/// Frames of one message, at most (classic CAN, 8 bytes each).
pub const GOUGH_MAX_FRAMES: usize = 16;

/// The protocol's settings (`docs/protocol.md`).
#[repr(C)]
#[derive(Debug, Clone, Copy, Default)]
pub struct gough_settings_t {
    /// Clip inputs to the `.tir` ranges: 1 on, 0 off.
    pub limits: u32,
    /// μ [-] reported in the fallback state (the estimators' prior).
    pub fallback_mu: f32,
    /// The car's wheelbase [m] for the front-to-rear preview; 0: none. The device refuses
    /// anything but 0 or a positive number (ack code 10).
    pub wheelbase: f32,
}

/// One protocol message, flattened: `kind` (`GOUGH_MSG_*`) says which fields count.
#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub struct gough_msg_t {
    /// `GOUGH_MSG_*`.
    pub kind: u32,
    /// `GOUGH_MSG_MEASUREMENT`.
    pub measurement: gough_measurement_t,
    /// `GOUGH_MSG_FORCES`, `GOUGH_MSG_ESTIMATE`, `GOUGH_MSG_CALIBRATION`,
    /// `GOUGH_MSG_SET_CALIBRATION`: wheel 0..3 (FL, FR, RL, RR).
    pub wheel: u32,
    /// `GOUGH_MSG_FORCES`, `GOUGH_MSG_ESTIMATE`: timestamp of the measurement [µs].
    pub t_us: u32,
    /// `GOUGH_MSG_FORCES`: the forces (ISO-W, contact point; flags are 16 bits on the wire).
    pub forces: gough_forces_t,
    /// `GOUGH_MSG_ESTIMATE`: μ, σ, μ_min, state, and in `flags` the change of surface
    /// (`GOUGH_EST_CHANGE`) and the model mismatch (`GOUGH_EST_MISMATCH`); `GOUGH_EST_NONE` is
    /// not on the wire: ignored when sending.
    pub estimate: gough_estimate_t,
    /// `GOUGH_MSG_CALIBRATION`, `GOUGH_MSG_SET_CALIBRATION`: the calibration (sent as it is:
    /// the receiving estimator checks it).
    pub calibration: gough_calibration_t,
    /// `GOUGH_MSG_PARAM_BEGIN`: length of the `.tir` text [bytes].
    pub param_len: u32,
    /// `GOUGH_MSG_PARAM_BEGIN`, `GOUGH_MSG_PARAM_COMMIT`: CRC-32 of the text.
    pub param_hash: u32,
    /// `GOUGH_MSG_PARAM_CHUNK`: where the chunk goes in the text [bytes].
    pub param_offset: u32,
    /// `GOUGH_MSG_PARAM_CHUNK`: bytes in `chunk` (≤ `GOUGH_CHUNK_LEN`).
    pub chunk_len: u32,
    /// `GOUGH_MSG_PARAM_CHUNK`: the text.
    pub chunk: [u8; GOUGH_CHUNK_LEN],
    /// `GOUGH_MSG_SETTINGS`.
    pub settings: gough_settings_t,
    /// `GOUGH_MSG_COMMAND`: 0 reset, 1 status request, 2 stop.
    pub command: u32,
    /// `GOUGH_MSG_ACK`: message-type byte of the request.
    pub ack_of: u32,
    /// `GOUGH_MSG_ACK`: sequence number of the request.
    pub ack_seq: u32,
    /// `GOUGH_MSG_ACK`: 0 ok, 1 bad hash, 2 bad length, 3 bad offset, 4 not in upload, 5 .tir
    /// error (`ack_line`), 6 no params, 7 no slip, 8 evaluation error, 9 not supported,
    /// 10 bad settings, 11 bad calibration; v5 (authentication): 12 no key, 13 MAC missing,
    /// 14 bad MAC, 15 stale freshness.
    pub ack_code: u32,
    /// `GOUGH_MSG_ACK` with code 5: 1-based line of the first error (0: the whole file).
    pub ack_line: u32,
}

/// One classic CAN frame.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default)]
pub struct gough_frame_t {
    /// 11-bit CAN identifier (0x300 measurements, 0x301 configuration, 0x310 results, 0x311
    /// status and acknowledgements).
    pub id: u32,
    /// Data bytes used (1..8).
    pub len: u32,
    /// Data.
    pub data: [u8; 8],
}

pub(crate) const ZERO_MSG: gough_msg_t = gough_msg_t {
    kind: GOUGH_MSG_NONE,
    measurement: gough_measurement_t {
        wheel: 0,
        t_us: 0,
        fz: 0.0,
        fy: 0.0,
        mz: 0.0,
        fx: 0.0,
        vx: 0.0,
        omega: 0.0,
        delta: 0.0,
        alpha: 0.0,
        kappa: 0.0,
        gamma: 0.0,
        present: 0,
    },
    wheel: 0,
    t_us: 0,
    forces: gough_forces_t {
        fx: 0.0,
        fy: 0.0,
        mz: 0.0,
        flags: 0,
    },
    estimate: gough_estimate_t {
        mu: 0.0,
        sigma: 0.0,
        mu_min: 0.0,
        state: 0,
        flags: 0,
    },
    calibration: gough_calibration_t {
        value: [0.0; GOUGH_CAL_PROPERTIES],
        sigma: [0.0; GOUGH_CAL_PROPERTIES],
        batches: 0,
    },
    param_len: 0,
    param_hash: 0,
    param_offset: 0,
    chunk_len: 0,
    chunk: [0; GOUGH_CHUNK_LEN],
    settings: gough_settings_t {
        limits: 0,
        fallback_mu: 0.0,
        wheelbase: 0.0,
    },
    command: 0,
    ack_of: 0,
    ack_seq: 0,
    ack_code: 0,
    ack_line: 0,
};

fn to_c_meas(m: &proto::Measurement) -> gough_measurement_t {
    let mut present = 0;
    let mut f = |x: Option<f32>, bit: u32| match x {
        Some(v) => {
            present |= bit;
            v
        }
        None => 0.0,
    };
    let (fx, vx, omega, delta, alpha, kappa, gamma) = (
        f(m.fx, GOUGH_HAS_FX),
        f(m.vx, GOUGH_HAS_VX),
        f(m.omega, GOUGH_HAS_OMEGA),
        f(m.delta, GOUGH_HAS_DELTA),
        f(m.alpha, GOUGH_HAS_ALPHA),
        f(m.kappa, GOUGH_HAS_KAPPA),
        f(m.gamma, GOUGH_HAS_GAMMA),
    );
    gough_measurement_t {
        wheel: m.wheel.index() as u32,
        t_us: m.t_us,
        fz: m.fz,
        fy: m.fy,
        mz: m.mz,
        fx,
        vx,
        omega,
        delta,
        alpha,
        kappa,
        gamma,
        present,
    }
}

fn ack_code(c: proto::AckCode) -> (u32, u32) {
    use proto::AckCode as A;
    match c {
        A::Ok => (0, 0),
        A::BadHash => (1, 0),
        A::BadLength => (2, 0),
        A::BadOffset => (3, 0),
        A::NotInUpload => (4, 0),
        A::TirError { line } => (5, line),
        A::NoParams => (6, 0),
        A::NoSlip => (7, 0),
        A::EvalError => (8, 0),
        A::NotSupported => (9, 0),
        A::BadSettings => (10, 0),
        A::BadCalibration => (11, 0),
        A::NoKey => (12, 0),
        A::MacMissing => (13, 0),
        A::BadMac => (14, 0),
        A::StaleFreshness => (15, 0),
    }
}

fn ack_from(code: u32, line: u32) -> Option<proto::AckCode> {
    use proto::AckCode as A;
    Some(match code {
        0 => A::Ok,
        1 => A::BadHash,
        2 => A::BadLength,
        3 => A::BadOffset,
        4 => A::NotInUpload,
        5 => A::TirError { line },
        6 => A::NoParams,
        7 => A::NoSlip,
        8 => A::EvalError,
        9 => A::NotSupported,
        10 => A::BadSettings,
        11 => A::BadCalibration,
        12 => A::NoKey,
        13 => A::MacMissing,
        14 => A::BadMac,
        15 => A::StaleFreshness,
        _ => return None,
    })
}

fn to_c(m: &Msg) -> gough_msg_t {
    let mut o = ZERO_MSG;
    match m {
        Msg::Measurement(x) => {
            o.kind = GOUGH_MSG_MEASUREMENT;
            o.measurement = to_c_meas(x);
        }
        // A compact measurement reaches C as the measurement it stands for.
        Msg::CompactMeasurement(x) => {
            o.kind = GOUGH_MSG_MEASUREMENT;
            o.measurement = to_c_meas(&x.measurement());
        }
        Msg::ParamBegin(x) => {
            o.kind = GOUGH_MSG_PARAM_BEGIN;
            o.param_len = x.len;
            o.param_hash = x.hash;
        }
        Msg::ParamChunk(x) => {
            o.kind = GOUGH_MSG_PARAM_CHUNK;
            o.param_offset = x.offset;
            let d = x.data.as_slice();
            o.chunk_len = d.len() as u32;
            for (c, b) in o.chunk.iter_mut().zip(d) {
                *c = *b;
            }
        }
        Msg::ParamCommit(x) => {
            o.kind = GOUGH_MSG_PARAM_COMMIT;
            o.param_hash = x.hash;
        }
        Msg::Settings(s) => {
            o.kind = GOUGH_MSG_SETTINGS;
            o.settings = gough_settings_t {
                limits: u32::from(s.limits),
                fallback_mu: s.fallback_mu,
                wheelbase: s.wheelbase,
            };
        }
        Msg::Command(c) => {
            o.kind = GOUGH_MSG_COMMAND;
            o.command = match c {
                proto::Command::Reset => 0,
                proto::Command::StatusRequest => 1,
                proto::Command::Stop => 2,
            };
        }
        Msg::Forces(f) => {
            o.kind = GOUGH_MSG_FORCES;
            o.wheel = f.wheel.index() as u32;
            o.t_us = f.t_us;
            o.forces = gough_forces_t {
                fx: f.fx,
                fy: f.fy,
                mz: f.mz,
                flags: u32::from(f.flags),
            };
        }
        Msg::Estimate(e) => {
            o.kind = GOUGH_MSG_ESTIMATE;
            o.wheel = e.wheel.index() as u32;
            o.t_us = e.t_us;
            o.estimate = estimate_c(&e.estimate());
        }
        Msg::Calibration(c) | Msg::SetCalibration(c) => {
            o.kind = if matches!(m, Msg::Calibration(_)) {
                GOUGH_MSG_CALIBRATION
            } else {
                GOUGH_MSG_SET_CALIBRATION
            };
            o.wheel = c.wheel.index() as u32;
            o.calibration = gough_calibration_t {
                value: c.value,
                sigma: c.sigma,
                batches: c.batches,
            };
        }
        Msg::Status(_) => o.kind = GOUGH_MSG_STATUS,
        Msg::CompactBatch(_) | Msg::CompactResults(_) => o.kind = GOUGH_MSG_OTHER,
        Msg::Ack(a) => {
            o.kind = GOUGH_MSG_ACK;
            o.ack_of = u32::from(a.of);
            o.ack_seq = u32::from(a.seq);
            let (c, l) = ack_code(a.code);
            o.ack_code = c;
            o.ack_line = l;
        }
    }
    o
}

fn from_c(m: &gough_msg_t) -> Result<Msg, i32> {
    let wheel = || proto::Wheel::from_index(m.wheel as usize).ok_or(GOUGH_E_ARG);
    Ok(match m.kind {
        GOUGH_MSG_MEASUREMENT => Msg::Measurement(measurement(&m.measurement)?),
        GOUGH_MSG_PARAM_BEGIN => Msg::ParamBegin(proto::ParamBegin {
            len: m.param_len,
            hash: m.param_hash,
        }),
        GOUGH_MSG_PARAM_CHUNK => {
            let d = m
                .chunk
                .get(..m.chunk_len as usize)
                .and_then(proto::Bytes::new)
                .ok_or(GOUGH_E_ARG)?;
            Msg::ParamChunk(proto::ParamChunk {
                offset: m.param_offset,
                data: d,
            })
        }
        GOUGH_MSG_PARAM_COMMIT => Msg::ParamCommit(proto::ParamCommit { hash: m.param_hash }),
        GOUGH_MSG_SETTINGS => {
            let s = &m.settings;
            if !finite(&[s.fallback_mu, s.wheelbase]) {
                return Err(GOUGH_E_NONFINITE);
            }
            Msg::Settings(Settings {
                limits: s.limits != 0,
                fallback_mu: s.fallback_mu,
                wheelbase: s.wheelbase,
            })
        }
        GOUGH_MSG_COMMAND => Msg::Command(match m.command {
            0 => proto::Command::Reset,
            1 => proto::Command::StatusRequest,
            2 => proto::Command::Stop,
            _ => return Err(GOUGH_E_ARG),
        }),
        GOUGH_MSG_FORCES => {
            let f = &m.forces;
            if !finite(&[f.fx, f.fy, f.mz]) {
                return Err(GOUGH_E_NONFINITE);
            }
            Msg::Forces(proto::Forces {
                wheel: wheel()?,
                t_us: m.t_us,
                fx: f.fx,
                fy: f.fy,
                mz: f.mz,
                flags: u16::try_from(f.flags).map_err(|_| GOUGH_E_ARG)?,
            })
        }
        GOUGH_MSG_ESTIMATE => {
            let e = &m.estimate;
            if !finite(&[e.mu, e.sigma, e.mu_min]) {
                return Err(GOUGH_E_NONFINITE);
            }
            Msg::Estimate(proto::Estimate {
                wheel: wheel()?,
                t_us: m.t_us,
                mu: e.mu,
                sigma: e.sigma,
                state: match e.state {
                    GOUGH_STATE_IDENTIFIABLE => mu::State::Identifiable,
                    GOUGH_STATE_NOT_IDENTIFIABLE => mu::State::NotIdentifiable,
                    GOUGH_STATE_FALLBACK => mu::State::Fallback,
                    _ => return Err(GOUGH_E_ARG),
                },
                mu_min: e.mu_min,
                change: e.flags & GOUGH_EST_CHANGE != 0,
                mismatch: e.flags & GOUGH_EST_MISMATCH != 0,
            })
        }
        GOUGH_MSG_CALIBRATION | GOUGH_MSG_SET_CALIBRATION => {
            let c = &m.calibration;
            let state = proto::CalibrationState {
                wheel: wheel()?,
                value: c.value,
                sigma: c.sigma,
                batches: c.batches,
            };
            if m.kind == GOUGH_MSG_CALIBRATION {
                Msg::Calibration(state)
            } else {
                Msg::SetCalibration(state)
            }
        }
        GOUGH_MSG_ACK => Msg::Ack(proto::Ack {
            of: u8::try_from(m.ack_of).map_err(|_| GOUGH_E_ARG)?,
            seq: u8::try_from(m.ack_seq).map_err(|_| GOUGH_E_ARG)?,
            code: ack_from(m.ack_code, m.ack_line).ok_or(GOUGH_E_ARG)?,
        }),
        _ => return Err(GOUGH_E_ARG),
    })
}

/// Encodes `msg` with sequence number `seq` into classic CAN frames `frames[0..*n]` (`cap`
/// frames available; `GOUGH_MAX_FRAMES` always suffice). `GOUGH_E_BUFFER`: more than `cap`
/// frames needed (`*n` gets how many). A status message cannot be sent from C
/// (`GOUGH_E_ARG`).
#[no_mangle]
pub unsafe extern "C" fn gough_msg_encode(
    msg: *const gough_msg_t,
    seq: u8,
    frames: *mut gough_frame_t,
    cap: usize,
    n: *mut usize,
) -> i32 {
    ret(|| {
        if msg.is_null() || frames.is_null() || n.is_null() {
            return Err(GOUGH_E_NULL);
        }
        // SAFETY: non-null, the caller's message.
        let m = from_c(unsafe { &*msg })?;
        let seg = Segmenter::new(&m, seq, Mtu::Classic).map_err(|_| GOUGH_E_ARG)?;
        // SAFETY: the caller's non-null frames (`cap` of them) and count.
        unsafe { write_frames(seg, u32::from(proto::id::of(m.msg_type())), frames, cap, n) }
    })
}

/// Writes the classic CAN frames of `seg` on identifier `id` into `frames[0..*n]`.
///
/// # Safety
/// `frames` points to `cap` writable frames, `n` to a writable count (both non-null).
unsafe fn write_frames(
    mut seg: Segmenter,
    id: u32,
    frames: *mut gough_frame_t,
    cap: usize,
    n: *mut usize,
) -> Result<(), i32> {
    let need = seg.frame_count();
    // SAFETY: non-null, the caller's count.
    unsafe { n.write(need) };
    if need > cap {
        return Err(GOUGH_E_BUFFER);
    }
    let mut buf = [0u8; 64];
    let mut k = 0;
    while let Some(f) = seg.next_frame(&mut buf) {
        let mut data = [0u8; 8];
        for (d, b) in data.iter_mut().zip(f) {
            *d = *b;
        }
        if k >= cap {
            return Err(GOUGH_E_BUFFER);
        }
        // SAFETY: k < cap frames of the caller's array.
        unsafe {
            frames.add(k).write(gough_frame_t {
                id,
                len: f.len() as u32,
                data,
            })
        };
        k += 1;
    }
    Ok(())
}

/// The device owner's signing state for secured messages (docs/protocol.md, "Security"): the
/// device key, the device's MAC length, its epoch and the last counter used. Fill it from the
/// device's `Status` (`auth`: MAC length, epoch, last accepted counter; with `gough replay
/// --key-file` or python-can) and keep it: [`gough_msg_encode_secured`] advances it.
#[repr(C)]
#[derive(Clone, Copy)]
pub struct gough_signer_t {
    /// The 16-byte device key (a key file's 32 hexadecimal digits).
    pub key: [u8; 16],
    /// MAC length \[bytes\], 4..=8: the device's.
    pub mac_len: u32,
    /// The device's epoch (its boot counter).
    pub epoch: u32,
    /// The last counter used: the device's last accepted counter at the start. After counter
    /// 0xFFFFFFFF the signer moves to epoch + 1, counter 0, as the device does.
    pub counter: u32,
    /// Nonzero: secure every message (measurements, status requests too), for a device
    /// provisioned to authenticate every message (`gough firmware run --secure-all`); its
    /// answers are checked by a `gough_verifier_t` ([`gough_rx_feed_secured`]). 0: the
    /// state-changing messages only.
    pub all: u32,
}

/// As [`gough_msg_encode`], a state-changing message (`GOUGH_MSG_PARAM_BEGIN`, `_CHUNK`,
/// `_COMMIT`, `GOUGH_MSG_SETTINGS`, `GOUGH_MSG_SET_CALIBRATION`, a reset or stop command)
/// secured with `*signer`'s key and next counter (AES-128-CMAC truncated to `mac_len` bytes);
/// every other message unsecured, unless `signer->all` is set (then every message is secured). `GOUGH_E_ARG` also for a `mac_len` outside 4..=8. The signer
/// advances only when frames were written.
#[no_mangle]
pub unsafe extern "C" fn gough_msg_encode_secured(
    signer: *mut gough_signer_t,
    msg: *const gough_msg_t,
    seq: u8,
    frames: *mut gough_frame_t,
    cap: usize,
    n: *mut usize,
) -> i32 {
    ret(|| {
        if signer.is_null() || msg.is_null() || frames.is_null() || n.is_null() {
            return Err(GOUGH_E_NULL);
        }
        // SAFETY: non-null, the caller's message and signer.
        let (m, st) = (from_c(unsafe { &*msg })?, unsafe { *signer });
        let mac_len = u8::try_from(st.mac_len)
            .ok()
            .and_then(proto::MacLen::new)
            .ok_or(GOUGH_E_ARG)?;
        let id = proto::id::of(m.msg_type());
        let mut s = proto::Signer::new(proto::Key::new(st.key), mac_len, st.epoch, st.counter);
        let seg = if st.all != 0 || proto::auth::is_state_changing(&m) {
            Segmenter::sealed(&m, seq, Mtu::Classic, &mut s)
        } else {
            Segmenter::new(&m, seq, Mtu::Classic)
        }
        .map_err(|_| GOUGH_E_ARG)?;
        // SAFETY: the caller's non-null frames (`cap` of them) and count.
        unsafe { write_frames(seg, u32::from(id), frames, cap, n) }?;
        let (epoch, counter) = s.freshness();
        // SAFETY: non-null, the caller's signer.
        unsafe {
            (*signer).epoch = epoch;
            (*signer).counter = counter;
        }
        Ok(())
    })
}

/// Starts a reassembler (one per CAN identifier received).
#[no_mangle]
pub unsafe extern "C" fn gough_rx_init(rx: *mut gough_rx_t) -> i32 {
    if rx.is_null() {
        return GOUGH_E_NULL;
    }
    // SAFETY: non-null, GOUGH_RX_SIZE bytes aligned to 8.
    unsafe { put(rx, MAGIC_RX, Reassembler::<MSG_BUF>::new()) };
    GOUGH_OK
}

/// A received frame's data bytes: its first `len` (1 to the frame's capacity), else
/// `GOUGH_E_ARG`.
fn frame_data(f: &gough_frame_t) -> Result<&[u8], i32> {
    f.data
        .get(..f.len as usize)
        .filter(|d| !d.is_empty())
        .ok_or(GOUGH_E_ARG)
}

/// Feeds one received frame at time `now_ms` [ms] (a message whose frames are more than 50 ms
/// apart is dropped). `*out` gets the message when this frame completes one, else
/// `kind = GOUGH_MSG_NONE`. `GOUGH_E_PROTO`: the frame or the message was dropped (counted).
#[no_mangle]
pub unsafe extern "C" fn gough_rx_feed(
    rx: *mut gough_rx_t,
    frame: *const gough_frame_t,
    now_ms: u32,
    out: *mut gough_msg_t,
) -> i32 {
    ret(|| {
        // SAFETY: a reassembler storage or null; exclusive for the call.
        let r: &mut Reassembler<MSG_BUF> = unsafe { get_mut(rx, MAGIC_RX)? };
        if frame.is_null() || out.is_null() {
            return Err(GOUGH_E_NULL);
        }
        // SAFETY: non-null, the caller's frame.
        let f = unsafe { &*frame };
        let data = frame_data(f)?;
        let (msg, code) = match r.feed(data, now_ms) {
            Feed::Pending => (ZERO_MSG, Ok(())),
            Feed::Done(m) => (to_c(&m), Ok(())),
            Feed::Dropped(_) => (ZERO_MSG, Err(GOUGH_E_PROTO)),
        };
        // SAFETY: non-null, the caller's output.
        unsafe { out.write(msg) };
        code
    })
}

/// Starts checking (in `*v`, which must not be copied or moved afterwards: initialise a new
/// one instead) the secured answers of a device that authenticates every message
/// (`gough firmware run --secure-all`; docs/protocol.md, "Security"): its 16-byte `key` (a
/// key file's 32 hexadecimal digits), MAC length (4..=8, its `Status`), its `epoch`, and the
/// device's transmit counter to continue above (the counter of a `Status` it sent, less one).
/// Each answer must then be secured, its MAC verify, and its counter be above the last one
/// accepted on its CAN identifier (at most 65,536 above the highest). `GOUGH_E_ARG`: `mac_len`
/// outside 4..=8.
#[no_mangle]
pub unsafe extern "C" fn gough_verifier_init(
    v: *mut gough_verifier_t,
    key: *const u8,
    mac_len: u32,
    epoch: u32,
    counter: u32,
) -> i32 {
    ret(|| {
        if v.is_null() || key.is_null() {
            return Err(GOUGH_E_NULL);
        }
        // SAFETY: non-null, the caller's 16 key bytes.
        let k: [u8; 16] = unsafe { key.cast::<[u8; 16]>().read_unaligned() };
        let mac_len = u8::try_from(mac_len)
            .ok()
            .and_then(proto::MacLen::new)
            .ok_or(GOUGH_E_ARG)?;
        let mut ver = proto::Verifier::new(proto::Key::new(k), mac_len, epoch)
            .with_policy(proto::Policy::All);
        ver.set_counter(counter);
        // SAFETY: non-null, GOUGH_VERIFIER_SIZE bytes aligned to 8.
        unsafe { put(aligned(v), MAGIC_VERIFIER, ver) };
        Ok(())
    })
}

/// As [`gough_rx_feed`], and a message it completes is checked by `*v` (its MAC over the
/// frame's identifier, its freshness): `GOUGH_E_AUTH` (and `kind = GOUGH_MSG_NONE`) when it is
/// refused — not secured, forged or altered, another key or epoch, stale — counted in `*v`.
#[no_mangle]
pub unsafe extern "C" fn gough_rx_feed_secured(
    rx: *mut gough_rx_t,
    v: *mut gough_verifier_t,
    frame: *const gough_frame_t,
    now_ms: u32,
    out: *mut gough_msg_t,
) -> i32 {
    ret(|| {
        // SAFETY: a reassembler storage or null; exclusive for the call.
        let r: &mut Reassembler<MSG_BUF> = unsafe { get_mut(rx, MAGIC_RX)? };
        // SAFETY: a verifier storage or null; exclusive for the call.
        let ver: &mut proto::Verifier = unsafe { get_mut(aligned(v), MAGIC_VERIFIER)? };
        if frame.is_null() || out.is_null() {
            return Err(GOUGH_E_NULL);
        }
        // SAFETY: non-null, the caller's frame.
        let f = unsafe { &*frame };
        let data = frame_data(f)?;
        let cid = u16::try_from(f.id).map_err(|_| GOUGH_E_ARG)?;
        let (msg, code) = match r.feed(data, now_ms) {
            Feed::Pending => (ZERO_MSG, Ok(())),
            Feed::Done(m) => match ver.check(cid, &m, r.last()) {
                Ok(()) => (to_c(&m), Ok(())),
                Err(_) => (ZERO_MSG, Err(GOUGH_E_AUTH)),
            },
            Feed::Dropped(_) => (ZERO_MSG, Err(GOUGH_E_PROTO)),
        };
        // SAFETY: non-null, the caller's output.
        unsafe { out.write(msg) };
        code
    })
}

/// What a `gough_verifier_t` counted (`gough_verifier_counts`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct gough_auth_counts_t {
    /// Messages accepted.
    pub accepted: u32,
    /// Refused: not secured.
    pub missing: u32,
    /// Refused: a MAC of the wrong length or value.
    pub bad_mac: u32,
    /// Refused: a counter not above the last accepted on its identifier, or too far above.
    pub stale: u32,
    /// The epoch, and the highest counter accepted in it.
    pub epoch: u32,
    /// The highest counter accepted in the epoch.
    pub counter: u32,
}

/// The counts of `*v` into `*out`.
#[no_mangle]
pub unsafe extern "C" fn gough_verifier_counts(
    v: *const gough_verifier_t,
    out: *mut gough_auth_counts_t,
) -> i32 {
    ret(|| {
        // SAFETY: a verifier storage or null.
        let ver: &proto::Verifier = unsafe { get(aligned(v.cast_mut()), MAGIC_VERIFIER)? };
        if out.is_null() {
            return Err(GOUGH_E_NULL);
        }
        let s = ver.status();
        // SAFETY: non-null, the caller's output.
        unsafe {
            out.write(gough_auth_counts_t {
                accepted: s.accepted,
                missing: s.missing,
                bad_mac: s.bad_mac,
                stale: s.stale,
                epoch: s.epoch,
                counter: s.counter,
            })
        };
        Ok(())
    })
}
