//! The bench's measures of an estimator's estimates against the truth of a case's wheel traces:
//! error while identifiable, how honest σ is, utilisation and latency to within ±0.1 of the
//! truth, change flags and the false ones among them, wheel-surfaces read in time, and two
//! estimators on the samples both call identifiable.

use super::sensors::WheelTrace;
use crate::mu::Estimate;
use gough::mu::State;

/// The issue's latency target: within ±0.1 this long after utilisation 0.5 \[s\].
pub const TARGET_LATENCY: f64 = 0.150;

/// An identifiable estimate off by more than this is a gross error \[-\].
pub const GROSS: f64 = 0.2;

/// Issue 55's target for a step of the surface: read within this \[s\] ([`StepRead`]).
pub const TARGET_STEP: f64 = 0.200;

/// Metrics of one estimator on one case (all wheels).
#[derive(Debug, Clone, Default)]
pub struct Metrics {
    /// Samples called identifiable.
    pub n_identifiable: usize,
    /// Mean |error| while identifiable.
    pub err_mean: Option<f64>,
    /// 95th percentile |error| while identifiable.
    pub err_p95: Option<f64>,
    /// Share of the identifiable samples with |error| ≤ 2σ (σ as reported).
    pub within_2sigma: Option<f64>,
    /// Share of all the case's samples that are identifiable and off by more than 0.2 (the
    /// issue's limit: at most 0.5 %).
    pub gross: f64,
    /// Share of all the case's samples with the model-mismatch indication set.
    pub mismatch: f64,
    /// Share of all the case's samples that are identifiable, off by more than 0.2 and without
    /// the mismatch indication: a wrong answer the estimate gives no warning of.
    pub gross_unflagged: f64,
    /// Median utilisation at which the estimate first stays within ±0.1.
    pub util_within: Option<f64>,
    /// Median latency from utilisation 0.5 to staying within ±0.1 \[s\].
    pub latency: Option<f64>,
    /// Median time from a change of surface to staying within ±0.1 of the new μ \[s\].
    pub detect: Option<f64>,
    /// Change flags without a change of road, or to a wrong value ([`false_change_flags`]).
    pub false_alarms: usize,
    /// Change flags raised.
    pub change_flags: usize,
    /// Wheel-surfaces (a wheel on one stretch of constant μ) whose utilisation reaches 0.5.
    pub ws_total: usize,
    /// Of those, the ones whose estimate settles within ±0.1 within [`TARGET_LATENCY`] of it.
    pub ws_within: usize,
    /// Samples of the case (all wheels).
    pub n_samples: usize,
    /// Samples at a utilisation of 0.5 or more.
    pub n_util_hi: usize,
    /// Of those, the identifiable ones.
    pub n_identifiable_util_hi: usize,
}

pub(crate) fn median(mut v: Vec<f64>) -> Option<f64> {
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    Some(v[v.len() / 2])
}

/// Segments of constant true μ: (start, end) index ranges.
pub(crate) fn segments(mu: &[f64]) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut s = 0;
    for i in 1..=mu.len() {
        if i == mu.len() || (mu[i] - mu[s]).abs() > 1e-9 {
            out.push((s, i));
            s = i;
        }
    }
    out
}

/// First row of segment `a..b` from which the reported estimate stays within ±0.1 of the truth
/// to the segment's end, held for at least 50 rows ("stays").
fn settled(tr: &WheelTrace, est: &[Estimate], a: usize, b: usize) -> Option<usize> {
    let mut first_ok = None;
    for i in (a..b).rev() {
        let e = &est[i];
        if e.state == State::Fallback || (e.mu - tr.mu_true[i]).abs() > 0.1 {
            break;
        }
        first_ok = Some(i);
    }
    first_ok.filter(|&ok| b - ok >= 50)
}

/// Time from the utilisation first reaching 0.5 in segment `a..b` to row `ok` \[s\].
fn latency_from(tr: &WheelTrace, a: usize, b: usize, ok: usize) -> Option<f64> {
    (a..b)
        .find(|&i| tr.util[i] >= 0.5)
        .map(|i5| (tr.rows[ok].t - tr.rows[i5].t).max(0.0))
}

