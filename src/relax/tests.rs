//! The transient model against its analytic solutions, through standstill, and the paper's
//! dynamic side-force loss under load fluctuation (Figs. 13–14).
use super::*;
use crate::math::Libm;
use proptest::prelude::*;
use std::vec::Vec;

fn cfg(damping: DampingSpeed) -> Config<f64> {
    Config {
        damping,
        sigma_min: 0.01,
        damp_vlow: 0.0,
        vxlow: 1.0,
        max_tan_alpha: 1.0,
        max_kappa: 1.0,
    }
}

const SIGMA: Sigma<f64> = Sigma {
    sigma_kappa: 0.15,
    sigma_alpha: 0.45,
};

/// Step in slip angle: tan α'(s) = tan α0·(1 − e^(−s/σα)) over travelled distance s, exactly,
/// for steps from 10 µs to 10 ms; and the longitudinal twin.
#[test]
fn step_response_is_the_analytic_first_order_response() {
    let vx = 20.0;
    let (tan_a0, kappa0) = (0.05f64, -0.08f64);
    for dt in [1e-5, 1e-4, 1e-3, 1e-2] {
        for damping in [DampingSpeed::Forward, DampingSpeed::Rolling] {
            let mut tr = Transient::new(0.0);
            let k = Kinematics {
                vx,
                vsx: -kappa0 * vx,
                vsy: tan_a0 * vx,
            };
            let n = (0.1 / dt) as usize;
            for i in 1..=n {
                let s = tr.step::<Libm>(&cfg(damping), dt, &k, &SIGMA).unwrap();
                let dist = vx * dt * i as f64;
                // Rolling: Vr = Vx − Vsx = Vx·(1 + κ0).
                let speed = match damping {
                    DampingSpeed::Forward => vx,
                    DampingSpeed::Rolling => vx * (1.0 + kappa0),
                };
                let t = dt * i as f64;
                let want_a = tan_a0 * vx / speed * (1.0 - (-speed * t / SIGMA.sigma_alpha).exp());
                let want_k = kappa0 * vx / speed * (1.0 - (-speed * t / SIGMA.sigma_kappa).exp());
                assert!((s.alpha.tan() - want_a).abs() < 1e-12, "dt {dt} s {dist}");
                assert!((s.kappa - want_k).abs() < 1e-12, "dt {dt} s {dist}");
            }
        }
    }
}

/// Sinusoidal slip angle: gain 1/√(1 + (ωp·σ)²) and phase −atan(ωp·σ) over path frequency ωp.
#[test]
fn frequency_response_matches_the_analytic_one() {
    let vx = 15.0;
    let dt = 1e-4;
    for &wp in &[0.5, 2.0, 5.0] {
        // ωp [rad/m] → ω = ωp·V [rad/s]
        let w = wp * vx;
        let mut tr = Transient::new(0.0);
        let cycles = 6.0;
        let t_end = cycles * 2.0 * core::f64::consts::PI / w;
        let n = (t_end / dt) as usize;
        let (mut sc, mut cc, mut norm) = (0.0, 0.0, 0.0);
        for i in 0..n {
            let tm = (i as f64 + 0.5) * dt; // midpoint of the step
            let x = 0.01 * (w * tm).sin();
            let k = Kinematics {
                vx,
                vsx: 0.0,
                vsy: x * vx,
            };
            let y = tr
                .step::<Libm>(&cfg(DampingSpeed::Forward), dt, &k, &SIGMA)
                .unwrap()
                .alpha
                .tan();
            let te = (i + 1) as f64 * dt;
            if te > t_end / 2.0 {
                sc += y * (w * te).sin();
                cc += y * (w * te).cos();
                norm += (w * te).sin().powi(2);
            }
        }
        let gain = (sc * sc + cc * cc).sqrt() / norm / 0.01;
        let phase = cc.atan2(sc);
        let ws = wp * SIGMA.sigma_alpha;
        let (g_want, p_want) = (1.0 / (1.0 + ws * ws).sqrt(), -ws.atan());
        assert!(
            (gain - g_want).abs() < 2e-3,
            "wp {wp}: gain {gain} vs {g_want}"
        );
        assert!(
            (phase - p_want).abs() < 2e-3,
            "wp {wp}: phase {phase} vs {p_want}"
        );
    }
}

