//! The corrected tyre file (`gough gap diagnose --write-tir FILE`): SIM.tir with the verdict's
//! fitted effect(s) put into its Magic Formula coefficients.
//!
//! Per effect ([`correct`]):
//! - **exact**: the effects that re-fit `.tir` keys (camber, MF 6.x inflation pressure, MF 6.x
//!   turn slip, combined slip, conicity/ply-steer): the keys at their values fitted on the whole
//!   log. The written file's sim is the sim with the effect, row for row.
//! - **approximate**, the relaxation lengths: σκ, σα × s·(1 + c·dfz) has no exact `.tir` form;
//!   the file's own σ law is fitted to the effect's σ on the log's rows (least squares of
//!   ln σ): MF 6.x the carcass stiffnesses and their load terms (σ = |K/C|, C = C0·(1 + PCF1·dfz +
//!   PCF2·dfz²)): `LONGITUDINAL_STIFFNESS LATERAL_STIFFNESS PCFX1 PCFX2 PCFY1 PCFY2`; MF 5.x
//!   `PTX1 PTX2 PTY1 PTY2`. Exact when c = 0 in MF 6.x (C0 / s).
//! - **approximate**, per-row friction and stiffness factors (speed-dependent friction, thermal,
//!   the MF 5.x pressure law): the best constant file for the effect's prediction on the log:
//!   `LMUX LMUY LKX LKY` fitted to it (noise-weighted least squares, as a fit of the diagnosis).
//!   What varies along the log (with slip speed, temperature, pressure) is left out and named:
//!   the file format has no temperature, and gough's reader ignores `LMUV`. Kept only when the
//!   written file closes more of the gap than the file without them (else the effect is left
//!   out: the MF 5.x pressure law about the log's median p has no constant part).
//! - **left out**: sensor lag and bias (the sensor's, not the tyre's: correct the log), the
//!   linear spin force of a file without turn-slip coefficients.
//!
//! The report's `corrected_tir` gives, over the scored rows of the log, the shrink of the
//! effect(s) fitted on the whole log (`shrink_fit`: the prediction the file is made from) and
//! of the written file's plain sim (`shrink_written`), beside the verdict's held-out shrink.
//! For exact mappings the two are equal (the file's sim is the effect's prediction; the
//! values are written in Rust's shortest round-trip form and read back bit for bit). For a pair
//! the diagnosis superposes the two effects' changes while the file composes them: equal where
//! they act on different terms.

use super::cv::{self, shrink};
use super::effects::{Ctx, Effect, Spec};
use super::fit::{levenberg_marquardt, Bounds};
use super::log::Log;
use super::sim::{Mods, Out, Sim};
use gough::mf::{Key, Params};
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::Path;

/// How an effect went into the file.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum How {
    /// The effect's own coefficients: the file is the effect.
    Exact,
    /// The file's coefficients fitted to the effect's prediction (or σ): the part of it that
    /// constant coefficients hold.
    Approximate,
    /// Nothing written.
    LeftOut,
}

/// One effect of the verdict in the corrected file.
#[derive(Debug, Clone, Serialize)]
pub struct Part {
    /// The effect.
    pub effect: String,
    /// How it went in.
    pub how: How,
    /// The keys written for it.
    pub keys: Vec<String>,
    /// What is left out and why (empty when exact).
    pub note: String,
}

/// The report's `corrected_tir`.
#[derive(Debug, Clone, Serialize)]
pub struct TirReport {
    /// Per named effect.
    pub effects: Vec<Part>,
    /// Every coefficient changed: its new value.
    pub coefficients: BTreeMap<String, f64>,
    /// ... and SIM.tir's value of it.
    pub coefficients_sim: BTreeMap<String, f64>,
    /// The effects (or parts of them) the file cannot hold.
    pub left_out: Vec<String>,
    /// The verdict's held-out shrink (as `verdict.shrink`).
    pub shrink_heldout: f64,
    /// The effect(s) fitted on the whole log, on the scored rows.
    pub shrink_fit: f64,
    /// The corrected file's plain sim, on the same rows.
    pub shrink_written: f64,
}

/// The corrected parameters and the report of how they were made.
#[derive(Debug, Clone)]
pub struct Corrected {
    /// SIM.tir with the changes.
    pub params: Params<f64>,
    /// The keys changed, in the order they were set.
    pub changes: Vec<(Key, f64)>,
    /// The report.
    pub report: TirReport,
}

const LAMBDAS: [&str; 4] = ["LMUX", "LMUY", "LKX", "LKY"];

