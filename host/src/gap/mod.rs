//! Sim-to-real gap diagnosis: where the sim and a measured log part, which unmodelled effect
//! causes it, and how far adding that effect shrinks the gap on data it was not fitted on.
//!
//! `gough gap diagnose --tir SIM.tir --log LOG.csv --report REPORT.json [--plots DIR]`:
//! 1. [`sim`]: the tyre model of SIM.tir (steady-state Magic Formula, plus the relaxation
//!    filters when the file has what they need) driven by the log's inputs, first-order hold.
//! 2. Baseline RMSE per channel and the noise floor ([`stats::noise_floor`]: the white part of
//!    the residual, from its second differences, robustly).
//! 3. [`regions`]: the operating regions (and frequency bands) that hold the gap.
//! 4. [`effects`]: ten candidate effects, each a parametric extension with a physical form, each
//!    fitted ([`fit`]: bounded Levenberg–Marquardt) and scored by blocked cross-validation
//!    ([`cv`]): held-out shrink of the gap in noise units.
//! 5. The verdict: the best effect when it closes a meaningful ([`MIN_SHRINK`]), significant
//!    ([`MIN_Z`]) part of the gap, else `none`; effects the data cannot tell apart
//!    ([`IND_T`]) are reported with it.
//! 6. With a `mu` column, the same questions for the friction estimator's output ([`mu`]).
//! 7. [`plot`]: residual maps before and after the winning effect.
//!
//! [`mod@bench`] is the withheld-effect benchmark (`gough gap bench`): logs from a truth model with
//! one effect switched on, diagnosed from SIM.tir and the log alone.
//!
//! Leaves out: Mx and My (not in the log's required channels); several simultaneous effects
//! (the candidates are tried one at a time); logs of more than one wheel.

pub mod bench;
pub mod cv;
pub mod effects;
pub mod fit;
pub mod log;
pub mod mu;
pub mod plot;
pub mod regions;
pub mod report;
pub mod sim;
pub mod stats;

use effects::{Ctx, Effect};
use gough::mf::Params;
use regions::Channels;
use report::{Baseline, EffectReport, HeldOut, Method, Report, SimInfo, Verdict};
use std::collections::BTreeMap;

/// The channels, in the order of every `[f64; 3]`.
pub const CHANNELS: [&str; 3] = ["fx", "fy", "mz"];

/// Verdict rule: the best effect must close at least this share of the gap (held-out, noise
/// units). Set from the benchmark's none cases (`gough gap bench`, README): the largest best
/// shrink over its none-case logs was below a third of it.
pub const MIN_SHRINK: f64 = 0.005;
/// ... and the held-out improvement must be significant against the noise floor:
/// [`cv::z_value`] at least this (a χ²-style test; under "the effect only fits noise" z ≤ 0 on
/// average with unit standard deviation).
pub const MIN_Z: f64 = 5.0;
/// Two effects are indistinguishable when their shrinks differ by less than this many standard
/// errors of the paired block differences (a 1-SE band would call two identical explanations
/// different about a third of the time).
pub const IND_T: f64 = 2.0;

/// Options of a diagnosis.
#[derive(Debug, Clone, Default)]
pub struct Options {
    /// Show a progress bar on the terminal.
    pub progress: bool,
    /// Draw residual maps into this directory.
    pub plots: Option<std::path::PathBuf>,
    /// At most this many training rows per fit (`None`: [`cv::FIT_ROWS`]); small values make
    /// quick tests.
    pub fit_rows: Option<usize>,
}

/// The outcome of a diagnosis: the report and what the benchmark scores.
#[derive(Debug, Clone)]
pub struct Diagnosis {
    /// The report.
    pub report: Report,
    /// Noise floor per channel.
    pub noise: [f64; 3],
    /// Sim RMSE per channel.
    pub rmse_before: [f64; 3],
    /// The verdict (`None`: "none").
    pub verdict: Option<Effect>,
    /// Effects indistinguishable from the verdict.
    pub indistinguishable: Vec<Effect>,
    /// Held-out shrink and its significance z per effect (0 for those not applicable).
    pub shrinks: Vec<(Effect, f64, f64)>,
}