/// Stop, slide at standstill, start again: the states stay bounded and finite, the low-speed
/// damping acts, and after the restart the slips settle to the steady values.
#[test]
fn standstill_stop_start_stays_bounded() {
    let mut c = cfg(DampingSpeed::Rolling);
    c.damp_vlow = 0.001;
    let mut tr = Transient::new(0.0);
    let dt = 1e-3;
    let mut t = 0.0;
    let mut max_tan = 0.0f64;
    while t < 6.0 {
        // 20 m/s → 0 in 2 s, 2 s at rest with the wheel pushed sideways, 0 → 10 m/s.
        let vx = if t < 2.0 {
            20.0 * (1.0 - t / 2.0)
        } else if t < 4.0 {
            0.0
        } else {
            5.0 * (t - 4.0)
        };
        let vsy = if (2.0..4.0).contains(&t) {
            0.5
        } else {
            0.03 * vx
        };
        let vsx = if (2.0..4.0).contains(&t) { -0.1 } else { 0.0 }; // pushed at rest
        let s = tr
            .step::<Libm>(&c, dt, &Kinematics { vx, vsx, vsy }, &SIGMA)
            .unwrap();
        assert!(s.alpha.is_finite() && s.kappa.is_finite());
        assert!(tr.v.abs() <= c.max_tan_alpha * SIGMA.sigma_alpha + 1e-12);
        assert!(tr.u.abs() <= c.max_kappa * SIGMA.sigma_kappa + 1e-12);
        if (3.2..4.0).contains(&t) {
            assert!(
                s.flags.contains(StepFlags::ALPHA_CLAMPED),
                "sliding at rest must hit the clamp"
            );
            assert!(s.flags.contains(StepFlags::LOW_SPEED));
        }
        max_tan = max_tan.max(s.alpha.tan().abs());
        t += dt;
    }
    let s = tr
        .step::<Libm>(
            &c,
            dt,
            &Kinematics {
                vx: 10.0,
                vsx: 0.0,
                vsy: 0.3,
            },
            &SIGMA,
        )
        .unwrap();
    assert!(
        (s.alpha.tan() - 0.03).abs() < 1e-3,
        "settled to tan α = 0.03, got {}",
        s.alpha.tan()
    );
    // At rest with no slip the states do not drift.
    let before = tr;
    for _ in 0..1000 {
        tr.step::<Libm>(
            &cfg(DampingSpeed::Rolling),
            dt,
            &Kinematics::default(),
            &SIGMA,
        )
        .unwrap();
    }
    assert_eq!(tr, before);
}

#[test]
fn bad_steps_are_refused_and_leave_the_state() {
    let mut tr = Transient { v: 0.01, u: -0.02 };
    let k = Kinematics {
        vx: 10.0,
        vsx: 0.0,
        vsy: 1.0,
    };
    let c = cfg(DampingSpeed::Rolling);
    assert_eq!(
        tr.step::<Libm>(&c, 0.0, &k, &SIGMA),
        Err(StepError::BadStep)
    );
    assert_eq!(
        tr.step::<Libm>(&c, 2.0, &k, &SIGMA),
        Err(StepError::BadStep)
    );
    assert_eq!(
        tr.step::<Libm>(&c, f64::NAN, &k, &SIGMA),
        Err(StepError::NonFinite)
    );
    let kn = Kinematics {
        vsy: f64::INFINITY,
        ..k
    };
    assert_eq!(
        tr.step::<Libm>(&c, 1e-3, &kn, &SIGMA),
        Err(StepError::NonFinite)
    );
    assert_eq!(tr, Transient { v: 0.01, u: -0.02 });
    // σ = 0 (no load) is floored, not divided by.
    let s = tr.step::<Libm>(&c, 1e-3, &k, &Sigma::default()).unwrap();
    assert!(s.flags.contains(StepFlags::SIGMA_FLOOR) && s.alpha.is_finite());
}

#[test]
fn decayed_sigma_bounds() {
    assert_eq!(decayed_sigma(0.4, 1000.0, -50000.0, 0.01), 0.4); // linear range
    let s: f64 = decayed_sigma(0.4, 4000.0, -50000.0, 0.2); // saturated: 4000 of 10000
    assert!((s - 0.16).abs() < 1e-12);
    assert_eq!(decayed_sigma(0.4, 0.0, 0.0, 0.0), 0.4);
}

