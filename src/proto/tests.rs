//! Protocol tests: byte-exact encodings, round trips of every message through frames, the
//! size bounds, and the reassembler against lost, duplicated, reordered, truncated and
//! garbage frames.
use super::*;
use crate::mu::State;
use proptest::prelude::*;
use std::vec::Vec;
use std::{format, vec};

fn meas() -> Measurement {
    Measurement {
        wheel: Wheel::RearLeft,
        t_us: 0x0102_0304,
        fz: 4000.0,
        fy: -1500.0,
        mz: 40.0,
        fx: Some(200.0),
        vx: Some(20.0),
        omega: None,
        delta: Some(0.01),
        alpha: Some(0.05),
        kappa: Some(-0.02),
        gamma: None,
    }
}

/// The largest value of each variant (every option present, longest chunk, largest integers).
pub(crate) fn largest() -> Vec<Msg> {
    let c = Counters {
        frames: u32::MAX,
        messages: u32::MAX,
        duplicates: u32::MAX,
        truncated: u32::MAX,
        bad_header: u32::MAX,
        bad_crc: u32::MAX,
        out_of_order: u32::MAX,
        overflow: u32::MAX,
        timeout: u32::MAX,
        decode: u32::MAX,
    };
    vec![
        Msg::Measurement(Measurement {
            omega: Some(1.0),
            gamma: Some(1.0),
            ..meas()
        }),
        Msg::ParamBegin(ParamBegin {
            len: u32::MAX,
            hash: u32::MAX,
        }),
        Msg::ParamChunk(ParamChunk {
            offset: u32::MAX,
            data: Bytes::new(&[0xFF; CHUNK_LEN]).unwrap(),
        }),
        Msg::ParamCommit(ParamCommit { hash: u32::MAX }),
        Msg::Settings(Settings {
            wheelbase: f32::MAX,
            ..Settings::default()
        }),
        Msg::Command(Command::Stop),
        Msg::CompactMeasurement(CompactMeasurement {
            t_us: u32::MAX,
            fields: CompactWheel {
                fz: u16::MAX,
                ..CompactWheel::default()
            },
            ..CompactMeasurement::default()
        }),
        Msg::CompactBatch(CompactBatch {
            t_us: u32::MAX,
            present: 0x0F,
            wheels: [CompactWheel {
                fz: u16::MAX,
                fy: i16::MIN,
                ..CompactWheel::default()
            }; 4],
        }),
        Msg::CompactResults(CompactResults {
            t_us: u32::MAX,
            wheels: [CompactWheelResult {
                fx: i16::MIN,
                mu: u16::MAX,
                mu_min: u8::MAX,
                status: u8::MAX,
                ..CompactWheelResult::default()
            }; 4],
        }),
        Msg::Forces(Forces {
            flags: u16::MAX,
            ..Forces::default()
        }),
        Msg::Estimate(Estimate {
            wheel: Wheel::RearRight,
            t_us: u32::MAX,
            mu: 1.0,
            sigma: 0.1,
            state: State::Fallback,
            mu_min: 0.1,
            change: true,
            mismatch: true,
        }),
        Msg::SetCalibration(CalibrationState {
            wheel: Wheel::RearRight,
            value: [f32::MAX; 4],
            sigma: [f32::MAX; 4],
            batches: u32::MAX,
        }),
        Msg::Calibration(CalibrationState {
            wheel: Wheel::RearRight,
            value: [f32::MAX; 4],
            sigma: [f32::MAX; 4],
            batches: u32::MAX,
        }),
        Msg::Status(Status {
            firmware: [255; 3],
            proto: 255,
            source: ParamSource::Uploaded,
            param_hash: u32::MAX,
            uptime_ms: u32::MAX,
            rx: c,
            link_errors: u32::MAX,
            eval_errors: u32::MAX,
            tx_messages: u32::MAX,
            stack_peak: u32::MAX,
            auth: AuthStatus {
                mac_len: u8::MAX,
                epoch: u32::MAX,
                counter: u32::MAX,
                accepted: u32::MAX,
                no_key: u32::MAX,
                missing: u32::MAX,
                bad_mac: u32::MAX,
                stale: u32::MAX,
            },
        }),
        Msg::Ack(Ack {
            of: 255,
            seq: 255,
            code: AckCode::TirError { line: u32::MAX },
        }),
    ]
}

#[test]
fn every_variant_fits_its_bound() {
    for m in largest() {
        let mut buf = [0u8; MAX_MSG_LEN];
        let n = m.encode(&mut buf).unwrap();
        assert!(n <= MAX_MSG_LEN, "{m:?}: {n}");
        assert_eq!(Msg::decode(&buf[..n]), Ok(m));
    }
}

