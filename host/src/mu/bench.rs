//! `gough mu bench` and `gough mu demo`: the estimators against simulated truth.
//!
//! The plant is the host vehicle simulation (`crate::sim`) on the bundled tyre; its per-wheel
//! Fy, Mz, Fz, Fx pass through a sensor model — additive Gaussian noise (Mz 2 N·m rms, Fy, Fx and
//! Fz 1 % of Fz rms, seeded) and a 10 ms pure delay — before any estimator sees them. The
//! peers additionally get the (delayed, exact) slip angle and slip ratio, which the Gough method
//! never reads.
//!
//! Metrics per estimator and case, over the four wheels:
//! - μ error |μ̂ − μ| (mean and 95th percentile) over the samples the estimator calls
//!   identifiable, and the share of them within twice the σ reported (whether σ is honest);
//! - the utilisation |F|/(μ·Fz) (architecture.md) reached when the reported estimate first stays
//!   within ±0.1 of the truth until the end of its surface (median over wheels);
//! - latency: time from the utilisation first reaching 0.5 on a surface to the estimate staying
//!   within ±0.1 (median over wheels);
//! - for surfaces that change: the time from the wheel entering the new surface to the estimate
//!   staying within ±0.1 of it;
//! - change flags, and the false ones among them ([`false_change_flags`]: no change of road
//!   since the identification they change from, or a wrong new value).

use super::peers::{HsuGerdes, Row, SlipSlope};
use super::table_estimator::{Config, Estimate, GoughTable, Hold, MuEstimator, Sample, State};
use crate::rng::Rng;
use crate::sim::{self, Log, Manoeuvre, Overrides, SimConfig};
use clap::Args;
use gough::math::Libm;
use gough::mf::Params;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Arguments of `gough mu bench`.
#[derive(Args)]
pub struct BenchArgs {
    /// Tyre property file (.tir).
    #[arg(
        long,
        default_value = "host-tests/data/tyres/MagicFormula61_Parameters.tir"
    )]
    pub tir: PathBuf,
    /// Output directory for the table (table.md, table.csv) and the plots.
    #[arg(long, default_value = "out/mu_bench")]
    pub out: PathBuf,
    /// Noise seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Only the first N cases (for a quick look).
    #[arg(long)]
    pub cases: Option<usize>,
    /// A setting of the Gough estimator's `Config` other than its default, as NAME=VALUE
    /// (the field's name, e.g. `trail_drop_min=0.1`); repeatable, or comma-separated.
    #[arg(long = "set", value_name = "NAME=VALUE", value_delimiter = ',')]
    pub set: Vec<String>,
    /// Aligning-torque sensor noise, rms \[N·m\], added to every row the estimators see. The
    /// sensors, not the estimator: what the estimator assumes is its own `sigma_mz` (`--set`).
    #[arg(long, value_name = "NM", allow_negative_numbers = true, default_value_t = Sensors::default().sigma_mz)]
    pub noise_mz: f64,
    /// Force sensor noise (Fy, Fx, Fz), rms, as a fraction of Fz \[-\]; the estimator's own
    /// assumption is `sigma_fy_rel` (`--set`).
    #[arg(long, value_name = "FRACTION", allow_negative_numbers = true, default_value_t = Sensors::default().sigma_rel)]
    pub noise_f: f64,
    /// Pure delay of every measured channel \[s\] (rounded to the simulation's step, 1 ms).
    #[arg(long, value_name = "S", allow_negative_numbers = true, default_value_t = Sensors::default().delay)]
    pub delay: f64,
    /// Weight of the bank's front-to-rear preview (`gough::mu::preview`: what a front wheel
    /// read, handed to the rear wheel on its side a wheelbase later), inside (0, 1); 0: every
    /// wheel alone.
    #[arg(long, value_name = "W", default_value_t = 0.9)]
    pub preview: f64,
    /// Shift every surface's μ in the suite by D (0.025: midway between two of the bank's
    /// hypotheses, which the suite's own surfaces coincide with); |D| ≤ 0.05.
    #[arg(
        long,
        value_name = "D",
        allow_negative_numbers = true,
        default_value_t = 0.0
    )]
    pub mu_shift: f64,
    /// A tyre model that is not the tyre: NAME=DELTA adds DELTA to the `.tir` parameter NAME
    /// of the estimators' copy of the file only (e.g. `PHY1=0.002`: its horizontal shift 2 mrad
    /// off), the simulation keeps the file; repeatable, or comma-separated. How the estimators
    /// fare when the file they are given is wrong.
    #[arg(
        long = "model-error",
        value_name = "NAME=DELTA",
        value_delimiter = ',',
        allow_hyphen_values = true
    )]
    pub model_error: Vec<String>,
}

impl BenchArgs {
    /// The preview these arguments ask for over the simulated vehicle's wheelbase (`None`:
    /// `--preview 0`).
    pub fn preview(&self) -> Result<Option<gough::mu::preview::Config<f64>>, String> {
        if self.preview == 0.0 {
            return Ok(None);
        }
        if !(self.preview > 0.0 && self.preview < 1.0) {
            return Err(format!(
                "--preview {}: a weight inside (0, 1), or 0 for none",
                self.preview
            ));
        }
        Ok(Some(gough::mu::preview::Config {
            wheelbase: sim_wheelbase(),
            weight: self.preview,
        }))
    }

    /// The sensor model these arguments ask for: each value finite and ≥ 0, the delay at most
    /// 1 s.
    pub fn sensors(&self) -> Result<Sensors, String> {
        for (name, v, max) in [
            ("--noise-mz", self.noise_mz, f64::MAX),
            ("--noise-f", self.noise_f, f64::MAX),
            ("--delay", self.delay, 1.0),
        ] {
            if !(v.is_finite() && (0.0..=max).contains(&v)) {
                return Err(format!(
                    "{name} {v}: expected a finite value from 0 to {}",
                    if max < f64::MAX { "1 s" } else { "any size" }
                ));
            }
        }
        Ok(Sensors {
            sigma_mz: self.noise_mz,
            sigma_rel: self.noise_f,
            delay: self.delay,
            ..Sensors::default()
        })
    }
}

/// Sets one field of the estimator's configuration from `NAME=VALUE` (the field's name as in
/// [`Config`]; SI units as documented there).
pub fn set_config(c: &mut Config<f64>, kv: &str) -> Result<(), String> {
    let (k, v) = kv
        .split_once('=')
        .ok_or_else(|| format!("--set {kv}: expected NAME=VALUE"))?;
    let (k, v) = (k.trim(), v.trim());
    let num = || -> Result<f64, String> {
        v.parse::<f64>()
            .ok()
            .filter(|x| x.is_finite())
            .ok_or_else(|| format!("--set {k}: '{v}' is not a finite number"))
    };
    let count = || -> Result<u16, String> {
        v.parse::<u16>()
            .map_err(|_| format!("--set {k}: '{v}' is not a count (0..=65535)"))
    };
    let f = match k {
        "change_count" => {
            c.change_count = count()?;
            return Ok(());
        }
        "init_count" => {
            c.init_count = count()?;
            return Ok(());
        }
        "gamma" => &mut c.gamma,
        "sigma_mz" => &mut c.sigma_mz,
        "sigma_fy_rel" => &mut c.sigma_fy_rel,
        "vx_min" => &mut c.vx_min,
        "fz_min_rel" => &mut c.fz_min_rel,
        "fy_min_rel" => &mut c.fy_min_rel,
        "fy_share_min" => &mut c.fy_share_min,
        "trail_drop_min" => &mut c.trail_drop_min,
        "trail_drop_abs_min" => &mut c.trail_drop_abs_min,
        "sigma_max" => &mut c.sigma_max,
        "trail_model_rel" => &mut c.trail_model_rel,
        "arm_model_rel" => &mut c.arm_model_rel,
        "combined_model_rel" => &mut c.combined_model_rel,
        "combined_force_rel" => &mut c.combined_force_rel,
        "mzr_model_rel" => &mut c.mzr_model_rel,
        "q" => &mut c.q,
        "gate" => &mut c.gate,
        "gate_sigma_max" => &mut c.gate_sigma_max,
        "change_min" => &mut c.change_min,
        "run_gap" => &mut c.run_gap,
        "mu_prior" => &mut c.mu_prior,
        "sigma_prior" => &mut c.sigma_prior,
        "lowpass_tau" => &mut c.lowpass_tau,
        "settle" => &mut c.settle,
        "settle_distance" => &mut c.settle_distance,
        "ambiguity_sigmas" => &mut c.ambiguity_sigmas,
        "ambiguity_margin" => &mut c.ambiguity_margin,
        _ => {
            return Err(format!(
                "--set {k}: no such setting of the estimator's Config"
            ))
        }
    };
    *f = num()?;
    Ok(())
}

/// Arguments of `gough mu demo`.
#[derive(Args)]
pub struct DemoArgs {
    /// Tyre property file (.tir).
    #[arg(
        long,
        default_value = "host-tests/data/tyres/MagicFormula61_Parameters.tir"
    )]
    pub tir: PathBuf,
    /// Manoeuvre (one of the simulation's).
    #[arg(long, default_value = "sine-dwell")]
    pub manoeuvre: String,
    /// Road (the simulation's spec grammar).
    #[arg(long, default_value = "mu=1.0+patch=0.4@45..300")]
    pub road: String,
    /// Output directory (estimates.csv, mu.png, gough.png).
    #[arg(long, default_value = "out/demo")]
    pub out: PathBuf,
    /// Noise seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
}

/// Sensor model of the benchmark.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sensors {
    /// Mz noise rms \[N·m\].
    pub sigma_mz: f64,
    /// Fy, Fx, Fz noise rms as a fraction of Fz.
    pub sigma_rel: f64,
    /// Pure delay \[s\].
    pub delay: f64,
    /// Longitudinal slip noise, rms \[-\].
    pub sigma_kappa: f64,
}