fn tyre61() -> Params<f64> {
    crate::tir::parse(include_str!(
        "../../host-tests/data/tyres/MagicFormula61_Parameters.tir"
    ))
    .unwrap()
    .params
}

/// Average |Fy| at α = 6° under Fz = Fz0·(1 + A·sin 2πft), dynamic (transient) and the average
/// of the steady-state curve over the same load cycle (the quasi-static reference).
fn fy_averages(p: &Params<f64>, f: f64, amp: f64, vx: f64) -> (f64, f64) {
    let opts = Options {
        transient: true,
        ..Options::default()
    };
    let mut tyre = TransientTyre::new(p);
    let dt = 2e-4;
    let tan_a = (6.0f64).to_radians().tan();
    let period = 1.0 / f;
    let settle = 3.0 * period + 1.0; // ≥ 1 s of travel for the lag to settle
    let cycles = 4.0;
    let (mut dynamic, mut quasi, mut n) = (0.0, 0.0, 0.0);
    let mut t = 0.0;
    while t < settle + cycles * period {
        let tm = t + dt / 2.0;
        let fz = p.fnomin * (1.0 + amp * (2.0 * core::f64::consts::PI * f * tm).sin());
        let op = Operating {
            kin: Kinematics {
                vx,
                vsx: 0.0,
                vsy: tan_a * vx,
            },
            fz,
            gamma: 0.0,
            phit: 0.0,
            p: None,
        };
        let (out, _) = tyre.step::<Libm>(p, &opts, dt, &op).unwrap();
        if t >= settle {
            let ss = mf::eval::<f64, Libm>(
                p,
                &Input {
                    fz,
                    alpha: tan_a.atan(),
                    vx,
                    ..Input::default()
                },
                &opts,
            )
            .unwrap();
            dynamic += out.fy.abs();
            quasi += ss.fy.abs();
            n += 1.0;
        }
        t += dt;
    }
    (dynamic / n, quasi / n)
}

/// Paper Figs. 13–14: a side-slipping wheel rolling with a sinusoidal load loses average side
/// force; the loss grows with frequency and amplitude and at lower speed (shorter wavelength);
/// its quasi-static part equals the steady-state curve averaged over the load cycle.
#[test]
fn dynamic_side_force_loss_under_load_fluctuation() {
    let p = tyre61();
    let fy0 = mf::eval::<f64, Libm>(
        &p,
        &Input {
            fz: p.fnomin,
            alpha: 6f64.to_radians(),
            vx: 20.0,
            ..Input::default()
        },
        &Options::default(),
    )
    .unwrap()
    .fy
    .abs();
    let loss = |f: f64, a: f64, v: f64| {
        let (d, q) = fy_averages(&p, f, a, v);
        (q - d) / fy0
    };
    // Quasi-static: at 0.2 Hz the dynamic average equals the averaged steady-state curve.
    let (d, q) = fy_averages(&p, 0.2, 0.5, 20.0);
    assert!((d - q).abs() < 2e-3 * fy0, "quasi-static {d} vs {q}");
    // and that average is below Fy at the mean load (the static loss of Fig. 14 at 0 Hz).
    assert!(q < fy0);
    let (l2, l8, l16) = (
        loss(2.0, 0.5, 20.0),
        loss(8.0, 0.5, 20.0),
        loss(16.0, 0.5, 20.0),
    );
    assert!(
        0.0 < l2 && l2 < l8 && l8 < l16,
        "loss grows with frequency: {l2} {l8} {l16}"
    );
    let (a_small, a_big) = (loss(8.0, 0.25, 20.0), loss(8.0, 0.75, 20.0));
    assert!(
        a_small < l8 && l8 < a_big,
        "loss grows with amplitude: {a_small} {l8} {a_big}"
    );
    let slow = loss(8.0, 0.5, 10.0);
    assert!(slow > l8, "loss grows at lower speed: {slow} vs {l8}");
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]
    /// Any finite kinematics, any step in [10 µs, 10 ms], any σ ≥ 0: finite and bounded states.
    #[test]
    fn bounded_for_any_finite_input(
        steps in proptest::collection::vec(
            (-60.0f64..60.0, -60.0f64..60.0, -60.0f64..60.0, 1e-5f64..1e-2, 0.0f64..2.0, 0.0f64..2.0), 1..200),
        rolling in any::<bool>(),
    ) {
        let c = cfg(if rolling { DampingSpeed::Rolling } else { DampingSpeed::Forward });
        let mut tr = Transient::new(0.0);
        for (vx, vsx, vsy, dt, sa, sk) in steps {
            let sig = Sigma { sigma_alpha: sa, sigma_kappa: sk };
            let s = tr.step::<Libm>(&c, dt, &Kinematics { vx, vsx, vsy }, &sig).unwrap();
            prop_assert!(s.alpha.is_finite() && s.kappa.is_finite());
            prop_assert!(s.alpha.abs() <= core::f64::consts::FRAC_PI_4 + 1e-12);
            prop_assert!(s.kappa.abs() <= 1.0 + 1e-12);
        }
    }

    /// The f32 device path stays finite and bounded too, and tracks f64.
    #[test]
    fn f32_tracks_f64(vx in 0.0f64..50.0, tan_a in -0.2f64..0.2, n in 1usize..500) {
        let c64 = cfg(DampingSpeed::Rolling);
        let c32 = Config { damping: DampingSpeed::Rolling, sigma_min: 0.01f32, damp_vlow: 0.0, vxlow: 1.0, max_tan_alpha: 1.0, max_kappa: 1.0 };
        let (mut a, mut b) = (Transient::new(0.0f64), Transient::new(0.0f32));
        let s32 = Sigma { sigma_alpha: 0.45f32, sigma_kappa: 0.15f32 };
        let mut last = (0.0, 0.0f32);
        for _ in 0..n {
            let x = a.step::<Libm>(&c64, 1e-3, &Kinematics { vx, vsx: 0.0, vsy: tan_a * vx }, &SIGMA).unwrap();
            let y = b.step::<Libm>(&c32, 1e-3, &Kinematics { vx: vx as f32, vsx: 0.0, vsy: (tan_a * vx) as f32 }, &s32).unwrap();
            last = (x.alpha, y.alpha);
        }
        prop_assert!((last.0 - last.1 as f64).abs() < 1e-5);
    }
}