/// Latency of one wheel on segment `a..b` (rows of constant true μ): from the utilisation
/// first reaching 0.5 to the estimate staying within ±0.1 \[s\], as [`metrics`] takes it.
pub fn segment_latency(tr: &WheelTrace, est: &[Estimate], a: usize, b: usize) -> Option<f64> {
    if est.len() != tr.rows.len() {
        return None;
    }
    latency_from(tr, a, b, settled(tr, est, a, b)?)
}

/// One wheel on one stretch of constant true μ that reaches utilisation 0.5 (a
/// "wheel-surface", as [`metrics`] counts them).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WheelSurface {
    /// Wheel index (0–3: FL, FR, RL, RR).
    pub wheel: usize,
    /// True μ of the stretch.
    pub mu: f64,
    /// Time of the stretch's first row \[s\].
    pub t_start: f64,
    /// Time of the stretch's last row \[s\].
    pub t_end: f64,
    /// Time the utilisation first reaches 0.5 on it \[s\].
    pub t_util05: f64,
    /// From then until the estimate stays within ±0.1 \[s\] (none: it never does for 50 rows).
    pub latency: Option<f64>,
}

impl WheelSurface {
    /// Within ±0.1 within [`TARGET_LATENCY`].
    pub fn within(&self) -> bool {
        self.latency.is_some_and(|l| l <= TARGET_LATENCY + 1e-9)
    }
}

/// Every wheel-surface of a case's traces with its latency (estimates `ests[w]` of wheel `w`).
pub fn wheel_surfaces(traces: &[WheelTrace], ests: &[Vec<Estimate>]) -> Vec<WheelSurface> {
    let mut out = Vec::new();
    for (w, (tr, est)) in traces.iter().zip(ests).enumerate() {
        if est.len() != tr.rows.len() {
            continue;
        }
        for (a, b) in segments(&tr.mu_true) {
            let Some(i5) = (a..b).find(|&i| tr.util[i] >= 0.5) else {
                continue;
            };
            out.push(WheelSurface {
                wheel: w,
                mu: tr.mu_true[a],
                t_start: tr.rows[a].t,
                t_end: tr.rows[b - 1].t,
                t_util05: tr.rows[i5].t,
                latency: segment_latency(tr, est, a, b),
            });
        }
    }
    out
}

/// Change flags that declare a change of surface where the road did not change (false change
/// alarms): a flag is a true one when the road under the wheel differs from the road on which
/// the estimator's previous identification began (the run of identifiable samples it changes
/// from) and the new value is within ±0.1 of it. A correction on one road (a wrong value
/// replaced by the right one), a flag to a wrong value, or one without any earlier
/// identification is false; a change identified late — the road changed seconds before, the
/// old identification held meanwhile — is a true one (its lateness is the latency's and the
/// "detect change" column's).
pub fn false_change_flags(tr: &WheelTrace, est: &[Estimate]) -> usize {
    false_flags(&tr.mu_true, est)
}

/// [`false_change_flags`] on the true μ of each row. Causal: the count over a prefix of the rows
/// is the count of the prefix (a warm run's own flags are those of the two runs in a row less
/// those of the first).
pub(crate) fn false_flags(mu_true: &[f64], est: &[Estimate]) -> usize {
    // True μ where the current identification began.
    let mut began: Option<f64> = None;
    let mut false_flags = 0;
    for (i, e) in est.iter().enumerate() {
        let Some(&now) = mu_true.get(i) else {
            break;
        };
        if e.change {
            let road_changed = began.is_some_and(|m| (m - now).abs() > 1e-9);
            if !(road_changed && (e.mu - now).abs() <= 0.1) {
                false_flags += 1;
            }
        }
        if e.state == State::Identifiable && (e.change || began.is_none()) {
            began = Some(now);
        }
    }
    false_flags
}