#[test]
fn measurement_bytes() {
    // Byte-exact: header, then postcard (wheel index, t_us fixed LE, f32 LE, option tags), CRC.
    let m = Msg::Measurement(Measurement {
        wheel: Wheel::FrontRight,
        t_us: 1000,
        fz: 1.0,
        fy: -2.0,
        mz: 0.5,
        fx: None,
        vx: None,
        omega: None,
        delta: None,
        alpha: Some(0.25),
        kappa: None,
        gamma: None,
    });
    let mut buf = [0xa5u8; MAX_MSG_LEN];
    let n = m.encode(&mut buf).unwrap();
    let body: &[u8] = &[
        0x05, 0x01, // version 5, type Measurement
        0x01, // wheel FrontRight
        0xe8, 0x03, 0x00, 0x00, // t_us 1000
        0x00, 0x00, 0x80, 0x3f, // fz 1.0
        0x00, 0x00, 0x00, 0xc0, // fy -2.0
        0x00, 0x00, 0x00, 0x3f, // mz 0.5
        0x00, 0x00, 0x00, 0x00, // fx vx omega delta: None
        0x01, 0x00, 0x00, 0x80, 0x3e, // alpha Some(0.25)
        0x00, 0x00, // kappa gamma None
    ];
    assert_eq!(&buf[..n - 4], body);
    assert_eq!(&buf[n - 4..n], &crc32(body).to_le_bytes());
    assert_eq!(buf[n], 0xa5, "nothing written past the message");
}

#[test]
fn settings_bytes() {
    // Protocol v3 and v4: limits (bool), fallback_mu and wheelbase (f32 LE); 9 body bytes.
    let m = Msg::Settings(Settings {
        limits: true,
        fallback_mu: 0.5,
        wheelbase: 2.5,
    });
    let mut buf = [0u8; MAX_MSG_LEN];
    let n = m.encode(&mut buf).unwrap();
    let body: &[u8] = &[
        0x05, 0x05, // version 5, type Settings
        0x01, // limits
        0x00, 0x00, 0x00, 0x3f, // fallback_mu 0.5
        0x00, 0x00, 0x20, 0x40, // wheelbase 2.5
    ];
    assert_eq!(&buf[..n - 4], body);
    assert_eq!(Msg::decode(&buf[..n]), Ok(m));
    // The wheelbase's range: 0 is none, a positive number the preview's, the rest refused.
    let wb = |wheelbase: f32| {
        Settings {
            wheelbase,
            ..Settings::default()
        }
        .wheelbase()
    };
    assert_eq!(Settings::default().wheelbase, 0.0);
    assert_eq!(wb(0.0), Ok(None));
    assert_eq!(wb(2.5), Ok(Some(2.5)));
    for bad in [-0.1, f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
        assert_eq!(wb(bad), Err(AckCode::BadSettings), "{bad}");
    }
}

#[test]
fn decode_errors() {
    let mut buf = [0u8; MAX_MSG_LEN];
    let n = Msg::Command(Command::Reset).encode(&mut buf).unwrap();
    assert_eq!(Msg::decode(&buf[..5]), Err(Error::Truncated));
    let mut bad = buf;
    bad[2] ^= 1;
    assert_eq!(Msg::decode(&bad[..n]), Err(Error::BadCrc));
    let reseal = |b: &mut [u8]| {
        let c = crc32(&b[..b.len() - 4]);
        let l = b.len();
        b[l - 4..].copy_from_slice(&c.to_le_bytes());
    };
    // Another version (v1; v2, before `Settings` carried the wheelbase; v4): dropped.
    for other in [1, 2, 3, PROTO_VERSION + 1] {
        let mut v = buf[..n].to_vec();
        v[0] = other;
        reseal(&mut v);
        assert_eq!(Msg::decode(&v), Err(Error::Version));
    }
    let mut v = buf[..n].to_vec();
    v[1] = 0x7f;
    reseal(&mut v);
    assert_eq!(Msg::decode(&v), Err(Error::UnknownType));
    let mut v = buf[..n].to_vec();
    v.insert(3, 0);
    reseal(&mut v);
    assert_eq!(Msg::decode(&v), Err(Error::Decode), "bytes over");
    let mut v = buf[..n].to_vec();
    v[2] = 9;
    reseal(&mut v);
    assert_eq!(Msg::decode(&v), Err(Error::Decode), "no such command");
}

fn frames(m: &Msg, seq: u8, mtu: Mtu) -> Vec<Vec<u8>> {
    let mut s = Segmenter::new(m, seq, mtu).unwrap();
    let mut out = Vec::new();
    let mut b = [0u8; 64];
    while let Some(f) = s.next_frame(&mut b) {
        out.push(f.to_vec());
    }
    assert_eq!(out.len(), s.frame_count());
    out
}

