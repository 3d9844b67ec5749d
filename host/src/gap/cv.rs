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

use super::effects::{spec, Ctx, Effect, Pair, Spec};
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
    sc.set_heldout(ctx, &base_r, held);
    sc.spec = Some(sp);
    sc
}

impl Score {
    /// Fills the held-out figures from the held-out residual `held` (`base_r`: the sim's).
    fn set_heldout(&mut self, ctx: &Ctx, base_r: &[Out], held: Vec<Out>) {
        let n = held.len();
        self.rmse_after = rmse_rows(&held, 0..n);
        self.shrink = shrink(&self.rmse_before, &self.rmse_after, &ctx.noise);
        for f in 0..K {
            let b = rmse_rows(base_r, block(n, f));
            let a = rmse_rows(&held, block(n, f));
            self.fold_shrinks[f] = shrink(&b, &a, &ctx.noise);
        }
        self.shrink_se = stats::sd(&self.fold_shrinks) / (K as f64).sqrt();
        for c in 0..3 {
            self.shrink_by_channel[c] = if self.rmse_before[c] > 0.0 {
                1.0 - self.rmse_after[c] / self.rmse_before[c]
            } else {
                0.0
            };
        }
        self.z = z_value(base_r, &held, &ctx.noise);
        self.heldout_resid = held;
    }
}

/// What cross-validation says about a pair: the first effect (scored alone before) together
/// with a second ([`Pair`]).
#[derive(Debug, Clone)]
pub struct PairScore {
    /// The pair against the sim: `effect`, `spec`, `theta_folds` are the second effect's;
    /// shrink, z, residuals the pair's (held-out).
    pub score: Score,
    /// The first effect's parameters of each fold, refitted with the second.
    pub theta_first_folds: Vec<Vec<f64>>,
    /// Significance of the pair's held-out improvement over the first effect alone
    /// ([`z_value`] of the first's held-out residual against the pair's).
    pub z_added: f64,
}

/// Cross-validates `second` on top of `first` (already scored alone, applicable): each block
/// predicted by the pair fitted on the other blocks, the first effect starting from its own
/// fold fit. `None` when `second` does not apply. `tick` is called after each fit (K).
pub fn score_pair(
    ctx: &Ctx,
    first: &Score,
    second: Effect,
    fit_rows: usize,
    tick: &mut dyn FnMut(),
) -> Option<PairScore> {
    let spa = first.spec.as_ref()?;
    let spb = spec(second, ctx).ok()?;
    let n = ctx.log.len();
    let base_r = ctx.base_resid();
    let max = if first.effect.cheap() && second.cheap() {
        usize::MAX
    } else {
        fit_rows
    };
    let pair = Pair { a: spa, b: &spb };
    let mut held = base_r.clone();
    let mut tb_folds = Vec::with_capacity(K);
    let mut ta_folds = Vec::with_capacity(K);
    for f in 0..K {
        let rows: Vec<usize> = train_rows(n, Some(f), max)
            .into_iter()
            .filter(|&i| ctx.settled.get(i).copied().unwrap_or(true))
            .collect();
        let start_a = first
            .theta_folds
            .get(f)
            .cloned()
            .unwrap_or_else(|| spa.starts[0].clone());
        let (ta, tb) = pair
            .fit(ctx, &rows, &start_a)
            .unwrap_or_else(|| (start_a.clone(), spb.starts[0].clone()));
        if let Some(pred) = pair.predict(ctx, &ta, &tb, None) {
            let r = ctx.resid(&pred);
            held[block(n, f)].copy_from_slice(&r[block(n, f)]);
        } else {
            held[block(n, f)].copy_from_slice(&first.heldout_resid[block(n, f)]);
        }
        ta_folds.push(ta);
        tb_folds.push(tb);
        tick();
    }
    let mut sc = Score {
        effect: second,
        not_applicable: None,
        spec: None,
        theta: vec![],
        theta_folds: tb_folds,
        rmse_before: first.rmse_before,
        rmse_after: first.rmse_before,
        shrink: 0.0,
        fold_shrinks: vec![0.0; K],
        shrink_se: 0.0,
        shrink_by_channel: [0.0; 3],
        heldout_resid: vec![],
        z: 0.0,
    };
    let z_added = z_value(&first.heldout_resid, &held, &ctx.noise);
    sc.set_heldout(ctx, &base_r, held);
    sc.spec = Some(spb);
    Some(PairScore {
        score: sc,
        theta_first_folds: ta_folds,
        z_added,
    })
}

/// Screens `second` on top of `first` (at its whole-log fit): fitted alone on the settled,
/// thinned rows of the whole log, the fall of Σ(r/σ)² it gives (in-sample, one fit; `None`
/// when it does not apply). Ranks the candidates before the cross-validation of the pairs.
pub fn screen_second(ctx: &Ctx, first: &Score, second: Effect, fit_rows: usize) -> Option<f64> {
    let spa = first.spec.as_ref()?;
    let spb = spec(second, ctx).ok()?;
    let max = if first.effect.cheap() && second.cheap() {
        usize::MAX
    } else {
        fit_rows
    };
    let rows: Vec<usize> = train_rows(ctx.log.len(), None, max)
        .into_iter()
        .filter(|&i| ctx.settled.get(i).copied().unwrap_or(true))
        .collect();
    Pair { a: spa, b: &spb }
        .fit_second(ctx, &rows, &first.theta)
        .map(|f| f.1)
}

/// The pair fitted on all (settled, thinned) rows: (θ first, θ second) for the report.
pub fn fit_pair_all(
    ctx: &Ctx,
    first: &Score,
    ps: &PairScore,
    fit_rows: usize,
) -> Option<(Vec<f64>, Vec<f64>)> {
    let (spa, spb) = (first.spec.as_ref()?, ps.score.spec.as_ref()?);
    let max = if first.effect.cheap() && ps.score.effect.cheap() {
        usize::MAX
    } else {
        fit_rows
    };
    let rows: Vec<usize> = train_rows(ctx.log.len(), None, max)
        .into_iter()
        .filter(|&i| ctx.settled.get(i).copied().unwrap_or(true))
        .collect();
    Pair { a: spa, b: spb }.fit(ctx, &rows, &first.theta)
}

/// Are `a` (the better) and `b` indistinguishable on held-out data? They are told apart only
/// as the verdict is told from `none`: `a` must close a relevant share more of the gap than
/// `b` (shrink difference ≥ `min_shrink`) *and* that must be significant against the noise
/// floor ([`z_value`] of `b`'s held-out residual against `a`'s ≥ `min_z`). Otherwise the data
/// cannot say which of the two it is (why not a t-test on the paired block shrinks: the
/// "Two effects at once" of docs/gap.md).
pub fn indistinguishable(
    a: &Score,
    b: &Score,
    noise: &[f64; 3],
    min_shrink: f64,
    min_z: f64,
) -> bool {
    let better = a.shrink - b.shrink;
    better.abs() < min_shrink || z_value(&b.heldout_resid, &a.heldout_resid, noise).abs() < min_z
}
