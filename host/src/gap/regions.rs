//! "Where": the operating regions that hold the gap.
//!
//! The gap of a row is its squared residual beyond noise, summed over channels in noise units:
//! e_i = Σc ((r_c,i/σc)² − 1), whose expectation is 0 where the sim is right. For each operating
//! variable the rows are cut into bins (quantiles of the variable, so each bin holds a similar
//! number of rows; equal time spans for `time`), and a bin's `share_of_gap` is Σbin e / Σall e.
//! A bin is reported when it holds at least [`MIN_SHARE`] of the gap and at least
//! [`MIN_CONCENTRATION`] times its share of the rows: the gap is concentrated there.
//!
//! `frequency` splits the gap by frequency instead of by rows: the residuals' periodogram
//! (zero-padded radix-2 FFT, the log's median step as the sample time, white noise's flat
//! share subtracted) in bands 0–0.1–0.3–1–3–10–30–100… Hz up to Nyquist. Its `share_of_rows`
//! is absent.

use super::log::Log;
use super::sim::Out;
use super::stats;
use serde::Serialize;

/// Number of quantile bins per variable.
pub const BINS: usize = 5;
/// Reported regions hold at least this share of the gap.
pub const MIN_SHARE: f64 = 0.2;
/// ... and at least this multiple of their share of the rows.
pub const MIN_CONCENTRATION: f64 = 1.25;
/// A gap (or a region's part of it) counts when it exceeds this many standard deviations of
/// what white noise at the noise floor would give.
pub const SIGNIFICANCE: f64 = 4.0;
/// At most this many regions are reported.
pub const MAX_REGIONS: usize = 16;

/// Per-channel numbers keyed `fx`, `fy`, `mz`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Channels {
    /// Fx \[N\].
    pub fx: f64,
    /// Fy \[N\].
    pub fy: f64,
    /// Mz \[N·m\].
    pub mz: f64,
}

impl From<[f64; 3]> for Channels {
    fn from(a: [f64; 3]) -> Channels {
        Channels {
            fx: a[0],
            fy: a[1],
            mz: a[2],
        }
    }
}

/// One region.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Region {
    /// Operating variable.
    pub variable: String,
    /// Lower end (unit of the variable; Hz for `frequency`, s for `time`).
    pub lo: f64,
    /// Upper end.
    pub hi: f64,
    /// Share of the gap beyond noise held here.
    pub share_of_gap: f64,
    /// Share of the rows here (absent for `frequency`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub share_of_rows: Option<f64>,
    /// RMSE of the sim per channel here.
    pub rmse: Channels,
    /// RMSE per channel with the winning effect (held-out), when there is one.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rmse_after: Option<Channels>,
}

/// The operating variables of a log, by name, with their per-row values.
pub fn variables(log: &Log) -> Vec<(&'static str, Vec<f64>)> {
    let mut v = vec![
        ("alpha", log.alpha.clone()),
        ("kappa", log.kappa.clone()),
        ("fz", log.fz.clone()),
        ("vx", log.vx.clone()),
        ("gamma", log.gamma.clone()),
    ];
    if let Some(p) = &log.p {
        v.push(("p", p.clone()));
    }
    if let Some(p) = &log.phit {
        v.push(("phit", p.clone()));
    }
    v.push((
        "slip_speed",
        (0..log.len()).map(|i| log.slip_speed(i)).collect(),
    ));
    v.push(("time", log.t.clone()));
    v
}

/// Bin edges of `x`: quantiles (or equal spans when `equal`), duplicates merged.
fn edges(x: &[f64], equal: bool) -> Vec<f64> {
    let (lo, hi) = x
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    if hi.partial_cmp(&lo) != Some(std::cmp::Ordering::Greater) {
        return vec![];
    }
    let mut e: Vec<f64> = (0..=BINS)
        .map(|k| {
            let q = k as f64 / BINS as f64;
            if equal {
                lo + q * (hi - lo)
            } else {
                stats::quantile(x, q)
            }
        })
        .collect();
    e.dedup_by(|a, b| (*a - *b).abs() <= 1e-12 * (hi - lo));
    e
}

fn bin_of(e: &[f64], v: f64) -> usize {
    let nb = e.len() - 1;
    (1..nb).take_while(|&k| v >= e[k]).count()
}

