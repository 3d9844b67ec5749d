//! The withheld-effect benchmark: "real" logs from a truth model with one effect, a pair of
//! effects or none switched on, diagnosed from SIM.tir and the log alone, and scored. Every
//! case's SIM.tir (and the truth's base) lacks 2–3 blocks of coefficients ([`decoys`]), never
//! the block of the case's own effect, so that the file alone never names the effect.
//!
//! ## The generator ([`generate`])
//! A test-trailer programme: every input a smooth random multisine (seeded, reproducible) —
//! α (±0.2 rad, content to 4 Hz), κ (±0.25), Fz (0.2–1.9 Fz0, with 1–6 Hz content), Vx
//! (4–35 m/s), γ (within CAMMAX), p (±8 % about NOMPRES, or 2.2 bar for MF 5.x files, which
//! ignore it), φt (±0.1 1/m); `p` and `phit` can be left out of the log (then INFLPRES, φt = 0). The truth model is the sim of the tyre file with one effect on
//! ([`truth`]); its outputs get white noise of `noise` × each clean channel's RMS.
//!
//! The truth forms deliberately differ from the diagnosis's extensions where physics allows
//! (the diagnosis must find the effect, not recognise its own formula): the camber truth also
//! changes the load dependence PKY7/PVY4, which the extension does not fit; the pressure truth
//! also changes PPY2 (MF 6.x) or grows the stiffness with dpi² (MF 5.x, about the log's median
//! pressure, the only reference such a file allows); combined slip also RBX2 and RCY1; the relaxation truth scales σα with
//! (Fz/Fz0)^(0.4·m), the extension with (1 + c·dfz); the friction truth decays as
//! 1 − d·(1 − e^(−Vs/2 m/s)) (a saturating Stribeck form), the extension as 1/(1 + a·Vs/V0);
//! the thermal truth has two temperature nodes (tread surface and carcass, [`thermal_truth`]),
//! a Gaussian grip law of their mix around an optimum and an exponential softening of both slip
//! stiffnesses with the carcass, driven by the sim's slip power from a cold start, against the
//! extension's one node, quadratic grip law, linear softening and the measured slip power; the bias truth drifts by 20 % over the log; the turn-slip
//! truth of an MF 5.x tyre grows with √(Fz/Fz0).
//!
//! ## Scoring ([`run`], [`targets`])
//! The diagnosis's targets per tyre (docs/gap.md): named right (exactly the true effects named) at m ≥ 0.3, false
//! alarms on none logs, held-out shrink achieved / achievable at m ≥ 0.3, pairs with both
//! named at m = 1.
//! Confusion matrix over effects (the verdict's top effect against the truth), with the cases
//! where the truth was reported indistinguishable from the verdict counted apart; the none-case
//! false-alarm rate; per effect and magnitude, the detection rate; and the shrink achieved (the
//! true effect's held-out shrink) against the shrink achievable (the noise-free truth against
//! the log: 1 − Σc noise_c/σc / Σc rmse_before_c/σc in the shrink's own units).

use super::effects::{Effect, ALL};
use super::log::Log;
use super::sim::{lag, Lambda, Mods, Out, SigmaMode, Sim};
use super::stats;
use crate::rng::Rng;
use gough::mf::{Key, Params};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// What to generate.
#[derive(Debug, Clone, PartialEq)]
pub struct GenConfig {
    /// Rows.
    pub rows: usize,
    /// Sample rate \[Hz\].
    pub rate: f64,
    /// Seed of the input programme and the noise.
    pub seed: u64,
    /// The effect switched on (`None`: the truth is the sim).
    pub truth: Option<Effect>,
    /// A second effect switched on at the same magnitude (a pair; `None`: one effect).
    pub truth2: Option<Effect>,
    /// Its magnitude (1 = large, clearly visible; 0.03 is at the edge of detectability).
    pub magnitude: f64,
    /// White noise, as a fraction of each clean channel's RMS.
    pub noise: f64,
    /// Add a reference `mu` column (the file's μy0: the truth runs on the file's own surface).
    pub mu: bool,
    /// Log (and vary) the inflation pressure; without, the log has no `p` column (INFLPRES).
    pub p: bool,
    /// Log (and vary) the turn slip; without, the log has no `phit` column (φt = 0).
    pub phit: bool,
    /// Load oscillation bursts (the situation of the paper's Figs. 13–14): in the second half
    /// of every 5 s, Fz × (1 + 0.3·w·sin 2πft) with w a sin² window and f = 2, 4, 8 Hz in turn.
    pub load_oscillation: bool,
    /// How the log samples the truth ([`Sampling`]).
    pub sampling: Sampling,
}

/// How a generated log samples the truth: as a logger does, or (the default) the truth run at
/// the log's own rows.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Sampling {
    /// Rate \[Hz\] at which the truth runs between the log's rows (each step between two rows
    /// cut into equal sub-steps no longer than 1/`truth_rate`); the log takes the truth at its
    /// rows: the continuous model as a logger samples it. `None`: the truth runs at the rows.
    pub truth_rate: Option<f64>,
    /// Timestamp jitter: each row's time lies off its nominal i/rate by a uniform draw within
    /// ± this fraction of the step (below 0.5, so that time still increases).
    pub jitter: f64,
    /// Fraction of the rows dropped at random (the truth runs on through them).
    pub drop: f64,
}

impl Sampling {
    /// Whether anything differs from the truth at the log's own rows.
    pub fn is_default(&self) -> bool {
        self.truth_rate.is_none() && self.jitter == 0.0 && self.drop == 0.0
    }

    /// Checks the values: a positive finite truth rate, jitter in [0, 0.5), drop in [0, 0.5].
    /// Each error names the value as the CLI's flag does, without its dashes (`truth-rate`,
    /// `jitter`, `drop`).
    pub fn check(&self) -> Result<(), String> {
        if let Some(r) = self.truth_rate.filter(|r| !(r.is_finite() && *r > 0.0)) {
            return Err(format!("truth-rate {r}: must be > 0 Hz"));
        }
        if !(0.0..0.5).contains(&self.jitter) {
            return Err(format!("jitter {}: expected 0 ≤ jitter < 0.5", self.jitter));
        }
        if !(0.0..=0.5).contains(&self.drop) {
            return Err(format!("drop {}: expected 0 ≤ drop ≤ 0.5", self.drop));
        }
        Ok(())
    }
}

impl Default for GenConfig {
    fn default() -> Self {
        GenConfig {
            rows: 6000,
            rate: 200.0,
            seed: 1,
            truth: None,
            truth2: None,
            magnitude: 1.0,
            noise: 0.01,
            mu: false,
            p: true,
            phit: true,
            load_oscillation: false,
            sampling: Sampling::default(),
        }
    }
}

/// A generated log and its noise-free truth.
#[derive(Debug, Clone)]
pub struct Generated {
    /// The log (inputs, noisy outputs).
    pub log: Log,
    /// The truth's outputs before noise.
    pub clean: Vec<Out>,
}

/// A unit-RMS sum of `n` sines with log-uniform frequencies in [f_lo, f_hi] Hz.
fn multisine(rng: &mut Rng, t: &[f64], f_lo: f64, f_hi: f64, n: usize) -> Vec<f64> {
    let comps: Vec<(f64, f64)> = (0..n)
        .map(|_| {
            let f = (f_lo.ln() + rng.uniform() * (f_hi.ln() - f_lo.ln())).exp();
            (
                2.0 * std::f64::consts::PI * f,
                rng.range(0.0, 2.0 * std::f64::consts::PI),
            )
        })
        .collect();
    let a = (2.0 / n as f64).sqrt();
    t.iter()
        .map(|&t| comps.iter().map(|&(w, ph)| a * (w * t + ph).sin()).sum())
        .collect()
}