#[test]
fn round_trip_classic_and_fd() {
    for mtu in [Mtu::Classic, Mtu::Fd] {
        let mut r = Reassembler::<MSG_BUF>::new();
        for (i, m) in largest().into_iter().enumerate() {
            let fs = frames(&m, i as u8, mtu);
            for f in &fs {
                assert!(f.len() <= mtu.bytes());
                assert_eq!(f.len(), mtu.frame_len(id::of(m.msg_type())));
                assert_eq!(segmenter::fd_len(f.len()), f.len());
            }
            let mut got = None;
            for (k, f) in fs.iter().enumerate() {
                match r.feed(f, 0) {
                    Feed::Pending => assert!(k + 1 < fs.len()),
                    Feed::Done(d) => got = Some(d),
                    Feed::Dropped(e) => panic!("{e}"),
                }
            }
            assert_eq!(got, Some(m));
        }
        assert_eq!(r.counters().dropped(), 0);
        assert_eq!(r.counters().messages, 15);
    }
}

#[test]
fn compact_measurement() {
    let m = meas();
    let c = CompactMeasurement::new(&m).unwrap();
    let back = c.measurement();
    assert_eq!(back.delta, None);
    assert!((back.fz - m.fz).abs() <= 0.25);
    assert!((back.fy - m.fy).abs() <= 0.5);
    assert!((back.mz - m.mz).abs() <= 0.05 + 1e-4);
    assert!((back.alpha.unwrap() - m.alpha.unwrap()).abs() <= 0.5e-4 + 1e-7);
    assert_eq!(back.fx.is_some(), m.fx.is_some());
    // Every field at the end of its range: 29 bytes, 5 classic frames, one 32-byte FD frame.
    let big = CompactMeasurement {
        wheel: Wheel::RearRight,
        t_us: u32::MAX,
        fields: CompactWheel {
            fz: u16::MAX,
            fy: i16::MAX,
            mz: i16::MIN,
            fx: -1,
            vx: i16::MAX,
            omega: i16::MAX,
            alpha: i16::MAX,
            kappa: i16::MAX,
            gamma: i16::MAX,
        },
    };
    let msg = Msg::CompactMeasurement(big);
    let mut b = [0u8; MSG_BUF];
    assert_eq!(msg.encode(&mut b).unwrap(), 29);
    // The exact size (fixed-width fields): 29 less the envelope, as for the batch below.
    assert_eq!(29 - 6, CompactMeasurement::POSTCARD_MAX_SIZE);
    // Byte layout: wheel, t_us LE, then the nested fields in place (Fz u16 LE, Fy, Mz, Fx i16 LE).
    assert_eq!(
        &b[2..15],
        &[3, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0x7F, 0x00, 0x80, 0xFF, 0xFF]
    );
    assert_eq!(frames(&msg, 0, Mtu::Classic).len(), 5);
    let fd = frames(&msg, 0, Mtu::Fd);
    assert_eq!((fd.len(), fd[0].len()), (1, 32));
    assert_eq!(id::of(msg.msg_type()), id::COMPACT);
    // Out of range or not finite: refused, never clamped.
    for bad in [
        Measurement { fz: -1.0, ..m },
        Measurement { fz: 40_000.0, ..m },
        Measurement { fy: f32::NAN, ..m },
        Measurement { mz: 5000.0, ..m },
        Measurement {
            alpha: Some(3.3),
            ..m
        },
        Measurement {
            vx: Some(f32::INFINITY),
            ..m
        },
    ] {
        assert_eq!(CompactMeasurement::new(&bad), None, "{bad:?}");
    }
    // Absent stays absent.
    let none = Measurement {
        fx: None,
        vx: None,
        omega: None,
        alpha: None,
        kappa: None,
        gamma: None,
        ..m
    };
    let c = CompactMeasurement::new(&none).unwrap();
    assert_eq!(c.fields.fx, CompactMeasurement::ABSENT);
    assert_eq!(
        c.measurement(),
        Measurement {
            fz: c.measurement().fz,
            fy: c.measurement().fy,
            mz: c.measurement().mz,
            delta: None,
            ..none
        }
    );
}

/// Four wheels' samples, each different.
fn four() -> [Measurement; 4] {
    Wheel::ALL.map(|w| {
        let k = w.index() as f32;
        Measurement {
            wheel: w,
            fz: 3000.0 + 500.0 * k,
            fy: -1500.0 + 100.0 * k,
            omega: Some(50.0 + k),
            gamma: (k > 1.0).then_some(-0.01),
            ..meas()
        }
    })
}

