//! Firmware self-test under QEMU (semihosting exit code 0 = pass; the output is compared
//! with `firmware/golden/selftest.out`):
//! 1. protocol round trip: every kind of message → frames → SLCAN text → frames → message;
//! 2. a known input gives the known Magic Formula output (MFeval 4.0 oracle, f32 budget);
//! 3. garbage (pseudo-random bytes and frames) never panics, is counted, and a good message
//!    still gets through afterwards;
//! 4. the application over a loopback driver: parameter upload (good, bad hash, bad text),
//!    a measurement answered with forces and an estimate, a status report;
//! 5. authentication (`gough::proto::auth`): without a key every state-changing message is
//!    refused; with the test key (`firmware/keys/test.key`) unsigned, forged and replayed
//!    messages are refused and counted, and a replayed chunk inside an upload loses nothing;
//! 6. the friction estimator on the device: a slip-angle ramp, then held, on the bundled tyre's
//!    own surface is read as that surface's μ, within ±0.1, and said to be identifiable.
#![no_std]
#![no_main]

use core::sync::atomic::{AtomicU32, Ordering};
use cortex_m_rt::entry;
use cortex_m_semihosting::hprintln;
use embedded_can::Frame as _;
use gough::mu::State;
use gough::proto::auth;
use gough::proto::slcan::{self, CanFrame, Decoder, Line};
use gough::proto::*;
use gough_firmware::app::App;
use gough_firmware::mps2;

static mut APP: App = App::new();

fn check(ok: bool, what: &str, fails: &mut u32) {
    hprintln!("{} {}", if ok { "ok  " } else { "FAIL" }, what);
    if !ok {
        *fails += 1;
    }
}

fn meas() -> Measurement {
    Measurement {
        wheel: Wheel::FrontLeft,
        t_us: 1_000,
        fz: 6752.0,
        fy: -4000.0,
        mz: -150.0,
        fx: Some(6800.0),
        vx: Some(16.6),
        omega: None,
        delta: None,
        alpha: Some(0.04),
        kappa: Some(0.05),
        gamma: None,
    }
}

/// Message → frames → SLCAN lines → frames → reassembler.
fn through_slcan(m: &Msg, seq: u8, r: &mut Reassembler<MSG_BUF>, frames: &mut u32) -> Option<Msg> {
    let mut seg = Segmenter::new(m, seq, Mtu::Classic).ok()?;
    let mut buf = [0u8; 64];
    let mut dec = Decoder::new();
    let mut out = None;
    while let Some(f) = seg.next_frame(&mut buf) {
        let cf = CanFrame::standard(id::of(m.msg_type()), f)?;
        let mut line = [0u8; slcan::MAX_LINE];
        for &b in slcan::encode(&cf, &mut line) {
            if let Some(Ok(Line::Frame(g))) = dec.push(b) {
                *frames += 1;
                if let Feed::Done(d) = r.feed(g.data(), 0) {
                    out = Some(d);
                }
            }
        }
    }
    out
}

struct Rng(u32);
impl Rng {
    fn next(&mut self) -> u32 {
        // xorshift32
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 17;
        self.0 ^= self.0 << 5;
        self.0
    }
}

/// A CAN driver that replays queued host frames and records what the device sends.
struct Loopback {
    rx: heapless::Deque<CanFrame, 64>,
    tx: Reassembler<MSG_BUF>,
    got: heapless::Vec<Msg, 8>,
    /// Secures the state-changing messages `send` sends, when set.
    signer: Option<Signer>,
}

impl embedded_can::nb::Can for Loopback {
    type Frame = CanFrame;
    type Error = embedded_can::ErrorKind;
    fn transmit(&mut self, f: &CanFrame) -> nb::Result<Option<CanFrame>, Self::Error> {
        if let Feed::Done(m) = self.tx.feed(f.data(), 0) {
            let _ = self.got.push(m);
        }
        Ok(None)
    }
    fn receive(&mut self) -> nb::Result<CanFrame, Self::Error> {
        self.rx.pop_front().ok_or(nb::Error::WouldBlock)
    }
}