/// The input programme at the log's nominal rows (i/rate): a log with inputs and zero outputs.
pub fn inputs(p: &Params<f64>, cfg: &GenConfig) -> Log {
    inputs_at(p, cfg, (0..cfg.rows).map(|i| i as f64 / cfg.rate).collect())
}

/// The input programme at times `t` (the same programme whatever the times: its multisines are
/// drawn from the seed alone).
pub fn inputs_at(p: &Params<f64>, cfg: &GenConfig, t: Vec<f64>) -> Log {
    let mut rng = Rng::new(cfg.seed);
    let n = t.len();
    let mut ms = |lo, hi, k| multisine(&mut rng, &t, lo, hi, k);
    let (a1, a2) = (ms(0.05, 0.5, 4), ms(0.5, 4.0, 4));
    let alpha = (0..n)
        .map(|i| (0.06 * a1[i] + 0.025 * a2[i]).clamp(-0.2, 0.2))
        .collect();
    let (k1, k2) = (ms(0.05, 0.5, 4), ms(0.5, 4.0, 4));
    let kappa = (0..n)
        .map(|i| (0.04 * k1[i] + 0.015 * k2[i]).clamp(-0.25, 0.25))
        .collect();
    let (f1, f2) = (ms(0.03, 0.3, 3), ms(1.0, 6.0, 3));
    let fzmax = if p.fzmax > 0.0 {
        p.fzmax
    } else {
        3.0 * p.fnomin
    };
    let osc = |t: f64| {
        if !cfg.load_oscillation {
            return 1.0;
        }
        let seg = (t / 5.0).floor();
        let ts = t - 5.0 * seg;
        if ts < 2.5 {
            return 1.0;
        }
        let f = [2.0, 4.0, 8.0][(seg as usize) % 3];
        let w = (std::f64::consts::PI * (ts - 2.5) / 2.5).sin().powi(2);
        1.0 + 0.3 * w * (std::f64::consts::TAU * f * t).sin()
    };
    let fz = (0..n)
        .map(|i| {
            (p.fnomin * (1.0 + 0.25 * f1[i] + 0.08 * f2[i]) * osc(t[i]))
                .clamp(0.2 * p.fnomin, (1.9 * p.fnomin).min(0.95 * fzmax))
        })
        .collect();
    let v1 = ms(0.01, 0.1, 3);
    let vx = v1
        .iter()
        .map(|v| (16.0 + 6.0 * v).clamp(4.0, 35.0))
        .collect();
    let g1 = ms(0.02, 0.3, 3);
    let gmax = if p.cammax > 0.0 { 0.9 * p.cammax } else { 0.1 };
    let gamma = g1.iter().map(|g| (0.03 * g).clamp(-gmax, gmax)).collect();
    let p1 = ms(0.01, 0.1, 2);
    let p_nom = if p.version.is_mf6() { p.nompres } else { 2.2e5 };
    let (plo, phi) = if p.version.is_mf6() && p.presmax > p.presmin {
        (p.presmin, p.presmax)
    } else {
        (0.5 * p_nom, 2.0 * p_nom)
    };
    let pr = p1
        .iter()
        .map(|v| (p_nom * (1.0 + 0.08 * v)).clamp(plo, phi))
        .collect();
    let ph = ms(0.02, 0.5, 3);
    let phit = ph.iter().map(|v| 0.05 * v).collect();
    Log {
        t,
        vx,
        alpha,
        kappa,
        gamma,
        fz,
        meas: vec![[0.0; 3]; n],
        p: cfg.p.then_some(pr),
        phit: cfg.phit.then_some(phit),
        mu: None,
        lines: vec![],
    }
}

fn bump(q: &mut Params<f64>, key: &str, f: impl Fn(f64) -> f64) {
    if let Some(k) = Key::from_name(key) {
        let v = q.get(k);
        q.set(k, f(v));
    }
}

/// The thermal truth's constants (module doc): a tread surface node and a carcass node, K above
/// ambient, heated by the slip power relative to the log's mean (a tyre run at its usual power
/// settles near its optimum), the surface cooled by convection growing with speed.
pub mod thermal {
    /// Surface and carcass time constants \[s\].
    pub const TAU_SURFACE: f64 = 2.5;
    /// See [`TAU_SURFACE`].
    pub const TAU_CARCASS: f64 = 20.0;
    /// Surface heating at the log's mean slip power \[K\] (per unit of the cooling rate).
    pub const GAIN: f64 = 50.0;
    /// Surface–carcass conduction and carcass cooling, per unit of the surface's convection at
    /// V0.
    pub const CONDUCTION: f64 = 0.5;
    /// See [`CONDUCTION`].
    pub const CARCASS_COOLING: f64 = 0.3;
    /// Grip's optimum temperature and width \[K\], and its largest loss (× m).
    pub const OPTIMUM: f64 = 40.0;
    /// See [`OPTIMUM`].
    pub const WIDTH: f64 = 35.0;
    /// See [`OPTIMUM`].
    pub const GRIP_LOSS: f64 = 0.25;
    /// Carcass softening of the slip stiffnesses \[1/K\] (× m).
    pub const SOFTENING: f64 = 0.004;
}

/// The thermal truth per row (module doc): two nodes, Ts (surface) and Tc (carcass), from
/// ambient (a cold start): τs·dTs/dt = G·u/ū − hs(V)·Ts − c·(Ts − Tc), τc·dTc/dt = c·(Ts − Tc) −
/// hc·Tc, with u the slip power |Fx·Vsx| + |Fy·Vsy| of the sim's forces `out` over Fz0·V0, ū
/// its mean over the log, hs(V) = 0.4 + 0.6·(|Vx|/V0)^0.8 (convection); grip around an
/// optimum, a Gaussian (exponential) law of the grip temperature 0.75·Ts + 0.25·Tc:
/// λμ = 1 − 0.25·m·(1 − exp(−((T − 40)/35)²)); the slip stiffnesses softening exponentially
/// with the carcass: λK = exp(−0.004·m·Tc). Integrated in sub-steps of at most 10 ms, the
/// inputs linear between rows.
pub fn thermal_truth(p: &Params<f64>, log: &Log, out: &[Out], m: f64) -> Vec<Lambda> {
    use thermal::*;
    let v0 = p.longvl.abs().max(1.0);
    let n = log.len();
    let u: Vec<f64> = (0..n)
        .map(|i| {
            let (vsx, vsy) = log.slip_velocity(i);
            ((out[i][0] * vsx).abs() + (out[i][1] * vsy).abs()) / (p.fnomin * v0)
        })
        .collect();
    let ubar = stats::mean(&u).max(1e-12);
    let (mut ts, mut tc) = (0.0f64, 0.0f64);
    let lam = |ts: f64, tc: f64| {
        let tg = 0.75 * ts + 0.25 * tc;
        let d = (tg - OPTIMUM) / WIDTH;
        Lambda {
            kx: (-SOFTENING * m * tc).exp(),
            ky: (-SOFTENING * m * tc).exp(),
            ..Lambda::mu((1.0 - GRIP_LOSS * m * (1.0 - (-d * d).exp())).max(0.05))
        }
    };
    let mut res = Vec::with_capacity(n);
    res.push(lam(ts, tc));
    for i in 1..n {
        let dt = (log.t[i] - log.t[i - 1]).max(0.0);
        let k = (dt / 0.01).ceil().max(1.0) as usize;
        let h = dt / k as f64;
        for j in 0..k {
            let w = (j as f64 + 0.5) / k as f64;
            let ui = u[i - 1] + w * (u[i] - u[i - 1]);
            let vi = log.vx[i - 1].abs() + w * (log.vx[i].abs() - log.vx[i - 1].abs());
            let hs = 0.4 + 0.6 * (vi / v0).powf(0.8);
            let dts = (GAIN * ui / ubar - hs * ts - CONDUCTION * (ts - tc)) / TAU_SURFACE;
            let dtc = (CONDUCTION * (ts - tc) - CARCASS_COOLING * tc) / TAU_CARCASS;
            ts += h * dts;
            tc += h * dtc;
        }
        res.push(lam(ts, tc));
    }
    res
}