/// The false change flags of a warm run (`warm`: the estimates of a second run over the traces
/// on the estimator that made `cold`), judged with the first run behind it: those of the two
/// runs in a row less those of the first (the count of [`false_change_flags`] is causal). A
/// flag at the warm run's start, where the road is the first run's start again, is true when
/// its value is right.
pub fn warm_false_change_flags(
    traces: &[WheelTrace],
    cold: &[Vec<Estimate>],
    warm: &[Vec<Estimate>],
) -> usize {
    traces
        .iter()
        .zip(cold.iter().zip(warm))
        .map(|(tr, (c, w))| {
            let mu: Vec<f64> = [tr.mu_true.as_slice(), &tr.mu_true].concat();
            let both: Vec<Estimate> = [c.as_slice(), w].concat();
            false_flags(&mu, &both) - false_flags(&tr.mu_true, c)
        })
        .sum()
}

/// One step of the surface under one wheel, and when the estimator read it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepRead {
    /// Wheel index (0–3: FL, FR, RL, RR).
    pub wheel: usize,
    /// True μ before and after the step \[-\].
    pub from: f64,
    /// See `from`.
    pub to: f64,
    /// Time of the first row on the new surface \[s\].
    pub t_step: f64,
    /// From `t_step` to the first row at which the estimate is identifiable within ±0.1 of
    /// the new μ and from which it stays within ±0.1 (in any state but the fallback) to the end
    /// of the new surface \[s\] (none: never).
    pub read: Option<f64>,
}

impl StepRead {
    /// Read within [`TARGET_STEP`].
    pub fn in_time(&self) -> bool {
        self.read.is_some_and(|r| r <= TARGET_STEP + 1e-9)
    }
}

/// Every step of the surface in the traces (each boundary between stretches of constant true
/// μ) and how soon estimates `ests[w]` of wheel `w` read it ([`StepRead::read`]).
pub fn step_reads(traces: &[WheelTrace], ests: &[Vec<Estimate>]) -> Vec<StepRead> {
    let mut out = Vec::new();
    for (w, (tr, est)) in traces.iter().zip(ests).enumerate() {
        if est.len() != tr.rows.len() {
            continue;
        }
        for (a, b) in segments(&tr.mu_true).into_iter().skip(1) {
            // Back from the stretch's end while within ±0.1: the earliest identifiable row.
            let mut first = None;
            for i in (a..b).rev() {
                let e = &est[i];
                if e.state == State::Fallback || (e.mu - tr.mu_true[i]).abs() > 0.1 {
                    break;
                }
                if e.state == State::Identifiable {
                    first = Some(i);
                }
            }
            out.push(StepRead {
                wheel: w,
                from: tr.mu_true[a - 1],
                to: tr.mu_true[a],
                t_step: tr.rows[a].t,
                read: first.map(|i| tr.rows[i].t - tr.rows[a].t),
            });
        }
    }
    out
}