impl Loopback {
    /// Queues the frames of `m` and lets the application take them.
    fn send(&mut self, app: &mut App, m: &Msg, seq: u8) {
        let seg = match self.signer.as_mut() {
            Some(s) if auth::is_state_changing(m) => Segmenter::sealed(m, seq, Mtu::Classic, s),
            _ => Segmenter::new(m, seq, Mtu::Classic),
        };
        self.send_seg(
            app,
            seg.unwrap_or_else(|_| mps2::exit(false)),
            id::of(m.msg_type()),
        );
    }
    /// Queues the frames of an encoded message on identifier `cid` and lets the application
    /// take them.
    fn send_seg(&mut self, app: &mut App, mut seg: Segmenter, cid: u16) {
        let mut buf = [0u8; 64];
        while let Some(f) = seg.next_frame(&mut buf) {
            if let Some(cf) = CanFrame::standard(cid, f) {
                let _ = self.rx.push_back(cf);
            }
        }
        while !self.rx.is_empty() {
            let _ = app.poll(self, 0);
        }
    }
    /// Runs one tick; returns what the device sent since the last call.
    fn finish(&mut self, app: &mut App) -> heapless::Vec<Msg, 8> {
        app.tick(self, 1);
        let out = self.got.clone();
        self.got.clear();
        out
    }
}

fn upload(
    lb: &mut Loopback,
    app: &mut App,
    text: &[u8],
    hash: u32,
    seq: &mut u8,
) -> heapless::Vec<Msg, 8> {
    let mut next = || {
        *seq = seq.wrapping_add(1);
        *seq
    };
    let begin = Msg::ParamBegin(ParamBegin {
        len: text.len() as u32,
        hash,
    });
    lb.send(app, &begin, next());
    for (i, c) in text.chunks(CHUNK_LEN).enumerate() {
        let data = Bytes::new(c).unwrap_or_else(|| mps2::exit(false));
        let offset = (i * CHUNK_LEN) as u32;
        lb.send(app, &Msg::ParamChunk(ParamChunk { offset, data }), next());
    }
    lb.send(app, &Msg::ParamCommit(ParamCommit { hash }), next());
    lb.finish(app)
}

fn acks(v: &[Msg]) -> heapless::Vec<AckCode, 8> {
    v.iter()
        .filter_map(|m| match m {
            Msg::Ack(a) => Some(a.code),
            _ => None,
        })
        .collect()
}