/// The coefficient part of the truth `effects` at `m` (module doc): SIM.tir's parameters
/// with the changes of the effects that are coefficient changes (camber, MF 6.x pressure,
/// turn slip where the sim evaluates it, combined slip, conicity/ply-steer); the others are
/// applied by [`truth`] along the run. `turn_slip`: the sim evaluates turn slip.
pub fn truth_params(p: &Params<f64>, effects: &[Effect], m: f64, turn_slip: bool) -> Params<f64> {
    let mut q = p.clone();
    for &effect in effects {
        match effect {
            Effect::Camber => {
                if p.version.is_mf6() {
                    bump(&mut q, "PKY6", |v| v * (1.0 + 0.6 * m));
                    bump(&mut q, "PKY7", |v| v + 0.3 * m);
                    bump(&mut q, "PVY3", |v| v + 0.3 * m * v.abs().max(0.1));
                    bump(&mut q, "QDZ8", |v| v + 0.5 * m * v.abs().max(0.1));
                } else {
                    bump(&mut q, "PVY3", |v| v * (1.0 + 0.6 * m));
                    bump(&mut q, "PVY4", |v| v + 0.3 * m * v.abs().max(0.1));
                    bump(&mut q, "PHY3", |v| v + 0.05 * m);
                    bump(&mut q, "QDZ8", |v| v + 0.5 * m * v.abs().max(0.1));
                }
            }
            Effect::InflationPressure if p.version.is_mf6() => {
                bump(&mut q, "PPY1", |v| v + 0.8 * m);
                bump(&mut q, "PPY2", |v| v + 0.5 * m);
                bump(&mut q, "PPY3", |v| v + 0.3 * m);
                bump(&mut q, "PPX3", |v| v + 0.3 * m);
                bump(&mut q, "PPZ1", |v| v + 0.5 * m);
            }
            Effect::TurnSlip if turn_slip => {
                bump(&mut q, "PKYP1", |v| v * (1.0 + 3.0 * m));
                bump(&mut q, "PDYP1", |v| v * (1.0 + 1.0 * m));
                bump(&mut q, "QDTP1", |v| v * (1.0 + 1.0 * m));
                bump(&mut q, "QCRP1", |v| v * (1.0 + 1.0 * m));
                bump(&mut q, "QDRP1", |v| v * (1.0 + 1.0 * m));
            }
            Effect::CombinedSlip => {
                bump(&mut q, "RBX1", |v| v * (1.0 - 0.35 * m));
                bump(&mut q, "RBY1", |v| v * (1.0 - 0.35 * m));
                bump(&mut q, "RBX2", |v| v * (1.0 + 0.3 * m));
                bump(&mut q, "RCY1", |v| v * (1.0 + 0.05 * m));
                bump(&mut q, "SSZ1", |v| v + 0.03 * m);
            }
            Effect::ConicityPlysteer => {
                bump(&mut q, "PHY1", |v| v + 0.004 * m);
                bump(&mut q, "PVY1", |v| v + 0.02 * m);
                bump(&mut q, "QHZ1", |v| v + 0.004 * m);
            }
            _ => {}
        }
    }
    q
}

/// The truth of `effects` at `m` as a tyre file: SIM.tir's `text` with [`truth_params`]'s
/// changes written in (`gough gap generate --truth-tir`: the car's tyre of docs/gap.md's loop
/// with the estimator). An error for an effect that is not a coefficient change (the sim of
/// `log` decides whether turn slip is one).
pub fn truth_tir(
    text: &str,
    p: &Params<f64>,
    log: &Log,
    effects: &[Effect],
    m: f64,
) -> Result<String, String> {
    let turn_slip = Sim::new(p.clone(), log).turn_slip;
    for &e in effects {
        let coefficients = match e {
            Effect::Camber | Effect::CombinedSlip | Effect::ConicityPlysteer => true,
            Effect::InflationPressure => p.version.is_mf6(),
            Effect::TurnSlip => turn_slip,
            _ => false,
        };
        if !coefficients {
            return Err(format!(
                "{}: the truth is not a change of the file's coefficients here; no tyre file",
                e.name()
            ));
        }
    }
    let q = truth_params(p, effects, m, turn_slip);
    let mut out = text.to_string();
    for &k in Key::ALL {
        if q.get(k) != p.get(k) {
            out = crate::tyre::set_or_add_in_tir(
                &out,
                k,
                q.get(k),
                "gough gap generate --truth-tir",
            )?;
        }
    }
    Ok(out)
}