/// The keys of the file's relaxation-length law fitted to the relaxation effect.
fn sigma_keys(p: &Params<f64>) -> [Key; 6] {
    if p.version.is_mf6() {
        [
            Key::LONGITUDINAL_STIFFNESS,
            Key::LATERAL_STIFFNESS,
            Key::PCFX1,
            Key::PCFX2,
            Key::PCFY1,
            Key::PCFY2,
        ]
    } else {
        [
            Key::PTX1,
            Key::PTX2,
            Key::PTY1,
            Key::PTY2,
            Key::PTX3,
            Key::PTX3,
        ]
    }
}

/// Fits the file's σ law (keys of [`sigma_keys`]) to the per-row σ `target` on `rows` from `q`:
/// least squares of ln(σ_file/σ_target) over both lengths. The stiffnesses fitted in log space.
/// (`like`: the diagnosis's sim, whose evaluation path the fit's sim takes.)
fn fit_sigma(
    like: &Sim,
    log: &Log,
    q: &Params<f64>,
    target: &[[f64; 2]],
    rows: &[usize],
) -> Params<f64> {
    let keys = sigma_keys(q);
    let mf6 = q.version.is_mf6();
    let nk = if mf6 { 6 } else { 4 };
    let mut base = q.clone();
    // Starts: the file's law where it has one; else one that gives σ of the target's order.
    let med = |c: usize| {
        let v: Vec<f64> = rows.iter().map(|&i| target[i][c]).collect();
        super::stats::median(&v)
    };
    if mf6 {
        // σ = |K/C|: without stiffnesses, C0 from the target's median σ and K at FNOMIN.
        for (c, k) in [
            (0, Key::LONGITUDINAL_STIFFNESS),
            (1, Key::LATERAL_STIFFNESS),
        ] {
            if base.get(k) <= 0.0 {
                let o = gough::mf::eval::<f64, gough::math::Libm>(
                    &base,
                    &gough::mf::Input {
                        fz: base.fnomin,
                        vx: base.longvl,
                        ..Default::default()
                    },
                    &gough::mf::Options::default(),
                );
                let kk = o
                    .map(|o| if c == 0 { o.k_xk } else { o.k_ya })
                    .unwrap_or(0.0);
                let s = med(c).max(1e-3);
                base.set(k, (kk.abs() / s).max(1.0));
            }
        }
    } else {
        if base.ptx1 == 0.0 {
            base.ptx1 = med(0) / base.unloaded_radius.max(1e-9);
        }
        if base.pty2 == 0.0 {
            base.pty2 = 1.0;
        }
        if base.pty1 == 0.0 {
            base.pty1 = med(1) / base.unloaded_radius.max(1e-9);
        }
    }
    let to_theta = |p: &Params<f64>| -> Vec<f64> {
        keys[..nk]
            .iter()
            .enumerate()
            .map(|(j, &k)| {
                let v = p.get(k);
                if mf6 && j < 2 {
                    v.max(1e-9).ln()
                } else {
                    v
                }
            })
            .collect()
    };
    let of_theta = |th: &[f64]| -> Params<f64> {
        let mut p = base.clone();
        for (j, &k) in keys[..nk].iter().enumerate() {
            p.set(k, if mf6 && j < 2 { th[j].exp() } else { th[j] });
        }
        p
    };
    let start = to_theta(&base);
    let sim0 = like.like(base.clone(), log);
    let resid = |th: &[f64]| -> Option<Vec<f64>> {
        let p = of_theta(th);
        let mut r = Vec::with_capacity(2 * rows.len());
        for &i in rows {
            let s = sim0.sigma_at(log, &p, &Mods::default(), i).ok()?;
            for c in 0..2 {
                let t = target[i][c];
                if t > 0.0 {
                    r.push((s[c].max(1e-9) / t).ln());
                }
            }
        }
        r.iter().all(|v| v.is_finite()).then_some(r)
    };
    let bounds = if mf6 {
        Bounds {
            lo: vec![start[0] - 5.0, start[1] - 5.0, -0.95, -2.0, -0.95, -2.0],
            hi: vec![start[0] + 5.0, start[1] + 5.0, 5.0, 5.0, 5.0, 5.0],
            scale: vec![0.2, 0.2, 0.2, 0.2, 0.2, 0.2],
        }
    } else {
        let s = |v: f64| v.abs().max(0.1);
        Bounds {
            lo: vec![0.0, -5.0 * s(start[1]), 0.0, 0.05],
            hi: vec![
                10.0 * s(start[0]),
                5.0 * s(start[1]),
                10.0 * s(start[2]),
                20.0 * s(start[3]),
            ],
            scale: vec![s(start[0]), s(start[1]), s(start[2]), s(start[3])],
        }
    };
    match levenberg_marquardt(resid, &start, &bounds, 30) {
        Some(f) => of_theta(&f.theta),
        None => base,
    }
}

