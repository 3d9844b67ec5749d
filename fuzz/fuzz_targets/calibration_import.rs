//! The calibration's way in: arbitrary bytes as the protocol's calibration message body
//! (`gough::proto::CalibrationState`, postcard: the decoder of `Msg::SetCalibration` /
//! `Msg::Calibration`) and as raw `Exported` values (any f32 bit patterns) into
//! `Bank::import_calibration` in f32 (`Fast`) and f64 (`Libm`). Never a panic; an import either
//! is refused with nothing changed or leaves a calibration with finite θ, a finite covariance
//! whose diagonal is ≥ 0, and θ within the estimator's bound; and the bank then runs a few
//! samples with finite estimates.
//!
//! Run: `cargo +nightly fuzz run calibration_import -- -max_total_time=60`.
#![no_main]

use gough::math::{Backend, Fast, Float, Libm};
use gough::mf::Params;
use gough::mu::calibration::Exported;
use gough::mu::{Bank, Config, Sample};
use gough::proto::{CalibrationState, Msg, MsgType, PROTO_VERSION};
use libfuzzer_sys::fuzz_target;

fn check<F: Float, M: Backend<F>>(p: &Params<F>, e: &Exported) {
    let Ok(mut bank) = Bank::new::<M>(p, None, Config::default()) else {
        return;
    };
    let before = *bank.calibration();
    match bank.import_calibration::<M>(e) {
        Err(_) => assert_eq!(*bank.calibration(), before, "a refusal changed the calibration"),
        Ok(()) => {
            let c = *bank.calibration();
            let cfg = *bank.config();
            for (k, t) in c.theta.iter().enumerate() {
                assert!(t.is_finite(), "{c:?}");
                assert!(t.abs() <= cfg.cal_bound * cfg.cal_sigma[k], "{c:?}");
                assert!(c.cov[k][k] >= F::ZERO, "{c:?}");
            }
            assert!(c.cov.iter().flatten().all(|x| x.is_finite()), "{c:?}");
            assert_eq!(c.batches, e.batches);
        }
    }
    // A few samples of a steady turn: the estimate stays finite.
    for i in 0..40u32 {
        let s = Sample {
            t_us: i * 1000,
            fz: F::from_f64(4000.0),
            fy: F::from_f64(-2000.0),
            mz: F::from_f64(-40.0),
            fx: None,
            kappa: None,
            vx: Some(F::from_f64(20.0)),
            gamma: None,
        };
        let est = bank.update::<M>(p, &s);
        assert!(est.mu.is_finite() && est.sigma.is_finite(), "{est:?}");
    }
}

fuzz_target!(|data: &[u8]| {
    let (p64, p32) = gough_fuzz::mf61();
    // As a message body: the protocol's decoder (the CRC is skipped when fuzzing).
    let mut msg = vec![PROTO_VERSION, MsgType::SetCalibration as u8];
    msg.extend_from_slice(data);
    msg.extend_from_slice(&[0; 4]);
    let from_msg = match Msg::decode(&msg) {
        Ok(Msg::SetCalibration(c)) | Ok(Msg::Calibration(c)) => Some(c),
        Ok(other) => panic!("decoded as another type: {other:?}"),
        Err(_) => None,
    };
    // As raw values: 4 + 4 f32 and the batches.
    let raw = (data.len() >= 36).then(|| {
        let f = |k: usize| f32::from_le_bytes([data[4 * k], data[4 * k + 1], data[4 * k + 2], data[4 * k + 3]]);
        Exported {
            value: [f(0), f(1), f(2), f(3)],
            sigma: [f(4), f(5), f(6), f(7)],
            batches: u32::from_le_bytes([data[32], data[33], data[34], data[35]]),
        }
    });
    for e in from_msg.map(|c: CalibrationState| c.exported()).into_iter().chain(raw) {
        check::<f32, Fast>(p32, &e);
        let mut x = e;
        // Values near the bounds as f64 reads them.
        x.value = x.value.map(|v| if v.is_finite() { v } else { 1.0 });
        check::<f64, Libm>(p64, &e);
        check::<f64, Libm>(p64, &x);
    }
});
