//! The diagnosis of the friction estimator's output, when the log has a reference `mu` column.
//!
//! The product's estimator ([`Method::Bank`]: the core's bank, default settings, the log's wheel
//! taken as SIM.tir describes the tyre, as `gough mu estimate` takes a one-wheel log) runs on the
//! log's measured Fx, Fy, Mz, Fz, Vx, κ and γ (never α). Its error against the reference μ is
//! taken on the rows where it has an estimate (state not `fallback`). Then:
//! - `where`: the operating regions holding the squared μ error, binned as the force gap is
//!   ([`super::regions`]), a region reported when it holds ≥ 20 % of the error and ≥ 1.25× its
//!   share of the rows;
//! - `effects`: does the effect explain the error? The estimator's model is SIM.tir at INFLPRES,
//!   without turn slip, on clean sensors. For each candidate, with the parameters it was fitted
//!   to on the *forces* (never on μ), its contribution to the channels is Δ = (sim with the
//!   effect) − (sim without it), where "without" is: γ at the median (`camber`), p = INFLPRES
//!   (`inflation_pressure`), φt = 0 (`turn_slip`), steady state (`relaxation_length`), and
//!   SIM.tir as it is for the others (bias, lag, friction changes, re-fitted terms). The
//!   estimator is run again on measured − Δ (κ, γ, Vx as logged); the effect explains the error
//!   as far as that shrinks it.
//! - `verdict`: the effect with the largest μ shrink 1 − rmse_after/rmse_before when that is at
//!   least [`MU_MIN_SHRINK`] and the estimator's error is at least [`MU_MIN_RMSE`]; else `none`.
//!   Effects within 20 % of its shrink are reported as indistinguishable, and if the force
//!   verdict is among them it is the μ verdict (the forces are the stronger evidence of which
//!   effect is present).

use super::cv::Score;
use super::effects::Spec;
use super::effects::{Ctx, Effect};
use super::log::Log;
use super::sim::{Mods, Out};
use super::stats;
use crate::mu::{Method, Sample, Setup};
use gough::mf::Params;
use gough::mu::State;
use gough::proto::Wheel;
use serde::Serialize;

/// The μ verdict needs a shrink of at least this.
pub const MU_MIN_SHRINK: f64 = 0.2;
/// ... of an error of at least this RMS (μ units): below it the estimator is right.
pub const MU_MIN_RMSE: f64 = 0.02;
/// Effects whose μ shrink is within this fraction of the best one's are reported with it.
pub const MU_CLOSE: f64 = 0.2;

/// The μ part of the report.
#[derive(Debug, Clone, Serialize)]
pub struct MuReport {
    /// Share of rows with an estimate (state not `fallback`).
    pub coverage: f64,
    /// RMS error of the estimate against the reference on those rows.
    pub rmse: f64,
    /// Mean error (estimate − reference).
    pub bias: f64,
    /// Regions holding the error, largest share first.
    #[serde(rename = "where")]
    pub where_: Vec<MuRegion>,
    /// Every effect applied to the estimator, largest shrink first.
    pub effects: Vec<MuEffect>,
    /// Which effect explains the error.
    pub verdict: MuVerdict,
}

/// A region of the μ error.
#[derive(Debug, Clone, Serialize)]
pub struct MuRegion {
    /// Operating variable.
    pub variable: String,
    /// Lower end.
    pub lo: f64,
    /// Upper end.
    pub hi: f64,
    /// Share of the squared μ error here.
    pub share_of_error: f64,
    /// Share of the estimated rows here.
    pub share_of_rows: f64,
    /// RMS μ error here.
    pub rmse: f64,
    /// Mean μ error here.
    pub bias: f64,
}

/// One effect applied to the estimator.
#[derive(Debug, Clone, Serialize)]
pub struct MuEffect {
    /// Name.
    pub effect: String,
    /// 1 − rmse_after/rmse_before of the μ error (rows estimated both times).
    pub shrink: f64,
    /// RMS μ error with the effect applied.
    pub rmse_after: f64,
    /// How it was applied, or why it could not be.
    pub note: String,
}

/// The μ verdict.
#[derive(Debug, Clone, Serialize)]
pub struct MuVerdict {
    /// Effect or `none`.
    pub effect: String,
    /// Its μ shrink.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub shrink: Option<f64>,
    /// Is it the force diagnosis's verdict too?
    pub agrees_with_forces: bool,
    /// Effects that explain the μ error about as well (μ shrink within [`MU_CLOSE`] of the
    /// best, relative, or 0.02).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub indistinguishable_from: Vec<String>,
}

