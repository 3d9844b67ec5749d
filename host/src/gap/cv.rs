//! Blocked cross-validation over time segments.
//!
//! The log is cut into [`K`] contiguous blocks of equal row count. For each block, the effect is
//! fitted on the other blocks and predicts the block; every row is thus predicted once, by
//! parameters that never saw it. Contiguous blocks (rather than random rows) keep neighbouring,
//! correlated samples on the same side of the split, so the held-out score is not flattered by
//! the autocorrelation of the gap. Stateful parts (relaxation, lag, temperature) run through the
//! whole log with the fold's parameters; only their parameters are held out.
//!
//! shrink = 1 − Σc rmse_after,c/σc / Σc rmse_before,c/σc over the channels c = fx, fy, mz, with
//! σc the noise floor: the held-out reduction of the gap in units of each channel's noise.
//! Its standard error is that of the K per-block shrinks (sd/√K).

use super::effects::{spec, Ctx, Effect, Spec};
use super::sim::Out;
use super::stats;

/// Number of blocks.
pub const K: usize = 5;
/// At most this many training rows enter a fit that evaluates the Magic Formula per row (an
/// evenly spaced subsample; a handful of parameters needs far fewer).
pub const FIT_ROWS: usize = 2000;

/// Rows of block `f` of `n`.
pub fn block(n: usize, f: usize) -> std::ops::Range<usize> {
    f * n / K..(f + 1) * n / K
}

/// Training rows for block `f` (all rows outside it; `None`: all rows), evenly thinned to at
/// most `max` rows.
pub fn train_rows(n: usize, f: Option<usize>, max: usize) -> Vec<usize> {
    let out = f.map(|f| block(n, f)).unwrap_or(0..0);
    let rows: Vec<usize> = (0..n).filter(|i| !out.contains(i)).collect();
    if rows.len() <= max {
        return rows;
    }
    let stride = rows.len().div_ceil(max);
    rows.into_iter().step_by(stride).collect()
}

/// The combined shrink of `after` against `before` (per channel RMSE), normalised by `noise`.
pub fn shrink(before: &[f64; 3], after: &[f64; 3], noise: &[f64; 3]) -> f64 {
    let b: f64 = (0..3).map(|c| before[c] / noise[c]).sum();
    let a: f64 = (0..3).map(|c| after[c] / noise[c]).sum();
    if b > 0.0 {
        1.0 - a / b
    } else {
        0.0
    }
}

/// Per-channel RMSE of residuals over `rows`.
pub fn rmse_rows(r: &[Out], rows: std::ops::Range<usize>) -> [f64; 3] {
    let mut out = [0.0; 3];
    for (c, o) in out.iter_mut().enumerate() {
        *o = stats::rms(r[rows.clone()].iter().map(|x| x[c]));
    }
    out
}

/// What cross-validation says about one effect.
#[derive(Debug, Clone)]
pub struct Score {
    /// The effect.
    pub effect: Effect,
    /// Why it was not tried, if it was not.
    pub not_applicable: Option<String>,
    /// Its parameters (names and scales), when applicable.
    pub spec: Option<Spec>,
    /// Parameters fitted on all rows (reported, and used for plots and μ).
    pub theta: Vec<f64>,
    /// Parameters of each fold.
    pub theta_folds: Vec<Vec<f64>>,
    /// Held-out RMSE per channel before (the sim) and after (the sim with the effect).
    pub rmse_before: [f64; 3],
    /// See `rmse_before`.
    pub rmse_after: [f64; 3],
    /// Held-out shrink (module doc).
    pub shrink: f64,
    /// Shrink of each block.
    pub fold_shrinks: Vec<f64>,
    /// Standard error of the shrink (sd of the block shrinks / √K).
    pub shrink_se: f64,
    /// Per channel 1 − rmse_after/rmse_before.
    pub shrink_by_channel: [f64; 3],
    /// Held-out residual per row.
    pub heldout_resid: Vec<Out>,
    /// Significance of the held-out improvement against the noise floor ([`z_value`]).
    pub z: f64,
}

