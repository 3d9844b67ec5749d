//! The Magic Formula in lanes (`gough::mf::eval_batch_lanes_scaled`) on every instruction set
//! this processor has: never a panic; for any columns (up to 40 points: chunks of 16, 8 and 4
//! with a padded tail, points in and out of contact side by side, turn slip on or off) and any
//! per-point factors on λμx, λμy, λKx, λKy, the same rejected point as `mf::eval` point by point,
//! and where every point is accepted every output finite; at the points inside a physical range
//! (|Fz| ≤ 10·FNOMIN, |κ| ≤ 10, |α| ≤ π, |γ| ≤ 1, |Vx| ≤ 1,000 m/s, p within 0.1–10× INFLPRES, the
//! factors within 0.1–10) each output within 1e-9·FNOMIN of `mf::eval` on that point's
//! parameters (relative to the output where it exceeds FNOMIN), with the same flags. Outside
//! that range two summands of 1e280 cancel (the first crash: Fz 1e140, γ 6e144), and the lanes'
//! last-bit differences from `libm` can be all of what is left.
//!
//! Run: `cargo +nightly fuzz run mf_lanes -- -max_total_time=60`.
#![no_main]

use gough::math::Libm;
use gough::mf::{self, BatchError, Columns, Flags, Input, Isa, Options, Outputs, Scales};
use libfuzzer_sys::fuzz_target;

/// Values per point: Fz, κ, α, γ, Vx, φt, p, and the four factors.
const PER_POINT: usize = 11;

fuzz_target!(|data: &[u8]| {
    if data.len() < 2 + 8 * PER_POINT {
        return;
    }
    let ps = gough_fuzz::tyres();
    let Some(p) = ps.get(data[0] as usize % ps.len().max(1)) else {
        return;
    };
    let bits = data[1];
    let n = ((data.len() - 2) / (8 * PER_POINT)).min(40);
    let x = |i: usize, k: usize| {
        let at = 2 + 8 * (i * PER_POINT + k);
        let mut b = [0u8; 8];
        b.copy_from_slice(&data[at..at + 8]);
        f64::from_le_bytes(b)
    };
    let col = |k: usize| (0..n).map(|i| x(i, k)).collect::<Vec<f64>>();
    let (fz, kappa, alpha, gamma, vx, phit, pres) =
        (col(0), col(1), col(2), col(3), col(4), col(5), col(6));
    let (lmux, lmuy, lkx, lky) = (col(7), col(8), col(9), col(10));
    let opts = Options {
        limits: bits & 1 != 0,
        alpha_star: bits & 2 != 0,
        turn_slip: bits & 4 != 0 && mf::turnslip::available(p),
        transient: bits & 8 != 0,
        moments: bits & 16 != 0,
        ..Options::default()
    };
    let with_p = bits & 32 != 0;
    let scaled = bits & 64 != 0;
    let cols = Columns {
        fz: &fz,
        kappa: &kappa,
        alpha: &alpha,
        gamma: &gamma,
        vx: &vx,
        phit: Some(&phit),
        p: with_p.then_some(pres.as_slice()),
    };
    let scales = if scaled {
        Scales {
            lmux: Some(&lmux),
            lmuy: Some(&lmuy),
            lkx: Some(&lkx),
            lky: Some(&lky),
        }
    } else {
        Scales::default()
    };
    // A physical range (see the module doc): where the lanes must agree with `mf::eval`.
    let sane = |i: usize| {
        let within = |v: f64, hi: f64| v.abs() <= hi;
        let factor = |v: f64| !scaled || (0.1..=10.0).contains(&v);
        within(fz[i], 10.0 * p.fnomin)
            && within(kappa[i], 10.0)
            && within(alpha[i], std::f64::consts::PI)
            && within(gamma[i], 1.0)
            && within(vx[i], 1000.0)
            && within(phit[i], 10.0)
            && (!with_p || (0.1 * p.inflpres..=10.0 * p.inflpres).contains(&pres[i]))
            && [lmux[i], lmuy[i], lkx[i], lky[i]].into_iter().all(factor)
    };
    // Point by point: each point's parameters, its result or the first rejection.
    let mut want = Vec::with_capacity(n);
    let mut first_err = None;
    for i in 0..n {
        let mut q = p.clone();
        if scaled {
            q.lmux *= lmux[i];
            q.lmuy *= lmuy[i];
            q.lkx *= lkx[i];
            q.lky *= lky[i];
        }
        let input = Input {
            fz: fz[i],
            kappa: kappa[i],
            alpha: alpha[i],
            gamma: gamma[i],
            phit: phit[i],
            vx: vx[i],
            p: with_p.then_some(pres[i]),
        };
        match mf::eval::<f64, Libm>(&q, &input, &opts) {
            Ok(o) => want.push(o),
            Err(e) => {
                first_err = Some((i, e));
                break;
            }
        }
    }
    for isa in [Isa::Avx512, Isa::Avx2, Isa::Baseline] {
        let mut c: [Vec<f64>; 5] = std::array::from_fn(|_| vec![0.0; n]);
        let mut flags = vec![Flags::default(); n];
        let [fx, fy, mz, mx, sy] = &mut c;
        let mut out = Outputs {
            fx: Some(fx),
            fy: Some(fy),
            mz: Some(mz),
            mx: Some(mx),
            sigma_y: Some(sy),
            flags: Some(&mut flags),
            ..Outputs::default()
        };
        let r = mf::eval_batch_lanes_scaled(isa, p, &cols, &scales, &opts, &mut out);
        match (r, first_err) {
            (Err(BatchError::Point { index, error }), Some((i, e))) => {
                assert_eq!((index, error), (i, e), "{isa:?}");
            }
            (Ok(_), None) => {
                for (i, o) in want.iter().enumerate() {
                    let wants = [o.fx, o.fy, o.mz, o.mx, o.sigma_y];
                    for (k, g) in c.iter().map(|col| col[i]).enumerate() {
                        assert!(g.is_finite(), "{isa:?} point {i} column {k}: {g}");
                    }
                    if !sane(i) {
                        continue;
                    }
                    for (k, w) in wants.iter().enumerate() {
                        let g = c[k][i];
                        assert!(
                            (g - w).abs() <= 1e-9 * p.fnomin * (1.0 + w.abs() / p.fnomin),
                            "{isa:?} point {i} column {k}: {g} vs {w}"
                        );
                    }
                    assert_eq!(flags[i], o.flags, "{isa:?} point {i}");
                }
            }
            (r, e) => panic!("{isa:?}: lanes {r:?}, point by point {e:?}"),
        }
    }
});