#[test]
fn compact_batch() {
    let ms = four();
    let b = CompactBatch::new(77, &ms).unwrap();
    assert_eq!(b.present, 0x0F);
    // Each wheel decodes to what its single compact measurement stands for, at the batch's time.
    for (got, m) in b.measurements().iter().zip(ms.iter()) {
        let single = CompactMeasurement::new(&Measurement { t_us: 77, ..*m }).unwrap();
        assert_eq!(*got, Some(single.measurement()));
    }
    // 77 body bytes, 83 encoded: two 48-byte FD frames, 14 classic frames; its own identifier.
    let msg = Msg::CompactBatch(b);
    let mut buf = [0u8; MSG_BUF];
    let n = msg.encode(&mut buf).unwrap();
    assert_eq!(n, 83);
    assert_eq!(n - 6, CompactBatch::POSTCARD_MAX_SIZE);
    // Byte layout: t_us LE, present, then wheel 0's Fz (u16 LE, 0.5 N).
    assert_eq!(&buf[2..9], &[77, 0, 0, 0, 0x0F, 0x70, 0x17]);
    assert_eq!(Msg::decode(&buf[..n]), Ok(msg));
    assert_eq!(id::of(msg.msg_type()), id::BATCH);
    let fd = frames(&msg, 3, Mtu::Fd);
    assert_eq!(fd.iter().map(Vec::len).collect::<Vec<_>>(), [48, 48]);
    assert_eq!(frames(&msg, 3, Mtu::Classic).len(), 14);
    // A subset: the others absent (zeros, bit clear).
    let two = CompactBatch::new(5, &[ms[3], ms[0]]).unwrap();
    assert_eq!(two.present, 0b1001);
    assert_eq!(two.wheels[1], CompactWheel::default());
    let back = two.measurements();
    assert!(back[0].is_some() && back[1].is_none() && back[2].is_none() && back[3].is_some());
    assert_eq!(CompactBatch::new(5, &[]).unwrap().measurements(), [None; 4]);
    // Refused, never clamped: a value out of range or not finite, or a wheel twice.
    for bad in [
        Measurement { fz: -1.0, ..ms[1] },
        Measurement {
            fy: f32::NAN,
            ..ms[1]
        },
        Measurement {
            kappa: Some(4.0),
            ..ms[1]
        },
    ] {
        assert_eq!(CompactBatch::new(0, &[ms[0], bad]), None, "{bad:?}");
    }
    assert_eq!(CompactBatch::new(0, &[ms[0], ms[0]]), None);
}

#[test]
fn compact_results() {
    let f = Forces {
        wheel: Wheel::FrontRight,
        t_us: 9,
        fx: 812.4,
        fy: -1500.6,
        mz: 41.26,
        flags: 0,
    };
    let e = Estimate {
        wheel: Wheel::FrontRight,
        t_us: 9,
        mu: 0.91234,
        sigma: 0.04321,
        state: State::NotIdentifiable,
        mu_min: 0.3,
        change: true,
        mismatch: false,
    };
    let w = CompactWheelResult::new(Some(&f), Some(&e)).unwrap();
    assert_eq!(CompactWheelResult::or_na(Some(&f), Some(&e)), w);
    assert_eq!(
        (w.fx, w.fy, w.mz, w.mu, w.sigma, w.mu_min),
        (812, -1501, 413, 9123, 432, 30)
    );
    assert_eq!(w.state(), Some(State::NotIdentifiable));
    assert!(w.change() && w.present() && !w.mismatch());
    assert_eq!(w.status & CompactWheelResult::MF_FLAGS, 0);
    // The mismatch indication: bit 5 (v4).
    let wm = CompactWheelResult::new(
        Some(&f),
        Some(&Estimate {
            mismatch: true,
            ..e
        }),
    )
    .unwrap();
    assert_eq!(wm.status, w.status | CompactWheelResult::MISMATCH);
    assert!(wm.mismatch());
    assert!((w.mu().unwrap() - e.mu).abs() <= 0.5e-4 + 1e-7);
    // μ_min rounds down: it stays a lower bound.
    let e2 = Estimate { mu_min: 0.349, ..e };
    let w2 = CompactWheelResult::new(Some(&f), Some(&e2)).unwrap();
    assert_eq!(w2.mu_min, 34);
    assert!(w2.mu_min().unwrap() <= e2.mu_min);
    // No forces, no estimate: not available; flags set: bit 3.
    let w3 = CompactWheelResult::new(None, None).unwrap();
    assert_eq!(
        (w3.fx(), w3.mu(), w3.mu_min(), w3.state()),
        (None, None, None, None)
    );
    assert!(w3.present() && !w3.change());
    let w4 = CompactWheelResult::new(Some(&Forces { flags: 4, ..f }), None).unwrap();
    assert_ne!(w4.status & CompactWheelResult::MF_FLAGS, 0);
    // Out of range or not finite: `new` refuses, the device's `or_na` sends "not available".
    for (bf, be) in [
        (Forces { fx: 40_000.0, ..f }, e),
        (Forces { mz: f32::NAN, ..f }, e),
        (f, Estimate { mu: -0.1, ..e }),
        (f, Estimate { sigma: 7.0, ..e }),
        (f, Estimate { mu_min: 2.6, ..e }),
        (
            f,
            Estimate {
                mu: f32::INFINITY,
                ..e
            },
        ),
    ] {
        assert_eq!(CompactWheelResult::new(Some(&bf), Some(&be)), None);
        let na = CompactWheelResult::or_na(Some(&bf), Some(&be));
        let got = [na.fx(), na.fy(), na.mz(), na.mu(), na.sigma(), na.mu_min()];
        assert_eq!(got.iter().filter(|v| v.is_none()).count(), 1, "{na:?}");
        assert_eq!(na.state(), Some(State::NotIdentifiable));
    }
    // 52 body bytes, 58 encoded: one 64-byte FD frame, 10 classic frames.
    let msg = Msg::CompactResults(CompactResults {
        t_us: 9,
        wheels: [CompactWheelResult::default(), w, w3, w4],
    });
    let mut buf = [0u8; MSG_BUF];
    let n = msg.encode(&mut buf).unwrap();
    assert_eq!(n, 58);
    assert_eq!(n - 6, CompactResults::POSTCARD_MAX_SIZE);
    // Wheel 1 at body offset 4 + 12: Fx 812 LE.
    assert_eq!(&buf[2 + 16..2 + 18], &812i16.to_le_bytes());
    assert_eq!(Msg::decode(&buf[..n]), Ok(msg));
    assert_eq!(id::of(msg.msg_type()), id::BATCH_RESULT);
    let fd = frames(&msg, 0, Mtu::Fd);
    assert_eq!(fd.iter().map(Vec::len).collect::<Vec<_>>(), [64]);
    assert_eq!(frames(&msg, 0, Mtu::Classic).len(), 10);
}