impl Default for Sensors {
    fn default() -> Self {
        Sensors {
            sigma_mz: 2.0,
            sigma_rel: 0.01,
            delay: 0.010,
            sigma_kappa: 0.005,
        }
    }
}

/// One wheel's measured rows (noisy, delayed) and its truth, per logged step.
pub struct WheelTrace {
    /// What the estimators see.
    pub rows: Vec<Row>,
    /// True μ under the wheel at the (undelayed) time of each row.
    pub mu_true: Vec<f64>,
    /// True utilisation |F|/(μ·Fz) at each row.
    pub util: Vec<f64>,
    /// Camber γ \[rad\] (delayed): static plus roll camber, known to an ECU from the suspension
    /// kinematics and the roll estimate.
    pub gamma: Vec<f64>,
    /// Measured longitudinal slip κ (delayed, with the sensor's noise): from wheel speed and a
    /// vehicle-speed estimate, as an ABS controller has it.
    pub kappa_meas: Vec<f64>,
}

impl WheelTrace {
    /// Row `i` as the Gough estimator's sample (Fx, Vx and camber carried; no slip).
    pub fn sample(&self, i: usize) -> Sample<f64> {
        let r = &self.rows[i];
        Sample {
            t: r.t,
            fz: r.fz,
            fy: r.fy,
            mz: r.mz,
            fx: Some(r.fx),
            vx: Some(r.vx),
            gamma: self.gamma.get(i).copied(),
        }
    }
}

/// Applies the sensor model to wheel `w` of a log.
pub fn measure(log: &Log, w: usize, s: &Sensors, seed: u64) -> WheelTrace {
    let mut n = Rng::new(
        seed.wrapping_mul(0x9E37_79B9_7F4A_7C15)
            .wrapping_add(w as u64 + 1),
    );
    let lag = (s.delay / log.dt).round() as usize;
    let recs = &log.records;
    let mut tr = WheelTrace {
        rows: Vec::with_capacity(recs.len()),
        mu_true: Vec::with_capacity(recs.len()),
        util: Vec::with_capacity(recs.len()),
        gamma: Vec::with_capacity(recs.len()),
        kappa_meas: Vec::with_capacity(recs.len()),
    };
    // κ's noise has a generator of its own, so that the other channels' noise is unchanged.
    let mut nk = Rng::new(
        seed.wrapping_mul(0xD1B5_4A32_D192_ED03)
            .wrapping_add(w as u64 + 101),
    );
    for (i, r) in recs.iter().enumerate() {
        let src = &recs[i.saturating_sub(lag)].wheels[w];
        let fz = src.fz.max(0.0);
        let sr = s.sigma_rel * fz;
        tr.rows.push(Row {
            t: r.t,
            fz: fz + sr * n.normal(),
            fy: src.fy + sr * n.normal(),
            mz: src.mz + s.sigma_mz * n.normal(),
            fx: src.fx + sr * n.normal(),
            vx: src.vx,
            alpha: src.alpha,
            kappa: src.kappa,
        });
        tr.gamma.push(src.gamma);
        tr.kappa_meas.push(src.kappa + s.sigma_kappa * nk.normal());
        let now = &r.wheels[w];
        tr.mu_true.push(now.mu_true);
        tr.util.push(if now.fz > 0.0 && now.mu_true > 0.0 {
            now.fx.hypot(now.fy) / (now.mu_true * now.fz)
        } else {
            0.0
        });
    }
    tr
}

/// The estimators compared.
pub const METHODS: [&str; 4] = ["gough", "hsu-gerdes", "slip-slope", "bank"];
/// Index of the bank (the product's estimator) in [`METHODS`].
const BANK: usize = 3;

/// The Gough tables of the left and right wheels: the simulation mounts the tyre on both sides
/// (mirrored where the side differs from the file's TYRESIDE), so does the estimator.
pub struct Tables {
    left: Box<GoughTable<f64>>,
    right: Box<GoughTable<f64>>,
}

impl Tables {
    /// For both sides of the vehicle.
    pub fn new(p: &Params<f64>) -> Result<Tables, String> {
        use gough::mf::Side;
        Ok(Tables {
            left: super::table::<f64, Libm>(p, Some(Side::Left))?,
            right: super::table::<f64, Libm>(p, Some(Side::Right))?,
        })
    }
    /// Table of wheel `w` (fl, fr, rl, rr).
    pub fn wheel(&self, w: usize) -> &GoughTable<f64> {
        if w.is_multiple_of(2) {
            &self.left
        } else {
            &self.right
        }
    }
}

/// Runs estimator `m` (index into [`METHODS`]) over wheel `w`'s trace.
pub fn run_method(
    m: usize,
    p: &Params<f64>,
    tables: &Tables,
    w: usize,
    tr: &WheelTrace,
) -> Vec<Estimate<f64>> {
    match m {
        0 => run_gough(p, tables, w, tr, &Config::default()).0,
        3 => run_bank(p, w, tr),
        1 => match HsuGerdes::new(p) {
            Some(mut e) => tr.rows.iter().map(|r| e.update(r)).collect(),
            None => Vec::new(),
        },
        _ => match SlipSlope::new(p) {
            Some(mut e) => tr.rows.iter().map(|r| e.update(r)).collect(),
            None => Vec::new(),
        },
    }
}

/// The bank estimator over wheel `w`'s trace (mounted on the wheel's side, measured κ), alone.
pub fn run_bank(p: &Params<f64>, w: usize, tr: &WheelTrace) -> Vec<Estimate<f64>> {
    let Some(mut e) = new_bank(p, w) else {
        return Vec::new();
    };
    (0..tr.rows.len())
        .map(|i| super::bank_estimate(e.update::<Libm>(p, &bank_row(tr, i))))
        .collect()
}

fn new_bank(p: &Params<f64>, w: usize) -> Option<gough::mu::bank::Bank<f64>> {
    let side = gough::proto::Wheel::from_index(w).map(|x| x.side());
    gough::mu::bank::Bank::new::<Libm>(p, side, gough::mu::bank::Config::default()).ok()
}

/// Row `i` of a trace as the bank's sample (Fx, measured κ, Vx, camber).
fn bank_row(tr: &WheelTrace, i: usize) -> gough::mu::bank::Sample<f64> {
    let mut r = tr.rows[i];
    r.kappa = tr.kappa_meas.get(i).copied().unwrap_or(f64::NAN);
    super::bank_sample(&r, true, true, tr.gamma.get(i).copied())
}

/// Wheelbase of the simulated vehicle \[m\] (the front-to-rear preview's distance).
pub fn sim_wheelbase() -> f64 {
    sim::VehicleParams::default().wheelbase()
}

/// The bank over a vehicle's four wheels (fl, fr, rl, rr, sampled together), sample by sample
/// as the firmware runs them: each front wheel, then each rear wheel with what its front wheel
/// read handed on a wheelbase later ([`gough::mu::preview`], `preview`; `None`: every wheel
/// alone). Traces of other lengths than four, or not of one length, run wheel by wheel alone.
pub fn run_banks(
    p: &Params<f64>,
    traces: &[WheelTrace],
    preview: Option<gough::mu::preview::Config<f64>>,
) -> Vec<Vec<Estimate<f64>>> {
    use gough::mu::preview::Preview;
    let n = traces.first().map_or(0, |t| t.rows.len());
    let together = traces.len() == 4 && traces.iter().all(|t| t.rows.len() == n);
    let (Some(cfg), true) = (preview, together) else {
        return traces
            .iter()
            .enumerate()
            .map(|(w, tr)| run_bank(p, w, tr))
            .collect();
    };
    let banks: Option<Vec<_>> = (0..4).map(|w| new_bank(p, w)).collect();
    let (Some(mut banks), Ok(pv)) = (banks, Preview::new(cfg)) else {
        return vec![Vec::new(); traces.len()];
    };
    let mut pvs = [pv.clone(), pv];
    let mut out: Vec<Vec<_>> = (0..4).map(|_| Vec::with_capacity(n)).collect();
    for i in 0..n {
        for (w, (bank, o)) in banks.iter_mut().zip(out.iter_mut()).enumerate() {
            let s = bank_row(&traces[w], i);
            let e = gough::mu::preview::update::<f64, Libm>(Some(&mut pvs), w, bank, p, &s);
            o.push(super::bank_estimate(e));
        }
    }
    out
}

/// The Gough estimator (settings `cfg`) over wheel `w`'s trace: its estimates and, per sample,
/// why each held estimate was held ([`MuEstimator::last_hold`]).
pub fn run_gough(
    p: &Params<f64>,
    tables: &Tables,
    w: usize,
    tr: &WheelTrace,
    cfg: &Config<f64>,
) -> super::Run {
    let mut e = MuEstimator::for_tyre(tables.wheel(w), p, *cfg);
    (0..tr.rows.len())
        .map(|i| (e.update::<Libm>(&tr.sample(i)), e.last_hold()))
        .unzip()
}

/// Where the Gough estimator's latency goes on one case: over each wheel's surfaces that reach
/// utilisation 0.5, the samples of the target's window — from that moment until the estimate
/// settles within ±0.1, at most [`TARGET_LATENCY`] — by what the estimator reported.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct HoldTally {
    /// Samples held, per [`Hold::ALL`] reason.
    pub held: [usize; Hold::ALL.len()],
    /// Samples reported identifiable but not yet (for good) within ±0.1.
    pub identifiable: usize,
    /// Wheel-surfaces that reach utilisation 0.5.
    pub windows: usize,
    /// Of them, those whose estimate settles within ±0.1 within [`TARGET_LATENCY`].
    pub within: usize,
}

/// The issue's latency target: within ±0.1 this long after utilisation 0.5 \[s\].
pub const TARGET_LATENCY: f64 = 0.150;

impl HoldTally {
    /// All samples of the windows.
    pub fn total(&self) -> usize {
        self.held.iter().sum::<usize>() + self.identifiable
    }

    /// Adds another tally's samples and windows.
    pub fn add(&mut self, o: &HoldTally) {
        for (a, b) in self.held.iter_mut().zip(o.held) {
            *a += b;
        }
        self.identifiable += o.identifiable;
        self.windows += o.windows;
        self.within += o.within;
    }

