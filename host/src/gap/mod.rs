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
//!    (the same two tests between them: [`cv::indistinguishable`]) are reported with it.
//! 6. Forward selection: the candidates ranked by how much they lower the misfit on top of the
//!    verdict ([`cv::screen_second`]), the best [`SECOND_CANDIDATES`] cross-validated as pairs
//!    with it ([`cv::score_pair`], both refitted together); the best pair's second effect is
//!    named too when it adds [`MIN_ADD_SHRINK`] of held-out shrink at significance
//!    [`MIN_Z_ADD`] over the first alone. With a second effect, the first is re-chosen among the
//!    best single candidates by the pair's held-out shrink (a second effect can make the wrong
//!    one look best alone).
//! 6. With a `mu` column, the same questions for the friction estimator's output ([`mu`]).
//! 7. `plot` (feature `plot`): residual maps before and after the winning effect.
//!
//! [`mod@bench`] is the withheld-effect benchmark (`gough gap bench`): logs from a truth model with
//! one effect or a pair switched on, diagnosed from SIM.tir and the log alone.
//!
//! Leaves out: Mx and My (not in the log's required channels); more than two simultaneous
//! effects; logs of more than one wheel.

pub mod bench;
pub mod cv;
pub mod effects;
pub mod fit;
pub mod log;
pub mod mu;
#[cfg(feature = "plot")]
pub mod plot;
pub mod regions;
pub mod report;
pub mod sim;
pub mod stats;
pub mod tirfile;

use effects::{Ctx, Effect};
use gough::mf::Params;
use regions::Channels;
use report::{
    Baseline, EffectReport, HeldOut, Method, NamedEffect, PairParams, Report, SecondReport,
    SimInfo, Verdict,
};
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

/// A second effect is kept only when the pair closes at least this much more of the gap
/// held-out than the first effect alone (shrink units) ...
pub const MIN_ADD_SHRINK: f64 = 0.02;
/// ... and that improvement is significant against the noise floor ([`cv::z_value`] of the
/// first effect's held-out residual against the pair's) at least this.
pub const MIN_Z_ADD: f64 = 5.0;
/// The second effect is sought among at most this many candidates, cross-validated as pairs:
/// those that lower the in-sample misfit most when fitted on top of the first
/// ([`cv::screen_second`], one fit each).
pub const SECOND_CANDIDATES: usize = 3;
/// With a second effect named, this many other single candidates (the best alone) are tried
/// as the first effect of the pair.
pub const FIRST_ALTERNATIVES: usize = 2;