#[test]
fn new_types_need_no_version_bump() {
    // A receiver that does not know a type drops that message alone (`UnknownType`), after the
    // version and CRC checks: adding types leaves every other message as it was.
    let mut buf = [0u8; MSG_BUF];
    let n = Msg::CompactBatch(CompactBatch::default())
        .encode(&mut buf)
        .unwrap();
    buf[1] = 0x7F;
    let crc = crc32(&buf[..n - 4]);
    buf[n - 4..n].copy_from_slice(&crc.to_le_bytes());
    assert_eq!(Msg::decode(&buf[..n]), Err(Error::UnknownType));
}

#[test]
fn known_frames() {
    // Command::StatusRequest, seq 5, classic: two frames 80 05 07 | 05 06 01 | crc.
    let m = Msg::Command(Command::StatusRequest);
    let fs = frames(&m, 5, Mtu::Classic);
    let crc = crc32(&[5, 6, 1]).to_le_bytes();
    assert_eq!(fs.len(), 2);
    assert_eq!(fs[0], [0x80, 5, 7, 5, 6, 1, crc[0], crc[1]]);
    assert_eq!(fs[1], [0x41, 5, crc[2], crc[3], 0, 0, 0, 0]);
    let fd = frames(&m, 5, Mtu::Fd);
    let mut one = vec![0xc0, 5, 7, 5, 6, 1, crc[0], crc[1], crc[2], crc[3]];
    one.resize(64, 0);
    assert_eq!(fd, [one]);
    // An estimate on CAN FD: one 32-byte frame on RESULT.
    let e = Msg::Estimate(Estimate {
        wheel: Wheel::RearLeft,
        t_us: 7,
        mu: 0.5,
        sigma: 0.25,
        state: State::Identifiable,
        mu_min: 0.375,
        change: true,
        mismatch: true,
    });
    let fd = frames(&e, 1, Mtu::Fd);
    assert_eq!(fd.len(), 1);
    assert_eq!(fd[0].len(), 32);
    // header c0 01 len 26 | version 5, Estimate | wheel 2, t_us 7 ..
    assert_eq!(fd[0][..7], [0xc0, 1, 26, 5, 0x82, 2, 7]);
    assert_eq!(fd[0][10..14], 0.5f32.to_le_bytes());
    assert_eq!(fd[0][14..18], 0.25f32.to_le_bytes());
    assert_eq!(fd[0][18], 0, "state Identifiable");
    assert_eq!(fd[0][19..23], 0.375f32.to_le_bytes());
    assert_eq!(fd[0][23], 1, "change");
    assert_eq!(fd[0][24], 1, "mismatch");
    assert_eq!(fd[0][25..29], crc32(&fd[0][3..25]).to_le_bytes());
    assert!(fd[0][29..].iter().all(|&b| b == 0), "padding");
    // On classic CAN: 26 bytes in 5 frames (5 in the first, 6 in each next).
    assert_eq!(frames(&e, 1, Mtu::Classic).len(), 5);
}