/// The truth's outputs (before noise) for the log's inputs: SIM.tir's sim with `effects` on at
/// `m` (module doc; none: the sim itself). Several effects compose: their coefficient changes
/// together, their λ multipliers multiplied, additions summed, then lag, then bias.
pub fn truth(
    p: &Params<f64>,
    log: &Log,
    effects: &[Effect],
    m: f64,
    seed: u64,
) -> Result<Vec<Out>, String> {
    let n = log.len();
    let mut lambda: Option<Vec<Lambda>> = None;
    let mut add: Option<Vec<Out>> = None;
    let lambda_of = |l: Vec<Lambda>, lambda: &mut Option<Vec<Lambda>>| {
        *lambda = Some(match lambda.take() {
            None => l,
            Some(old) => old
                .iter()
                .zip(&l)
                .map(|(a, b)| Lambda {
                    mux: a.mux * b.mux,
                    muy: a.muy * b.muy,
                    kx: a.kx * b.kx,
                    ky: a.ky * b.ky,
                })
                .collect(),
        });
    };
    let mut sigma: Option<Vec<[f64; 2]>> = None;
    let mut lags = [0.0; 3];
    let mut bias = [0.0; 3];
    let probe = Sim::new(p.clone(), log);
    let err = |(i, e): (usize, String)| format!("truth model, row {i}: {e}");
    let base = probe.run(log, p, &Mods::default()).map_err(err)?;
    let rms_c = |c: usize| stats::rms(base.out.iter().map(|o| o[c]));
    let q = truth_params(p, effects, m, probe.turn_slip);
    for &effect in effects {
        match effect {
            Effect::Camber | Effect::CombinedSlip | Effect::ConicityPlysteer => {}
            Effect::InflationPressure => {
                if !p.version.is_mf6() {
                    // MF 5.x files carry no nominal pressure: the tyre is taken as measured at the
                    // log's median pressure (as the extension assumes), with a stiffness that also
                    // grows with dpi² (which the extension does not fit).
                    let pr = log.p.as_ref().ok_or("pressure truth needs a p column")?;
                    let p_ref = stats::median(pr);
                    lambda_of(
                        pr.iter()
                            .map(|&x| {
                                let d = (x - p_ref) / p_ref;
                                Lambda {
                                    kx: 1.0 + m * d + 2.0 * m * d * d,
                                    ky: 1.0 + m * d + 2.0 * m * d * d,
                                    mux: 1.0 - 0.6 * m * d,
                                    muy: 1.0 - 0.6 * m * d,
                                }
                            })
                            .collect(),
                        &mut lambda,
                    );
                }
            }
            Effect::TurnSlip => {
                if !probe.turn_slip {
                    let r0 = p.unloaded_radius;
                    let a: Vec<Out> = (0..n)
                        .map(|i| {
                            let fzn = (log.fz[i] / p.fnomin).max(0.0);
                            let k = 2.0 * m * log.fz[i].max(0.0) * r0 * log.phit_at(i) * fzn.sqrt();
                            [0.0, k, 0.5 * k * r0]
                        })
                        .collect();
                    add = Some(match add.take() {
                        None => a,
                        Some(old) => old
                            .iter()
                            .zip(&a)
                            .map(|(x, y)| [x[0] + y[0], x[1] + y[1], x[2] + y[2]])
                            .collect(),
                    });
                }
            }
            Effect::RelaxationLength => {
                sigma = Some(
                    (0..n)
                        .map(|i| {
                            let fzn = (log.fz[i] / p.fnomin).max(0.05);
                            [1.0 + 0.3 * m, (1.0 + 0.5 * m) * fzn.powf(0.4 * m)]
                        })
                        .collect(),
                );
            }
            Effect::SpeedDependentFriction => {
                lambda_of(
                    (0..n)
                        .map(|i| {
                            Lambda::mu(1.0 - 0.3 * m * (1.0 - (-log.slip_speed(i) / 2.0).exp()))
                        })
                        .collect(),
                    &mut lambda,
                );
            }
            Effect::Thermal => lambda_of(thermal_truth(p, log, &base.out, m), &mut lambda),
            Effect::SensorLag => lags = [0.008 * m, 0.015 * m, 0.025 * m],
            Effect::SensorBias => {
                let mut rng = Rng::new(seed ^ 0xB1A5);
                for (c, b) in bias.iter_mut().enumerate() {
                    let s = if rng.uniform() < 0.5 { -1.0 } else { 1.0 };
                    *b = s * 0.05 * m * rms_c(c);
                }
            }
        }
    }
    let sim = Sim::new(q.clone(), log);
    let mods = Mods {
        lambda: lambda.as_deref(),
        add: add.as_deref(),
        sigma: match &sigma {
            Some(s) => SigmaMode::Scaled(s),
            None => SigmaMode::Model,
        },
    };
    let mut out = sim.run(log, &q, &mods).map_err(err)?.out;
    for (c, &tau) in lags.iter().enumerate() {
        if tau > 0.0 {
            let u: Vec<f64> = out.iter().map(|o| o[c]).collect();
            for (o, y) in out.iter_mut().zip(lag(&u, &log.t, tau)) {
                o[c] = y;
            }
        }
    }
    if bias != [0.0; 3] {
        let t_end = log.t.last().copied().unwrap_or(1.0).max(1e-9);
        for (o, &t) in out.iter_mut().zip(&log.t) {
            for c in 0..3 {
                o[c] += bias[c] * (1.0 + 0.2 * t / t_end);
            }
        }
    }
    Ok(out)
}

/// A block of coefficients a sim file can lack (all of them zero). The bench takes 2–3 of them
/// out of every case's file ([`decoys`]), never the block of the case's own effect, so that
/// "which block is missing" never names the effect.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Block {
    /// Combined-slip weights and the κ-induced side force (R*).
    CombinedSlip,
    /// Turn slip (P*P*, Q*P*).
    TurnSlip,
    /// Inflation pressure (PP*).
    Pressure,
    /// Camber terms of Fx, Fy, Mz.
    Camber,
    /// Zero-slip offsets of Fy and the trail (conicity, ply steer).
    Conicity,
}

impl Block {
    /// Every block.
    pub const ALL: [Block; 5] = [
        Block::CombinedSlip,
        Block::TurnSlip,
        Block::Pressure,
        Block::Camber,
        Block::Conicity,
    ];

    /// Name (the effect's).
    pub const fn name(self) -> &'static str {
        match self {
            Block::CombinedSlip => "combined_slip",
            Block::TurnSlip => "turn_slip",
            Block::Pressure => "inflation_pressure",
            Block::Camber => "camber",
            Block::Conicity => "conicity_plysteer",
        }
    }

    /// The `.tir` keys of the block (those a file does not carry are skipped).
    pub const fn keys(self) -> &'static [&'static str] {
        match self {
            Block::CombinedSlip => &[
                "RBX1", "RBX2", "RBX3", "RCX1", "REX1", "REX2", "RHX1", "RBY1", "RBY2", "RBY3",
                "RBY4", "RCY1", "REY1", "REY2", "RHY1", "RHY2", "RVY1", "RVY2", "RVY3", "RVY4",
                "RVY5", "RVY6",
            ],
            Block::TurnSlip => &[
                "PDXP1", "PDXP2", "PDXP3", "PKYP1", "PDYP1", "PDYP2", "PDYP3", "PDYP4", "PHYP1",
                "PHYP2", "PHYP3", "PHYP4", "PECP1", "PECP2", "QDTP1", "QCRP1", "QCRP2", "QBRP1",
                "QDRP1", "QDRP2",
            ],
            Block::Pressure => &[
                "PPX1", "PPX2", "PPX3", "PPX4", "PPY1", "PPY2", "PPY3", "PPY4", "PPY5", "PPZ1",
                "PPZ2",
            ],
            Block::Camber => &[
                "PDX3", "PDY3", "PKY3", "PKY6", "PKY7", "PVY3", "PVY4", "PHY3", "PEY5", "QBZ4",
                "QBZ5", "QDZ3", "QDZ4", "QDZ8", "QDZ9", "QDZ10", "QDZ11", "QHZ3", "QHZ4",
            ],
            Block::Conicity => &["PHY1", "PHY2", "PVY1", "PVY2", "QHZ1", "QHZ2"],
        }
    }

    /// The block an effect re-fits, if it has one.
    pub const fn of(e: Effect) -> Option<Block> {
        match e {
            Effect::CombinedSlip => Some(Block::CombinedSlip),
            Effect::TurnSlip => Some(Block::TurnSlip),
            Effect::InflationPressure => Some(Block::Pressure),
            Effect::Camber => Some(Block::Camber),
            Effect::ConicityPlysteer => Some(Block::Conicity),
            _ => None,
        }
    }
}

/// `p` without `blocks` (their coefficients set to zero).
pub fn without(p: &Params<f64>, blocks: &[Block]) -> Params<f64> {
    let mut q = p.clone();
    for b in blocks {
        for k in b.keys() {
            if let Some(k) = Key::from_name(k) {
                q.set(k, 0.0);
            }
        }
    }
    q
}

/// 2 or 3 decoy blocks (seeded), none of them the block of one of `effects`.
pub fn decoys(effects: &[Effect], seed: u64) -> Vec<Block> {
    let mut rng = Rng::new(seed ^ 0xDEC0_1234);
    let mut cand: Vec<Block> = Block::ALL
        .iter()
        .copied()
        .filter(|b| !effects.iter().any(|&e| Block::of(e) == Some(*b)))
        .collect();
    // Fisher–Yates.
    for i in (1..cand.len()).rev() {
        let j = ((rng.uniform() * (i + 1) as f64) as usize).min(i);
        cand.swap(i, j);
    }
    let k = if rng.uniform() < 0.5 { 2 } else { 3 };
    cand.truncate(k);
    cand
}