    /// Shares of the samples \[held per [`Hold::ALL`] reason…, identifiable\] (0 when empty).
    pub fn shares(&self) -> Vec<f64> {
        let n = self.total().max(1) as f64;
        self.held
            .iter()
            .chain([&self.identifiable])
            .map(|&k| k as f64 / n)
            .collect()
    }
}

/// [`HoldTally`] of the Gough estimator's estimates `est` and reasons `holds` on the traces.
pub fn hold_tally(
    traces: &[WheelTrace],
    ests: &[Vec<Estimate<f64>>],
    holds: &[Vec<Option<Hold>>],
) -> HoldTally {
    let mut out = HoldTally::default();
    for ((tr, est), hs) in traces.iter().zip(ests).zip(holds) {
        if est.len() != tr.rows.len() || hs.len() != tr.rows.len() {
            continue;
        }
        for (a, b) in segments(&tr.mu_true) {
            let Some(i5) = (a..b).find(|&i| tr.util[i] >= 0.5) else {
                continue;
            };
            let ok = settled(tr, est, a, b);
            let deadline = tr.rows[i5].t + TARGET_LATENCY;
            let mut end = (i5..b).find(|&i| tr.rows[i].t > deadline).unwrap_or(b);
            if let Some(ok) = ok {
                end = end.min(ok.max(i5));
            }
            for h in &hs[i5..end] {
                match h.and_then(|h| Hold::ALL.iter().position(|&x| x == h)) {
                    Some(k) => out.held[k] += 1,
                    None => out.identifiable += 1,
                }
            }
            out.windows += 1;
            let lat = ok.and_then(|ok| latency_from(tr, a, b, ok));
            out.within += usize::from(lat.is_some_and(|l| l <= TARGET_LATENCY));
        }
    }
    out
}