/// Runs the product's estimator ([`Method::Bank`], through [`crate::mu::Estimator`]) over the
/// log, its wheel as SIM.tir describes the tyre; `meas` (Fx, Fy, Mz per row) replaces the
/// measured channels. Returns (μ, has an estimate) per row.
pub fn run_estimator(
    params: &Params<f64>,
    log: &Log,
    meas: &[Out],
) -> Result<Vec<(f64, bool)>, String> {
    let mut est = Method::Bank
        .estimator(params, &Setup::one_wheel(None))
        .map_err(|e| format!("friction estimator: {e}"))?;
    Ok((0..log.len())
        .map(|i| {
            let s = Sample {
                t: log.t[i],
                fz: log.fz[i],
                fy: meas[i][1],
                mz: meas[i][2],
                fx: Some(meas[i][0]),
                vx: Some(log.vx[i]),
                kappa: Some(log.kappa[i]),
                alpha: Some(log.alpha[i]),
                gamma: Some(log.gamma[i]),
            };
            let e = est.update(Wheel::FrontLeft, &s);
            (e.mu, e.state != State::Fallback)
        })
        .collect())
}

fn error_stats(mu: &[(f64, bool)], reference: &[f64], mask: &[bool]) -> (f64, f64) {
    let e: Vec<f64> = (0..mu.len())
        .filter(|&i| mask[i])
        .map(|i| mu[i].0 - reference[i])
        .collect();
    (stats::rms(e.iter().copied()), stats::mean(&e))
}

/// The μ diagnosis (module doc). `scores`: the force diagnosis's effects with their fits.
pub fn diagnose(
    ctx: &Ctx,
    scores: &[Score],
    force_verdict: Option<Effect>,
) -> Result<MuReport, String> {
    let log = ctx.log;
    let Some(reference) = &log.mu else {
        return Err("no mu column".into());
    };
    let p = &ctx.sim.params;
    let base = run_estimator(p, log, &log.meas)?;
    let mask: Vec<bool> = base.iter().map(|b| b.1).collect();
    let n_est = mask.iter().filter(|&&m| m).count();
    let (rmse, bias) = error_stats(&base, reference, &mask);
    let err: Vec<f64> = (0..log.len()).map(|i| base[i].0 - reference[i]).collect();
    let where_ = mu_regions(log, &err, &mask);

    let mut effects = Vec::new();
    for s in scores {
        let name = s.effect.name().to_string();
        let (Some(sp), None) = (&s.spec, &s.not_applicable) else {
            effects.push(MuEffect {
                effect: name,
                shrink: 0.0,
                rmse_after: rmse,
                note: format!(
                    "not applicable: {}",
                    s.not_applicable.clone().unwrap_or_default()
                ),
            });
            continue;
        };
        let applied = contribution(ctx, s.effect, sp, &s.theta).and_then(|(delta, note)| {
            let m: Vec<Out> = log
                .meas
                .iter()
                .zip(&delta)
                .map(|(x, d)| [x[0] - d[0], x[1] - d[1], x[2] - d[2]])
                .collect();
            run_estimator(p, log, &m).map(|r| (r, note))
        });
        match applied {
            Ok((r, note)) => {
                let both: Vec<bool> = (0..log.len()).map(|i| mask[i] && r[i].1).collect();
                let (b, _) = error_stats(&base, reference, &both);
                let (a, _) = error_stats(&r, reference, &both);
                effects.push(MuEffect {
                    effect: name,
                    shrink: if b > 0.0 { 1.0 - a / b } else { 0.0 },
                    rmse_after: a,
                    note,
                });
            }
            Err(why) => effects.push(MuEffect {
                effect: name,
                shrink: 0.0,
                rmse_after: rmse,
                note: why,
            }),
        }
    }
    let verdict = mu_verdict(&effects, rmse, force_verdict);
    let mut order: Vec<usize> = (0..effects.len()).collect();
    order.sort_by(|&a, &b| effects[b].shrink.total_cmp(&effects[a].shrink));
    let effects = order.iter().map(|&k| effects[k].clone()).collect();
    Ok(MuReport {
        coverage: n_est as f64 / log.len().max(1) as f64,
        rmse,
        bias,
        where_,
        effects,
        verdict,
    })
}

/// The μ verdict: the effect with the largest μ shrink, and those that come close to it (within
/// [`MU_CLOSE`] of its shrink, relative, or 0.02). The estimator's error is strongly
/// autocorrelated (a likelihood with memory) and concentrated where the effect acts, so neither a row-level
/// nor a 5-block test has a usable standard error here; the band is a practical-equivalence
/// margin. When the force diagnosis's verdict is in that group (and itself shrinks the error by
/// [`MU_MIN_SHRINK`]) it is preferred: the forces are the stronger evidence of which effect is
/// present. Needs an error of at least [`MU_MIN_RMSE`] and a shrink of at least [`MU_MIN_SHRINK`].
fn mu_verdict(effects: &[MuEffect], rmse: f64, force: Option<Effect>) -> MuVerdict {
    let none = MuVerdict {
        effect: "none".into(),
        shrink: None,
        agrees_with_forces: force.is_none(),
        indistinguishable_from: vec![],
    };
    let Some(top) =
        (0..effects.len()).max_by(|&a, &b| effects[a].shrink.total_cmp(&effects[b].shrink))
    else {
        return none;
    };
    let best = effects[top].shrink;
    if rmse < MU_MIN_RMSE || best < MU_MIN_SHRINK {
        return none;
    }
    let margin = (MU_CLOSE * best).max(0.02);
    let group: Vec<usize> = (0..effects.len())
        .filter(|&k| effects[k].shrink >= best - margin)
        .collect();
    let pick = force
        .and_then(|f| {
            group
                .iter()
                .copied()
                .find(|&k| effects[k].effect == f.name() && effects[k].shrink >= MU_MIN_SHRINK)
        })
        .unwrap_or(top);
    MuVerdict {
        effect: effects[pick].effect.clone(),
        shrink: Some(effects[pick].shrink),
        agrees_with_forces: force.map(|f| f.name()) == Some(effects[pick].effect.as_str()),
        indistinguishable_from: group
            .iter()
            .filter(|&&k| k != pick)
            .map(|&k| effects[k].effect.clone())
            .collect(),
    }
}