/// The fine time grid of a sampled log and the indices of the log's rows in it: the row times
/// (i + jitter·u)/rate, u uniform in [−1, 1], each kept with probability 1 − drop (the first
/// always), and between two kept rows equal sub-steps no longer than 1/truth_rate.
pub fn sampled(cfg: &GenConfig) -> (Vec<f64>, Vec<usize>) {
    let s = cfg.sampling;
    let mut rng = Rng::new(cfg.seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ 0x0071_AE55);
    let mut rows_t = Vec::with_capacity(cfg.rows);
    for i in 0..cfg.rows {
        let t = (i as f64 + s.jitter * rng.range(-1.0, 1.0)) / cfg.rate;
        let keep = rng.uniform() >= s.drop;
        if i == 0 || keep {
            rows_t.push(t);
        }
    }
    let fine = s.truth_rate.unwrap_or(cfg.rate);
    let mut t = Vec::with_capacity(rows_t.len());
    let mut rows = Vec::with_capacity(rows_t.len());
    for (k, &tk) in rows_t.iter().enumerate() {
        if k > 0 {
            let t0 = rows_t[k - 1];
            let m = ((tk - t0) * fine).ceil().max(1.0) as usize;
            for j in 1..m {
                t.push(t0 + (tk - t0) * j as f64 / m as f64);
            }
        }
        rows.push(t.len());
        t.push(tk);
    }
    (t, rows)
}

/// Generates a log: inputs, the truth's outputs, noise. With a [`Sampling`] other than the
/// default, the truth runs on a fine grid through the log's (jittered, thinned) row times and
/// the log takes it at those rows ([`sampled`]).
pub fn generate(p: &Params<f64>, cfg: &GenConfig) -> Result<Generated, String> {
    let effects: Vec<Effect> = cfg.truth.into_iter().chain(cfg.truth2).collect();
    let (mut log, clean) = if cfg.sampling.is_default() {
        let log = inputs(p, cfg);
        let clean = truth(p, &log, &effects, cfg.magnitude, cfg.seed)?;
        (log, clean)
    } else {
        cfg.sampling.check()?;
        let (t, rows) = sampled(cfg);
        let fine = inputs_at(p, cfg, t);
        let clean = truth(p, &fine, &effects, cfg.magnitude, cfg.seed)?;
        (fine.select(&rows), rows.iter().map(|&i| clean[i]).collect())
    };
    let mut rng = Rng::new(cfg.seed.wrapping_mul(0x2545_F491_4F6C_DD1D) ^ 0x5EED);
    let sd: Vec<f64> = (0..3)
        .map(|c| cfg.noise * stats::rms(clean.iter().map(|o| o[c])))
        .collect();
    log.meas = clean
        .iter()
        .map(|o| {
            [
                o[0] + sd[0] * rng.normal(),
                o[1] + sd[1] * rng.normal(),
                o[2] + sd[2] * rng.normal(),
            ]
        })
        .collect();
    if cfg.mu {
        let mu0 = gough::mf::eval::<f64, gough::math::Libm>(
            p,
            &gough::mf::Input {
                fz: p.fnomin,
                vx: p.longvl,
                ..Default::default()
            },
            &gough::mf::Options {
                limits: false,
                ..Default::default()
            },
        )
        .map_err(|e| format!("μy0: {e}"))?
        .mu_y;
        log.mu = Some(vec![mu0; log.len()]);
    }
    Ok(Generated { log, clean })
}

/// Benchmark settings.
#[derive(Debug, Clone, PartialEq)]
pub struct BenchConfig {
    /// Tyre files.
    pub tyres: Vec<PathBuf>,
    /// Magnitudes.
    pub magnitudes: Vec<f64>,
    /// Noise levels.
    pub noises: Vec<f64>,
    /// Seeds per (tyre, effect, magnitude, noise).
    pub seeds: u64,
    /// Seeds per (tyre, noise) for the none case.
    pub none_seeds: u64,
    /// Rows per log.
    pub rows: usize,
    /// Sample rates \[Hz\], taken in turn over tyres, noise levels, magnitudes and seeds.
    pub rates: Vec<f64>,
    /// How every log samples its truth ([`Sampling`]).
    pub sampling: Sampling,
    /// Load oscillation bursts in every log ([`GenConfig::load_oscillation`]).
    pub load_oscillation: bool,
    /// Take 2–3 decoy blocks out of every case's sim file ([`decoys`]).
    pub decoys: bool,
    /// Pairs of effects, both on at [`BenchConfig::pair_magnitude`].
    pub pairs: Vec<(Effect, Effect)>,
    /// Seeds per (tyre, pair, noise).
    pub pair_seeds: u64,
    /// Magnitude of both effects of a pair.
    pub pair_magnitude: f64,
    /// Worker threads.
    pub jobs: usize,
    /// Show a progress bar.
    pub progress: bool,
    /// The effects of the single-effect logs (every one by default); pairs only where one of
    /// theirs is among them. The none logs always run.
    pub effects: Vec<Effect>,
}

/// One benchmark case and its outcome.
#[derive(Debug, Clone)]
pub struct CaseResult {
    /// Tyre file name.
    pub tyre: String,
    /// Truth.
    pub truth: Option<Effect>,
    /// Second effect of a pair.
    pub truth2: Option<Effect>,
    /// Blocks taken out of the sim file (and the truth's) as decoys.
    pub decoys: Vec<Block>,
    /// Rate \[Hz\].
    pub rate: f64,
    /// Every effect named (the verdict first).
    pub named: Vec<Effect>,
    /// The verdict's held-out shrink (all named effects).
    pub verdict_shrink: f64,
    /// The best second candidate tried: (effect, shrink added over the first, z of it).
    pub best_second: Option<(Effect, f64, f64)>,
    /// Magnitude.
    pub magnitude: f64,
    /// Noise level.
    pub noise: f64,
    /// Seed.
    pub seed: u64,
    /// Verdict.
    pub verdict: Option<Effect>,
    /// Effects reported indistinguishable from the verdict.
    pub indistinguishable: Vec<Effect>,
    /// The true effect's held-out shrink (0 for none).
    pub achieved: f64,
    /// The shrink the noise-free truth reaches.
    pub achievable: f64,
    /// The effect with the best held-out shrink (`None`: no effect applicable).
    pub best: Option<Effect>,
    /// Best held-out shrink of any effect.
    pub best_shrink: f64,
    /// That effect's significance z.
    pub best_z: f64,
    /// Wall time of the diagnosis \[s\].
    pub seconds: f64,
}