/// The regions holding the gap of residuals `before` (normalised by `noise`), largest share
/// first. `after`: the winning effect's held-out residuals, for the `rmse_after` column.
pub fn regions(log: &Log, before: &[Out], after: Option<&[Out]>, noise: &[f64; 3]) -> Vec<Region> {
    let n = log.len();
    let e: Vec<f64> = before
        .iter()
        .map(|r| (0..3).map(|c| (r[c] / noise[c]).powi(2) - 1.0).sum())
        .collect();
    let total: f64 = e.iter().sum();
    // Under white Gaussian noise alone e_i has mean 0 and variance 2 per channel: a gap smaller
    // than SIGNIFICANCE standard deviations of Σe is noise, and so is a bin's share of it.
    if n == 0 || total <= SIGNIFICANCE * (6.0 * n as f64).sqrt() {
        return vec![];
    }
    let mut out = Vec::new();
    for (name, x) in variables(log) {
        let ed = edges(&x, name == "time");
        if ed.len() < 3 {
            continue; // (nearly) constant: no region to tell apart
        }
        let nb = ed.len() - 1;
        let mut idx: Vec<Vec<usize>> = vec![vec![]; nb];
        for (i, &v) in x.iter().enumerate() {
            idx[bin_of(&ed, v)].push(i);
        }
        for (b, rows) in idx.iter().enumerate() {
            if rows.is_empty() {
                continue;
            }
            let excess = rows.iter().map(|&i| e[i]).sum::<f64>();
            let share = excess / total;
            let rows_share = rows.len() as f64 / n as f64;
            if share < MIN_SHARE
                || share < MIN_CONCENTRATION * rows_share
                || excess <= SIGNIFICANCE * (6.0 * rows.len() as f64).sqrt()
            {
                continue;
            }
            let rm = |r: &[Out]| -> Channels {
                let mut a = [0.0; 3];
                for (c, v) in a.iter_mut().enumerate() {
                    *v = stats::rms(rows.iter().map(|&i| r[i][c]));
                }
                a.into()
            };
            out.push(Region {
                variable: name.to_string(),
                lo: ed[b],
                hi: ed[b + 1],
                share_of_gap: share,
                share_of_rows: Some(rows_share),
                rmse: rm(before),
                rmse_after: after.map(rm),
            });
        }
    }
    out.extend(frequency(log, before, after, noise, total));
    out.sort_by(|a, b| b.share_of_gap.total_cmp(&a.share_of_gap));
    out.truncate(MAX_REGIONS);
    out
}

/// Per band: (lo, hi) \[Hz\], excess energy in noise units (all channels), and per channel the
/// raw energy Σ|X|²/N2 (the band's share of Σ r²).
struct Bands {
    edges: Vec<(f64, f64)>,
    excess: Vec<f64>,
    /// Standard deviation of `excess` under white noise alone.
    sd: Vec<f64>,
    energy: Vec<[f64; 3]>,
}

fn bands(log: &Log, r: &[Out], noise: &[f64; 3]) -> Option<Bands> {
    let n = log.len();
    if n < 8 {
        return None;
    }
    let dts: Vec<f64> = log.t.windows(2).map(|w| w[1] - w[0]).collect();
    let dt = stats::median(&dts);
    if dt <= 0.0 {
        return None;
    }
    let nyq = 0.5 / dt;
    let mut ed = vec![0.0];
    let mut decade = 0.1;
    'grow: while decade < nyq {
        for m in [1.0, 3.0] {
            if decade * m >= nyq {
                break 'grow;
            }
            ed.push(decade * m);
        }
        decade *= 10.0;
    }
    ed.push(nyq);
    let edges: Vec<(f64, f64)> = ed.windows(2).map(|w| (w[0], w[1])).collect();
    let n2 = n.next_power_of_two();
    let mut excess = vec![0.0; edges.len()];
    let mut energy = vec![[0.0; 3]; edges.len()];
    let mut count = vec![0usize; edges.len()];
    for c in 0..3 {
        let mut re = vec![0.0; n2];
        let mut im = vec![0.0; n2];
        for i in 0..n {
            re[i] = r[i][c];
        }
        stats::fft(&mut re, &mut im);
        let s2 = noise[c] * noise[c];
        for k in 0..n2 {
            let fk = k.min(n2 - k) as f64 / (n2 as f64 * dt);
            // The last band includes Nyquist.
            let b = edges
                .iter()
                .position(|&(_, hi)| fk < hi)
                .unwrap_or(edges.len() - 1);
            let pw = re[k] * re[k] + im[k] * im[k];
            energy[b][c] += pw / n2 as f64;
            count[b] += 1;
            excess[b] += (pw / s2 - n as f64) / n2 as f64;
        }
    }
    // A periodogram ordinate of white noise has sd equal to its mean (N); zero padding
    // correlates neighbouring ordinates over N2/N bins.
    let (nf, n2f) = (n as f64, n2 as f64);
    let sd = count
        .iter()
        .map(|&k| (k as f64 * n2f / nf).sqrt() * nf / n2f)
        .collect();
    Some(Bands {
        edges,
        excess,
        sd,
        energy,
    })
}

fn frequency(
    log: &Log,
    before: &[Out],
    after: Option<&[Out]>,
    noise: &[f64; 3],
    total: f64,
) -> Vec<Region> {
    let n = log.len() as f64;
    let Some(b) = bands(log, before, noise) else {
        return vec![];
    };
    let a = after.and_then(|a| bands(log, a, noise));
    let mut out = Vec::new();
    for (k, &(lo, hi)) in b.edges.iter().enumerate() {
        let share = b.excess[k] / total;
        if share < MIN_SHARE || b.excess[k] <= SIGNIFICANCE * b.sd[k] {
            continue;
        }
        let rm = |e: &[f64; 3]| -> Channels {
            [(e[0] / n).sqrt(), (e[1] / n).sqrt(), (e[2] / n).sqrt()].into()
        };
        out.push(Region {
            variable: "frequency".into(),
            lo,
            hi,
            share_of_gap: share,
            share_of_rows: None,
            rmse: rm(&b.energy[k]),
            rmse_after: a.as_ref().map(|a| rm(&a.energy[k])),
        });
    }
    out
}