fn method() -> Method {
    Method {
        cross_validation: format!(
            "blocked: {} contiguous blocks of equal row count; each block predicted by the \
             effect fitted on the other blocks (at most {} evenly spaced training rows per fit \
             for effects that evaluate the Magic Formula)",
            cv::K,
            cv::FIT_ROWS
        ),
        shrink: "1 - sum_c(rmse_after_c/noise_c) / sum_c(rmse_before_c/noise_c), c = fx, fy, mz, \
                 on held-out rows"
            .into(),
        verdict_rule: format!(
            "the best effect is the verdict when its held-out shrink >= {MIN_SHRINK} and the \
             held-out improvement is significant against the noise floor: z = dSSE / (2 \
             sqrt(sum (delta/noise)^2)) >= {MIN_Z}, delta the change of prediction (chi2-style; \
             z <= 0 on average when the effect only fits noise); else none. {MIN_SHRINK} is set \
             from the benchmark's none-case logs (gough gap bench): the largest best shrink \
             found there stays far below it"
        ),
        indistinguishable_rule: format!(
            "an effect is indistinguishable from the verdict when their shrinks differ by at \
             most {IND_T} standard errors of the paired block differences (or 0.001)"
        ),
    }
}

/// Runs the diagnosis of `log` against the sim of `params`. `tir` and `log_name` name the
/// inputs in the report and in errors.
pub fn diagnose(
    params: Params<f64>,
    log: &log::Log,
    tir: &str,
    log_name: &str,
    opts: &Options,
) -> Result<Diagnosis, String> {
    let sim = sim::Sim::new(params, log);
    let ctx = Ctx::new(log, &sim)
        .map_err(|(i, e)| format!("{log_name}: line {}: sim: {e}", log.line(i)))?;
    let steps = effects::ALL.len() * (cv::K + 1);
    let bar = opts.progress.then(|| {
        let b = indicatif::ProgressBar::with_draw_target(
            Some(steps as u64),
            indicatif::ProgressDrawTarget::stderr(),
        );
        if let Ok(style) = indicatif::ProgressStyle::with_template(
            "gap {bar:40} {pos}/{len} fits {elapsed_precise} (eta {eta}) {msg}",
        ) {
            b.set_style(style);
        }
        b
    });
    let mut scores = Vec::new();
    for e in effects::ALL {
        if let Some(b) = &bar {
            b.set_message(e.name());
        }
        let mut tick = || {
            if let Some(b) = &bar {
                b.inc(1);
            }
        };
        scores.push(cv::score(
            &ctx,
            e,
            opts.fit_rows.unwrap_or(cv::FIT_ROWS).max(10),
            &mut tick,
        ));
    }
    if let Some(b) = &bar {
        b.finish_and_clear();
    }
    // Largest held-out shrink first (an effect that does not apply scores 0); among equals the
    // applicable ones first.
    scores.sort_by(|a, b| {
        b.shrink
            .total_cmp(&a.shrink)
            .then(b.not_applicable.is_none().cmp(&a.not_applicable.is_none()))
    });
    let base_r = ctx.base_resid();
    let noise = ctx.noise;
    let n = log.len();
    let rmse_before = cv::rmse_rows(&base_r, 0..n);

    // Verdict.
    let best = scores.iter().find(|s| s.not_applicable.is_none());
    let winner = best.filter(|s| s.shrink >= MIN_SHRINK && s.z >= MIN_Z);
    let indist: Vec<Effect> = match winner {
        Some(w) => scores
            .iter()
            .filter(|s| {
                s.effect != w.effect
                    && s.not_applicable.is_none()
                    && cv::indistinguishable(w, s, IND_T)
            })
            .map(|s| s.effect)
            .collect(),
        None => vec![],
    };
    let verdict = match (winner, best) {
        (Some(w), _) => {
            let c = (0..3)
                .max_by(|&a, &b| {
                    let d = |c: usize| (w.rmse_before[c] - w.rmse_after[c]) / noise[c];
                    d(a).total_cmp(&d(b))
                })
                .unwrap_or(1);
            Verdict {
                effect: w.effect.name().into(),
                shrink: Some(w.shrink),
                channel: Some(CHANNELS[c].into()),
                indistinguishable_from: indist.iter().map(|e| e.name().to_string()).collect(),
                reason: None,
            }
        }
        (None, Some(b)) => Verdict {
            effect: "none".into(),
            shrink: None,
            channel: None,
            indistinguishable_from: vec![],
            reason: Some(format!(
                "best candidate {} closes {:.4} of the gap held-out (needs >= {MIN_SHRINK}) with \
                 significance z = {:.1} against the noise floor (needs >= {MIN_Z})",
                b.effect.name(),
                b.shrink,
                b.z
            )),
        },
        (None, None) => Verdict {
            effect: "none".into(),
            shrink: None,
            channel: None,
            indistinguishable_from: vec![],
            reason: Some("no candidate effect applies to this log".into()),
        },
    };

    let after = winner.map(|w| w.heldout_resid.as_slice());
    let where_ = regions::regions(log, &base_r, after, &noise);

    let effects_report: Vec<EffectReport> = scores
        .iter()
        .map(|s| {
            let (params, params_sim) = match &s.spec {
                Some(sp) => (
                    sp.reported(&s.theta)
                        .into_iter()
                        .collect::<BTreeMap<_, _>>(),
                    sp.reported(&sp.starts[0])
                        .into_iter()
                        .map(|(k, v)| if k == "tau" { (k, 0.0) } else { (k, v) })
                        .collect::<BTreeMap<_, _>>(),
                ),
                None => (BTreeMap::new(), BTreeMap::new()),
            };
            EffectReport {
                effect: s.effect.name().into(),
                shrink: s.shrink,
                shrink_se: s.shrink_se,
                z: s.z,
                shrink_by_channel: s.shrink_by_channel.into(),
                heldout: HeldOut {
                    rmse_before: s.rmse_before.into(),
                    rmse_after: s.rmse_after.into(),
                },
                params,
                params_sim,
                form: s.effect.form().into(),
                applicable: s.not_applicable.is_none(),
                note: s.not_applicable.clone(),
            }
        })
        .collect();

    let mu = match &log.mu {
        Some(_) => Some(mu::diagnose(&ctx, &scores, winner.map(|w| w.effect))?),
        None => None,
    };

    if let Some(dir) = &opts.plots {
        let win = winner.and_then(|w| w.spec.as_ref().map(|sp| (sp, w)));
        plot::residual_maps(dir, &ctx, win)?;
    }

    let report = Report {
        tir: tir.into(),
        log: log_name.into(),
        rows: n,
        sim: SimInfo {
            version: sim.params.version.name().into(),
            relaxation_filters: sim.filters,
            turn_slip: sim.turn_slip,
            pressure: if log.p.is_some() {
                "the log's p column".into()
            } else {
                "INFLPRES of SIM.tir".into()
            },
            hold: if sim.filters {
                "first-order hold: each relaxation step gets the kinematics at its midpoint \
                 (second-order exact); sigma of the step's start"
                    .into()
            } else {
                "steady state: no filters, each row evaluated at its own inputs".into()
            },
        },
        baseline: Baseline {
            rmse: Channels::from(rmse_before),
            noise_floor: Channels::from(noise),
            noise_floor_method: "white part of the sim residual: 1.4826*MAD of its second \
                                 differences / sqrt(6)"
                .into(),
        },
        where_,
        effects: effects_report,
        verdict,
        method: method(),
        mu,
    };
    Ok(Diagnosis {
        report,
        noise,
        rmse_before,
        verdict: winner.map(|w| w.effect),
        indistinguishable: indist,
        shrinks: scores.iter().map(|s| (s.effect, s.shrink, s.z)).collect(),
    })
}