/// Diagnoses one generated case; with `decoy`, 2–3 blocks out of the sim file ([`decoys`]).
pub fn run_case(
    p: &Params<f64>,
    tyre: &str,
    cfg: &GenConfig,
    decoy: bool,
) -> Result<CaseResult, String> {
    let effects: Vec<Effect> = cfg.truth.into_iter().chain(cfg.truth2).collect();
    let code = effects
        .iter()
        .fold(7u64, |h, e| h.wrapping_mul(31).wrapping_add(*e as u64 + 1));
    let blocks = if decoy {
        decoys(&effects, cfg.seed.wrapping_mul(1_000_003) ^ code)
    } else {
        vec![]
    };
    let p = &without(p, &blocks);
    let g = generate(p, cfg)?;
    let start = std::time::Instant::now();
    let d = super::diagnose(
        p.clone(),
        &g.log,
        tyre,
        "generated",
        &super::Options::default(),
    )?;
    let seconds = start.elapsed().as_secs_f64();
    let n = g.log.len();
    let truth_r = super::effects::resid(&g.log, &g.clean);
    let rmse_truth = super::cv::rmse_rows(&truth_r, 0..n);
    let achievable = super::cv::shrink(&d.rmse_before, &rmse_truth, &d.noise);
    let verdict_shrink = d.report.verdict.shrink.unwrap_or(0.0);
    let achieved = match (cfg.truth, cfg.truth2) {
        (Some(t), None) => d
            .shrinks
            .iter()
            .find(|s| s.0 == t)
            .map(|s| s.1)
            .unwrap_or(0.0),
        (Some(_), Some(_)) => verdict_shrink,
        _ => 0.0,
    };
    let best = d.shrinks.iter().max_by(|a, b| a.1.total_cmp(&b.1)).copied();
    let (best_shrink, best_z) = best.map(|b| (b.1, b.2)).unwrap_or((0.0, 0.0));
    let first_shrink = d
        .verdict
        .and_then(|v| d.shrinks.iter().find(|s| s.0 == v).map(|s| s.1))
        .unwrap_or(0.0);
    let best_second = d
        .seconds
        .iter()
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .map(|s| (s.0, s.1 - first_shrink, s.2));
    Ok(CaseResult {
        tyre: tyre.into(),
        truth: cfg.truth,
        truth2: cfg.truth2,
        decoys: blocks,
        rate: cfg.rate,
        named: d.named.clone(),
        verdict_shrink,
        best_second,
        magnitude: cfg.magnitude,
        noise: cfg.noise,
        seed: cfg.seed,
        verdict: d.verdict,
        indistinguishable: d.indistinguishable,
        achieved,
        achievable,
        best: best.map(|b| b.0),
        best_shrink,
        best_z,
        seconds,
    })
}

/// Is the case named right: exactly its effects named (none for a none case)?
pub fn named_right(r: &CaseResult) -> bool {
    let mut want: Vec<Effect> = r.truth.into_iter().chain(r.truth2).collect();
    let mut got = r.named.clone();
    want.sort();
    got.sort();
    want == got
}

fn short(e: Option<Effect>) -> &'static str {
    match e {
        None => "none",
        Some(Effect::Camber) => "cam",
        Some(Effect::InflationPressure) => "pres",
        Some(Effect::TurnSlip) => "turn",
        Some(Effect::CombinedSlip) => "comb",
        Some(Effect::RelaxationLength) => "relax",
        Some(Effect::SpeedDependentFriction) => "speed",
        Some(Effect::Thermal) => "therm",
        Some(Effect::SensorLag) => "lag",
        Some(Effect::SensorBias) => "bias",
        Some(Effect::ConicityPlysteer) => "conic",
    }
}

fn name(e: Option<Effect>) -> &'static str {
    e.map(|e| e.name()).unwrap_or("none")
}

/// Runs the benchmark; returns the case results.
pub fn run(cfg: &BenchConfig) -> Result<Vec<CaseResult>, String> {
    let mut tyres = Vec::new();
    for t in &cfg.tyres {
        let ty = crate::tyre::load(t)?;
        let nm = t
            .file_name()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        tyres.push((nm, ty.params));
    }
    let mut cases: Vec<(usize, GenConfig)> = Vec::new();
    let rate = |k: usize| {
        cfg.rates
            .get(k % cfg.rates.len().max(1))
            .copied()
            .unwrap_or(200.0)
    };
    for (ti, _) in tyres.iter().enumerate() {
        for (ni, &noise) in cfg.noises.iter().enumerate() {
            for s in 0..cfg.none_seeds {
                cases.push((
                    ti,
                    GenConfig {
                        rows: cfg.rows,
                        rate: rate(ti + ni + s as usize),
                        seed: 1000 + s,
                        truth: None,
                        magnitude: 0.0,
                        noise,
                        load_oscillation: cfg.load_oscillation,
                        sampling: cfg.sampling,
                        ..GenConfig::default()
                    },
                ));
            }
            for &e in &cfg.effects {
                for (mi, &m) in cfg.magnitudes.iter().enumerate() {
                    for s in 0..cfg.seeds {
                        cases.push((
                            ti,
                            GenConfig {
                                rows: cfg.rows,
                                rate: rate(ti + ni + mi + s as usize),
                                seed: 1 + s,
                                truth: Some(e),
                                magnitude: m,
                                noise,
                                load_oscillation: cfg.load_oscillation,
                                sampling: cfg.sampling,
                                ..GenConfig::default()
                            },
                        ));
                    }
                }
            }
            for (pi, &(a, b)) in cfg.pairs.iter().enumerate() {
                if !cfg.effects.contains(&a) && !cfg.effects.contains(&b) {
                    continue;
                }
                for s in 0..cfg.pair_seeds {
                    cases.push((
                        ti,
                        GenConfig {
                            rows: cfg.rows,
                            rate: rate(ti + ni + pi + s as usize),
                            seed: 500 + s,
                            truth: Some(a),
                            truth2: Some(b),
                            magnitude: cfg.pair_magnitude,
                            noise,
                            load_oscillation: cfg.load_oscillation,
                            sampling: cfg.sampling,
                            ..GenConfig::default()
                        },
                    ));
                }
            }
        }
    }
    let bar = cfg.progress.then(|| {
        let b = indicatif::ProgressBar::with_draw_target(
            Some(cases.len() as u64),
            indicatif::ProgressDrawTarget::stderr(),
        );
        if let Ok(style) = indicatif::ProgressStyle::with_template(
            "gap bench {bar:40} {pos}/{len} logs {elapsed_precise} (eta {eta})",
        ) {
            b.set_style(style);
        }
        b
    });
    let next = std::sync::atomic::AtomicUsize::new(0);
    let results = std::sync::Mutex::new(Vec::new());
    let failure = std::sync::Mutex::new(None::<String>);
    std::thread::scope(|s| {
        for _ in 0..cfg.jobs.max(1) {
            s.spawn(|| loop {
                let k = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                let Some((ti, gc)) = cases.get(k) else { break };
                let (nm, p) = &tyres[*ti];
                match run_case(p, nm, gc, cfg.decoys) {
                    Ok(r) => {
                        if let Ok(mut v) = results.lock() {
                            v.push((k, r));
                        }
                    }
                    Err(e) => {
                        if let Ok(mut f) = failure.lock() {
                            *f = Some(format!(
                                "{nm}, {}{} m={} seed {}: {e}",
                                name(gc.truth),
                                gc.truth2
                                    .map(|e| format!("+{}", e.name()))
                                    .unwrap_or_default(),
                                gc.magnitude,
                                gc.seed
                            ));
                        }
                    }
                }
                if let Some(b) = &bar {
                    b.inc(1);
                }
            });
        }
    });
    if let Some(b) = &bar {
        b.finish_and_clear();
    }
    if let Some(e) = failure.into_inner().ok().flatten() {
        return Err(e);
    }
    let mut v = results
        .into_inner()
        .map_err(|_| "a benchmark worker panicked".to_string())?;
    v.sort_by_key(|r| r.0);
    Ok(v.into_iter().map(|r| r.1).collect())
}