/// The held-out improvement in noise units, ΔSSE = Σ_i Σ_c ((rb/σc)² − (ra/σc)²), over its
/// standard deviation under the hypothesis that the effect only fits noise: with δ = rb − ra
/// the change of prediction and white noise ε at the floor, rb² − ra² = 2εδ − δ², whose sum has
/// sd 2·√(Σ(δ/σ)²). So z = ΔSSE / (2·√(Σ(δ/σ)²)), a χ²-style test against the noise floor that
/// does not care in how many blocks the effect shows (a friction effect may be excited in one
/// block only). Under that hypothesis z has mean −√(Σ(δ/σ)²)/2 ≤ 0 and unit sd; a real gap
/// closed by δ gives z ≈ ‖δ/σ‖/2.
pub fn z_value(before: &[Out], after: &[Out], noise: &[f64; 3]) -> f64 {
    let (mut dsse, mut dd) = (0.0, 0.0);
    for (b, a) in before.iter().zip(after) {
        for c in 0..3 {
            let (zb, za) = (b[c] / noise[c], a[c] / noise[c]);
            dsse += zb * zb - za * za;
            dd += (zb - za) * (zb - za);
        }
    }
    if dd > 0.0 {
        dsse / (2.0 * dd.sqrt())
    } else {
        0.0
    }
}

/// Cross-validates `effect`, fitting on at most `fit_rows` training rows (effects that evaluate
/// the Magic Formula; the cheap ones use all); `tick` is called after each fit (K + 1).
pub fn score(ctx: &Ctx, effect: Effect, fit_rows: usize, tick: &mut dyn FnMut()) -> Score {
    let log = ctx.log;
    let n = log.len();
    let base_r = ctx.base_resid();
    let rmse_before = rmse_rows(&base_r, 0..n);
    let mut sc = Score {
        effect,
        not_applicable: None,
        spec: None,
        theta: vec![],
        theta_folds: vec![],
        rmse_before,
        rmse_after: rmse_before,
        shrink: 0.0,
        fold_shrinks: vec![0.0; K],
        shrink_se: 0.0,
        shrink_by_channel: [0.0; 3],
        heldout_resid: base_r.clone(),
        z: 0.0,
    };
    let sp = match spec(effect, ctx) {
        Ok(s) => s,
        Err(why) => {
            sc.not_applicable = Some(why);
            for _ in 0..=K {
                tick();
            }
            return sc;
        }
    };
    let max = if effect.cheap() { usize::MAX } else { fit_rows };
    let mut held = base_r.clone();
    let settled = |rows: Vec<usize>| -> Vec<usize> {
        rows.into_iter()
            .filter(|&i| ctx.settled.get(i).copied().unwrap_or(true))
            .collect()
    };
    for f in 0..K {
        let rows = settled(train_rows(n, Some(f), max));
        let theta = sp
            .fit(ctx, &rows)
            .map(|fit| fit.theta)
            .unwrap_or_else(|| sp.starts[0].clone());
        // Exact run with the fold's parameters; a failure keeps the sim's prediction.
        if let Some(pred) = sp.predict(ctx, &theta, None) {
            let r = ctx.resid(&pred);
            held[block(n, f)].copy_from_slice(&r[block(n, f)]);
        }
        sc.theta_folds.push(theta);
        tick();
    }
    let rows = settled(train_rows(n, None, max));
    sc.theta = sp
        .fit(ctx, &rows)
        .map(|fit| fit.theta)
        .unwrap_or_else(|| sp.starts[0].clone());
    tick();
    sc.rmse_after = rmse_rows(&held, 0..n);
    sc.shrink = shrink(&sc.rmse_before, &sc.rmse_after, &ctx.noise);
    for f in 0..K {
        let b = rmse_rows(&base_r, block(n, f));
        let a = rmse_rows(&held, block(n, f));
        sc.fold_shrinks[f] = shrink(&b, &a, &ctx.noise);
    }
    sc.shrink_se = stats::sd(&sc.fold_shrinks) / (K as f64).sqrt();
    for c in 0..3 {
        sc.shrink_by_channel[c] = if sc.rmse_before[c] > 0.0 {
            1.0 - sc.rmse_after[c] / sc.rmse_before[c]
        } else {
            0.0
        };
    }
    sc.z = z_value(&base_r, &held, &ctx.noise);
    sc.heldout_resid = held;
    sc.spec = Some(sp);
    sc
}

/// Are `a` (the better) and `b` indistinguishable: is the difference of their shrinks within
/// `t` standard errors of the paired block differences (or below 0.001)?
pub fn indistinguishable(a: &Score, b: &Score, t: f64) -> bool {
    let d: Vec<f64> = a
        .fold_shrinks
        .iter()
        .zip(&b.fold_shrinks)
        .map(|(x, y)| x - y)
        .collect();
    let se = stats::sd(&d) / (K as f64).sqrt();
    (a.shrink - b.shrink).abs() <= (t * se).max(1e-3)
}