/// Options of a diagnosis.
#[derive(Debug, Clone, Default)]
pub struct Options {
    /// Show a progress bar on the terminal.
    pub progress: bool,
    /// Draw residual maps into this directory (with the `plot` feature; without it, an error).
    pub plots: Option<std::path::PathBuf>,
    /// At most this many training rows per fit (`None`: [`cv::FIT_ROWS`]); small values make
    /// quick tests.
    pub fit_rows: Option<usize>,
    /// The fits' evaluations row by row with `mf::eval`, the reference ([`sim::Sim::lanes`]
    /// off): the same results, bit for bit, in every build; without it, optimised builds
    /// evaluate in lanes, about 1.5× faster and different in the last bits.
    pub exact: bool,
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
    /// The verdict (`None`: "none"): the first effect named.
    pub verdict: Option<Effect>,
    /// Every effect named (the verdict first; a second one from forward selection).
    pub named: Vec<Effect>,
    /// The second-effect candidates tried: (effect, held-out shrink of the pair, z of its
    /// improvement over the first alone).
    pub seconds: Vec<(Effect, f64, f64)>,
    /// Effects indistinguishable from the verdict.
    pub indistinguishable: Vec<Effect>,
    /// Held-out shrink and its significance z per effect (0 for those not applicable).
    pub shrinks: Vec<(Effect, f64, f64)>,
    /// The corrected tyre file's coefficients (with a verdict): [`tirfile`].
    pub corrected: Option<tirfile::Corrected>,
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
            "an effect is indistinguishable from the verdict unless the verdict closes at least \
             {MIN_SHRINK} more of the gap held-out and that is significant against the noise \
             floor: z = (SSE_other - SSE_verdict) / (2 sqrt(sum (delta/noise)^2)) >= {MIN_Z}, \
             delta the difference of their held-out predictions (the verdict rule, between two \
             effects)"
        ),
        second_effect_rule: format!(
            "forward selection: every other candidate fitted on top of the first effect (in \
             sample, one fit) and the {SECOND_CANDIDATES} that lower the misfit most \
             cross-validated as pairs (the blocks as above, both effects refitted together, \
             their changes of the sim's output superposed); the best pair's second effect is \
             named when the pair's held-out shrink exceeds the first's alone by >= \
             {MIN_ADD_SHRINK} and z of the first's held-out residual against the pair's >= \
             {MIN_Z_ADD}; then the first effect is re-chosen among the best single candidates by \
             the shrink of their pair with the second. At most two effects"
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
    #[cfg(not(feature = "plot"))]
    if let Some(dir) = &opts.plots {
        return Err(format!(
            "{}: residual maps need gough-host's `plot` feature",
            dir.display()
        ));
    }
    let mut sim = sim::Sim::new(params, log);
    sim.lanes &= !opts.exact;
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
    let first_round = winner;
    let indist: Vec<Effect> = match winner {
        Some(w) => scores
            .iter()
            .filter(|s| {
                s.effect != w.effect
                    && s.not_applicable.is_none()
                    && cv::indistinguishable(w, s, &noise, MIN_SHRINK, MIN_Z)
            })
            .map(|s| s.effect)
            .collect(),
        None => vec![],
    };
    // Forward selection: a second effect on top of the first, kept only when the pair is
    // significantly better than the first alone on held-out blocks.
    let fit_rows = opts.fit_rows.unwrap_or(cv::FIT_ROWS).max(10);
    let mut pairs: Vec<cv::PairScore> = Vec::new();
    if let Some(w) = winner {
        let mut screened: Vec<(Effect, f64)> = scores
            .iter()
            .filter(|s| s.effect != w.effect && s.not_applicable.is_none())
            .filter_map(|s| {
                cv::screen_second(&ctx, w, s.effect, fit_rows)
                    .filter(|d| *d > 0.0)
                    .map(|d| (s.effect, d))
            })
            .collect();
        screened.sort_by(|a, b| b.1.total_cmp(&a.1));
        let cands: Vec<Effect> = screened
            .iter()
            .take(SECOND_CANDIDATES)
            .map(|c| c.0)
            .collect();
        let bar2 = opts.progress.then(|| {
            indicatif::ProgressBar::with_draw_target(
                Some((cands.len() * cv::K) as u64),
                indicatif::ProgressDrawTarget::stderr(),
            )
        });
        for e in cands {
            let mut tick = || {
                if let Some(b) = &bar2 {
                    b.inc(1);
                }
            };
            if let Some(ps) = cv::score_pair(&ctx, w, e, fit_rows, &mut tick) {
                pairs.push(ps);
            }
        }
        if let Some(b) = &bar2 {
            b.finish_and_clear();
        }
        pairs.sort_by(|a, b| b.score.shrink.total_cmp(&a.score.shrink));
    }
    let adds = |first: &cv::Score, p: &cv::PairScore| {
        p.score.shrink - first.shrink >= MIN_ADD_SHRINK && p.z_added >= MIN_Z_ADD
    };
    let mut second: Option<cv::PairScore> = winner
        .and_then(|w| pairs.first().filter(|p| adds(w, p)))
        .cloned();
    // With a second effect, re-choose the first: the best single candidates other than these
    // two, each paired with the second; the best pair (that still passes the rule) wins.
    let mut first_alts: Vec<(Effect, cv::PairScore)> = Vec::new();
    let mut winner = winner;
    if let (Some(w), Some(p2)) = (winner, second.clone()) {
        let e2 = p2.score.effect;
        for alt in scores
            .iter()
            .filter(|s| {
                s.not_applicable.is_none()
                    && s.effect != w.effect
                    && s.effect != e2
                    && s.shrink >= MIN_SHRINK
                    && s.z >= MIN_Z
            })
            .take(FIRST_ALTERNATIVES)
        {
            if let Some(ps) = cv::score_pair(&ctx, alt, e2, fit_rows, &mut || {}) {
                if adds(alt, &ps)
                    && ps.score.shrink > second.as_ref().map_or(0.0, |q| q.score.shrink)
                {
                    // The better pair: the one held so far becomes an alternative.
                    let cur_first = winner.map(|x| x.effect).unwrap_or(w.effect);
                    if let Some(old) = second.replace(ps) {
                        first_alts.push((cur_first, old));
                    }
                    winner = Some(alt);
                } else {
                    first_alts.push((alt.effect, ps));
                }
            }
        }
    }
    let second = second.as_ref();
    // The first effect's alternatives: alone, those indistinguishable from it alone; with a
    // second effect, the other firsts whose pair with it is indistinguishable from the pair.
    let indist: Vec<Effect> = match (winner, second) {
        (Some(_), Some(p2)) => first_alts
            .iter()
            .filter(|(_, q)| cv::indistinguishable(&p2.score, &q.score, &noise, MIN_SHRINK, MIN_Z))
            .map(|(e, _)| *e)
            .collect(),
        _ => indist,
    };
    let swapped = winner.map(|w| w.effect) != first_round.map(|w| w.effect);
    let second_indist: Vec<Effect> = match second {
        Some(p2) if !swapped => pairs
            .iter()
            .filter(|q| q.score.effect != p2.score.effect)
            .filter(|q| cv::indistinguishable(&p2.score, &q.score, &noise, MIN_SHRINK, MIN_Z))
            .map(|q| q.score.effect)
            .collect(),
        _ => vec![],
    };
    let channel_of = |before: &[f64; 3], after: &[f64; 3]| -> String {
        let c = (0..3)
            .max_by(|&a, &b| {
                let d = |c: usize| (before[c] - after[c]) / noise[c];
                d(a).total_cmp(&d(b))
            })
            .unwrap_or(1);
        CHANNELS[c].into()
    };
    let names = |v: &[Effect]| v.iter().map(|e| e.name().to_string()).collect::<Vec<_>>();
    let verdict = match (winner, best) {
        (Some(w), _) => {
            let mut named = vec![NamedEffect {
                effect: w.effect.name().into(),
                shrink_alone: w.shrink,
                shrink_added: w.shrink,
                z_added: w.z,
                channel: channel_of(&w.rmse_before, &w.rmse_after),
                indistinguishable_from: names(&indist),
            }];
            let total = match second {
                Some(p2) => {
                    let e2 = p2.score.effect;
                    let alone = scores
                        .iter()
                        .find(|s| s.effect == e2)
                        .map(|s| s.shrink)
                        .unwrap_or(0.0);
                    named[0].shrink_added = p2.score.shrink - alone;
                    named.push(NamedEffect {
                        effect: e2.name().into(),
                        shrink_alone: alone,
                        shrink_added: p2.score.shrink - w.shrink,
                        z_added: p2.z_added,
                        channel: channel_of(&w.rmse_after, &p2.score.rmse_after),
                        indistinguishable_from: names(&second_indist),
                    });
                    p2.score.shrink
                }
                None => w.shrink,
            };
            Verdict {
                effect: w.effect.name().into(),
                shrink: Some(total),
                channel: Some(named[0].channel.clone()),
                indistinguishable_from: names(&indist),
                effects: named,
                reason: None,
            }
        }
        (None, Some(b)) => Verdict {
            effect: "none".into(),
            shrink: None,
            channel: None,
            indistinguishable_from: vec![],
            effects: vec![],
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
            effects: vec![],
            reason: Some("no candidate effect applies to this log".into()),
        },
    };
    let seconds_report: Vec<SecondReport> = match first_round {
        Some(w) => pairs
            .iter()
            .map(|p| SecondReport {
                effect: p.score.effect.name().into(),
                shrink_pair: p.score.shrink,
                shrink_added: p.score.shrink - w.shrink,
                z_added: p.z_added,
                kept: second.is_some_and(|s| s.score.effect == p.score.effect),
            })
            .collect(),
        None => vec![],
    };
    // The kept pair's parameters on the whole log (reported with each effect).
    let pair_theta = match (winner, second) {
        (Some(w), Some(p2)) => cv::fit_pair_all(&ctx, w, p2, fit_rows),
        _ => None,
    };

    // The corrected file: the named effects at their whole-log fits.
    let corrected = match (winner, second, &pair_theta) {
        (Some(w), Some(p2), Some((ta, tb))) => match (&w.spec, &p2.score.spec) {
            (Some(sa), Some(sb)) => Some(tirfile::correct(
                &ctx,
                &[(sa, ta.as_slice()), (sb, tb.as_slice())],
                p2.score.shrink,
                fit_rows,
            )),
            _ => None,
        },
        (Some(w), None, _) => w
            .spec
            .as_ref()
            .map(|sa| tirfile::correct(&ctx, &[(sa, w.theta.as_slice())], w.shrink, fit_rows)),
        _ => None,
    };

    let after = match (second, winner) {
        (Some(p2), _) => Some(p2.score.heldout_resid.as_slice()),
        (None, w) => w.map(|w| w.heldout_resid.as_slice()),
    };
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
                        .map(|(k, v)| {
                            if k.starts_with("tau") {
                                (k, 0.0)
                            } else {
                                (k, v)
                            }
                        })
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

    #[cfg(feature = "plot")]
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
        second: seconds_report,
        pair_params: match (winner, second, pair_theta) {
            (Some(w), Some(p2), Some((ta, tb))) => match (&w.spec, &p2.score.spec) {
                (Some(sa), Some(sb)) => Some(PairParams {
                    first: sa.reported(&ta).into_iter().collect(),
                    second: sb.reported(&tb).into_iter().collect(),
                }),
                _ => None,
            },
            _ => None,
        },
        method: method(),
        mu,
        corrected_tir: corrected.as_ref().map(|c| c.report.clone()),
    };
    Ok(Diagnosis {
        report,
        noise,
        rmse_before,
        verdict: winner.map(|w| w.effect),
        named: winner
            .map(|w| w.effect)
            .into_iter()
            .chain(second.map(|p| p.score.effect))
            .collect(),
        seconds: pairs
            .iter()
            .map(|p| (p.score.effect, p.score.shrink, p.z_added))
            .collect(),
        indistinguishable: indist,
        shrinks: scores.iter().map(|s| (s.effect, s.shrink, s.z)).collect(),
        corrected,
    })
}

/// Writes `text` to `path` through a temporary file beside it (no half-written file), the
/// directory created when missing.
pub fn write_atomic(path: &std::path::Path, text: &str) -> Result<(), String> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)
            .map_err(|e| format!("{}: cannot create: {e}", dir.display()))?;
    }
    let tmp = path.with_extension("tmp");
    std::fs::write(&tmp, text)
        .and_then(|_| std::fs::rename(&tmp, path))
        .map_err(|e| format!("{}: cannot write: {e}", path.display()))
}