#[entry]
fn main() -> ! {
    let mut fails = 0u32;
    hprintln!(
        "gough selftest (proto v{}, max message {} bytes)",
        PROTO_VERSION,
        MAX_MSG_LEN
    );

    // 1. round trip
    let msgs = [
        Msg::Measurement(meas()),
        Msg::ParamBegin(ParamBegin {
            len: 25427,
            hash: 0xdead_beef,
        }),
        Msg::ParamChunk(ParamChunk {
            offset: 48,
            data: Bytes::new(b"FNOMIN = 4000 $ nominal load").unwrap_or_else(|| mps2::exit(false)),
        }),
        Msg::ParamCommit(ParamCommit { hash: 0xdead_beef }),
        Msg::Settings(Settings::default()),
        Msg::Command(Command::StatusRequest),
        Msg::Forces(Forces {
            wheel: Wheel::RearRight,
            t_us: 7,
            fx: 1.0,
            fy: -2.0,
            mz: 3.0,
            flags: 5,
        }),
        Msg::Estimate(Estimate {
            wheel: Wheel::FrontRight,
            t_us: 9,
            mu: 0.8,
            sigma: 0.05,
            state: State::Identifiable,
            mu_min: 0.5,
            change: true,
            mismatch: true,
        }),
        Msg::Ack(Ack {
            of: 4,
            seq: 3,
            code: AckCode::TirError { line: 12 },
        }),
    ];
    let mut r = Reassembler::<MSG_BUF>::new();
    let (mut n_ok, mut frames) = (0u32, 0u32);
    for (i, m) in msgs.iter().enumerate() {
        if through_slcan(m, i as u8, &mut r, &mut frames) == Some(*m) {
            n_ok += 1;
        }
    }
    hprintln!(
        "round trip: {}/{} messages in {} frames",
        n_ok,
        msgs.len(),
        frames
    );
    check(
        n_ok as usize == msgs.len() && r.counters().dropped() == 0,
        "protocol round trip",
        &mut fails,
    );

    // 2. known input → known output: MFeval 4.0, MagicFormula61_Parameters.tir, useMode 111,
    // Fz 6752 N, kappa 0.05, alpha 0.04 rad, Vx 16.6 m/s (oracle combined sweep).
    // SAFETY: the only reference to APP.
    let app: &mut App = unsafe { &mut *core::ptr::addr_of_mut!(APP) };
    let mut lb = Loopback {
        rx: heapless::Deque::new(),
        tx: Reassembler::new(),
        got: heapless::Vec::new(),
        signer: None,
    };
    let ok = app
        .load_tir(gough_firmware::BUNDLED_TIR, ParamSource::Bundled)
        .is_ok();
    check(ok, "bundled tyre parses on the device", &mut fails);
    check(
        (0..4).all(|i| app.estimator(i).is_some()),
        "the four wheels' friction estimators start on the device",
        &mut fails,
    );
    let (fx0, fy0, mz0) = (
        6_897.759_634_803_259_f64,
        -4_219.670_752_246_919_f64,
        -163.226_771_332_549_84_f64,
    );
    let tol_f = 1e-4 * 6752.0; // tolerance.rs: f32 budget 1e-4·FNOMIN
    let tol_m = tol_f * 0.3936; // × R0
    match app.evaluate(&meas()) {
        Ok(f) => {
            hprintln!(
                "mf61 Fz 6752 kappa 0.05 alpha 0.04: Fx {:.1} Fy {:.1} Mz {:.2} flags {:#x}",
                f.fx,
                f.fy,
                f.mz,
                f.flags
            );
            let e = |a: f32, b: f64| (a as f64 - b).abs();
            check(
                e(f.fx, fx0) <= tol_f && e(f.fy, fy0) <= tol_f && e(f.mz, mz0) <= tol_m,
                "Magic Formula matches the MFeval oracle within the f32 budget",
                &mut fails,
            );
        }
        Err(c) => {
            hprintln!("evaluate failed: {:?}", c);
            fails += 1;
        }
    }

    // 3. garbage: random bytes into the SLCAN decoder and random frames into the reassembler
    let mut rng = Rng(0x1234_5678);
    let mut dec = Decoder::new();
    let mut r = Reassembler::<MSG_BUF>::new();
    let (mut lines, mut bad_lines, mut delivered) = (0u32, 0u32, 0u32);
    for i in 0..200_000u32 {
        let x = rng.next();
        // Mostly hex digits and 't' so that some lines are frames.
        let b = match x % 8 {
            0 => b't',
            1 => b'\r',
            2..=5 => b"0123456789ABCDEF"[(x >> 8) as usize % 16],
            _ => (x >> 16) as u8,
        };
        match dec.push(b) {
            Some(Ok(Line::Frame(f))) => {
                lines += 1;
                if let Feed::Done(_) = r.feed(f.data(), i / 100) {
                    delivered += 1;
                }
            }
            Some(Ok(_)) => lines += 1,
            Some(Err(_)) => bad_lines += 1,
            None => {}
        }
        if x.is_multiple_of(64) {
            let mut fr = [0u8; 8];
            for v in fr.iter_mut() {
                *v = rng.next() as u8;
            }
            fr[0] = (fr[0] & 0xC0) | (fr[0] & 1);
            if let Feed::Done(_) = r.feed(&fr[..(x as usize >> 8) % 9], i / 100) {
                delivered += 1;
            }
        }
    }
    let c = *r.counters();
    hprintln!(
        "garbage: {} lines, {} bad lines, {} frames fed, {} dropped, {} delivered",
        lines,
        bad_lines,
        c.frames,
        c.dropped(),
        delivered
    );
    let mut frames = 0;
    let after = through_slcan(&msgs[0], 200, &mut r, &mut frames);
    check(
        delivered == 0 && after == Some(msgs[0]),
        "garbage: nothing delivered, a good message still goes through",
        &mut fails,
    );

    // 4. the application over a loopback driver; first without a key (refused), then with the
    // test key, epoch 1.
    let key =
        Key::from_hex(include_str!("../../keys/test.key")).unwrap_or_else(|| mps2::exit(false));
    let settings = Msg::Settings(Settings::default());
    lb.signer = Some(Signer::new(key, MacLen::DEFAULT, 1, 0));
    lb.send(app, &settings, 1);
    lb.signer = None;
    lb.send(app, &settings, 2);
    lb.send(app, &Msg::Command(Command::Reset), 3);
    let a = acks(&lb.finish(app));
    check(
        a.as_slice() == [AckCode::NoKey; 3] && app.status().auth.no_key == 3,
        "auth: a device without a key refuses settings and reset, secured or not (NoKey, counted)",
        &mut fails,
    );
    app.provision(Verifier::new(key, MacLen::DEFAULT, 1));
    lb.signer = Some(Signer::new(key, MacLen::DEFAULT, 1, 0));
    let text = gough_firmware::BUNDLED_TIR.as_bytes();
    let hash = crc32(text);
    let mut seq = 0u8;
    let a = acks(&upload(&mut lb, app, text, hash, &mut seq));
    check(
        a.as_slice() == [AckCode::Ok, AckCode::Ok],
        "upload: begin and commit acknowledged",
        &mut fails,
    );
    let a = acks(&upload(&mut lb, app, text, hash ^ 1, &mut seq));
    check(
        a.as_slice() == [AckCode::Ok, AckCode::BadHash],
        "upload with a wrong hash: rejected",
        &mut fails,
    );
    let bad = b"[MODEL]\nFITTYP = 61\nFNOMIN = oops\n";
    let a = acks(&upload(&mut lb, app, bad, crc32(bad), &mut seq));
    hprintln!("bad text: {:?}", a.as_slice());
    check(
        matches!(a.as_slice(), [AckCode::Ok, AckCode::TirError { line: l }] if *l > 0),
        "upload of a bad .tir: rejected with its line",
        &mut fails,
    );
    // Unsigned, forged (another key), replayed: each refused with its code, and counted.
    let mut forger = Signer::new(Key::new([0x5a; 16]), MacLen::DEFAULT, 1, 0);
    let replay = lb
        .signer
        .as_mut()
        .and_then(|s| Segmenter::sealed(&settings, 7, Mtu::Classic, s).ok())
        .unwrap_or_else(|| mps2::exit(false));
    lb.send_seg(app, replay.clone(), id::CONFIG);
    let signer = lb.signer.take();
    lb.send(app, &settings, 8);
    lb.signer = Some(forger.clone());
    lb.send(app, &settings, 9);
    lb.signer = signer;
    lb.send_seg(app, replay.clone(), id::CONFIG);
    let a = acks(&lb.finish(app));
    hprintln!("unsigned, forged, replayed: {:?}", a.as_slice());
    check(
        a.as_slice()
            == [
                AckCode::Ok,
                AckCode::MacMissing,
                AckCode::BadMac,
                AckCode::StaleFreshness,
            ],
        "auth: unsigned, forged and replayed settings refused with their own codes",
        &mut fails,
    );
    // An upload with a replayed and a forged chunk in the middle: both refused, the upload goes on.
    let mut next = || {
        seq = seq.wrapping_add(1);
        seq
    };
    lb.send(
        app,
        &Msg::ParamBegin(ParamBegin {
            len: text.len() as u32,
            hash,
        }),
        next(),
    );
    let mut last = None;
    for (i, c) in text.chunks(CHUNK_LEN).enumerate() {
        let data = Bytes::new(c).unwrap_or_else(|| mps2::exit(false));
        let chunk = Msg::ParamChunk(ParamChunk {
            offset: (i * CHUNK_LEN) as u32,
            data,
        });
        let sq = next();
        let seg = lb
            .signer
            .as_mut()
            .and_then(|s| Segmenter::sealed(&chunk, sq, Mtu::Classic, s).ok())
            .unwrap_or_else(|| mps2::exit(false));
        lb.send_seg(app, seg.clone(), id::CONFIG);
        if i == 10 {
            if let Some(old) = last.take() {
                lb.send_seg(app, old, id::CONFIG);
            }
            if let Ok(f) = Segmenter::sealed(&chunk, next(), Mtu::Classic, &mut forger) {
                lb.send_seg(app, f, id::CONFIG);
            }
        }
        last = Some(seg);
    }
    lb.send(app, &Msg::ParamCommit(ParamCommit { hash }), next());
    let a = acks(&lb.finish(app));
    let au = app.status().auth;
    hprintln!(
        "upload with a replayed and a forged chunk: {:?}; auth: epoch {} counter {} accepted {} no key {} missing {} bad mac {} stale {}",
        a.as_slice(),
        au.epoch,
        au.counter,
        au.accepted,
        au.no_key,
        au.missing,
        au.bad_mac,
        au.stale
    );
    check(
        a.as_slice() == [AckCode::Ok, AckCode::StaleFreshness, AckCode::BadMac, AckCode::Ok]
            && (au.missing, au.bad_mac, au.stale) == (1, 2, 2),
        "auth: a replayed and a forged chunk refused, the upload still commits; all counted in Status",
        &mut fails,
    );
    lb.send(app, &Msg::Measurement(meas()), 1);
    lb.send(app, &Msg::Command(Command::StatusRequest), 2);
    let out = lb.finish(app);
    let forces = out
        .iter()
        .any(|m| matches!(m, Msg::Forces(f) if f.t_us == 1_000));
    let status = out.iter().find_map(|m| match m {
        Msg::Status(s) => Some(*s),
        _ => None,
    });
    let estimate = out
        .iter()
        .any(|m| matches!(m, Msg::Estimate(e) if e.t_us == 1_000 && e.wheel == Wheel::FrontLeft));
    check(
        forces && estimate,
        "measurement answered with forces and an estimate",
        &mut fails,
    );
    check(
        matches!(status, Some(s) if s.source == ParamSource::Uploaded && s.param_hash == hash),
        "status reports the uploaded parameter set",
        &mut fails,
    );

    // Counter wrap: the device at counter u32::MAX - 2; three secured settings go through, the
    // third in the next epoch, which the device stores (the board's epoch_store).
    static STORED: AtomicU32 = AtomicU32::new(0);
    fn store(e: u32) -> bool {
        STORED.store(e, Ordering::Relaxed);
        true
    }
    let mut v = Verifier::new(key, MacLen::DEFAULT, 1);
    v.set_counter(u32::MAX - 2);
    app.provision(v);
    app.epoch_store = Some(store);
    lb.signer = Some(Signer::new(key, MacLen::DEFAULT, 1, u32::MAX - 2));
    for i in 0..3 {
        lb.send(app, &settings, 20 + i);
    }
    let a = acks(&lb.finish(app));
    let au = app.status().auth;
    hprintln!(
        "counter wrap: {:?}; epoch {} counter {}, stored epoch {}",
        a.as_slice(),
        au.epoch,
        au.counter,
        STORED.load(Ordering::Relaxed)
    );
    check(
        a.as_slice() == [AckCode::Ok; 3]
            && (au.epoch, au.counter, au.accepted) == (2, 1, 3)
            && STORED.load(Ordering::Relaxed) == 2,
        "auth: counter wrap: the device moves to the next epoch and stores it",
        &mut fails,
    );

    // 6. the estimator: a slip-angle ramp at 1 kHz on the tyre's own surface (λμ = 1) to
    // 0.1 rad in 0.3 s, held 0.2 s, the "measured" forces (Fy, Mz only) from the Magic Formula
    // itself; the estimate must find μy0. (Lateral force alone, the bank's σ reaches its
    // identifiable bound about 20 ms into the hold: the stream holds ten times that.)
    let mu0 = app.estimator(3).map_or(0.0, |e| e.mu0());
    let mut last = None;
    let mut n_forces = 0u32;
    const SAMPLES: u32 = 500;
    for i in 0..SAMPLES {
        let alpha = 0.1 * i.min(300) as f32 / 300.0;
        let probe = Measurement {
            wheel: Wheel::RearRight,
            t_us: 10_000 + 1_000 * i,
            fz: 6752.0,
            vx: Some(20.0),
            alpha: Some(alpha),
            ..Measurement::default()
        };
        let Ok(f) = app.evaluate(&probe) else {
            fails += 1;
            break;
        };
        let m = Measurement {
            fy: f.fy,
            mz: f.mz,
            ..probe
        };
        lb.send(app, &Msg::Measurement(m), i as u8);
        for msg in lb.finish(app) {
            match msg {
                Msg::Forces(_) => n_forces += 1,
                Msg::Estimate(e) => last = Some(e),
                _ => {}
            }
        }
    }
    match last {
        Some(e) => {
            // Coarse on purpose: the estimator's tuning (src/mu) moves the digits.
            hprintln!(
                "estimator: {} samples, {} forces; final {:?}, mu {:.1} (tyre's mu0 {:.1})",
                SAMPLES,
                n_forces,
                e.state,
                e.mu,
                mu0
            );
            check(
                n_forces == SAMPLES && e.state == State::Identifiable && (e.mu - mu0).abs() <= 0.1,
                "estimator on the device reads the tyre's own surface within 0.1",
                &mut fails,
            );
        }
        None => check(false, "estimator on the device answers", &mut fails),
    }

    hprintln!("selftest: {} failed", fails);
    mps2::exit(fails == 0)
}