/// The effect's contribution to the channels, Δ = with − without (module doc), and a note.
fn contribution(
    ctx: &Ctx,
    effect: Effect,
    sp: &Spec,
    theta: &[f64],
) -> Result<(Vec<Out>, String), String> {
    let log = ctx.log;
    let sim = ctx.sim;
    let with = sp
        .predict(ctx, theta, None)
        .ok_or("the sim with the effect failed on this log")?;
    let fail = |(i, e): (usize, String)| format!("sim without the effect, row {i}: {e}");
    let (without, note) = match effect {
        Effect::Camber => {
            let mut l = log.clone();
            let g = stats::median(&log.gamma);
            l.gamma.iter_mut().for_each(|x| *x = g);
            let s2 = sim.like(sim.params.clone(), &l);
            let w = s2.run(&l, &sim.params, &Mods::default()).map_err(fail)?;
            (
                w.out,
                "camber contribution (varying γ, re-fitted terms) removed",
            )
        }
        Effect::InflationPressure => {
            let mut l = log.clone();
            l.p = None;
            let w = sim.run(&l, &sim.params, &Mods::default()).map_err(fail)?;
            (
                w.out,
                "pressure contribution (p ≠ INFLPRES, re-fitted terms) removed",
            )
        }
        Effect::TurnSlip => {
            let mut l = log.clone();
            l.phit = None;
            let s2 = sim.like(sim.params.clone(), &l);
            let w = s2.run(&l, &sim.params, &Mods::default()).map_err(fail)?;
            (
                w.out,
                "turn-slip contribution removed (the estimator's model has none)",
            )
        }
        Effect::RelaxationLength => {
            let mut s2 = sim.clone();
            s2.filters = false;
            s2.opts.transient = false;
            let w = s2.run(log, &sim.params, &Mods::default()).map_err(fail)?;
            (w.out, "transient (relaxation) contribution removed")
        }
        _ => (ctx.base.out.clone(), "the effect's contribution removed"),
    };
    let delta = with
        .iter()
        .zip(&without)
        .map(|(a, b)| [a[0] - b[0], a[1] - b[1], a[2] - b[2]])
        .collect();
    Ok((delta, note.to_string()))
}

fn mu_regions(log: &Log, err: &[f64], mask: &[bool]) -> Vec<MuRegion> {
    let rows: Vec<usize> = (0..log.len()).filter(|&i| mask[i]).collect();
    let total: f64 = rows.iter().map(|&i| err[i] * err[i]).sum();
    if rows.is_empty() || total <= 0.0 {
        return vec![];
    }
    let mut out = Vec::new();
    for (name, x) in super::regions::variables(log) {
        let xs: Vec<f64> = rows.iter().map(|&i| x[i]).collect();
        let (lo, hi) = xs
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                (a.min(v), b.max(v))
            });
        if hi.partial_cmp(&lo) != Some(std::cmp::Ordering::Greater) {
            continue;
        }
        let nb = super::regions::BINS;
        let mut ed: Vec<f64> = (0..=nb)
            .map(|k| stats::quantile(&xs, k as f64 / nb as f64))
            .collect();
        ed.dedup_by(|a, b| (*a - *b).abs() <= 1e-12 * (hi - lo));
        if ed.len() < 3 {
            continue;
        }
        for b in 0..ed.len() - 1 {
            let last = b + 2 == ed.len();
            let sel: Vec<usize> = rows
                .iter()
                .copied()
                .filter(|&i| x[i] >= ed[b] && (x[i] < ed[b + 1] || last))
                .collect();
            if sel.is_empty() {
                continue;
            }
            let e: Vec<f64> = sel.iter().map(|&i| err[i]).collect();
            let share = e.iter().map(|v| v * v).sum::<f64>() / total;
            let rs = sel.len() as f64 / rows.len() as f64;
            if share < super::regions::MIN_SHARE || share < super::regions::MIN_CONCENTRATION * rs {
                continue;
            }
            out.push(MuRegion {
                variable: name.into(),
                lo: ed[b],
                hi: ed[b + 1],
                share_of_error: share,
                share_of_rows: rs,
                rmse: stats::rms(e.iter().copied()),
                bias: stats::mean(&e),
            });
        }
    }
    out.sort_by(|a, b| b.share_of_error.total_cmp(&a.share_of_error));
    out.truncate(super::regions::MAX_REGIONS);
    out
}