/// The prediction the file is made from: the effects at `thetas` (one, or a pair superposed as
/// the diagnosis does), every row, exact.
fn prediction(ctx: &Ctx, effects: &[(&Spec, &[f64])]) -> Option<Vec<Out>> {
    match effects {
        [(s, th)] => s.predict(ctx, th, None),
        [(a, ta), (b, tb)] => super::effects::Pair { a, b }.predict(ctx, ta, tb, None),
        _ => None,
    }
}

/// The shrink of `pred` over the scored rows (`Ctx::settled`), in the diagnosis's units.
fn shrink_of(ctx: &Ctx, pred: &[Out]) -> f64 {
    let n = ctx.log.len();
    let before = cv::rmse_rows(&ctx.base_resid(), 0..n);
    let after = cv::rmse_rows(&ctx.resid(pred), 0..n);
    shrink(&before, &after, &ctx.noise)
}

/// The corrected parameters for the named effects at their whole-log fits `effects` (the
/// verdict's one or two), and how each went in. `shrink_heldout`: the verdict's.
pub fn correct(
    ctx: &Ctx,
    effects: &[(&Spec, &[f64])],
    shrink_heldout: f64,
    fit_rows: usize,
) -> Corrected {
    let (log, sim) = (ctx.log, ctx.sim);
    let p0 = &sim.params;
    let mut q = p0.clone();
    let mut parts = Vec::new();
    let mut left_out = Vec::new();
    let mut lambda_effects = Vec::new();
    let rows: Vec<usize> = cv::train_rows(log.len(), None, fit_rows)
        .into_iter()
        .filter(|&i| ctx.settled.get(i).copied().unwrap_or(true))
        .collect();
    for &(sp, th) in effects {
        let e = sp.effect;
        let name = e.name().to_string();
        if let Some(keys) = sp.keys() {
            for (k, &v) in keys.iter().zip(th) {
                q.set(*k, v);
            }
            parts.push(Part {
                effect: name,
                how: How::Exact,
                keys: keys.iter().map(|k| k.name().to_string()).collect(),
                note: String::new(),
            });
            continue;
        }
        match e {
            Effect::RelaxationLength => {
                let target = sp.sigmas(ctx, th);
                q = fit_sigma(ctx.sim, log, &q, &target, &rows);
                let nk = if q.version.is_mf6() { 6 } else { 4 };
                parts.push(Part {
                    effect: name,
                    how: How::Approximate,
                    keys: sigma_keys(&q)[..nk]
                        .iter()
                        .map(|k| k.name().to_string())
                        .collect(),
                    note: "σ × s·(1 + c·dfz) through the file's own σ law, fitted to the \
                           effect's σ on the log's rows"
                        .into(),
                });
            }
            Effect::SpeedDependentFriction | Effect::Thermal | Effect::InflationPressure => {
                lambda_effects.push(e);
                let what = match e {
                    Effect::SpeedDependentFriction => {
                        "λμ's dependence on slip and forward speed (gough's reader ignores LMUV)"
                    }
                    Effect::Thermal => {
                        "the tread temperature and its dynamics (a .tir has no temperature state)"
                    }
                    _ => "the pressure dependence (MF 5.x has no pressure terms)",
                };
                left_out.push(format!("{name}: {what}"));
                parts.push(Part {
                    effect: name,
                    how: How::Approximate,
                    keys: LAMBDAS.iter().map(|s| s.to_string()).collect(),
                    note: format!(
                        "constant λ's fitted to the effect's prediction on the log; left out: \
                         {what}; the effect's model and parameters are in `effects`"
                    ),
                });
            }
            _ => {
                let why = match e {
                    Effect::SensorLag | Effect::SensorBias => {
                        "a sensor's, not the tyre's: correct the log, not the file"
                    }
                    _ => "SIM.tir has no turn-slip coefficients to hold the linear spin force",
                };
                left_out.push(format!("{name}: {why}"));
                parts.push(Part {
                    effect: name,
                    how: How::LeftOut,
                    keys: vec![],
                    note: format!("{why}; the effect's model and parameters are in `effects`"),
                });
            }
        }
    }
    let target = prediction(ctx, effects);
    let written = |q: &Params<f64>| {
        ctx.sim
            .like(q.clone(), log)
            .run(log, q, &Mods::default())
            .map(|r| shrink_of(ctx, &r.out))
            .unwrap_or(f64::NAN)
    };
    if !lambda_effects.is_empty() {
        if let Some(target) = &target {
            // Kept only where the constant λ's close more of the gap on the log than the file
            // without them (a pressure law about the log's median p has no constant part).
            if let Some(ql) = fit_lambdas(ctx, &q, target, &rows, lambda_effects[0]) {
                if written(&ql) > written(&q) {
                    q = ql;
                } else {
                    for part in parts.iter_mut().filter(|p| p.how == How::Approximate) {
                        if lambda_effects.iter().any(|e| e.name() == part.effect) {
                            part.how = How::LeftOut;
                            part.keys.clear();
                            part.note = format!(
                                "{}; constant λ's fitted to it close less of the gap than none",
                                part.note
                            );
                        }
                    }
                }
            }
        }
    }
    let changes: Vec<(Key, f64)> = Key::ALL
        .iter()
        .copied()
        .filter(|&k| q.get(k) != p0.get(k))
        .map(|k| (k, q.get(k)))
        .collect();
    let shrink_fit = target.as_ref().map(|t| shrink_of(ctx, t)).unwrap_or(0.0);
    let shrink_written = written(&q);
    let report = TirReport {
        effects: parts,
        coefficients: changes
            .iter()
            .map(|(k, v)| (k.name().to_string(), *v))
            .collect(),
        coefficients_sim: changes
            .iter()
            .map(|(k, _)| (k.name().to_string(), p0.get(*k)))
            .collect(),
        left_out,
        shrink_heldout,
        shrink_fit,
        shrink_written,
    };
    Corrected {
        params: q,
        changes,
        report,
    }
}