#[test]
fn calibration_bytes_both_ways() {
    let e = crate::mu::calibration::Exported {
        value: [1.05, 0.5, -0.001, 2.0],
        sigma: [0.25, 0.125, 0.0625, 1.0],
        batches: 0x0102_0304,
    };
    let c = CalibrationState::new(Wheel::FrontRight, &e);
    assert_eq!(c.exported(), e);
    let mut want = vec![5u8, 0x86, 1];
    for x in e.value.iter().chain(e.sigma.iter()) {
        want.extend_from_slice(&x.to_le_bytes());
    }
    want.extend_from_slice(&[4, 3, 2, 1]);
    let crc = crc32(&want);
    want.extend_from_slice(&crc.to_le_bytes());
    for (m, t, cid) in [
        (Msg::Calibration(c), 0x86u8, id::STATUS),
        (Msg::SetCalibration(c), 0x09, id::CONFIG),
    ] {
        want[1] = t;
        let crc = crc32(&want[..want.len() - 4]);
        let n = want.len();
        want[n - 4..].copy_from_slice(&crc.to_le_bytes());
        let mut buf = [0xa5u8; MSG_BUF];
        let n = m.encode(&mut buf).unwrap();
        assert_eq!(&buf[..n], &want[..], "{m:?}");
        assert_eq!(Msg::decode(&buf[..n]), Ok(m));
        assert_eq!(id::of(m.msg_type()), cid);
        // 43 bytes: one 64-byte FD frame, 8 classic frames.
        assert_eq!(frames(&m, 0, Mtu::Fd).len(), 1);
        assert_eq!(frames(&m, 0, Mtu::Classic).len(), 8);
    }
}

#[test]
fn lost_duplicated_reordered_truncated() {
    let m = Msg::Measurement(meas());
    let fs = frames(&m, 9, Mtu::Classic);
    assert!(fs.len() >= 4);
    let feed_all = |r: &mut Reassembler<MSG_BUF>, seq: &[&Vec<u8>]| -> Vec<Feed> {
        seq.iter().map(|f| r.feed(f, 0)).collect()
    };
    // lost frame 2
    let mut r = Reassembler::<MSG_BUF>::new();
    let seq: Vec<&Vec<u8>> = fs
        .iter()
        .enumerate()
        .filter(|(i, _)| *i != 2)
        .map(|(_, f)| f)
        .collect();
    let out = feed_all(&mut r, &seq);
    assert!(!out.iter().any(|f| matches!(f, Feed::Done(_))));
    assert!(r.counters().out_of_order > 0);
    // duplicated frames are ignored: the message still arrives once
    let mut r = Reassembler::<MSG_BUF>::new();
    let seq: Vec<&Vec<u8>> = fs.iter().flat_map(|f| [f, f]).collect();
    let out = feed_all(&mut r, &seq);
    assert_eq!(out.iter().filter(|f| matches!(f, Feed::Done(_))).count(), 1);
    assert_eq!(r.counters().duplicates as usize, fs.len());
    // reordered
    let mut r = Reassembler::<MSG_BUF>::new();
    let mut seq: Vec<&Vec<u8>> = fs.iter().collect();
    seq.swap(1, 2);
    let out = feed_all(&mut r, &seq);
    assert!(!out.iter().any(|f| matches!(f, Feed::Done(_))));
    // truncated last frame (cut inside the message, not only its padding): dropped
    let mut r = Reassembler::<MSG_BUF>::new();
    let mut last = fs.last().unwrap().clone();
    let mut enc = [0u8; MSG_BUF];
    let n = m.encode(&mut enc).unwrap();
    let left = (n - 5) % 6;
    let left = if left == 0 { 6 } else { left };
    last.truncate(2 + left - 1);
    let mut seq: Vec<&Vec<u8>> = fs[..fs.len() - 1].iter().collect();
    seq.push(&last);
    let out = feed_all(&mut r, &seq);
    assert_eq!(out.last(), Some(&Feed::Dropped(Error::Truncated)));
    // then a good message goes through
    let out = feed_all(&mut r, &fs.iter().collect::<Vec<_>>());
    assert_eq!(out.last(), Some(&Feed::Done(m)));
    // timeout between frames
    let mut r = Reassembler::<MSG_BUF>::new();
    assert_eq!(r.feed(&fs[0], 0), Feed::Pending);
    assert_eq!(r.feed(&fs[1], 10), Feed::Pending);
    assert_eq!(
        r.feed(&fs[2], 10 + FRAME_TIMEOUT_MS + 1),
        Feed::Dropped(Error::OutOfOrder)
    );
    assert_eq!(r.counters().timeout, 1);
    // flipped bit in a middle frame: CRC
    let mut r = Reassembler::<MSG_BUF>::new();
    let mut bad = fs.clone();
    bad[1][4] ^= 0x10;
    let out = feed_all(&mut r, &bad.iter().collect::<Vec<_>>());
    assert_eq!(out.last(), Some(&Feed::Dropped(Error::BadCrc)));
    // a message longer than the buffer
    let mut small = Reassembler::<16>::new();
    assert_eq!(small.feed(&fs[0], 0), Feed::Dropped(Error::Overflow));
}