/// An identifiable estimate off by more than this is a gross error \[-\].
pub const GROSS: f64 = 0.2;

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
fn settled(tr: &WheelTrace, est: &[Estimate<f64>], a: usize, b: usize) -> Option<usize> {
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
pub fn segment_latency(tr: &WheelTrace, est: &[Estimate<f64>], a: usize, b: usize) -> Option<f64> {
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
pub fn wheel_surfaces(traces: &[WheelTrace], ests: &[Vec<Estimate<f64>>]) -> Vec<WheelSurface> {
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
pub fn false_change_flags(tr: &WheelTrace, est: &[Estimate<f64>]) -> usize {
    // True μ where the current identification began.
    let mut began: Option<f64> = None;
    let mut false_flags = 0;
    for (i, e) in est.iter().enumerate() {
        let Some(&now) = tr.mu_true.get(i) else {
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

/// Metrics of estimates `est` against the trace(s).
pub fn metrics(traces: &[WheelTrace], ests: &[Vec<Estimate<f64>>]) -> Metrics {
    let mut errs = Vec::new();
    let (mut utils, mut lats, mut dets) = (Vec::new(), Vec::new(), Vec::new());
    let (mut false_alarms, mut change_flags) = (0, 0);
    let mut covered = 0;
    let (mut gross, mut samples) = (0usize, 0usize);
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
            if tr.util[i] >= 0.5 {
                util_hi += 1;
                ident_hi += usize::from(e.state == State::Identifiable);
            }
            if e.state == State::Identifiable {
                let err = (e.mu - tr.mu_true[i]).abs();
                errs.push(err);
                covered += usize::from(err <= 2.0 * e.sigma);
                gross += usize::from(err > GROSS);
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
pub fn common(traces: &[WheelTrace], a: &[Vec<Estimate<f64>>], b: &[Vec<Estimate<f64>>]) -> Common {
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

/// A benchmark case: a manoeuvre on a road.
#[derive(Debug, Clone)]
pub struct Case {
    /// Manoeuvre name.
    pub manoeuvre: &'static str,
    /// Road spec.
    pub road: String,
}

/// The suite: every manoeuvre on μ = 1.0, 0.7, 0.5, 0.3, 0.1, plus surface changes, plus the
/// straight ABS stop (the `abs-split` manoeuvre on one surface) on each μ.
pub fn suite() -> Vec<Case> {
    suite_shifted(0.0)
}

/// [`suite`] with every surface's μ shifted by `d` (`gough mu bench --mu-shift`): with
/// `d` = 0.025 each lies midway between two of the bank's hypotheses (0.10, 0.15, …), which the
/// suite's own surfaces all coincide with. `d` = 0 gives the suite's road specs unchanged.
pub fn suite_shifted(d: f64) -> Vec<Case> {
    let m = |mu: f64| -> String {
        let v = ((mu + d) * 1e6).round() / 1e6;
        format!("{v:?}")
    };
    let mut v = Vec::new();
    for man in [
        "step-steer",
        "sine-dwell",
        "brake-in-turn",
        "constant-radius",
        "slalom",
    ] {
        for mu in [1.0, 0.7, 0.5, 0.3, 0.1] {
            v.push(Case {
                manoeuvre: man,
                road: format!("mu={}", m(mu)),
            });
        }
    }
    v.push(Case {
        manoeuvre: "abs-split",
        road: format!("split={}/{}", m(0.9), m(0.2)),
    });
    v.push(Case {
        manoeuvre: "sine-dwell",
        road: format!("mu={}+patch={}@45..300", m(1.0), m(0.4)),
    });
    v.push(Case {
        manoeuvre: "slalom",
        road: format!("step={}@0,{}@90", m(1.0), m(0.3)),
    });
    v.push(Case {
        manoeuvre: "constant-radius",
        road: format!("mu={}+patch={}@-5..5", m(0.9), m(0.3)),
    });
    // Straight ABS stops (the μ-split stop's braking on one surface): μ from Fx against κ.
    for mu in [1.0, 0.7, 0.5, 0.3, 0.1] {
        v.push(Case {
            manoeuvre: "abs-split",
            road: format!("mu={}", m(mu)),
        });
    }
    v
}

/// A CSV field as RFC 4180 has it: quoted (inner quotes doubled) when it holds a comma, a quote
/// or a line break — a road spec such as `step=1.0@0,0.3@90` does.
pub(crate) fn csv_field(s: &str) -> std::borrow::Cow<'_, str> {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\"")).into()
    } else {
        s.into()
    }
}

fn fmt(x: Option<f64>, digits: usize) -> String {
    x.map_or("–".into(), |v| format!("{v:.digits$}"))
}

/// A straight ABS stop: the `abs-split` manoeuvre on one surface (not among issue 39's cases;
/// the suite adds them after those).
pub fn straight_stop(c: &Case) -> bool {
    c.manoeuvre == "abs-split" && c.road.starts_with("mu=")
}

/// Simulates a case.
pub fn simulate_case(p: &Params<f64>, c: &Case) -> Result<Log, String> {
    let m = Manoeuvre::by_name(c.manoeuvre, &Overrides::default())?;
    let mut cfg = SimConfig::new(m);
    cfg.road = sim::Road::parse(&c.road)?;
    sim::simulate(&cfg, p, false)
}

/// The estimators' tyre model under `--model-error`: `p` with each NAME=DELTA added to the
/// parameter NAME (a `.tir` key, any case). Refuses an unknown name, a DELTA that is not a
/// finite number, and a result the `.tir` checks refuse.
pub fn model_with_error(p: &Params<f64>, errors: &[String]) -> Result<Params<f64>, String> {
    let mut q = p.clone();
    for kv in errors {
        let (name, v) = kv
            .split_once('=')
            .ok_or_else(|| format!("--model-error {kv}: expected NAME=DELTA"))?;
        let key = gough::mf::Key::from_name(name.trim())
            .ok_or_else(|| format!("--model-error {kv}: no .tir parameter '{}'", name.trim()))?;
        let d: f64 = v
            .trim()
            .parse()
            .ok()
            .filter(|d: &f64| d.is_finite())
            .ok_or_else(|| format!("--model-error {kv}: '{}' is not a finite number", v.trim()))?;
        q.set(key, q.get(key) + d);
    }
    gough::tir::validate(&q).map_err(|(k, why)| {
        format!(
            "--model-error: the estimators' tyre is not a valid one ({}: {why:?})",
            k.name()
        )
    })?;
    Ok(q)
}

/// Runs the benchmark.
pub fn run(a: BenchArgs) -> Result<(), String> {
    let mut cfg = Config::default();
    for kv in &a.set {
        set_config(&mut cfg, kv)?;
    }
    let sensors = a.sensors()?;
    let t = crate::tyre::load(&a.tir)?;
    // `sim`: the tyre the simulation runs; `p`: the estimators' model of it (the same file
    // unless `--model-error`).
    let sim = t.params;
    let p = model_with_error(&sim, &a.model_error)?;
    let tables = Tables::new(&p)?;
    if !(a.mu_shift.is_finite() && a.mu_shift.abs() <= 0.05) {
        return Err(format!(
            "--mu-shift {}: expected a value from -0.05 to 0.05",
            a.mu_shift
        ));
    }
    let mut cases = suite_shifted(a.mu_shift);
    if let Some(n) = a.cases {
        cases.truncate(n);
    }
    std::fs::create_dir_all(&a.out).map_err(|e| format!("{}: {e}", a.out.display()))?;
    let mut md = String::new();
    if !a.model_error.is_empty() {
        let _ = writeln!(
            md,
            "Model error (`--model-error`): the estimators' tyre is {} with {}; the simulation's is the file.\n",
            a.tir.display(),
            a.model_error.join(", ")
        );
    }
    let _ = writeln!(md, "| manoeuvre | road | estimator | identifiable samples | mean err | p95 err | within 2σ | off by > 0.2 | util when within ±0.1 | latency from util 0.5 [s] | detect change [s] | false alarms |");
    let _ = writeln!(md, "|---|---|---|---|---|---|---|---|---|---|---|---|");
    let mut csv = String::from("manoeuvre,road,estimator,n_identifiable,err_mean,err_p95,within_2sigma,gross,util_within,latency_s,detect_s,false_alarms,ws_within,ws_total\n");
    let mut wheels_csv =
        String::from("manoeuvre,road,wheel,mu,t_start_s,t_end_s,t_util05_s,latency_s,within\n");
    let mut misses: Vec<(&Case, WheelSurface)> = Vec::new();
    let bar = indicatif::ProgressBar::new(cases.len() as u64);
    let mut tallies: Vec<(&Case, HoldTally)> = Vec::new();
    let mut gough_wins = 0;
    let mut comparable = 0;
    let mut within = [0usize; METHODS.len()];
    let mut ws = [(0usize, 0usize); METHODS.len()];
    // The same over the issue's cases: the suite without the straight ABS stops.
    let mut within_issue = [0usize; METHODS.len()];
    let mut ws_issue = [(0usize, 0usize); METHODS.len()];
    let issue_cases = cases.iter().filter(|c| !straight_stop(c)).count();
    let mut alarms = [0usize; METHODS.len()];
    let mut flags = [0usize; METHODS.len()];
    let mut worst: [Option<f64>; METHODS.len()] = [None; METHODS.len()];
    let mut worst_gross = [0.0f64; METHODS.len()];
    // Identifiable samples over the suite: (identifiable, all, identifiable at utilisation
    // ≥ 0.5, all at ≥ 0.5).
    let mut shares = [(0usize, 0usize, 0usize, 0usize); METHODS.len()];
    let mut per_case: Vec<(&Case, Vec<Metrics>, Vec<Common>)> = Vec::new();
    for c in &cases {
        bar.set_message(format!("{} on {}", c.manoeuvre, c.road));
        let log = simulate_case(&sim, c)?;
        let traces: Vec<WheelTrace> = (0..4).map(|w| measure(&log, w, &sensors, a.seed)).collect();
        let mut ms = Vec::new();
        let mut all_ests: Vec<Vec<Vec<Estimate<f64>>>> = Vec::new();
        for (m, method) in METHODS.iter().enumerate() {
            let ests: Vec<Vec<Estimate<f64>>> = if m == 0 {
                let (ests, holds): (Vec<_>, Vec<_>) = traces
                    .iter()
                    .enumerate()
                    .map(|(w, tr)| run_gough(&p, &tables, w, tr, &cfg))
                    .unzip();
                tallies.push((c, hold_tally(&traces, &ests, &holds)));
                ests
            } else if m == BANK {
                run_banks(&p, &traces, a.preview()?)
            } else {
                traces
                    .iter()
                    .enumerate()
                    .map(|(w, tr)| run_method(m, &p, &tables, w, tr))
                    .collect()
            };
            let mt = metrics(&traces, &ests);
            if m == BANK {
                for x in wheel_surfaces(&traces, &ests) {
                    let _ = writeln!(
                        wheels_csv,
                        "{},{},{},{},{:.3},{:.3},{:.3},{},{}",
                        csv_field(c.manoeuvre),
                        csv_field(&c.road),
                        WHEELS.get(x.wheel).copied().unwrap_or("?"),
                        x.mu,
                        x.t_start,
                        x.t_end,
                        x.t_util05,
                        fmt(x.latency, 3),
                        x.within()
                    );
                    if !x.within() {
                        misses.push((c, x));
                    }
                }
            }
            let _ = writeln!(
                md,
                "| {} | {} | {} | {} | {} | {} | {} | {:.2} % | {} | {} | {} | {} |",
                c.manoeuvre,
                c.road,
                method,
                mt.n_identifiable,
                fmt(mt.err_mean, 3),
                fmt(mt.err_p95, 3),
                mt.within_2sigma
                    .map_or("–".into(), |x| format!("{:.1} %", 100.0 * x)),
                100.0 * mt.gross,
                fmt(mt.util_within, 2),
                fmt(mt.latency, 3),
                fmt(mt.detect, 3),
                if m == 0 {
                    mt.false_alarms.to_string()
                } else {
                    "n/a".into()
                }
            );
            let _ = writeln!(
                csv,
                "{},{},{},{},{},{},{},{:.5},{},{},{},{},{},{}",
                csv_field(c.manoeuvre),
                csv_field(&c.road),
                method,
                mt.n_identifiable,
                fmt(mt.err_mean, 4),
                fmt(mt.err_p95, 4),
                fmt(mt.within_2sigma, 4),
                mt.gross,
                fmt(mt.util_within, 3),
                fmt(mt.latency, 4),
                fmt(mt.detect, 4),
                mt.false_alarms,
                mt.ws_within,
                mt.ws_total
            );
            let in_time = mt.latency.is_some_and(|l| l <= TARGET_LATENCY + 1e-9);
            within[m] += usize::from(in_time);
            ws[m].0 += mt.ws_within;
            ws[m].1 += mt.ws_total;
            if !straight_stop(c) {
                within_issue[m] += usize::from(in_time);
                ws_issue[m].0 += mt.ws_within;
                ws_issue[m].1 += mt.ws_total;
            }
            alarms[m] += mt.false_alarms;
            flags[m] += mt.change_flags;
            shares[m].0 += mt.n_identifiable;
            shares[m].1 += mt.n_samples;
            shares[m].2 += mt.n_identifiable_util_hi;
            shares[m].3 += mt.n_util_hi;
            worst_gross[m] = worst_gross[m].max(mt.gross);
            worst[m] = match (worst[m], mt.err_p95) {
                (Some(a), Some(b)) => Some(a.max(b)),
                (a, b) => a.or(b),
            };
            ms.push(mt);
            all_ests.push(ests);
        }
        // Each other estimator against the bank on the samples both call identifiable (the
        // bank's own entry left empty).
        let commons: Vec<Common> = all_ests
            .iter()
            .enumerate()
            .map(|(m, e)| {
                if m == BANK {
                    Common::default()
                } else {
                    common(&traces, &all_ests[BANK], e)
                }
            })
            .collect();
        // "Better than both peers where they produce an estimate": compare p95 error.
        for peer in &ms[1..3] {
            if let (Some(g), Some(q)) = (ms[0].err_p95, peer.err_p95) {
                comparable += 1;
                if g <= q {
                    gough_wins += 1;
                }
            }
        }
        if c.road.contains("patch") || c.road.contains("step") {
            let name = format!(
                "{}_{}",
                c.manoeuvre,
                c.road.replace(['=', '+', '@', '.', ',', '/'], "_")
            );
            // The front-left wheel's estimates, the bank's and the table estimator's.
            plot_mu(
                &traces[0],
                &[
                    ("bank", &all_ests[BANK][0]),
                    ("gough (table)", &all_ests[0][0]),
                ],
                &a.out.join(format!("mu_{name}.png")),
                &format!("{} on {} (front left)", c.manoeuvre, c.road),
            )?;
        }
        per_case.push((c, ms, commons));
        bar.inc(1);
    }
    bar.finish_and_clear();
    let mut summary = format!("\nThe table estimator (`gough`) at or below both peers' p95 error in {gough_wins} of {comparable} comparisons where a peer produced an estimate.\n");
    for (m, name) in METHODS.iter().enumerate() {
        let _ = writeln!(
            summary,
            "{name}: within ±0.1 within {TARGET_LATENCY} s of utilisation 0.5 on {} of {} cases and {} of {} wheel-surfaces; {} false change alarms of {} change flags; worst p95 error {}; worst share of samples identifiable and off by > {GROSS}: {:.2} %.",
            within[m],
            cases.len(),
            ws[m].0,
            ws[m].1,
            alarms[m],
            flags[m],
            fmt(worst[m], 3),
            100.0 * worst_gross[m],
        );
    }
    for (m, name) in METHODS.iter().enumerate() {
        let _ = writeln!(
            summary,
            "{name}, without the straight ABS stops: within ±0.1 within {TARGET_LATENCY} s of utilisation 0.5 on {} of {issue_cases} cases and {} of {} wheel-surfaces.",
            within_issue[m], ws_issue[m].0, ws_issue[m].1,
        );
    }
    for (m, name) in METHODS.iter().enumerate() {
        let (i, n, ih, nh) = shares[m];
        let pct = |a: usize, b: usize| 100.0 * a as f64 / b.max(1) as f64;
        let _ = writeln!(
            summary,
            "{name}: identifiable on {:.1} % of the suite's samples ({i} of {n}), {:.1} % of those at utilisation 0.5 or more ({ih} of {nh}).",
            pct(i, n),
            pct(ih, nh),
        );
    }
    md.push_str(&summary);
    md.push_str(&against_the_others(&per_case));
    md.push_str(&misses_table(&misses));
    if !a.set.is_empty() {
        let _ = writeln!(
            md,
            "\nThe Gough estimator ran with these settings changed from their defaults: {}.",
            a.set.join(", ")
        );
    }
    if a.mu_shift != 0.0 {
        let _ = writeln!(
            md,
            "\nEvery surface of the suite shifted by {:+} (the road specs above are the shifted ones).",
            a.mu_shift
        );
    }
    if sensors != Sensors::default() {
        let _ = writeln!(
            md,
            "\nSensor model changed from the default: Mz {} N·m rms, F {:.2} % Fz rms, {:.1} ms delay.",
            sensors.sigma_mz,
            100.0 * sensors.sigma_rel,
            1000.0 * sensors.delay
        );
    }
    let (holds_md, holds_csv) = hold_tables(&tallies);
    md.push_str(&holds_md);
    std::fs::write(a.out.join("table.md"), &md).map_err(|e| e.to_string())?;
    std::fs::write(a.out.join("table.csv"), &csv).map_err(|e| e.to_string())?;
    std::fs::write(a.out.join("holds.csv"), &holds_csv).map_err(|e| e.to_string())?;
    std::fs::write(a.out.join("wheels.csv"), &wheels_csv).map_err(|e| e.to_string())?;
    print!("{md}");
    eprintln!(
        "-> {}/table.md, table.csv, wheels.csv, holds.csv, mu_*.png",
        a.out.display()
    );
    Ok(())
}

/// Wheel names in the order of the traces.
const WHEELS: [&str; 4] = ["fl", "fr", "rl", "rr"];

/// "Wheel-surfaces the bank does not read within 150 ms": one row per miss (`wheels.csv` has
/// every wheel-surface).
fn misses_table(misses: &[(&Case, WheelSurface)]) -> String {
    let mut md = format!(
        "\n## Wheel-surfaces the bank does not read within {TARGET_LATENCY} s\n\n\
         Each wheel on each stretch of one μ that reaches utilisation 0.5, where the bank's estimate \
         does not stay within ±0.1 from at most {TARGET_LATENCY} s after that (out/mu_bench/wheels.csv \
         lists every wheel-surface):\n\n\
         | manoeuvre | road | wheel | μ | stretch [s] | utilisation 0.5 at [s] | latency [s] |\n\
         |---|---|---|---|---|---|---|\n"
    );
    for (c, x) in misses {
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} | {:.3}–{:.3} | {:.3} | {} |",
            c.manoeuvre,
            c.road,
            WHEELS.get(x.wheel).copied().unwrap_or("?"),
            x.mu,
            x.t_start,
            x.t_end,
            x.t_util05,
            x.latency
                .map_or("never for 50 rows".into(), |l| format!("{l:.3}")),
        );
    }
    md
}

/// "The bank against the others, case by case": for each case, every measure on which another
/// estimator does better than the bank (index 3 of [`METHODS`]) — more wheel-surfaces within
/// ±0.1 within [`TARGET_LATENCY`], a lower p95 error or a smaller share off by more than
/// [`GROSS`] while identifiable (where it is identifiable at all), a shorter median latency —
/// the p95 error and the count off by more than [`GROSS`] also like for like, on the samples
/// both call identifiable ([`Common`], `commons[m]`), and per other estimator how many cases
/// the bank is level or ahead on each measure.
pub fn against_the_others(per_case: &[(&Case, Vec<Metrics>, Vec<Common>)]) -> String {
    let mut md = format!(
        "\n## The bank against the others, case by case\n\nWhere another estimator does better than the bank on one of the issue's measures: wheel-surfaces within ±0.1 within {TARGET_LATENCY} s of utilisation 0.5 (ws), p95 error while identifiable (p95, with the identifiable samples n; and like for like, on the samples both call identifiable), share of the case's samples identifiable and off by > {GROSS} (gross; like for like: count off by > {GROSS} on the samples both call identifiable), median latency (latency; like for like: over the wheel-surfaces both settle on). Cases not listed: the bank level or ahead on all of them.\n\n| manoeuvre | road | behind on |\n|---|---|---|\n"
    );
    // Per other estimator: [ws, p95, gross, latency, and p95, gross, latency like for like]
    // as (bank level or ahead, comparable).
    let mut tally = [[(0usize, 0usize); 7]; METHODS.len()];
    for (c, ms, commons) in per_case {
        let Some(b) = ms.get(BANK) else { continue };
        let mut behind = Vec::new();
        for (m, o) in ms.iter().enumerate().filter(|&(m, _)| m != BANK) {
            let name = METHODS[m];
            let t = &mut tally[m];
            let cm = commons.get(m).cloned().unwrap_or_default();
            // One comparable measure: counted, and listed when the bank is behind.
            let mut measure = |i: usize, ok: bool, why: &dyn Fn() -> String| {
                t[i].1 += 1;
                t[i].0 += usize::from(ok);
                if !ok {
                    behind.push(format!("{name}: {}", why()));
                }
            };
            measure(0, o.ws_within <= b.ws_within, &|| {
                format!("ws {} > {}", o.ws_within, b.ws_within)
            });
            if let (Some(x), Some(y)) = (o.err_p95, b.err_p95) {
                measure(1, y <= x, &|| {
                    format!(
                        "p95 {x:.3} < {y:.3} (n {} vs {})",
                        o.n_identifiable, b.n_identifiable
                    )
                });
            }
            if let (Some(y), Some(x)) = cm.p95 {
                measure(4, y <= x, &|| {
                    format!("p95 like for like {x:.3} < {y:.3} (n {})", cm.n)
                });
            }
            if o.n_identifiable > 0 {
                measure(2, b.gross <= o.gross, &|| {
                    format!("gross {:.2} % < {:.2} %", 100.0 * o.gross, 100.0 * b.gross)
                });
            }
            if cm.n > 0 {
                measure(5, cm.gross.0 <= cm.gross.1, &|| {
                    format!(
                        "off by > {GROSS} like for like {} < {} (n {})",
                        cm.gross.1, cm.gross.0, cm.n
                    )
                });
            }
            if let (Some(y), Some(x), n) = cm.latency {
                measure(6, y <= x, &|| {
                    format!("latency like for like {x:.3} < {y:.3} s (over {n} wheel-surfaces)")
                });
            }
            if let Some(x) = o.latency {
                measure(3, b.latency.is_some_and(|y| y <= x), &|| {
                    format!(
                        "latency {x:.3} < {} s (over {} vs {} wheel-surfaces)",
                        fmt(b.latency, 3),
                        o.ws_within,
                        b.ws_within
                    )
                });
            }
        }
        if !behind.is_empty() {
            let _ = writeln!(
                md,
                "| {} | {} | {} |",
                c.manoeuvre,
                c.road,
                behind.join("; ")
            );
        }
    }
    md.push('\n');
    for (m, t) in tally.iter().enumerate().filter(|&(m, _)| m != BANK) {
        let name = METHODS[m];
        let _ = writeln!(
            md,
            "bank against {name}: ws level or ahead on {} of {} cases; p95 on {} of {} (both identifiable; like for like on {} of {}); gross on {} of {} ({name} identifiable; like for like on {} of {}); latency on {} of {} ({name} with one; like for like on {} of {}).",
            t[0].0, t[0].1, t[1].0, t[1].1, t[4].0, t[4].1, t[2].0, t[2].1, t[5].0, t[5].1, t[3].0, t[3].1, t[6].0, t[6].1
        );
    }
    md
}

/// The "where the latency goes" table (Markdown, and CSV with one row per case and a total).
fn hold_tables(tallies: &[(&Case, HoldTally)]) -> (String, String) {
    let mut md = String::from(
        "\n## Where the Gough estimator's latency goes\n\nPer case, over the wheels' surfaces that reach utilisation 0.5 (\"wheel-surfaces\"): how many settle within ±0.1 of the truth within 150 ms, and what the estimator reported over the samples of that window (from utilisation 0.5 until it settles, at most 150 ms): held, and why (`MuEstimator::last_hold`), or identifiable but not yet for good within ±0.1.\n\n| manoeuvre | road | wheel-surfaces | within 150 ms |",
    );
    let mut csv = String::from("manoeuvre,road,wheel_surfaces,within_150ms");
    for h in Hold::ALL {
        let _ = write!(md, " {} |", h.name());
        let _ = write!(csv, ",{}", h.name());
    }
    md.push_str(" identifiable |\n|---|---|---|---|");
    csv.push_str(",identifiable\n");
    for _ in 0..=Hold::ALL.len() {
        md.push_str("---|");
    }
    md.push('\n');
    let mut total = HoldTally::default();
    let mut row = |man: &str, road: &str, t: &HoldTally| {
        let _ = write!(md, "| {man} | {road} | {} | {} |", t.windows, t.within);
        let _ = write!(
            csv,
            "{},{},{},{}",
            csv_field(man),
            csv_field(road),
            t.windows,
            t.within
        );
        for x in t.shares() {
            if t.total() == 0 {
                md.push_str(" – |");
                csv.push(',');
            } else {
                let _ = write!(md, " {:.0} % |", 100.0 * x);
                let _ = write!(csv, ",{x:.4}");
            }
        }
        md.push('\n');
        csv.push('\n');
    };
    for (c, t) in tallies {
        row(c.manoeuvre, &c.road, t);
        total.add(t);
    }
    row("all", "", &total);
    (md, csv)
}

/// The product's main job on one command: a manoeuvre on a road whose friction changes, the
/// estimator at every wheel, a short table, plots.
pub fn demo(a: DemoArgs) -> Result<(), String> {
    let t = crate::tyre::load(&a.tir)?;
    let p = t.params;
    let case = Case {
        manoeuvre: sim::MANOEUVRES
            .iter()
            .copied()
            .find(|m| *m == a.manoeuvre)
            .ok_or_else(|| {
                format!(
                    "unknown manoeuvre '{}' (one of {})",
                    a.manoeuvre,
                    sim::MANOEUVRES.join(", ")
                )
            })?,
        road: a.road.clone(),
    };
    let log = simulate_case(&p, &case)?;
    let sensors = Sensors::default();
    std::fs::create_dir_all(&a.out).map_err(|e| format!("{}: {e}", a.out.display()))?;
    let mut csv = String::from("t,wheel,mu_true,mu,sigma,state,util\n");
    println!(
        "{} on '{}' ({}), estimator at every wheel (noise: Mz 2 N·m, F 1 % Fz, 10 ms lag; rear wheels told what the front ones read, {:.1} m later):",
        case.manoeuvre,
        case.road,
        p.version.name(),
        sim_wheelbase()
    );
    println!("wheel | true μ (start → end) | estimate at end | state | max utilisation | within ±0.1 from util");
    let mut first: Option<(WheelTrace, Vec<Estimate<f64>>)> = None;
    let traces: Vec<WheelTrace> = (0..4).map(|w| measure(&log, w, &sensors, a.seed)).collect();
    let ests = run_banks(
        &p,
        &traces,
        Some(gough::mu::preview::Config::with_wheelbase(sim_wheelbase())),
    );
    for (w, ((name, tr), est)) in WHEELS.iter().zip(traces).zip(ests).enumerate() {
        for (i, e) in est.iter().enumerate().step_by(10) {
            let _ = writeln!(
                csv,
                "{:.3},{},{:.3},{:.4},{:.4},{},{:.3}",
                tr.rows[i].t,
                name,
                tr.mu_true[i],
                e.mu,
                e.sigma,
                e.state.name(),
                tr.util[i]
            );
        }
        let m = metrics(std::slice::from_ref(&tr), std::slice::from_ref(&est));
        let last = est.last().copied().unwrap_or(Estimate {
            mu: f64::NAN,
            sigma: f64::NAN,
            sigma_model: f64::NAN,
            state: State::Fallback,
            change: false,
        });
        println!(
            "{:5} | {:.2} → {:.2} | {:.3} ± {:.3} | {} | {:.2} | {}",
            name,
            tr.mu_true.first().copied().unwrap_or(f64::NAN),
            tr.mu_true.last().copied().unwrap_or(f64::NAN),
            last.mu,
            last.sigma,
            last.state.name(),
            tr.util.iter().copied().fold(0.0, f64::max),
            fmt(m.util_within, 2)
        );
        if w == 0 {
            // The front-left wheel's measured channels as a LOG for `gough mu estimate`, which
            // takes a log as the file describes the tyre: mirrored (α, γ, Fy, Mz negated) when
            // the file's tyre is a right-hand one.
            let s = if p.mirrored_on(Some(gough::mf::Side::Left)) {
                -1.0
            } else {
                1.0
            };
            let rows: Vec<Vec<f64>> = tr
                .rows
                .iter()
                .zip(&tr.gamma)
                .zip(&tr.mu_true)
                .zip(&tr.kappa_meas)
                .map(|(((r, &g), &m), &k)| {
                    vec![
                        r.t,
                        r.fz,
                        s * r.fy,
                        s * r.mz,
                        r.fx,
                        r.vx,
                        k,
                        s * r.alpha,
                        s * g,
                        m,
                    ]
                })
                .collect();
            crate::csvio::write(
                &a.out.join("log_fl.csv"),
                &[
                    "t", "fz", "fy", "mz", "fx", "vx", "kappa", "alpha", "gamma", "mu",
                ],
                &rows,
            )
            .map_err(|e| format!("{}: {e}", a.out.display()))?;
        }
        if first.is_none() {
            first = Some((tr, est));
        }
    }
    std::fs::write(a.out.join("estimates.csv"), csv).map_err(|e| e.to_string())?;
    if let Some((tr, est)) = first {
        plot_mu(
            &tr,
            &[("bank", &est)],
            &a.out.join("mu.png"),
            &format!("{} on {} (front left)", case.manoeuvre, case.road),
        )?;
        plot_gough(&p, &log, 0, &a.out.join("gough.png"))?;
    }
    eprintln!(
        "-> {}/estimates.csv, log_fl.csv, mu.png, gough.png",
        a.out.display()
    );
    Ok(())
}

/// μ against time: truth and estimates (σ band for the first).
pub fn plot_mu(
    tr: &WheelTrace,
    series: &[(&str, &Vec<Estimate<f64>>)],
    path: &Path,
    title: &str,
) -> Result<(), String> {
    use plotters::prelude::*;
    crate::plot::font()?;
    let e = |x: &dyn std::fmt::Display| format!("{}: {x}", path.display());
    let root = BitMapBackend::new(path, (900, 450)).into_drawing_area();
    root.fill(&WHITE).map_err(|x| e(&x))?;
    let t_end = tr.rows.last().map_or(1.0, |r| r.t);
    let mut ch = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 18))
        .margin(10)
        .x_label_area_size(35)
        .y_label_area_size(45)
        .build_cartesian_2d(0.0..t_end, 0.0..1.4)
        .map_err(|x| e(&x))?;
    ch.configure_mesh()
        .x_desc("t [s]")
        .y_desc("μ")
        .label_style(("sans-serif", 12))
        .draw()
        .map_err(|x| e(&x))?;
    let step = (tr.rows.len() / 2000).max(1);
    ch.draw_series(LineSeries::new(
        tr.rows
            .iter()
            .zip(&tr.mu_true)
            .step_by(step)
            .map(|(r, &m)| (r.t, m)),
        BLACK.stroke_width(2),
    ))
    .map_err(|x| e(&x))?
    .label("true μ")
    .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 15, y)], BLACK));
    ch.draw_series(LineSeries::new(
        tr.rows
            .iter()
            .zip(&tr.util)
            .step_by(step)
            .map(|(r, &u)| (r.t, u.min(1.4))),
        RGBColor(180, 180, 180),
    ))
    .map_err(|x| e(&x))?
    .label("utilisation |F|/(μFz)")
    .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 15, y)], RGBColor(180, 180, 180)));
    let colours = [
        RGBColor(214, 39, 40),
        RGBColor(31, 119, 180),
        RGBColor(44, 160, 44),
    ];
    for (k, (name, est)) in series.iter().enumerate() {
        let c = colours[k % 3];
        ch.draw_series(
            tr.rows
                .iter()
                .zip(est.iter())
                .step_by(step)
                .filter(|(_, e)| e.state == State::Identifiable)
                .map(|(r, e)| Circle::new((r.t, e.mu), 1, c.filled())),
        )
        .map_err(|x| e(&x))?
        .label(format!("{name} (identifiable)"))
        .legend(move |(x, y)| Circle::new((x + 7, y), 3, c.filled()));
        ch.draw_series(LineSeries::new(
            tr.rows
                .iter()
                .zip(est.iter())
                .step_by(step)
                .map(|(r, e)| (r.t, e.mu)),
            c.mix(0.5),
        ))
        .map_err(|x| e(&x))?;
    }
    ch.configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .label_font(("sans-serif", 12))
        .draw()
        .map_err(|x| e(&x))?;
    root.present().map_err(|x| e(&x))?;
    Ok(())
}

