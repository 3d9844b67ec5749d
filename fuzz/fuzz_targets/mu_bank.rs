//! The friction estimator (`gough::mu::bank::Bank`) fed arbitrary bytes as samples, in f32 with
//! the device's `Fast` backend and in f64: it must never panic, and every estimate must be
//! finite (σ ≥ 0), whatever the samples — NaN, ±∞, Fz ≤ 0, time going backwards or wrapping.
//! The f32 bank is a rear wheel: a front wheel's bank on the same samples hands it its readings
//! through a front-to-rear preview (`gough::mu::preview`, 0.5 m), and a flag feeds it a raw
//! profile of the sample's values (any floats) as a reading.
//!
//! Run: `cargo +nightly fuzz run mu_bank -- -max_total_time=60`.
#![no_main]

use gough::math::{Fast, Libm};
use gough::mf::Side;
use gough::mu::{Bank, Config, Reading, Sample, CELLS};
use gough::mu::preview::{self, Preview};
use libfuzzer_sys::fuzz_target;

/// 4 bytes as an f32 (any bit pattern: NaN, ±∞, subnormals included).
fn f(b: &[u8]) -> f32 {
    f32::from_le_bytes([b[0], b[1], b[2], b[3]])
}

fuzz_target!(|data: &[u8]| {
    let (p64, p32) = gough_fuzz::mf61();
    let side = if data.first().is_some_and(|b| b & 1 == 1) { Some(Side::Right) } else { None };
    let (Ok(mut e32), Ok(mut e64)) = (
        Bank::new::<Fast>(p32, side, Config::default()),
        Bank::new::<Libm>(p64, side, Config::default()),
    ) else {
        return;
    };
    let (Ok(mut front), Ok(mut pv)) = (
        Bank::new::<Fast>(p32, side, Config::default()),
        Preview::new(preview::Config::with_wheelbase(0.5f32)),
    ) else {
        return;
    };
    // One sample per 33 bytes: a flags byte, t_us, then Fz, Fy, Mz, Fx, κ, Vx, γ.
    for c in data.chunks_exact(33) {
        let flags = c[0];
        let t_us = u32::from_le_bytes([c[1], c[2], c[3], c[4]]);
        let v: Vec<f32> = c[5..].chunks_exact(4).map(f).collect();
        let opt = |bit: u8, x: f32| (flags & bit != 0).then_some(x);
        let s = Sample {
            t_us,
            fz: v[0],
            fy: v[1],
            mz: v[2],
            fx: opt(1, v[3]),
            kappa: opt(2, v[4]),
            vx: opt(4, v[5]),
            gamma: opt(8, v[6]),
        };
        front.update::<Fast>(p32, &s);
        pv.front(&front);
        pv.rear::<Fast>(&mut e32, &s);
        if flags & 16 != 0 {
            let profile: [f32; CELLS] = core::array::from_fn(|k| v[k % v.len()]);
            if let Some(r) = Reading::new(&profile, v[6]) {
                e32.preview::<Fast>(r);
            }
        }
        let e = e32.update::<Fast>(p32, &s);
        assert!(e.mu.is_finite() && e.sigma.is_finite() && e.sigma >= 0.0, "{e:?}");
        let d = |x: f32| f64::from(x);
        let s64 = Sample {
            t_us,
            fz: d(s.fz),
            fy: d(s.fy),
            mz: d(s.mz),
            fx: s.fx.map(d),
            kappa: s.kappa.map(d),
            vx: s.vx.map(d),
            gamma: s.gamma.map(d),
        };
        let e = e64.update::<Libm>(p64, &s64);
        assert!(e.mu.is_finite() && e.sigma.is_finite() && e.sigma >= 0.0, "{e:?}");
    }
});