#[test]
fn transient_tyre_converges_to_the_steady_state() {
    let p = tyre61();
    let opts = Options {
        transient: true,
        ..Options::default()
    };
    let mut tyre = TransientTyre::new(&p);
    tyre.config.damping = DampingSpeed::Forward;
    let (vx, a, k) = (20.0, 0.04f64, -0.05f64);
    let op = Operating {
        kin: Kinematics {
            vx,
            vsx: -k * vx,
            vsy: a.tan() * vx,
        },
        fz: 5000.0,
        gamma: 0.01,
        phit: 0.0,
        p: None,
    };
    let mut outs = Vec::new();
    for _ in 0..2000 {
        outs.push(tyre.step::<Libm>(&p, &opts, 1e-3, &op).unwrap().0);
    }
    let ss = mf::eval::<f64, Libm>(
        &p,
        &Input {
            fz: 5000.0,
            kappa: k,
            alpha: a,
            gamma: 0.01,
            vx,
            ..Input::default()
        },
        &opts,
    )
    .unwrap();
    let last = outs.last().unwrap();
    assert!((last.fy - ss.fy).abs() < 1e-6 * p.fnomin && (last.fx - ss.fx).abs() < 1e-6 * p.fnomin);
    // The force builds up: after 0.5·σ of travel it is well below the steady value.
    let sigma = ss.sigma_y;
    let i = ((0.5 * sigma / vx) / 1e-3) as usize;
    assert!(outs[i].fy.abs() < 0.6 * ss.fy.abs());
}