/// The case results as CSV (one row per log).
pub fn cases_csv(res: &[CaseResult]) -> String {
    let mut s = String::from(
        "tyre,truth,truth2,magnitude,noise,seed,rate,decoys,verdict,named,indistinguishable,verdict_shrink,achieved,achievable,best,best_shrink,best_z,best_second,second_added,second_z,seconds\n",
    );
    let join = |v: &[Effect]| v.iter().map(|e| e.name()).collect::<Vec<_>>().join(" ");
    for r in res {
        let (bs, ba, bz) = match r.best_second {
            Some((e, a, z)) => (e.name(), a, z),
            None => ("", 0.0, 0.0),
        };
        let _ =
            writeln!(
            s,
            "{},{},{},{},{},{},{},{},{},{},{},{:.5},{:.5},{:.5},{},{:.5},{:.2},{},{:.5},{:.2},{:.3}",
            r.tyre,
            name(r.truth),
            name(r.truth2),
            r.magnitude,
            r.noise,
            r.seed,
            r.rate,
            r.decoys.iter().map(|b| b.name()).collect::<Vec<_>>().join(" "),
            name(r.verdict),
            join(&r.named),
            join(&r.indistinguishable),
            r.verdict_shrink,
            r.achieved,
            r.achievable,
            name(r.best),
            r.best_shrink,
            r.best_z,
            bs,
            ba,
            bz,
            r.seconds
        );
    }
    s
}

/// The targets per tyre, measured on `res` (Markdown table).
pub fn targets(tyres: &[String], res: &[CaseResult]) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "**Targets** (issue 40): named right = exactly the true effect(s) named; shrink ratio = mean held-out shrink achieved / mean achievable over the single-effect logs at m ≥ 0.3 (and its smallest value per effect)\n"
    );
    let _ = writeln!(
        s,
        "| tyre | named right, m ≥ 0.3 (target ≥ 95 %) | false alarms on none logs (target 0) | shrink ratio, m ≥ 0.3 (target ≥ 0.8): all; worst effect | pairs, both named at m = 1 (target ≥ 80 %) |\n|---|---|---|---|---|"
    );
    let pct = |a: usize, b: usize| 100.0 * a as f64 / b.max(1) as f64;
    for t in tyres {
        let of: Vec<&CaseResult> = res.iter().filter(|r| &r.tyre == t).collect();
        let single: Vec<&&CaseResult> = of
            .iter()
            .filter(|r| r.truth.is_some() && r.truth2.is_none() && r.magnitude >= 0.3 - 1e-9)
            .collect();
        let right = single.iter().filter(|r| named_right(r)).count();
        let none: Vec<&&CaseResult> = of.iter().filter(|r| r.truth.is_none()).collect();
        let fa = none.iter().filter(|r| !r.named.is_empty()).count();
        let ratio = |rows: &[&&CaseResult]| {
            let a: f64 = rows.iter().map(|r| r.achieved).sum();
            let b: f64 = rows.iter().map(|r| r.achievable).sum();
            if b > 0.0 {
                a / b
            } else {
                f64::NAN
            }
        };
        let mut worst = (f64::INFINITY, "");
        for e in ALL {
            let rows: Vec<&&CaseResult> = single
                .iter()
                .copied()
                .filter(|r| r.truth == Some(e))
                .collect();
            if !rows.is_empty() {
                let q = ratio(&rows);
                if q < worst.0 {
                    worst = (q, e.name());
                }
            }
        }
        let pairs: Vec<&&CaseResult> = of
            .iter()
            .filter(|r| r.truth2.is_some() && r.magnitude >= 1.0 - 1e-9)
            .collect();
        let both = pairs.iter().filter(|r| named_right(r)).count();
        let _ = writeln!(
            s,
            "| {t} | {right}/{} = {:.1} % | {fa}/{} | {:.3}; {:.3} ({}) | {both}/{} = {:.1} % |",
            single.len(),
            pct(right, single.len()),
            none.len(),
            ratio(&single),
            worst.0,
            worst.1,
            pairs.len(),
            pct(both, pairs.len())
        );
    }
    s.push('\n');
    s
}

