//! The staged Magic Formula (`gough::mf::prepared`): the load stage, the friction stage and the
//! slip stage with its slopes must never panic, and for finite input give finite numbers or an
//! error; the slip stage's forces are `mf::eval`'s, and so are `mf::relaxation_lengths`' σ.
//!
//! Run: `cargo +nightly fuzz run mf_staged -- -max_total_time=60`.
#![no_main]

use gough::math::Libm;
use gough::mf::prepared::{Operating, Prepared};
use gough::mf::{self, Input, Options, Params, Side};
use libfuzzer_sys::fuzz_target;

fn check<F: gough::math::Float>(p: &Params<F>, i: &Input<F>, o: &Options, lmu: F)
where
    Libm: gough::math::Backend<F>,
{
    let Ok(prep) = Prepared::new::<Libm>(p, &Operating::from(i), o) else {
        return;
    };
    let staged = prep.eval::<Libm>(i.kappa, i.alpha);
    if let (Ok(s), Ok(e)) = (&staged, &mf::eval::<F, Libm>(p, i, o)) {
        assert!(
            s.fx == e.fx && s.fy == e.fy && s.mz == e.mz,
            "{s:?} vs {e:?}"
        );
    }
    if let Ok(s) = staged {
        assert!(F::all_finite(&[s.fx, s.fy, s.mz, s.t, s.m_zr]));
    }
    // The relaxation lengths from the load stage alone: finite, and `eval`'s where it gives them.
    let sigma = mf::relaxation_lengths::<F, Libm>(p, i, o);
    if let Ok((sx, sy)) = sigma {
        assert!(F::all_finite(&[sx, sy]));
        if let Ok(e) = mf::eval::<F, Libm>(p, i, o) {
            assert!(sx == e.sigma_x && sy == e.sigma_y, "{sx:?} {sy:?} vs {e:?}");
        }
    }
    let mu = prep.with_mu(lmu, lmu);
    if let Ok((f, d)) = prep.eval_d::<Libm>(&mu, i.kappa, i.alpha) {
        let all = [
            f.fx, f.fy, f.mz, d.kappa.fx, d.kappa.fy, d.kappa.mz, d.alpha.fx, d.alpha.fy,
            d.alpha.mz,
        ];
        assert!(F::all_finite(&all), "{all:?}");
    }
    if let Ok((f, d)) = prep.eval_d_mu::<Libm>(lmu, i.kappa, i.alpha) {
        let all = [
            f.fx,
            f.fy,
            f.mz,
            d.lmu.fx,
            d.lmu.fy,
            d.lmu.mz,
            d.slip.kappa.fx,
            d.slip.alpha.fy,
        ];
        assert!(F::all_finite(&all), "{all:?}");
    }
    // Both scalings times s at s = 1 (the friction estimator's slope in a surface), with the
    // file's λμx, λμy in proportion to `lmu`.
    if let Ok((f, d)) = prep.eval_d_scale::<Libm>(lmu * p.lmux, lmu * p.lmuy, i.kappa, i.alpha) {
        let all = [f.fx, f.fy, f.mz, d.lmu.fx, d.lmu.fy, d.lmu.mz];
        assert!(F::all_finite(&all), "{all:?}");
    }
}

fuzz_target!(|data: &[u8]| {
    if data.len() < 2 + 8 * 7 {
        return;
    }
    let ps = gough_fuzz::tyres();
    let Some(p) = ps.get(data[0] as usize % ps.len().max(1)) else {
        return;
    };
    let bits = data[1];
    let x = |k: usize| {
        let mut b = [0u8; 8];
        b.copy_from_slice(&data[2 + 8 * k..10 + 8 * k]);
        f64::from_le_bytes(b)
    };
    let o = Options {
        limits: bits & 1 != 0,
        alpha_star: bits & 2 != 0,
        turn_slip: false,
        mounted: match (bits >> 2) & 3 {
            0 => None,
            1 => Some(Side::Left),
            _ => Some(Side::Right),
        },
        transient: bits & 16 != 0,
        moments: false,
    };
    let i = Input {
        fz: x(0),
        kappa: x(1),
        alpha: x(2),
        gamma: x(3),
        phit: 0.0,
        vx: x(4),
        p: if bits & 32 != 0 { Some(x(5)) } else { None },
    };
    let lmu = x(6);
    check(p, &i, &o, lmu);
    let i32 = Input {
        fz: i.fz as f32,
        kappa: i.kappa as f32,
        alpha: i.alpha as f32,
        gamma: i.gamma as f32,
        phit: 0.0,
        vx: i.vx as f32,
        p: i.p.map(|v| v as f32),
    };
    check(&p.cast::<f32>(), &i32, &o, lmu as f32);
});