/// The fixed-point path (issue 7): the same filter and Magic Formula in Q31.32 (`fixed::Fix`,
/// `FixMath`) against f64, over 4 s at 1 kHz — a steering sine with braking pulses while the
/// speed falls from 20 m/s through standstill and rises again, σ from each step's evaluation
/// as the firmware does it. Error ≤ 0.5 % of the run's peak force (issue 7's bound); the
/// measured figures print with `--nocapture`.
#[cfg(feature = "fixed")]
#[test]
fn fixed_point_filter_and_forces_track_f64() {
    use crate::fixed::{Fix, FixMath};
    use crate::math::{Float, Real};
    use crate::mf::Input;
    let p64 = tyre61();
    let pfx = p64.cast::<Fix>();
    let (c64, cfx) = (Config::from_params(&p64), Config::from_params(&pfx));
    let opts = Options {
        transient: true,
        moments: false,
        ..Options::default()
    };
    let (mut a, mut b) = (Transient::new(0.0f64), Transient::new(Fix::ZERO));
    let (mut s64, mut sfx) = (
        SIGMA,
        Sigma {
            sigma_kappa: Fix::from_f64(SIGMA.sigma_kappa),
            sigma_alpha: Fix::from_f64(SIGMA.sigma_alpha),
        },
    );
    let (mut peak, mut worst_f, mut worst_m, mut worst_slip) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    let tau = 2.0 * core::f64::consts::PI;
    for i in 0..4000 {
        let t = i as f64 * 1e-3;
        let vx = if t < 2.0 {
            20.0 * (1.0 - t / 2.0)
        } else {
            2.5 * (t - 2.0)
        };
        let tan_a = 0.08 * (tau * 1.5 * t).sin();
        let kappa = -0.06 * (tau * 0.7 * t).sin().max(0.0);
        let k = Kinematics {
            vx,
            vsx: -kappa * vx.abs(),
            vsy: tan_a * vx.abs(),
        };
        let kf = Kinematics {
            vx: Fix::from_f64(k.vx),
            vsx: Fix::from_f64(k.vsx),
            vsy: Fix::from_f64(k.vsy),
        };
        let x = a.step::<Libm>(&c64, 1e-3, &k, &s64).unwrap();
        let y = b
            .step::<FixMath>(&cfx, Fix::from_f64(1e-3), &kf, &sfx)
            .unwrap();
        worst_slip = worst_slip
            .max((x.alpha - y.alpha.to_f64()).abs())
            .max((x.kappa - y.kappa.to_f64()).abs());
        let i64 = Input {
            fz: 4500.0,
            kappa: x.kappa,
            alpha: x.alpha,
            vx,
            ..Input::default()
        };
        let ifx = Input {
            fz: Fix::from_f64(4500.0),
            kappa: y.kappa,
            alpha: y.alpha,
            vx: kf.vx,
            ..Input::default()
        };
        let o = mf::eval::<f64, Libm>(&p64, &i64, &opts).unwrap();
        let q = mf::eval::<Fix, FixMath>(&pfx, &ifx, &opts).unwrap();
        peak = peak.max(o.fx.hypot(o.fy));
        worst_f = worst_f
            .max((o.fx - q.fx.to_f64()).abs())
            .max((o.fy - q.fy.to_f64()).abs());
        worst_m = worst_m.max((o.mz - q.mz.to_f64()).abs());
        s64 = Sigma {
            sigma_kappa: o.sigma_x,
            sigma_alpha: o.sigma_y,
        };
        sfx = Sigma {
            sigma_kappa: q.sigma_x,
            sigma_alpha: q.sigma_y,
        };
    }
    std::println!(
        "Q31.32 filter + MF vs f64 over 4 s: slips {worst_slip:.2e}, forces {worst_f:.3e} N ({:.2e} of the peak {peak:.0} N), Mz {worst_m:.3e} N m",
        worst_f / peak
    );
    assert!(peak > 3000.0, "the run reaches large forces: {peak}");
    assert!(worst_f <= 0.005 * peak, "{worst_f} N of {peak} N");
}

/// Constant inputs: the first-order hold is the held step (one sub-step, weights summing to φ1).
#[test]
fn hold_with_constant_inputs_is_the_held_step() {
    for damping in [DampingSpeed::Forward, DampingSpeed::Rolling] {
        for dt in [1e-5, 1e-3, 1e-2, 0.5] {
            let k = Kinematics {
                vx: 17.0,
                vsx: 0.9,
                vsy: -1.3,
            };
            let smp = Sample {
                kin: k,
                sigma: SIGMA,
            };
            let (mut a, mut b) = (Transient::new(0.0), Transient::new(0.0));
            for _ in 0..20 {
                let x = a.step::<Libm>(&cfg(damping), dt, &k, &SIGMA).unwrap();
                let y = b.step_hold::<Libm>(&cfg(damping), dt, &smp, &smp).unwrap();
                assert!((x.alpha - y.alpha).abs() < 1e-12, "{dt}: {x:?} {y:?}");
                assert!((x.kappa - y.kappa).abs() < 1e-12, "{dt}: {x:?} {y:?}");
            }
        }
    }
}