#[test]
fn dbc_lists_every_identifier() {
    let mut s = std::string::String::new();
    dbc::write(&mut s, Mtu::Classic).unwrap();
    for (cid, name, _) in id::ALL {
        assert!(s.contains(&format!("BO_ {cid} {name}: 8")));
    }
    let mut f = std::string::String::new();
    dbc::write(&mut f, Mtu::Fd).unwrap();
    assert!(f.contains(&format!("BO_ {} GOUGH_RESULT: 32", id::RESULT)));
    assert!(f.contains(&format!("BO_ {} GOUGH_STATUS: 64", id::STATUS)));
    assert!(f.contains("SIG_VALTYPE_ 784 mu : 1;"));
    assert!(s.contains("\"Measurement\""));
    // The four-wheel messages: the batch in 48-byte frames (byte signals), the results in one
    // 64-byte frame with per-wheel physical signals (the status byte's bits among them).
    assert!(f.contains(&format!("BO_ {} GOUGH_BATCH: 48", id::BATCH)));
    assert!(f.contains(&format!("BO_ {} GOUGH_BATCH_RESULT: 64", id::BATCH_RESULT)));
    assert!(f.contains(" SG_ RR_mu m133 : 408|16@1+ (0.0001,0) [0|0] \"\" HOST"));
    assert!(f.contains(" SG_ FL_state m133 : 160|2@1+ (1,0) [0|0] \"\" HOST"));
    assert!(f.contains(" SG_ FL_present m133 : 164|1@1+ (1,0) [0|0] \"\" HOST"));
    assert!(f.contains("VAL_ 786 FR_state 0 \"Identifiable\""));
    assert!(s.contains(&format!("BO_ {} GOUGH_BATCH_RESULT: 8", id::BATCH_RESULT)));
}

fn any_msg() -> impl Strategy<Value = Msg> {
    let f = -1e6f32..1e6f32;
    let of = proptest::option::of(-1e3f32..1e3f32);
    prop_oneof![
        (any::<u32>(), any::<u8>(), any::<[[u8; 18]; 4]>()).prop_map(|(t_us, present, w)| {
            let i = |b: &[u8; 18], k: usize| i16::from_le_bytes([b[k], b[k + 1]]);
            Msg::CompactBatch(CompactBatch {
                t_us,
                present,
                wheels: w.map(|b| CompactWheel {
                    fz: u16::from_le_bytes([b[0], b[1]]),
                    fy: i(&b, 2),
                    mz: i(&b, 4),
                    fx: i(&b, 6),
                    vx: i(&b, 8),
                    omega: i(&b, 10),
                    alpha: i(&b, 12),
                    kappa: i(&b, 14),
                    gamma: i(&b, 16),
                }),
            })
        }),
        (
            any::<u32>(),
            any::<[(i16, i16, i16, u16, u16, u8, u8); 4]>()
        )
            .prop_map(|(t_us, w)| {
                Msg::CompactResults(CompactResults {
                    t_us,
                    wheels: w.map(
                        |(fx, fy, mz, mu, sigma, mu_min, status)| CompactWheelResult {
                            fx,
                            fy,
                            mz,
                            mu,
                            sigma,
                            mu_min,
                            status,
                        },
                    ),
                })
            }),
        (
            0usize..4,
            any::<u32>(),
            f.clone(),
            f.clone(),
            f.clone(),
            of.clone(),
            of.clone(),
            of.clone(),
            of
        )
            .prop_map(|(w, t, fz, fy, mz, fx, vx, alpha, kappa)| Msg::Measurement(
                Measurement {
                    wheel: Wheel::from_index(w).unwrap(),
                    t_us: t,
                    fz,
                    fy,
                    mz,
                    fx,
                    vx,
                    omega: None,
                    delta: None,
                    alpha,
                    kappa,
                    gamma: None,
                }
            )),
        (
            any::<u32>(),
            proptest::collection::vec(any::<u8>(), 0..=CHUNK_LEN)
        )
            .prop_map(|(o, d)| {
                Msg::ParamChunk(ParamChunk {
                    offset: o,
                    data: Bytes::new(&d).unwrap(),
                })
            }),
        (any::<u8>(), any::<u8>(), any::<u32>()).prop_map(|(of, seq, line)| Msg::Ack(Ack {
            of,
            seq,
            code: AckCode::TirError { line }
        })),
        (
            0usize..4,
            any::<u32>(),
            f.clone(),
            f.clone(),
            f,
            any::<u16>()
        )
            .prop_map(|(w, t_us, fx, fy, mz, flags)| Msg::Forces(Forces {
                wheel: Wheel::from_index(w).unwrap(),
                t_us,
                fx,
                fy,
                mz,
                flags
            })),
        (
            0usize..4,
            any::<u32>(),
            0f32..2.0,
            0f32..1.0,
            0usize..3,
            0f32..2.0,
            0u8..4
        )
            .prop_map(
                |(w, t_us, mu, sigma, st, mu_min, change)| Msg::Estimate(Estimate {
                    wheel: Wheel::from_index(w).unwrap(),
                    t_us,
                    mu,
                    sigma,
                    state: [State::Identifiable, State::NotIdentifiable, State::Fallback][st],
                    mu_min,
                    change: change & 1 == 1,
                    mismatch: change & 2 == 2,
                })
            ),
        (
            0usize..4,
            any::<bool>(),
            proptest::array::uniform4(-10f32..10.0),
            proptest::array::uniform4(0f32..1.0),
            any::<u32>()
        )
            .prop_map(|(w, host, value, sigma, batches)| {
                let c = CalibrationState {
                    wheel: Wheel::from_index(w).unwrap(),
                    value,
                    sigma,
                    batches,
                };
                if host {
                    Msg::SetCalibration(c)
                } else {
                    Msg::Calibration(c)
                }
            }),
    ]
}

