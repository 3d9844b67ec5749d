//! One wheel's whole per-sample pipeline (`gough::wheel::Corner`: transient filter → Magic
//! Formula → forces, and the friction estimator) fed arbitrary bytes as measurements, in f32
//! with the device's `Fast` backend, limits on or off, mounted on either side or as the file
//! describes it: it must never panic, every estimate must be finite (σ ≥ 0, μ_min finite),
//! whatever the samples — NaN, ±∞, Fz ≤ 0, absurd slips and speeds, time going backwards or
//! wrapping — and forces, when the pipeline gives them, are finite.
//!
//! Run: `cargo +nightly fuzz run wheel -- -max_total_time=60`.
#![no_main]

use gough::math::Fast;
use gough::mf::Side;
use gough::mu::Config;
use gough::wheel::{Corner, Measurement};
use libfuzzer_sys::fuzz_target;

/// 4 bytes as an f32 (any bit pattern: NaN, ±∞, subnormals included).
fn f(b: &[u8]) -> f32 {
    f32::from_le_bytes([b[0], b[1], b[2], b[3]])
}

fuzz_target!(|data: &[u8]| {
    let p = &gough_fuzz::mf61().1;
    let Some((&head, data)) = data.split_first() else {
        return;
    };
    let mounted = match head % 3 {
        0 => None,
        1 => Some(Side::Left),
        _ => Some(Side::Right),
    };
    let limits = head & 4 != 0;
    let mut c = Corner::<f32>::on(mounted);
    if c.start_estimator::<Fast>(p, Config::default()).is_err() {
        return;
    }
    // One measurement per 46 bytes: a flags byte, another, t_us, then Fz, Fy, Mz, Fx, Vx, ω,
    // α, κ, γ.
    for m in data.chunks_exact(46) {
        let (flags, t_us) = (m[0], u32::from_le_bytes([m[2], m[3], m[4], m[5]]));
        let v: Vec<f32> = m[6..].chunks_exact(4).map(f).collect();
        let opt = |bit: u8, x: f32| (flags & bit != 0).then_some(x);
        let x = Measurement {
            t_us,
            fz: v[0],
            fy: v[1],
            mz: v[2],
            fx: opt(1, v[3]),
            vx: opt(2, v[4]),
            omega: opt(4, v[5]),
            alpha: opt(8, v[6]),
            kappa: opt(16, v[7]),
            gamma: opt(32, v[8]),
        };
        if m[1] & 1 != 0 {
            c.reset_filter();
        }
        if let Ok(o) = c.forces::<Fast>(p, limits, &x) {
            let finite_in = v.iter().all(|x| x.is_finite());
            assert!(
                !finite_in || (o.fx.is_finite() && o.fy.is_finite() && o.mz.is_finite()),
                "{x:?} -> {o:?}"
            );
        }
        let e = c.estimate::<Fast>(p, &x).expect("the estimator runs");
        assert!(
            e.mu.is_finite() && e.sigma.is_finite() && e.sigma >= 0.0 && e.mu_min.is_finite(),
            "{x:?} -> {e:?}"
        );
        let cal = c.estimator().expect("runs").calibration();
        assert!(
            cal.theta.iter().all(|t| t.is_finite())
                && cal.cov.iter().flatten().all(|x| x.is_finite()),
            "{cal:?}"
        );
    }
});