/// A slip speed rising linearly from 0 (σ constant): v(t) = (c/a)·(t − (1 − e^(−a·t))/a) with
/// a = Vx/σα, exactly at every sample, for 1 kHz and 100 Hz steps.
#[test]
fn hold_is_exact_for_a_ramp() {
    let (vx, c) = (12.0, 4.0); // Vsy = c·t [m/s]
    let a = vx / SIGMA.sigma_alpha;
    for dt in [1e-3, 1e-2] {
        let mut tr = Transient::new(0.0);
        let smp = |t: f64| Sample {
            kin: Kinematics {
                vx,
                vsx: 0.0,
                vsy: c * t,
            },
            sigma: SIGMA,
        };
        for i in 1..=30 {
            let (t0, t1) = ((i - 1) as f64 * dt, i as f64 * dt);
            let s = tr
                .step_hold::<Libm>(&cfg(DampingSpeed::Forward), dt, &smp(t0), &smp(t1))
                .unwrap();
            let v = c / a * (t1 - (1.0 - (-a * t1).exp()) / a);
            assert!((tr.v - v).abs() < 1e-13, "dt {dt} t {t1}: {} vs {v}", tr.v);
            assert!((s.alpha.tan() - v / SIGMA.sigma_alpha).abs() < 1e-12);
        }
    }
}

/// Fy of a `TransientTyre` at α = 4° under Fz = Fz0·(1 + amp·sin 2πft), sampled every `dt`
/// (the step's end is the sample), as (t, Fy) from t = 0 on.
fn fy_under_load(
    p: &Params<f64>,
    f: f64,
    amp: f64,
    vx: f64,
    dt: f64,
    hold: bool,
    t_end: f64,
) -> Vec<(f64, f64)> {
    let opts = Options {
        transient: true,
        ..Options::default()
    };
    let mut tyre = TransientTyre::new(p);
    tyre.config.damping = DampingSpeed::Forward;
    tyre.hold = hold;
    let tan_a = 4f64.to_radians().tan();
    let n = (t_end / dt).round() as usize;
    let mut out = Vec::with_capacity(n + 1);
    for i in 0..=n {
        let t = i as f64 * dt;
        // The held step samples the load at the step's midpoint (its best choice), the hold
        // step at its end.
        let tl = if hold || i == 0 { t } else { t - dt / 2.0 };
        let fz = p.fnomin * (1.0 + amp * (2.0 * core::f64::consts::PI * f * tl).sin());
        let op = Operating {
            kin: Kinematics {
                vx,
                vsx: 0.0,
                vsy: tan_a * vx,
            },
            fz,
            gamma: 0.0,
            phit: 0.0,
            p: None,
        };
        let (o, _) = tyre.step::<Libm>(p, &opts, dt, &op).unwrap();
        out.push((t, o.fy));
    }
    out
}

/// The paper's situation of Figs. 13–14 (Fz ±30 % at 8 Hz, α = 4°) sampled at 100 Hz and 1 kHz:
/// the first-order hold matches a 10 kHz run of the same model to a small fraction of the force
/// swing at both rates; the held step with the previous step's σ does not at 100 Hz (the error
/// this replaces). Figures print with `--nocapture`.
#[test]
fn hold_at_the_log_rate_matches_the_continuous_model_under_load_oscillation() {
    let p = tyre61();
    let (f, amp, t_end, settle) = (8.0, 0.3, 2.0, 1.0);
    for vx in [10.0, 25.0] {
        let reference = fy_under_load(&p, f, amp, vx, 1e-4, true, t_end);
        let swing = {
            let tail = reference.iter().filter(|r| r.0 >= settle);
            let (lo, hi) = tail.fold((f64::MAX, f64::MIN), |a, r| (a.0.min(r.1), a.1.max(r.1)));
            hi - lo
        };
        let err = |dt: f64, hold: bool| {
            let run = fy_under_load(&p, f, amp, vx, dt, hold, t_end);
            let every = (dt / 1e-4).round() as usize;
            let (mut s2, mut n) = (0.0, 0.0);
            for (i, r) in run.iter().enumerate() {
                if r.0 >= settle {
                    let d = r.1 - reference[i * every].1;
                    s2 += d * d;
                    n += 1.0;
                }
            }
            (s2 / n).sqrt() / swing
        };
        let (h100, h1k, o100, o1k) = (
            err(1e-2, true),
            err(1e-3, true),
            err(1e-2, false),
            err(1e-3, false),
        );
        std::println!(
            "vx {vx}: rms error / Fy swing: hold 100 Hz {h100:.2e}, 1 kHz {h1k:.2e}; held step 100 Hz {o100:.2e}, 1 kHz {o1k:.2e}"
        );
        assert!(h100 < 5e-3 && h1k < 5e-4, "hold: {h100} {h1k}");
        assert!(
            o100 > 4.0 * h100,
            "held step at 100 Hz: {o100} vs hold {h100}"
        );
    }
}