/// The benchmark's tables (Markdown).
pub fn table(cfg: &BenchConfig, res: &[CaseResult]) -> String {
    let mut s = String::new();
    let truths: Vec<Option<Effect>> = std::iter::once(None)
        .chain(ALL.iter().map(|&e| Some(e)))
        .collect();
    let tyres: Vec<String> = cfg
        .tyres
        .iter()
        .map(|t| {
            t.file_name()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default()
        })
        .collect();
    let secs: Vec<f64> = res.iter().map(|r| r.seconds).collect();
    let _ = writeln!(
        s,
        "{} logs of {} rows at {:?} Hz (in turn){}{}{}: tyres {}; magnitudes {:?}; noise {:?} of each channel's RMS; \
         {} seed(s) per effect case, {} per none case; pairs {} at m = {}, {} seed(s) each. Diagnosis time per log: median {:.2} s, max {:.2} s.\n",
        res.len(),
        cfg.rows,
        cfg.rates,
        if cfg.sampling.is_default() {
            String::new()
        } else {
            format!(
                ", the truth run at {} between the rows, timestamps jittered by ±{} of the step, {} of the rows dropped",
                cfg.sampling
                    .truth_rate
                    .map(|r| format!("{r} Hz"))
                    .unwrap_or_else(|| "the log's rate".into()),
                cfg.sampling.jitter,
                cfg.sampling.drop
            )
        },
        if cfg.load_oscillation {
            ", load oscillation bursts of ±30 % at 2, 4, 8 Hz"
        } else {
            ""
        },
        if cfg.decoys {
            ", 2–3 decoy blocks taken out of every case's sim file (never the case's effect's)"
        } else {
            ""
        },
        tyres.join(", "),
        cfg.magnitudes,
        cfg.noises,
        cfg.seeds,
        cfg.none_seeds,
        cfg.pairs
            .iter()
            .map(|(a, b)| format!("{}+{}", a.name(), b.name()))
            .collect::<Vec<_>>()
            .join(", "),
        cfg.pair_magnitude,
        cfg.pair_seeds,
        stats::median(&secs),
        secs.iter().cloned().fold(0.0, f64::max)
    );
    s += &targets(&tyres, res);
    let pair_rows: Vec<&CaseResult> = res.iter().filter(|r| r.truth2.is_some()).collect();
    let res: Vec<CaseResult> = res.iter().filter(|r| r.truth2.is_none()).cloned().collect();
    let res = &res[..];
    // Confusion matrix.
    let _ = writeln!(s, "**Confusion matrix** (rows: truth; columns: verdict; `≈`: truth reported indistinguishable from a different verdict)\n");
    let mut head = String::from("| truth \\ verdict |");
    let mut rule = String::from("|---|");
    for v in &truths {
        let _ = write!(head, " {} |", short(*v));
        rule.push_str("---:|");
    }
    head.push_str(" ≈ | n |");
    rule.push_str("---:|---:|");
    let _ = writeln!(s, "{head}\n{rule}");
    for t in &truths {
        let rows: Vec<&CaseResult> = res.iter().filter(|r| r.truth == *t).collect();
        if rows.is_empty() {
            continue;
        }
        let _ = write!(s, "| {} |", name(*t));
        for v in &truths {
            let c = rows.iter().filter(|r| r.verdict == *v).count();
            if c == 0 {
                s.push_str(" · |");
            } else {
                let _ = write!(s, " {c} |");
            }
        }
        let amb = rows
            .iter()
            .filter(|r| r.verdict != *t && t.is_some_and(|t| r.indistinguishable.contains(&t)))
            .count();
        let _ = writeln!(s, " {amb} | {} |", rows.len());
    }
    // False alarms.
    let none: Vec<&CaseResult> = res.iter().filter(|r| r.truth.is_none()).collect();
    let fa = none.iter().filter(|r| r.verdict.is_some()).count();
    let worst_none = none
        .iter()
        .max_by(|a, b| a.best_shrink.total_cmp(&b.best_shrink));
    let max_none = worst_none.map_or(f64::NEG_INFINITY, |r| r.best_shrink);
    let worst_name = worst_none.map_or("none", |r| name(r.best));
    let max_z = none
        .iter()
        .map(|r| r.best_z)
        .fold(f64::NEG_INFINITY, f64::max);
    let _ = writeln!(
        s,
        "\n**None-case false alarm rate**: {fa}/{} = {:.1} %; in the none cases the best effect's held-out shrink was at most {:.4} ({worst_name}; verdict threshold {}) and its significance z at most {:.1} (threshold {}).\n",
        none.len(),
        100.0 * fa as f64 / none.len().max(1) as f64,
        max_none,
        super::MIN_SHRINK,
        max_z,
        super::MIN_Z
    );
    // Detection by magnitude and achieved vs achievable.
    let _ = writeln!(s, "**Detection rate by magnitude** (verdict = truth; in brackets: verdict = truth or truth indistinguishable from it) and **held-out shrink achieved / achievable** (mean over that magnitude's logs)\n");
    let mut head = String::from("| effect |");
    let mut rule = String::from("|---|");
    for m in &cfg.magnitudes {
        let _ = write!(head, " m = {m} |");
        rule.push_str("---|");
    }
    let _ = writeln!(s, "{head}\n{rule}");
    for &e in &ALL {
        let _ = write!(s, "| {} |", e.name());
        for &m in &cfg.magnitudes {
            let rows: Vec<&CaseResult> = res
                .iter()
                .filter(|r| r.truth == Some(e) && r.magnitude == m)
                .collect();
            if rows.is_empty() {
                s.push_str(" – |");
                continue;
            }
            let hit = rows.iter().filter(|r| r.verdict == Some(e)).count();
            let soft = rows
                .iter()
                .filter(|r| r.verdict == Some(e) || r.indistinguishable.contains(&e))
                .count();
            let ach = stats::mean(&rows.iter().map(|r| r.achieved).collect::<Vec<_>>());
            let able = stats::mean(&rows.iter().map(|r| r.achievable).collect::<Vec<_>>());
            let _ = write!(
                s,
                " {hit}/{n} ({soft}/{n}); {ach:.3} / {able:.3} |",
                n = rows.len()
            );
        }
        s.push('\n');
    }
    // Second effects named on single-effect logs, and the largest added shrink tried there.
    let single: Vec<&CaseResult> = res.iter().filter(|r| r.truth.is_some()).collect();
    let extra = single.iter().filter(|r| r.named.len() > 1).count();
    let max_add = single
        .iter()
        .filter_map(|r| r.best_second.map(|b| (b.1, b.2, r)))
        .max_by(|a, b| a.0.total_cmp(&b.0));
    let _ = writeln!(
        s,
        "\n**Second effect on single-effect logs**: named on {extra}/{} (thresholds: added shrink ≥ {}, z ≥ {}); the largest added held-out shrink of a second candidate there: {}.\n",
        single.len(),
        super::MIN_ADD_SHRINK,
        super::MIN_Z_ADD,
        match max_add {
            Some((a, z, r)) => format!(
                "{a:.4} (z {z:.1}; {} on a {} m = {} log)",
                r.best_second.map(|b| b.0.name()).unwrap_or(""),
                name(r.truth),
                r.magnitude
            ),
            None => "none tried".into(),
        }
    );
    if !pair_rows.is_empty() {
        let _ = writeln!(
            s,
            "**Pairs** (both effects on; named: the effects of the verdict, first first)\n\n| pair | tyre | both named | first named right | named (count) | shrink: verdict / achievable |\n|---|---|---|---|---|---|"
        );
        for &(a, b) in &cfg.pairs {
            for t in &tyres {
                let rows: Vec<&&CaseResult> = pair_rows
                    .iter()
                    .filter(|r| r.truth == Some(a) && r.truth2 == Some(b) && &r.tyre == t)
                    .collect();
                if rows.is_empty() {
                    continue;
                }
                let both = rows.iter().filter(|r| named_right(r)).count();
                let first = rows
                    .iter()
                    .filter(|r| r.verdict == Some(a) || r.verdict == Some(b))
                    .count();
                let mut seen: Vec<(String, usize)> = Vec::new();
                for r in &rows {
                    let k = if r.named.is_empty() {
                        "none".to_string()
                    } else {
                        r.named
                            .iter()
                            .map(|e| short(Some(*e)))
                            .collect::<Vec<_>>()
                            .join("+")
                    };
                    match seen.iter_mut().find(|x| x.0 == k) {
                        Some(x) => x.1 += 1,
                        None => seen.push((k, 1)),
                    }
                }
                let vs = stats::mean(&rows.iter().map(|r| r.verdict_shrink).collect::<Vec<_>>());
                let able = stats::mean(&rows.iter().map(|r| r.achievable).collect::<Vec<_>>());
                let _ = writeln!(
                    s,
                    "| {}+{} | {t} | {both}/{n} | {first}/{n} | {} | {vs:.3} / {able:.3} |",
                    a.name(),
                    b.name(),
                    seen.iter()
                        .map(|(k, c)| format!("{k} ({c})"))
                        .collect::<Vec<_>>()
                        .join(", "),
                    n = rows.len()
                );
            }
        }
    }
    s
}

/// The pairs of the benchmark: effects of different kinds (a friction or stiffness change with
/// a sensor fault or an offset).
pub const PAIRS: [(Effect, Effect); 5] = [
    (Effect::Thermal, Effect::SensorLag),
    (Effect::CombinedSlip, Effect::ConicityPlysteer),
    (Effect::InflationPressure, Effect::SensorBias),
    (Effect::RelaxationLength, Effect::Camber),
    (Effect::SpeedDependentFriction, Effect::TurnSlip),
];

/// The default benchmark of `gough gap bench` (docs/gap.md): the bundled MF 6.1 example tyre and
/// `reference_tire_tvd3.tir`, logs at 100 and 200 Hz in turn with load oscillation bursts, 2–3
/// decoy blocks out of every sim file, the single effects and [`PAIRS`].
pub fn default_config(data: &Path, quick: bool) -> BenchConfig {
    let tyres = ["MagicFormula61_Parameters.tir", "reference_tire_tvd3.tir"]
        .iter()
        .map(|f| data.join(f))
        .collect();
    if quick {
        BenchConfig {
            tyres,
            magnitudes: vec![1.0],
            noises: vec![0.02],
            seeds: 1,
            none_seeds: 1,
            rows: 1500,
            rates: vec![100.0, 200.0],
            sampling: Sampling::default(),
            load_oscillation: true,
            decoys: true,
            pairs: PAIRS[..2].to_vec(),
            pair_seeds: 1,
            pair_magnitude: 1.0,
            jobs: 1,
            progress: true,
            effects: ALL.to_vec(),
        }
    } else {
        BenchConfig {
            tyres,
            magnitudes: vec![1.0, 0.3, 0.1],
            noises: vec![0.01, 0.03],
            seeds: 1,
            none_seeds: 3,
            rows: 4000,
            rates: vec![100.0, 200.0],
            sampling: Sampling::default(),
            load_oscillation: true,
            decoys: true,
            pairs: PAIRS.to_vec(),
            pair_seeds: 1,
            pair_magnitude: 1.0,
            jobs: 1,
            progress: true,
            effects: ALL.to_vec(),
        }
    }
}