proptest! {
    #[test]
    fn compact_batch_within_half_a_count(
        w in proptest::collection::vec((0usize..4, 0f32..30_000.0, -30_000f32..30_000.0,
            proptest::option::of(-3.0f32..3.0)), 0..4),
        t_us in any::<u32>(),
    ) {
        let mut ms: Vec<Measurement> = Vec::new();
        for (wi, fz, fy, alpha) in w {
            let wheel = Wheel::from_index(wi).unwrap();
            if ms.iter().all(|m| m.wheel != wheel) {
                ms.push(Measurement { wheel, fz, fy, alpha, ..meas() });
            }
        }
        let b = CompactBatch::new(t_us, &ms).unwrap();
        let back = b.measurements();
        for m in &ms {
            let g = back[m.wheel.index()].unwrap();
            prop_assert_eq!(g.t_us, t_us);
            prop_assert!((g.fz - m.fz).abs() <= 0.25 + 1e-2);
            prop_assert!((g.fy - m.fy).abs() <= 0.5 + 1e-2);
            prop_assert_eq!(g.alpha.is_some(), m.alpha.is_some());
        }
        prop_assert_eq!(back.iter().filter(|m| m.is_some()).count(), ms.len());
    }

    #[test]
    fn parse_emit_round_trip(m in any_msg(), seq in any::<u8>(), fd in any::<bool>()) {
        let mtu = if fd { Mtu::Fd } else { Mtu::Classic };
        let mut r = Reassembler::<MSG_BUF>::new();
        let fs = frames(&m, seq, mtu);
        let mut done = None;
        for f in &fs {
            if let Feed::Done(d) = r.feed(f, 0) { done = Some(d); }
        }
        prop_assert_eq!(done, Some(m));
    }

    /// Any frame sequence: no panic, and every delivered message is one that was sent.
    #[test]
    fn feed_survives_anything(
        msgs in proptest::collection::vec(any_msg(), 1..4),
        ops in proptest::collection::vec((0u8..6, any::<u8>(), any::<u8>(), 0u32..100), 0..80),
    ) {
        let mut pool: Vec<Vec<u8>> = Vec::new();
        for (i, m) in msgs.iter().enumerate() {
            pool.extend(frames(m, i as u8, Mtu::Classic));
        }
        let mut r = Reassembler::<MSG_BUF>::new();
        let mut now = 0u32;
        for (op, a, b, dt) in ops {
            now = now.wrapping_add(dt);
            let pick = pool[a as usize % pool.len()].clone();
            let frame = match op {
                0 | 1 => pick,
                2 => { let mut f = pick; let l = f.len(); f.truncate(b as usize % (l + 1)); f }
                3 => { let mut f = pick; let l = f.len(); f[b as usize % l] ^= a | 1; f }
                4 => vec![a, b, a ^ b, b, a],
                _ => vec![a; b as usize % 70],
            };
            if let Feed::Done(d) = r.feed(&frame, now) {
                prop_assert!(msgs.contains(&d), "delivered a message nobody sent: {:?}", d);
            }
        }
    }
}