/// `LMUX LMUY LKX LKY` of `q` fitted to `target` (a log whose outputs are the prediction),
/// noise-weighted as the diagnosis's fits.
fn fit_lambdas(
    ctx: &Ctx,
    q: &Params<f64>,
    target: &[Out],
    rows: &[usize],
    label: Effect,
) -> Option<Params<f64>> {
    let mut log = ctx.log.clone();
    log.meas = target.to_vec();
    let sim = ctx.sim.like(q.clone(), &log);
    let base = sim.run(&log, q, &Mods::default()).ok()?;
    let c2 = Ctx {
        log: &log,
        sim: &sim,
        base,
        ..ctx.clone()
    };
    let sp = Spec::of_keys(label, q, &LAMBDAS);
    let f = sp.fit(&c2, rows)?;
    Some(sp.params(q, &f.theta))
}

/// `text` (SIM.tir's) with the corrected coefficients written in
/// ([`crate::tyre::set_or_add_in_tir`]), and a check that it reads back to them bit for bit.
pub fn write(text: &str, c: &Corrected) -> Result<String, String> {
    let mut out = text.to_string();
    for &(k, v) in &c.changes {
        out = crate::tyre::set_or_add_in_tir(&out, k, v, "gough gap diagnose --write-tir")?;
    }
    let back = gough::tir::parse(&out).map_err(|e| format!("the corrected file: {e}"))?;
    for &(k, v) in &c.changes {
        if back.params.get(k) != v {
            return Err(format!(
                "the corrected file reads {} = {} back, not {v}",
                k.name(),
                back.params.get(k)
            ));
        }
    }
    Ok(out)
}

/// Writes the corrected file of a diagnosis to `out` (SIM.tir's `text` unchanged without a
/// verdict); the line that says what went in and what is left out.
pub fn write_corrected(text: &str, out: &Path, c: Option<&Corrected>) -> Result<String, String> {
    let Some(c) = c else {
        super::write_atomic(out, text)?;
        return Ok(format!(
            "corrected file: {} (no verdict: SIM.tir unchanged)",
            out.display()
        ));
    };
    super::write_atomic(out, &write(text, c)?)?;
    let r = &c.report;
    let parts: Vec<String> = r
        .effects
        .iter()
        .map(|p| {
            let how = match p.how {
                How::Exact => "exact",
                How::Approximate => "approximate",
                How::LeftOut => "left out",
            };
            format!("{} {how}", p.effect)
        })
        .collect();
    let mut line = format!(
        "corrected file: {} ({}; {} coefficients; shrink of the written file {:.3}, of the effect fitted on the whole log {:.3}, held-out {:.3})",
        out.display(),
        parts.join(", "),
        r.coefficients.len(),
        r.shrink_written,
        r.shrink_fit,
        r.shrink_heldout
    );
    if !r.left_out.is_empty() {
        line += &format!("; left out: {}", r.left_out.join("; "));
    }
    Ok(line)
}