/// Fig. 14's dynamic side-force loss (mean |Fy| below the mean of the steady-state curve over the
/// load cycle, per Fy at the mean load) from a 100 Hz first-order-hold run equals the 10 kHz one.
#[test]
fn dynamic_side_force_loss_from_a_100_hz_run_is_the_continuous_one() {
    let p = tyre61();
    let (f, amp, vx, settle, t_end) = (8.0, 0.3, 10.0, 1.0, 3.0);
    let opts = Options {
        transient: true,
        ..Options::default()
    };
    let steady = |t: f64| {
        let fz = p.fnomin * (1.0 + amp * (2.0 * core::f64::consts::PI * f * t).sin());
        let inp = Input {
            fz,
            alpha: 4f64.to_radians(),
            vx,
            ..Input::default()
        };
        mf::eval::<f64, Libm>(&p, &inp, &opts).unwrap().fy.abs()
    };
    let fy_mean = mf::eval::<f64, Libm>(
        &p,
        &Input {
            fz: p.fnomin,
            alpha: 4f64.to_radians(),
            vx,
            ..Input::default()
        },
        &opts,
    )
    .unwrap()
    .fy
    .abs();
    let loss = |dt: f64, hold: bool| {
        let run = fy_under_load(&p, f, amp, vx, dt, hold, t_end);
        let (mut d, mut q, mut n) = (0.0, 0.0, 0.0);
        for r in run.iter().filter(|r| r.0 >= settle && r.0 < t_end - 1e-9) {
            d += r.1.abs();
            q += steady(r.0);
            n += 1.0;
        }
        (q - d) / n / fy_mean
    };
    let (cont, l100, old100) = (loss(1e-4, true), loss(1e-2, true), loss(1e-2, false));
    std::println!("Fig. 14 loss at 8 Hz ±30 %, 10 m/s: continuous {cont:.4}, hold 100 Hz {l100:.4}, held step 100 Hz {old100:.4}");
    assert!(cont > 0.005, "a loss to measure: {cont}");
    assert!((l100 - cont).abs() < 0.05 * cont, "{l100} vs {cont}");
}

/// The steady state of constant slips is a fixed point of the step (both damping speeds at
/// zero longitudinal slip, the forward one under braking too), σ floored as the step floors
/// it: a σ below `sigma_min` gives the deflections of `sigma_min`.
#[test]
fn the_steady_state_is_a_fixed_point_of_the_step() {
    let vx = 15.0;
    for (damping, tan_a, kappa) in [
        (DampingSpeed::Forward, 0.04, -0.06),
        (DampingSpeed::Rolling, -0.07, 0.0),
    ] {
        let c = cfg(damping);
        let k = Kinematics {
            vx,
            vsx: -kappa * vx,
            vsy: tan_a * vx,
        };
        let mut tr = Transient::steady(&c, &SIGMA, kappa, tan_a);
        assert_eq!(
            (tr.v, tr.u),
            (SIGMA.sigma_alpha * tan_a, SIGMA.sigma_kappa * kappa)
        );
        let s = tr.step::<Libm>(&c, 1e-3, &k, &SIGMA).unwrap();
        assert!((s.alpha.tan() - tan_a).abs() < 1e-12 && (s.kappa - kappa).abs() < 1e-12);
    }
    let c = cfg(DampingSpeed::Forward);
    let tiny = Sigma {
        sigma_kappa: 0.0,
        sigma_alpha: 1e-4,
    };
    let tr = Transient::steady(&c, &tiny, 0.1, 0.2);
    assert_eq!((tr.v, tr.u), (0.01 * 0.2, 0.01 * 0.1));
    // Clamped as the step clamps: |tan α'| ≤ 1.
    let tr = Transient::steady(&c, &SIGMA, 0.0, 3.0);
    assert_eq!(tr.v, SIGMA.sigma_alpha);
}