/// Metrics of estimates `est` against the trace(s).
pub fn metrics(traces: &[WheelTrace], ests: &[Vec<Estimate>]) -> Metrics {
    let mut errs = Vec::new();
    let (mut utils, mut lats, mut dets) = (Vec::new(), Vec::new(), Vec::new());
    let (mut false_alarms, mut change_flags) = (0, 0);
    let mut covered = 0;
    let (mut gross, mut samples) = (0usize, 0usize);
    let (mut mismatch, mut gross_unflagged) = (0usize, 0usize);
    let (mut ws_total, mut ws_within) = (0, 0);
    let (mut util_hi, mut ident_hi) = (0, 0);
    for (tr, est) in traces.iter().zip(ests) {
        if est.len() != tr.rows.len() {
            continue;
        }
        samples += est.len();
        false_alarms += false_change_flags(tr, est);
        change_flags += est.iter().filter(|e| e.change).count();
        for (i, e) in est.iter().enumerate() {
            mismatch += usize::from(e.mismatch);
            if tr.util[i] >= 0.5 {
                util_hi += 1;
                ident_hi += usize::from(e.state == State::Identifiable);
            }
            if e.state == State::Identifiable {
                let err = (e.mu - tr.mu_true[i]).abs();
                errs.push(err);
                covered += usize::from(err <= 2.0 * e.sigma);
                gross += usize::from(err > GROSS);
                gross_unflagged += usize::from(err > GROSS && !e.mismatch);
            }
        }
        let segs = segments(&tr.mu_true);
        for (k, &(a, b)) in segs.iter().enumerate() {
            if tr.util[a..b].iter().any(|&u| u >= 0.5) {
                ws_total += 1;
                if settled(tr, est, a, b)
                    .and_then(|ok| latency_from(tr, a, b, ok))
                    .is_some_and(|l| l <= TARGET_LATENCY + 1e-9)
                {
                    ws_within += 1;
                }
            }
            let Some(ok) = settled(tr, est, a, b) else {
                continue;
            };
            let umax = tr.util[a..=ok].iter().copied().fold(0.0, f64::max);
            utils.push(umax);
            if let Some(l) = latency_from(tr, a, b, ok) {
                lats.push(l);
            }
            if k > 0 {
                dets.push(tr.rows[ok].t - tr.rows[a].t);
            }
        }
    }
    let n = errs.len();
    let err_mean = (n > 0).then(|| errs.iter().sum::<f64>() / n as f64);
    let err_p95 = p95(errs);
    Metrics {
        n_identifiable: n,
        err_mean,
        err_p95,
        within_2sigma: (n > 0).then(|| covered as f64 / n as f64),
        gross: gross as f64 / samples.max(1) as f64,
        mismatch: mismatch as f64 / samples.max(1) as f64,
        gross_unflagged: gross_unflagged as f64 / samples.max(1) as f64,
        ws_total,
        ws_within,
        util_within: median(utils),
        latency: median(lats),
        detect: median(dets),
        false_alarms,
        change_flags,
        n_samples: samples,
        n_util_hi: util_hi,
        n_identifiable_util_hi: ident_hi,
    }
}

/// The 95th percentile of `errs` (the bench's rank: the sample at ⌊0.95·n⌋), none if empty.
fn p95(mut errs: Vec<f64>) -> Option<f64> {
    let n = errs.len();
    (n > 0).then(|| {
        errs.sort_by(f64::total_cmp);
        errs[((n as f64 * 0.95) as usize).min(n - 1)]
    })
}

/// Two estimators on the samples both call identifiable (like for like).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Common {
    /// Samples both call identifiable (all wheels).
    pub n: usize,
    /// 95th percentile |error| of the first (the bank) and the second over those samples.
    pub p95: (Option<f64>, Option<f64>),
    /// Of those samples, the ones off by more than [`GROSS`]: the first's and the second's.
    pub gross: (usize, usize),
    /// Median latency \[s\] of the first and the second over the wheel-surfaces both settle on
    /// (as [`segment_latency`] takes it), and how many those are.
    pub latency: (Option<f64>, Option<f64>, usize),
}

/// [`Common`] of estimates `a` and `b` (per wheel, as [`metrics`] takes them) against the traces.
pub fn common(traces: &[WheelTrace], a: &[Vec<Estimate>], b: &[Vec<Estimate>]) -> Common {
    let (mut ea, mut eb) = (Vec::new(), Vec::new());
    let (mut la, mut lb) = (Vec::new(), Vec::new());
    for ((tr, a), b) in traces.iter().zip(a).zip(b) {
        for (s, e) in segments(&tr.mu_true) {
            if let (Some(x), Some(y)) = (segment_latency(tr, a, s, e), segment_latency(tr, b, s, e))
            {
                la.push(x);
                lb.push(y);
            }
        }
        for (i, (x, y)) in a.iter().zip(b).enumerate() {
            if x.state == State::Identifiable && y.state == State::Identifiable {
                if let Some(&mu) = tr.mu_true.get(i) {
                    ea.push((x.mu - mu).abs());
                    eb.push((y.mu - mu).abs());
                }
            }
        }
    }
    let gross = |e: &[f64]| e.iter().filter(|&&x| x > GROSS).count();
    let n_ws = la.len();
    Common {
        n: ea.len(),
        gross: (gross(&ea), gross(&eb)),
        p95: (p95(ea), p95(eb)),
        latency: (median(la), median(lb), n_ws),
    }
}