/// The Gough plot: the model's Fy–Mz family for μ = 0.1…1.0 at the wheel's mean load, and the
/// wheel's simulated trajectory, as one [`crate::plot::gough`] panel.
pub fn plot_gough(p: &Params<f64>, log: &Log, w: usize, path: &Path) -> Result<(), String> {
    use crate::plot::{self, GoughSeries};
    use gough::mf::{self, Input, Options};
    use plotters::prelude::*;
    plot::font()?;
    let e = plot::err(path);
    let fz_mean =
        log.records.iter().map(|r| r.wheels[w].fz).sum::<f64>() / log.records.len().max(1) as f64;
    let mu0 = log.mu_y0;
    let mut curves = Vec::new();
    for (k, mu) in [0.1, 0.3, 0.5, 0.7, 1.0].into_iter().enumerate() {
        let mut q = p.clone();
        q.lmux = mu / mu0;
        q.lmuy = mu / mu0;
        let points = (-120..=120)
            .filter_map(|i| {
                let a = i as f64 * 0.0025;
                mf::eval::<f64, Libm>(
                    &q,
                    &Input {
                        fz: fz_mean,
                        alpha: a,
                        vx: 20.0,
                        ..Input::default()
                    },
                    &Options {
                        limits: false,
                        ..Options::default()
                    },
                )
                .ok()
                .map(|o| (o.mz, o.fy))
            })
            .collect();
        let c = Palette99::pick(k).to_rgba();
        curves.push(GoughSeries {
            label: format!("μ = {mu}"),
            colour: RGBColor(c.0, c.1, c.2),
            points,
        });
    }
    let step = (log.records.len() / 3000).max(1);
    let trajectory = GoughSeries {
        label: "simulated wheel".into(),
        colour: BLACK,
        points: log
            .records
            .iter()
            .step_by(step)
            .map(|r| (r.wheels[w].mz, r.wheels[w].fy))
            .collect(),
    };
    let root = BitMapBackend::new(path, (700, 600)).into_drawing_area();
    root.fill(&WHITE).map_err(&e)?;
    plot::gough(
        &root,
        &format!("Gough plot: model family at Fz = {fz_mean:.0} N, and the wheel's trajectory"),
        &curves,
        &[trajectory],
        None,
    )
    .map_err(&e)?;
    root.present().map_err(&e)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `--mu-shift`: every surface of the suite moved by the same amount, the specs unchanged
    /// at 0; the shifted ones lie midway between the bank's hypotheses.
    #[test]
    fn the_shifted_suite_moves_every_surface() {
        let roads =
            |d: f64| -> Vec<String> { suite_shifted(d).into_iter().map(|c| c.road).collect() };
        assert_eq!(
            roads(0.0),
            suite().into_iter().map(|c| c.road).collect::<Vec<_>>()
        );
        assert!(roads(0.0).contains(&"step=1.0@0,0.3@90".to_string()));
        let r = roads(0.025);
        assert_eq!(r.len(), suite().len());
        for want in [
            "mu=1.025",
            "mu=0.125",
            "split=0.925/0.225",
            "mu=1.025+patch=0.425@45..300",
            "step=1.025@0,0.325@90",
            "mu=0.925+patch=0.325@-5..5",
        ] {
            assert!(r.contains(&want.to_string()), "{want}: {r:?}");
        }
        for c in suite_shifted(0.025) {
            sim::Road::parse(&c.road).unwrap();
        }
    }

    /// The comparison lists exactly the measures on which another estimator beats the bank,
    /// and counts the rest level or ahead; an estimator never identifiable is not compared on
    /// p95 or gross.
    #[test]
    fn the_comparison_lists_where_the_bank_is_behind() {
        let bank = Metrics {
            n_identifiable: 1000,
            err_p95: Some(0.02),
            gross: 0.004,
            latency: Some(0.05),
            ws_within: 3,
            ws_total: 4,
            ..Metrics::default()
        };
        let silent = Metrics {
            ws_total: 4,
            ..Metrics::default()
        };
        let better_p95 = Metrics {
            n_identifiable: 20,
            err_p95: Some(0.01),
            gross: 0.0,
            latency: Some(0.5),
            ws_within: 1,
            ws_total: 4,
            ..Metrics::default()
        };
        let more_ws = Metrics {
            n_identifiable: 50,
            err_p95: Some(0.05),
            gross: 0.01,
            latency: Some(0.0),
            ws_within: 4,
            ws_total: 4,
            ..Metrics::default()
        };
        let case = Case {
            manoeuvre: "slalom",
            road: "mu=0.1".into(),
        };
        let level = Case {
            manoeuvre: "slalom",
            road: "mu=0.5".into(),
        };
        // Like for like: on the 20 samples both call identifiable, the bank's p95 is lower than
        // the table estimator's, and slip-slope is off by > 0.2 less often.
        let like = vec![
            Common {
                n: 20,
                p95: (Some(0.005), Some(0.01)),
                gross: (0, 0),
                latency: (Some(0.04), Some(0.5), 1),
            },
            Common::default(),
            Common {
                n: 50,
                p95: (Some(0.01), Some(0.05)),
                gross: (3, 1),
                latency: (Some(0.05), Some(0.0), 3),
            },
            Common::default(),
        ];
        let md = against_the_others(&[
            (
                &case,
                vec![better_p95, silent.clone(), more_ws, bank.clone()],
                like,
            ),
            (
                &level,
                vec![silent.clone(), silent, Metrics::default(), bank],
                vec![Common::default(); 4],
            ),
        ]);
        let row = md
            .lines()
            .find(|l| l.starts_with("| slalom | mu=0.1 |"))
            .unwrap();
        assert!(
            row.contains("gough: p95 0.010 < 0.020 (n 20 vs 1000)"),
            "{row}"
        );
        assert!(row.contains("gough: gross 0.00 % < 0.40 %"), "{row}");
        assert!(
            !row.contains("gough: ws") && !row.contains("gough: latency"),
            "{row}"
        );
        assert!(row.contains("slip-slope: ws 4 > 3"), "{row}");
        assert!(row.contains("slip-slope: latency 0.000 < 0.050 s"), "{row}");
        assert!(!row.contains("hsu-gerdes"), "{row}");
        assert!(!row.contains("gough: p95 like for like"), "{row}");
        assert!(
            row.contains("slip-slope: off by > 0.2 like for like 1 < 3 (n 50)"),
            "{row}"
        );
        assert!(!md.contains("| slalom | mu=0.5 |"), "{md}");
        assert!(md.contains("bank against gough: ws level or ahead on 2 of 2 cases; p95 on 0 of 1 (both identifiable; like for like on 1 of 1); gross on 0 of 1 (gough identifiable; like for like on 1 of 1); latency on 1 of 1 (gough with one; like for like on 1 of 1)"), "{md}");
        assert!(
            md.contains(
                "bank against hsu-gerdes: ws level or ahead on 2 of 2 cases; p95 on 0 of 0"
            ),
            "{md}"
        );
        assert!(
            md.contains("bank against slip-slope: ws level or ahead on 1 of 2 cases"),
            "{md}"
        );
    }

    /// The bundled MF 6.1 tyre, as the bench runs it.
    fn bundled_tyre() -> Params<f64> {
        crate::tyre::load(Path::new(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../host-tests/data/tyres/MagicFormula61_Parameters.tir"
        )))
        .unwrap()
        .params
    }

    /// The sensor model is what `--noise-mz`, `--noise-f` and `--delay` ask for: without noise
    /// and delay every row is the simulation's own; the delay shifts the rows by whole steps
    /// and the noise has the rms asked for; a negative or non-finite value, or a delay over
    /// 1 s, is refused.
    #[test]
    fn sensor_arguments_reach_the_rows() {
        use clap::Parser;
        #[derive(Parser)]
        struct Cli {
            #[command(flatten)]
            a: BenchArgs,
        }
        let parse = |extra: &[&str]| {
            Cli::try_parse_from(["bench"].iter().chain(extra))
                .unwrap()
                .a
                .sensors()
        };
        assert_eq!(parse(&[]).unwrap(), Sensors::default());
        for bad in [
            &["--noise-mz", "-1"][..],
            &["--noise-f", "NaN"],
            &["--delay", "2"],
        ] {
            let e = parse(bad).unwrap_err();
            assert!(e.starts_with(bad[0]), "{e}");
        }
        let p = bundled_tyre();
        let case = Case {
            manoeuvre: "step-steer",
            road: "mu=0.5".into(),
        };
        let log = simulate_case(&p, &case).unwrap();
        let exact = parse(&["--noise-mz", "0", "--noise-f", "0", "--delay", "0"]).unwrap();
        let late = parse(&["--noise-mz", "0", "--noise-f", "0", "--delay", "0.02"]).unwrap();
        let noisy = parse(&["--noise-mz", "5", "--noise-f", "0.02", "--delay", "0"]).unwrap();
        let w = 1;
        let (tr, tl, tn) = (
            measure(&log, w, &exact, 1),
            measure(&log, w, &late, 1),
            measure(&log, w, &noisy, 1),
        );
        let (mut se_mz, mut se_fy) = (0.0, 0.0);
        for (i, r) in log.records.iter().enumerate() {
            let x = &r.wheels[w];
            let (a, b, c) = (&tr.rows[i], &tl.rows[i], &tn.rows[i]);
            assert_eq!(
                (a.fz, a.fy, a.mz, a.fx),
                (x.fz, x.fy, x.mz, x.fx),
                "row {i}"
            );
            if i >= 20 {
                assert_eq!(b.mz, tr.rows[i - 20].mz, "row {i}");
            }
            se_mz += (c.mz - x.mz).powi(2);
            se_fy += ((c.fy - x.fy) / (0.02 * x.fz)).powi(2);
        }
        let n = log.records.len() as f64;
        let (rms_mz, rms_fy) = ((se_mz / n).sqrt(), (se_fy / n).sqrt());
        assert!((rms_mz - 5.0).abs() < 0.25, "Mz noise {rms_mz}");
        assert!((rms_fy - 1.0).abs() < 0.05, "Fy noise {rms_fy} of 2 % Fz");
    }

    /// Why the step steer on μ 1.0 stays ambiguous with perfect sensors: its front-left wheel,
    /// steady at 4 s (Fz ≈ 3,370 N, γ ≈ −0.036 rad, utilisation ≈ 0.56, trail 9.1 mm), makes a
    /// point that the simulation's own Magic Formula puts on two surfaces: the true one, and
    /// one near λμ 0.62 (μ ≈ 0.63) at utilisation ≈ 0.89, where the trail has collapsed to
    /// the grippy curve's value at that force. No single reading can choose between
    /// them; only how the point got there can (README, "Not the sensors: a single point").
    #[test]
    fn one_steady_point_lies_on_two_surfaces() {
        use gough::mf::{self, Input, Options, Side};
        let p = bundled_tyre();
        let case = Case {
            manoeuvre: "step-steer",
            road: "mu=1.0".into(),
        };
        let log = simulate_case(&p, &case).unwrap();
        let rec = log.records.iter().find(|r| r.t >= 4.0).unwrap();
        let w = &rec.wheels[0]; // front left
        let tau_m = -w.mz / w.fy;
        let opts = Options {
            transient: true,
            mounted: Some(Side::Left),
            ..Options::default()
        };
        // The trail on surface λμ at the measured |Fy|, on the rising side of the force (small
        // slip first), with the record's load, camber, slip ratio and speed; None when the
        // surface never reaches the force.
        let eval = |q: &Params<f64>, alpha: f64| {
            let inp = Input {
                fz: w.fz,
                kappa: w.kappa_t,
                alpha,
                gamma: w.gamma,
                vx: w.vx,
                ..Input::default()
            };
            mf::eval::<f64, Libm>(q, &inp, &opts).unwrap()
        };
        let trail_at_force = |lam: f64| -> Option<(f64, f64)> {
            let mut q = p.clone();
            q.lmuy = lam;
            q.lmux = lam;
            let sgn = w.alpha_t.signum();
            let (mut lo, mut hi) = (0.0, 0.0);
            for i in 1..=400 {
                let a = sgn * 0.0005 * i as f64;
                if eval(&q, a).fy.abs() >= w.fy.abs() {
                    hi = a;
                    break;
                }
                lo = a;
            }
            if hi == 0.0 {
                return None;
            }
            for _ in 0..50 {
                let mid = 0.5 * (lo + hi);
                if eval(&q, mid).fy.abs() < w.fy.abs() {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            let o = eval(&q, hi);
            // Utilisation as the bench counts it: |F|/(μ·Fz), μ = λμ·μy0.
            Some((-o.mz / o.fy, w.fx.hypot(w.fy) / (lam * log.mu_y0 * w.fz)))
        };
        let lam_true = 1.0 / log.mu_y0;
        let grid: Vec<f64> = (40..=130).map(|i| 0.01 * i as f64).collect();
        let d: Vec<Option<(f64, f64)>> = grid
            .iter()
            .map(|&l| trail_at_force(l).map(|(t, u)| (t - tau_m, u)))
            .collect();
        // Surfaces whose curve passes through the measured point: sign changes of d.
        let mut roots = Vec::new();
        for i in 1..grid.len() {
            if let (Some((a, _)), Some((b, u))) = (d[i - 1], d[i]) {
                if a * b <= 0.0 && a != b {
                    let l = grid[i - 1] + (grid[i] - grid[i - 1]) * a / (a - b);
                    roots.push((l, u * grid[i] / l));
                }
            }
        }
        std::println!(
            "trail {:.2} mm at Fy {:.0} N, Fz {:.0} N, γ {:.4}: on λμ {roots:.3?}",
            1000.0 * tau_m,
            w.fy,
            w.fz,
            w.gamma
        );
        assert_eq!(roots.len(), 2, "{roots:?}");
        let (hi, lo) = (roots[1], roots[0]);
        assert!(
            (hi.0 - lam_true).abs() < 0.02,
            "{roots:?} against {lam_true}"
        );
        assert!((0.55..0.7).contains(&lo.0), "{roots:?}");
        assert!(hi.1 < 0.6 && lo.1 > 0.85, "utilisations {roots:?}");
    }

    /// A road spec with a comma stays one field of table.csv.
    #[test]
    fn csv_fields_with_commas_are_quoted() {
        assert_eq!(csv_field("mu=0.5"), "mu=0.5");
        assert_eq!(csv_field("step=1.0@0,0.3@90"), "\"step=1.0@0,0.3@90\"");
        assert_eq!(csv_field("a\"b"), "\"a\"\"b\"");
    }

    /// The tally's window: from the utilisation first reaching 0.5 to the estimate settling
    /// (at most 150 ms), every sample counted once, by its reason; a surface that never reaches
    /// utilisation 0.5 has no window.
    #[test]
    fn hold_tally_counts_the_window_by_reason() {
        // 1 kHz, 400 rows; two surfaces: μ 0.5 (rows 0..300), μ 0.3 (300..400).
        let n = 400;
        let row = |i: usize| Row {
            t: i as f64 * 1e-3,
            fz: 4000.0,
            vx: 20.0,
            ..Row::default()
        };
        let mu_true: Vec<f64> = (0..n).map(|i| if i < 300 { 0.5 } else { 0.3 }).collect();
        // Utilisation 0.5 from row 10 on the first surface; never on the second.
        let util: Vec<f64> = (0..n)
            .map(|i| if (10..300).contains(&i) { 0.6 } else { 0.2 })
            .collect();
        let tr = WheelTrace {
            rows: (0..n).map(row).collect(),
            mu_true,
            util,
            gamma: vec![0.0; n],
            kappa_meas: vec![0.0; n],
        };
        let est = |mu: f64, state: State| Estimate {
            mu,
            sigma: 0.01,
            sigma_model: 0.0,
            state,
            change: false,
        };
        // Rows 0..40 no excitation, 40..70 ambiguous, 70..80 confirming, 80..100 identifiable but
        // 0.2 off, from 100 on within ±0.1 (settled at row 100: latency 90 ms).
        let (mut ests, mut holds) = (Vec::new(), Vec::new());
        for i in 0..n {
            let (e, h) = match i {
                0..40 => (est(0.8, State::Fallback), Some(Hold::NoExcitation)),
                40..70 => (est(0.8, State::Fallback), Some(Hold::Ambiguous)),
                70..80 => (est(0.8, State::Fallback), Some(Hold::Confirming)),
                80..100 => (est(0.7, State::Identifiable), None),
                _ => (est(mu_true_at(i), State::Identifiable), None),
            };
            ests.push(e);
            holds.push(h);
        }
        fn mu_true_at(i: usize) -> f64 {
            if i < 300 {
                0.5
            } else {
                0.3
            }
        }
        let t = hold_tally(std::slice::from_ref(&tr), &[ests.clone()], &[holds.clone()]);
        let k = |h: Hold| t.held[Hold::ALL.iter().position(|&x| x == h).unwrap()];
        assert_eq!((t.windows, t.within), (1, 1));
        assert_eq!(
            (
                k(Hold::NoExcitation),
                k(Hold::Ambiguous),
                k(Hold::Confirming),
                t.identifiable
            ),
            (30, 30, 10, 20)
        );
        assert_eq!(t.total(), 90);
        // Settling later than 150 ms: the window stops at the deadline, and it is not within.
        for e in &mut ests[100..300] {
            e.mu = 0.7;
        }
        for e in &mut ests[250..300] {
            e.mu = 0.5;
        }
        let t = hold_tally(std::slice::from_ref(&tr), &[ests], &[holds]);
        assert_eq!((t.windows, t.within), (1, 0));
        assert_eq!(
            t.total(),
            151,
            "rows 10..=160 (the deadline's row 160 included)"
        );
        assert_eq!(t.identifiable, 151 - 70);
    }

    /// `--model-error` adds each delta to its parameter (any case) and to nothing else.
    #[test]
    fn a_model_error_changes_its_parameters_only() {
        let p = crate::tyre::load(std::path::Path::new(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../host-tests/data/tyres/MagicFormula61_Parameters.tir"
        )))
        .unwrap()
        .params;
        let q = model_with_error(&p, &["PHY1=0.002".into(), "pvy1 = -0.01".into()]).unwrap();
        assert!((q.phy1 - p.phy1 - 0.002).abs() < 1e-15);
        assert!((q.pvy1 - p.pvy1 + 0.01).abs() < 1e-15);
        let mut back = q.clone();
        back.phy1 = p.phy1;
        back.pvy1 = p.pvy1;
        assert_eq!(back, p);
        assert_eq!(model_with_error(&p, &[]).unwrap(), p);
        for bad in ["PHY1", "NOPE=1", "PHY1=x", "PHY1=NaN", "FNOMIN=-1e9"] {
            assert!(model_with_error(&p, &[bad.into()]).is_err(), "{bad}");
        }
    }

    /// Every field of the estimator's `Config` can be set by name (and only it), to the value
    /// given; a bad value or name is an error naming it.
    #[test]
    fn set_config_reaches_every_field() {
        let names = [
            "gamma",
            "sigma_mz",
            "sigma_fy_rel",
            "vx_min",
            "fz_min_rel",
            "fy_min_rel",
            "fy_share_min",
            "trail_drop_min",
            "trail_drop_abs_min",
            "sigma_max",
            "trail_model_rel",
            "arm_model_rel",
            "combined_model_rel",
            "combined_force_rel",
            "mzr_model_rel",
            "q",
            "gate",
            "gate_sigma_max",
            "change_min",
            "change_count",
            "run_gap",
            "init_count",
            "mu_prior",
            "sigma_prior",
            "lowpass_tau",
            "settle",
            "settle_distance",
            "ambiguity_sigmas",
            "ambiguity_margin",
        ];
        let mut all = Config::default();
        for n in names {
            let mut c = Config::default();
            set_config(&mut c, &format!("{n}=7")).unwrap();
            assert_ne!(c, Config::default(), "{n}");
            set_config(&mut all, &format!(" {n} = 7 ")).unwrap();
        }
        // Every field set: the Debug form holds no default value any more but 7s.
        let dbg = format!("{all:?}");
        let values: Vec<&str> = dbg
            .split(", ")
            .map(|kv| kv.rsplit(": ").next().unwrap().trim_end_matches(" }"))
            .collect();
        assert_eq!(values.len(), names.len(), "{dbg}");
        assert!(values.iter().all(|v| *v == "7.0" || *v == "7"), "{dbg}");
        for bad in [
            "q",
            "q=",
            "q=nan",
            "q=inf",
            "init_count=-1",
            "init_count=0.5",
            "nope=1",
        ] {
            let e = set_config(&mut Config::default(), bad).unwrap_err();
            assert!(e.contains(bad.split('=').next().unwrap()), "{bad}: {e}");
        }
    }

    /// A trace at 1 kHz with true μ `mu_true` and utilisation `util` per row (its measured
    /// channels constant: the metrics read the estimates against the truth only).
    fn flat_trace(mu_true: Vec<f64>, util: Vec<f64>) -> WheelTrace {
        let n = mu_true.len();
        WheelTrace {
            rows: (0..n)
                .map(|i| Row {
                    t: i as f64 * 1e-3,
                    fz: 4000.0,
                    fy: 0.0,
                    mz: 0.0,
                    fx: 0.0,
                    vx: 20.0,
                    alpha: f64::NAN,
                    kappa: f64::NAN,
                })
                .collect(),
            mu_true,
            util,
            gamma: vec![0.0; n],
            kappa_meas: vec![0.0; n],
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
            sigma_model: 0.0,
            state,
            change: false,
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
            sigma_model: 0.0,
            state: State::Identifiable,
            change,
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
                sigma_model: 0.0,
                state: State::Identifiable,
                change: false,
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

    /// Straight running with a static camber makes points that read like ice at full sliding:
    /// the camber thrust alone passes `fy_min_rel` (|Fy|/Fz ≈ 0.05 at 0.85·Fz0) and the
    /// residual torque leaves a trail of a few mm (Fy ≈ 300 N, Mz ≈ −2 N·m), so the trail looks
    /// collapsed and the reading says μ ≈ 0.05. Every per-reading check passes many of them
    /// ([`MuEstimator::raw`] returns a reading: 320 here). They come in runs; it is
    /// `init_count` that keeps them from becoming an estimate: with it at 1 this test counts
    /// 22 wrong estimates below a utilisation of 0.2 (and over the whole bench suite, 36; a
    /// scratch run). At 6 none, but then a burst at higher utilisation in the slalom on μ 1.0
    /// becomes a wrong estimate (p95 error 0.68 there): 13 stays.
    #[test]
    fn straight_running_with_camber_never_reads_ice() {
        let p = bundled_tyre();
        let tables = Tables::new(&p).unwrap();
        let (mut hazards, mut wrong, mut right) = (0, 0, 0);
        for manoeuvre in ["sine-dwell", "slalom"] {
            let case = Case {
                manoeuvre,
                road: "mu=1.0".into(),
            };
            let log = simulate_case(&p, &case).unwrap();
            for w in 0..4 {
                let tr = measure(&log, w, &Sensors::default(), 1);
                let est = run_method(0, &p, &tables, w, &tr);
                let probe = MuEstimator::for_tyre(tables.wheel(w), &p, Config::default());
                for (i, e) in est.iter().enumerate() {
                    let low = tr.util[i] < 0.2;
                    // What one reading of the sample (unfiltered) says.
                    let raw = probe.raw::<Libm>(&tr.sample(i));
                    if low && raw.is_some_and(|x| (x.lambda * probe.mu0() - 1.0).abs() > 0.5) {
                        hazards += 1;
                    }
                    if e.state == State::Identifiable {
                        if (e.mu - tr.mu_true[i]).abs() > 0.1 && low {
                            wrong += 1;
                        } else {
                            right += 1;
                        }
                    }
                }
            }
        }
        println!("ice-like readings below utilisation 0.2: {hazards}; wrong estimates there: {wrong}; other identifiable: {right}");
        assert!(
            hazards > 50,
            "the hazard this test guards is gone ({hazards}): revisit it"
        );
        assert_eq!(wrong, 0);
        assert!(right > 1000);
    }
}