/// `TransientTyre::start` answers with the steady-state Magic Formula at the given slips and
/// leaves the tyre in that steady state: a step with the same inputs gives the same forces.
#[test]
fn a_started_tyre_stays_in_the_steady_state_of_its_slips() {
    let p = tyre61();
    let (vx, a, k) = (20.0, 0.05f64, -0.03f64);
    let op = Operating {
        kin: Kinematics {
            vx,
            vsx: -k * vx,
            vsy: a.tan() * vx,
        },
        fz: 5000.0,
        gamma: 0.02,
        ..Operating::default()
    };
    let steady = Options {
        moments: false,
        ..Options::default()
    };
    let transient = Options {
        transient: true,
        ..steady
    };
    let mut tyre = TransientTyre::new(&p);
    tyre.config.damping = DampingSpeed::Forward;
    assert!(tyre.sigma().is_none());
    let o = tyre.start::<Libm>(&p, &steady, &op, k, a).unwrap();
    let input = Input {
        fz: 5000.0,
        kappa: k,
        alpha: a,
        gamma: 0.02,
        vx,
        ..Input::default()
    };
    assert_eq!(o, mf::eval::<f64, Libm>(&p, &input, &steady).unwrap());
    assert_eq!(
        tyre.sigma(),
        Some(Sigma {
            sigma_kappa: o.sigma_x,
            sigma_alpha: o.sigma_y
        })
    );
    for _ in 0..100 {
        let (f, s) = tyre.step::<Libm>(&p, &transient, 1e-3, &op).unwrap();
        assert!((s.alpha - a).abs() < 1e-12 && (s.kappa - k).abs() < 1e-12);
        assert!((f.fy - o.fy).abs() < 1e-9 * p.fnomin && (f.fx - o.fx).abs() < 1e-9 * p.fnomin);
    }
    // A start the Magic Formula refuses changes nothing.
    let before = (tyre.state, tyre.sigma());
    let bad = Operating { fz: f64::NAN, ..op };
    assert!(tyre.start::<Libm>(&p, &steady, &bad, k, a).is_err());
    assert_eq!((tyre.state, tyre.sigma()), before);
}

/// `TransientTyre::step_between` is the first-order hold with the caller's σ, then the Magic
/// Formula at its slips (turn slip and pressure of the operating point included), to the bit.
#[test]
fn step_between_is_the_hold_then_the_magic_formula() {
    let p = tyre61();
    let opts = Options {
        transient: true,
        ..Options::default()
    };
    let kin = |a: f64| Kinematics {
        vx: 10.0,
        vsx: 0.1,
        vsy: a.tan() * 10.0,
    };
    let s0 = Sample {
        kin: kin(0.01),
        sigma: SIGMA,
    };
    let s1 = Sample {
        kin: kin(0.03),
        sigma: Sigma {
            sigma_kappa: 0.2,
            sigma_alpha: 0.5,
        },
    };
    let op = Operating {
        kin: s1.kin,
        fz: 4500.0,
        gamma: -0.01,
        phit: 0.0,
        p: Some(2.0e5),
    };
    let mut tyre = TransientTyre::new(&p);
    tyre.restart(SIGMA, -0.01, 0.01f64.tan());
    let mut by_hand = tyre.state;
    let (o, s) = tyre
        .step_between::<Libm>(&p, &opts, 0.01, &s0, &s1, &op)
        .unwrap();
    let sh = by_hand
        .step_hold::<Libm>(&tyre.config, 0.01, &s0, &s1)
        .unwrap();
    assert_eq!(s, sh);
    assert_eq!(tyre.state, by_hand);
    let input = Input {
        fz: 4500.0,
        kappa: sh.kappa,
        alpha: sh.alpha,
        gamma: -0.01,
        phit: 0.0,
        vx: 10.0,
        p: Some(2.0e5),
    };
    assert_eq!(o, mf::eval::<f64, Libm>(&p, &input, &opts).unwrap());
}