/// One estimator's measures over the suite, added up case by case (the bench's closing lines).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Totals {
    /// Cases whose median latency is within [`TARGET_LATENCY`].
    pub within: usize,
    /// Wheel-surfaces within ±0.1 within [`TARGET_LATENCY`], of those reaching utilisation 0.5.
    pub ws: (usize, usize),
    /// [`Totals::within`] over the issue's cases (the suite without the straight ABS stops).
    pub within_issue: usize,
    /// [`Totals::ws`] over the issue's cases.
    pub ws_issue: (usize, usize),
    /// False change alarms ([`false_change_flags`]).
    pub alarms: usize,
    /// Change flags raised.
    pub flags: usize,
    /// The worst case's p95 error while identifiable (none: never identifiable).
    pub worst_p95: Option<f64>,
    /// The worst case's share of samples identifiable and off by more than [`GROSS`].
    pub worst_gross: f64,
    /// Samples identifiable, all samples, identifiable at utilisation ≥ 0.5, all at ≥ 0.5.
    pub shares: (usize, usize, usize, usize),
}

impl Totals {
    /// Adds one case's metrics; `issue_case`: it is one of the issue's cases.
    pub fn add(&mut self, mt: &Metrics, issue_case: bool) {
        let in_time = mt.latency.is_some_and(|l| l <= TARGET_LATENCY + 1e-9);
        self.within += usize::from(in_time);
        self.ws.0 += mt.ws_within;
        self.ws.1 += mt.ws_total;
        if issue_case {
            self.within_issue += usize::from(in_time);
            self.ws_issue.0 += mt.ws_within;
            self.ws_issue.1 += mt.ws_total;
        }
        self.alarms += mt.false_alarms;
        self.flags += mt.change_flags;
        self.shares.0 += mt.n_identifiable;
        self.shares.1 += mt.n_samples;
        self.shares.2 += mt.n_identifiable_util_hi;
        self.shares.3 += mt.n_util_hi;
        self.worst_gross = self.worst_gross.max(mt.gross);
        self.worst_p95 = match (self.worst_p95, mt.err_p95) {
            (Some(a), Some(b)) => Some(a.max(b)),
            (a, b) => a.or(b),
        };
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mu::Sample;

    /// A trace at 1 kHz with true μ `mu_true` and utilisation `util` per row (its measured
    /// channels constant: the metrics read the estimates against the truth only).
    fn flat_trace(mu_true: Vec<f64>, util: Vec<f64>) -> WheelTrace {
        let n = mu_true.len();
        WheelTrace {
            rows: (0..n)
                .map(|i| Sample {
                    t: i as f64 * 1e-3,
                    fz: 4000.0,
                    fx: Some(0.0),
                    vx: Some(20.0),
                    kappa: Some(0.0),
                    gamma: Some(0.0),
                    ..Sample::default()
                })
                .collect(),
            slip_sensor: Vec::new(),
            mu_true,
            util,
        }
    }

    /// The error metrics count identifiable samples only; "within 2σ" is the share of them
    /// whose error is at most twice the σ they report.
    #[test]
    fn metrics_count_errors_and_their_sigma() {
        let n = 6;
        let tr = flat_trace(vec![0.5; n], vec![0.6; n]);
        let e = |mu: f64, sigma: f64, state: State| Estimate {
            mu,
            sigma,
            state,
            change: false,
            mismatch: false,
        };
        let est = vec![
            e(0.8, 0.4, State::Fallback),
            e(0.55, 0.03, State::Identifiable), // 0.05 ≤ 0.06
            e(0.6, 0.03, State::Identifiable),  // 0.10 > 0.06
            e(0.6, 0.03, State::NotIdentifiable),
            e(0.48, 0.011, State::Identifiable), // 0.02 ≤ 0.022
            e(0.5, 0.05, State::Identifiable),
        ];
        let m = metrics(std::slice::from_ref(&tr), std::slice::from_ref(&est));
        assert_eq!(m.n_identifiable, 4);
        assert_eq!(m.within_2sigma, Some(0.75));
        assert!((m.err_mean.unwrap() - 0.17 / 4.0).abs() < 1e-12);
        let none = vec![e(0.8, 0.4, State::Fallback); n];
        let m = metrics(std::slice::from_ref(&tr), std::slice::from_ref(&none));
        assert_eq!((m.n_identifiable, m.within_2sigma), (0, None));
    }

    /// A change flag is false unless the road changed since the identification it changes from
    /// began and the new value is right: a late true one counts as true; a correction on one
    /// road, a flag to a wrong value and a flag without an earlier identification as false.
    #[test]
    fn false_change_flags_are_those_without_a_change_of_road() {
        let n = 400;
        // Road 0.9 for 200 samples, then 0.3.
        let road = |i: usize| if i < 200 { 0.9 } else { 0.3 };
        let tr = flat_trace((0..n).map(road).collect(), vec![0.7; n]);
        let e = |mu: f64, change: bool| Estimate {
            mu,
            sigma: 0.02,
            state: State::Identifiable,
            change,
            mismatch: false,
        };
        let run = |flags: &[(usize, f64)]| {
            let mut mu = 0.5;
            let est: Vec<_> = (0..n)
                .map(|i| match flags.iter().find(|(k, _)| *k == i) {
                    Some(&(_, m)) => {
                        mu = m;
                        e(m, true)
                    }
                    None => e(mu, false),
                })
                .collect();
            false_change_flags(&tr, &est)
        };
        // Read 0.5 on 0.9 from the start, corrected at 50 (no change of road: false), the change
        // read at 350, 150 samples late (true).
        assert_eq!(run(&[(50, 0.9), (350, 0.3)]), 1);
        // The change read as 0.6 (wrong value: false).
        assert_eq!(run(&[(50, 0.9), (350, 0.6)]), 2);
        // Only the late true one.
        assert_eq!(run(&[(350, 0.3)]), 0);
        // A flag on the very first sample has no identification to change from.
        assert_eq!(run(&[(0, 0.9)]), 1);
        // Warm: the same traces again after a first run that ended identified on 0.3. The
        // flag back to 0.9 at the warm run's start is a true change; a flag at its sample 50
        // (0.9 → 0.9, no change of road) a false one.
        let mut cold = vec![e(0.9, false); n];
        cold[200..].fill(e(0.3, false));
        cold[210] = e(0.3, true);
        let mut warm = cold.clone();
        warm[0] = e(0.9, true);
        warm[1..200].fill(e(0.9, false));
        let t = std::slice::from_ref(&tr);
        assert_eq!(false_change_flags(&tr, &cold), 0);
        assert_eq!(
            warm_false_change_flags(t, &[cold.clone()], &[warm.clone()]),
            0
        );
        warm[50] = e(0.9, true);
        assert_eq!(warm_false_change_flags(t, &[cold], &[warm]), 1);
    }

    /// A step is read at the first row that is identifiable within ±0.1 of the new μ and from
    /// which the estimate stays within ±0.1 (held while not identifiable) to the stretch's end:
    /// not at an earlier visit within ±0.1 that is left again, nor at a row within ±0.1 that is
    /// only not identifiable; never if the estimate leaves ±0.1 at the end.
    #[test]
    fn a_step_is_read_when_the_estimate_is_identifiable_within_01_for_good() {
        let n = 1000;
        // μ 0.9 for 400 rows (1 kHz), then 0.3.
        let tr = flat_trace(
            (0..n).map(|i| if i < 400 { 0.9 } else { 0.3 }).collect(),
            vec![0.7; n],
        );
        let e = |mu: f64, state: State| Estimate {
            mu,
            sigma: 0.02,
            state,
            change: false,
            mismatch: false,
        };
        let est: Vec<Estimate> = (0..n)
            .map(|i| match i {
                0..400 => e(0.9, State::Identifiable),
                // Passes through 0.3 (identifiable) and leaves again.
                400..450 => e(0.9, State::NotIdentifiable),
                450..460 => e(0.32, State::Identifiable),
                460..500 => e(0.6, State::NotIdentifiable),
                // Within ±0.1 but not identifiable: not yet read.
                500..530 => e(0.35, State::NotIdentifiable),
                // Read at 530, held (not identifiable) within ±0.1 later.
                530..900 => e(0.28, State::Identifiable),
                _ => e(0.31, State::NotIdentifiable),
            })
            .collect();
        let s = step_reads(std::slice::from_ref(&tr), std::slice::from_ref(&est));
        assert_eq!(s.len(), 1);
        assert_eq!((s[0].wheel, s[0].from, s[0].to), (0, 0.9, 0.3));
        assert!((s[0].t_step - 0.4).abs() < 1e-12);
        assert!((s[0].read.unwrap() - 0.13).abs() < 1e-9, "{s:?}");
        assert!(s[0].in_time());
        // Late: read at 650 (0.25 s); never: off by more than 0.1 at the end.
        let mut late = est.clone();
        late[530..650].fill(e(0.6, State::Identifiable));
        let s = step_reads(std::slice::from_ref(&tr), std::slice::from_ref(&late));
        assert!((s[0].read.unwrap() - 0.25).abs() < 1e-9 && !s[0].in_time());
        let mut never = est;
        never[n - 1] = e(0.9, State::Identifiable);
        let s = step_reads(std::slice::from_ref(&tr), std::slice::from_ref(&never));
        assert_eq!(s[0].read, None);
        // No step, no reads.
        let flat = flat_trace(vec![0.5; 10], vec![0.7; 10]);
        assert!(step_reads(&[flat], &[vec![e(0.5, State::Identifiable); 10]]).is_empty());
    }

    /// The per-wheel listing (`wheels.csv`, the misses table) counts what [`metrics`] counts: a
    /// stretch of μ 0.5 read 100 ms after utilisation 0.5, one of μ 0.2 read 200 ms after it, a
    /// third below utilisation 0.5 (not a wheel-surface).
    #[test]
    fn the_wheel_listing_agrees_with_the_metrics() {
        let n = 3000;
        let mu = |i: usize| [0.5, 0.2, 0.9][i / 1000];
        // Utilisation 0.5 from 300 ms into each of the first two stretches, 0.2 on the third.
        let util = (0..n).map(|i| {
            if i < 2000 && i % 1000 >= 300 {
                0.7
            } else {
                0.2
            }
        });
        let tr = flat_trace((0..n).map(mu).collect(), util.collect());
        let read_from = |i: usize| if i < 1000 { 400 } else { 1500 };
        let est: Vec<_> = (0..n)
            .map(|i| Estimate {
                mu: if i >= read_from(i) { mu(i) } else { 1.2 },
                sigma: 0.02,
                state: State::Identifiable,
                change: false,
                mismatch: false,
            })
            .collect();
        let ws = wheel_surfaces(std::slice::from_ref(&tr), std::slice::from_ref(&est));
        assert_eq!(ws.len(), 2, "{ws:?}");
        assert_eq!((ws[0].wheel, ws[0].mu, ws[0].t_util05), (0, 0.5, 0.3));
        assert!((ws[0].latency.unwrap() - 0.1).abs() < 1e-9 && ws[0].within());
        assert!((ws[1].t_util05 - 1.3).abs() < 1e-9);
        assert!((ws[1].latency.unwrap() - 0.2).abs() < 1e-9 && !ws[1].within());
        let m = metrics(std::slice::from_ref(&tr), std::slice::from_ref(&est));
        assert_eq!(m.ws_total, ws.len());
        assert_eq!(m.ws_within, ws.iter().filter(|x| x.within()).count());
    }
}
