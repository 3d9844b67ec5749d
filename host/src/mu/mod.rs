//! Friction estimation on logs: the core's estimator (`gough::mu::bank`) driven by CSV rows, its
//! peers — the previous table estimator ([`table_estimator`], moved here from the core) and the
//! literature baselines ([`peers`]) — and the closed-loop benchmark on the vehicle simulation
//! ([`bench`](mod@bench)). Nothing here re-implements the core's estimator.
pub mod bench;
pub mod bound;
pub mod calibrate;
pub mod demo;
pub mod map;
pub mod peers;
pub mod scenario;
pub mod table_estimator;

use crate::csvio;
use gough::math::{Backend, Float, Libm};
use gough::mf::{Params, Side};
use gough::mu::bank;
use peers::{HsuGerdes, Row, SlipSlope};
use std::path::Path;
use table_estimator::{Config, Estimate, GoughTable, Hold, MuEstimator, Sample, State};

/// The Gough table of `p` mounted on `mounted` (`GoughTable::for_wheel_into`), built in place on
/// the heap: a debug build copies a value the size of an f64 table several times on its way
/// out of `GoughTable::for_wheel` — enough to overflow a test thread's stack.
pub fn table<F: Float, M: Backend<F>>(
    p: &Params<F>,
    mounted: Option<Side>,
) -> Result<Box<GoughTable<F>>, String> {
    let mut t = Box::new(GoughTable::zeroed());
    t.for_wheel_into::<M>(p, mounted)
        .map_err(|e| e.to_string())?;
    Ok(t)
}

/// How the tyre is mounted on wheels 0–3 of a log whose rows are of `wheels`: a car's log (a
/// wheel other than 0) each wheel on its side (`gough::proto::Wheel::side`, as
/// `gough::wheel::Car` on the device), one wheel's log on `side` (`None`: as the file describes
/// the tyre).
pub fn mounting(wheels: &[usize], side: Option<Side>) -> [Option<Side>; 4] {
    if wheels.iter().any(|&w| w != 0) {
        gough::proto::Wheel::ALL.map(|w| Some(w.side()))
    } else {
        [side; 4]
    }
}

/// Which estimator.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Method {
    /// The exact-model bank of the core (`gough::mu::bank`: Fy, Mz, Fz, Fx, κ, Vx, γ — never
    /// α): the current estimator.
    Bank,
    /// The table estimator ([`table_estimator::MuEstimator`], uses Fy, Mz, Fz, Fx, Vx — never
    /// α): the previous one, kept as a peer in the bench.
    Gough,
    /// Hsu, Laws & Gerdes (2010): pneumatic trail with the slip angle.
    HsuGerdes,
    /// Gustafsson (1997): longitudinal slip slope.
    SlipSlope,
}

/// Float path of the estimator (the bank or the table estimator).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Precision {
    /// f64 (host).
    F64,
    /// f32 (the device's).
    F32,
}

/// Optional log columns, in the order of [`Log`]'s presence flags.
pub const OPTIONAL: [&str; 5] = ["fx", "vx", "kappa", "alpha", "gamma"];

/// A log as the estimators read it: rows, the camber column (NaN where absent) and which of
/// [`OPTIONAL`] were present.
pub type Log = (Vec<Row>, Vec<f64>, [bool; 5]);

/// Reads a log into rows; the error is one line naming file, line and column. Time must
/// increase strictly. Absent optional values read as NaN (never mistaken for a measured 0).
/// A `wheel` column is not read (see [`read_car_log`]).
pub fn read_log(path: &Path) -> Result<Log, String> {
    read_rows(path, false).map(|(log, _)| log)
}

/// [`read_log`] for a log of up to four wheels: with a `wheel` column (0–3: FL, FR, RL, RR;
/// rows of the wheels interleaved in time) each row's wheel, time increasing per wheel; without
/// it every row is wheel 0 and time increases throughout.
pub fn read_car_log(path: &Path) -> Result<(Log, Vec<usize>), String> {
    read_rows(path, true)
}

fn read_rows(path: &Path, per_wheel: bool) -> Result<(Log, Vec<usize>), String> {
    let t = csvio::read::<csvio::WheelRow>(path).map_err(|e| e.to_string())?;
    let mut rows = Vec::with_capacity(t.rows.len());
    let mut gamma = Vec::with_capacity(t.rows.len());
    let mut wheels = Vec::with_capacity(t.rows.len());
    let mut last = [f64::NEG_INFINITY; 4];
    let v = |x: Option<f64>| x.unwrap_or(f64::NAN);
    for (r, line) in t.rows.iter().zip(&t.lines) {
        let w = match r.wheel.filter(|_| per_wheel) {
            None => 0,
            Some(w) if w.fract() == 0.0 && (0.0..=3.0).contains(&w) => w as usize,
            Some(w) => {
                return Err(format!(
                    "{}: line {line}, column wheel: {w} is not 0, 1, 2 or 3",
                    path.display()
                ))
            }
        };
        if r.t <= last[w] {
            return Err(format!(
                "{}: line {line}, column t: time does not increase ({} after {}{})",
                path.display(),
                r.t,
                last[w],
                if per_wheel && t.has("wheel") {
                    format!(", wheel {w}")
                } else {
                    String::new()
                }
            ));
        }
        last[w] = r.t;
        rows.push(Row {
            t: r.t,
            fz: r.fz,
            fy: r.fy,
            mz: r.mz,
            fx: v(r.fx),
            vx: v(r.vx),
            kappa: v(r.kappa),
            alpha: v(r.alpha),
        });
        gamma.push(v(r.gamma));
        wheels.push(w);
    }
    Ok(((rows, gamma, OPTIONAL.map(|c| t.has(c))), wheels))
}

/// The bank over a log of up to four wheels (`wheels[i]`: row `i`'s wheel, 0–3 = FL, FR, RL,
/// RR), row by row as a car's controller runs it: a bank per wheel, and with `wheelbase` \[m\]
/// the front-to-rear preview ([`gough::mu::preview`]) from each front wheel to the rear wheel on
/// its side. Wheel `w`'s tyre is mounted on `mounted[w]` ([`mounting`]; `None`: as the file
/// describes it).
/// In f64 or f32 (`Libm`, as [`estimate`]); a one-wheel log gives [`estimate`]'s bank
/// estimates.
#[allow(clippy::too_many_arguments)]
pub fn estimate_car(
    p: &Params<f64>,
    rows: &[Row],
    wheels: &[usize],
    has_fx: bool,
    gamma: &[f64],
    prec: Precision,
    wheelbase: Option<f64>,
    mounted: [Option<Side>; 4],
) -> Result<Vec<Estimate<f64>>, String> {
    match prec {
        Precision::F64 => run_car::<f64, Libm>(p, rows, wheels, has_fx, gamma, wheelbase, mounted),
        Precision::F32 => run_car::<f32, Libm>(
            &p.cast::<f32>(),
            rows,
            wheels,
            has_fx,
            gamma,
            wheelbase,
            mounted,
        ),
    }
}

fn run_car<F: gough::math::Float, M: gough::math::Backend<F>>(
    p: &Params<F>,
    rows: &[Row],
    wheels: &[usize],
    has_fx: bool,
    gamma: &[f64],
    wheelbase: Option<f64>,
    mounted: [Option<Side>; 4],
) -> Result<Vec<Estimate<f64>>, String> {
    use gough::mu::preview::{self, Preview};
    if wheels.len() != rows.len() {
        return Err(format!(
            "{} rows, {} wheel indices",
            rows.len(),
            wheels.len()
        ));
    }
    let has_kappa = rows.iter().any(|r| r.kappa.is_finite());
    let new = |w: usize| {
        bank::Bank::new::<M>(p, mounted[w], bank::Config::default()).map_err(|e| e.to_string())
    };
    let mut banks = [new(0)?, new(1)?, new(2)?, new(3)?];
    let mut pvs = match wheelbase {
        Some(l) => {
            let pv = Preview::new(preview::Config::with_wheelbase(F::from_f64(l)))
                .map_err(|e| format!("--wheelbase {l}: {e}"))?;
            Some([pv.clone(), pv])
        }
        None => None,
    };
    let c = |x: f64| F::from_f64(x);
    let back = |x: F| x.to_f64();
    let mut out = Vec::with_capacity(rows.len());
    for (i, (r, &w)) in rows.iter().zip(wheels).enumerate() {
        let s = bank_sample(
            r,
            has_fx,
            has_kappa,
            gamma.get(i).copied().filter(|g| g.is_finite()),
        );
        let s = bank::Sample {
            t_us: s.t_us,
            fz: c(s.fz),
            fy: c(s.fy),
            mz: c(s.mz),
            fx: s.fx.map(c),
            kappa: s.kappa.map(c),
            vx: s.vx.map(c),
            gamma: s.gamma.map(c),
        };
        let w = w.min(3);
        let e = preview::update::<F, M>(pvs.as_mut(), w, &mut banks[w], p, &s);
        out.push(bank_estimate(bank::Estimate {
            mu: back(e.mu),
            sigma: back(e.sigma),
            mu_min: back(e.mu_min),
            state: e.state,
            change: e.change,
        }));
    }
    Ok(out)
}

/// A log row as the bank's sample: the time in wrapping microseconds (only differences are
/// used, so an offset clock gives the same estimates), κ where the log has it.
pub fn bank_sample(
    r: &Row,
    has_fx: bool,
    has_kappa: bool,
    gamma: Option<f64>,
) -> bank::Sample<f64> {
    bank::Sample {
        t_us: (r.t * 1e6).round() as i64 as u32,
        fz: r.fz,
        fy: r.fy,
        mz: r.mz,
        fx: has_fx.then_some(r.fx),
        kappa: (has_kappa && r.kappa.is_finite()).then_some(r.kappa),
        vx: r.vx.is_finite().then_some(r.vx),
        gamma,
    }
}

/// The bank's estimate as the bench's and the CLI's estimate type.
pub fn bank_estimate(b: bank::Estimate<f64>) -> Estimate<f64> {
    Estimate {
        mu: b.mu,
        sigma: b.sigma,
        sigma_model: 0.0,
        state: match b.state {
            bank::State::Identifiable => State::Identifiable,
            bank::State::NotIdentifiable => State::NotIdentifiable,
            bank::State::Fallback => State::Fallback,
        },
        change: b.change,
    }
}

/// One estimator's run over a log: an estimate per row, and for the Gough estimator why each
/// held estimate was held (`MuEstimator::last_hold`; empty for the peers).
pub type Run = (Vec<Estimate<f64>>, Vec<Option<Hold>>);

/// Runs one estimator over rows; returns one estimate per row and, for the Gough method, why
/// each held estimate was held (`MuEstimator::last_hold`; empty for the peers). `side`: the
/// side the wheel is on (`None`: as the file describes the tyre; the bank and the table
/// estimator mirror it for the other side, the peers take the signals as they are).
pub fn estimate(
    p: &Params<f64>,
    rows: &[Row],
    has_fx: bool,
    gamma: &[f64],
    method: Method,
    prec: Precision,
    side: Option<Side>,
) -> Result<Run, String> {
    // Per-row camber when the log has it (NaN = not logged → the estimator's default).
    let g_of = |i: usize| gamma.get(i).copied().filter(|g| g.is_finite());
    let cfg = Config::<f64>::default();
    match method {
        Method::Bank => Ok((
            estimate_car(
                p,
                rows,
                &vec![0; rows.len()],
                has_fx,
                gamma,
                prec,
                None,
                [side; 4],
            )?,
            Vec::new(),
        )),
        Method::Gough => match prec {
            Precision::F64 => {
                let table = table::<f64, Libm>(p, side)?;
                let mut est = MuEstimator::for_tyre(&table, p, cfg);
                Ok(rows
                    .iter()
                    .enumerate()
                    .map(|(i, r)| {
                        let e = est.update::<Libm>(&Sample {
                            t: r.t,
                            fz: r.fz,
                            fy: r.fy,
                            mz: r.mz,
                            fx: has_fx.then_some(r.fx),
                            vx: r.vx.is_finite().then_some(r.vx),
                            gamma: g_of(i),
                        });
                        (e, est.last_hold())
                    })
                    .unzip())
            }
            Precision::F32 => {
                let p32 = p.cast::<f32>();
                let table = table::<f32, Libm>(&p32, side)?;
                let cfg32 = Config::<f32>::default();
                let mut est = MuEstimator::for_tyre(&table, &p32, cfg32);
                Ok(rows
                    .iter()
                    .enumerate()
                    .map(|(i, r)| {
                        let e = est.update::<Libm>(&Sample {
                            t: r.t as f32,
                            fz: r.fz as f32,
                            fy: r.fy as f32,
                            mz: r.mz as f32,
                            fx: has_fx.then_some(r.fx as f32),
                            vx: r.vx.is_finite().then_some(r.vx as f32),
                            gamma: g_of(i).map(|g| g as f32),
                        });
                        let e = Estimate {
                            mu: e.mu as f64,
                            sigma: e.sigma as f64,
                            sigma_model: e.sigma_model as f64,
                            state: e.state,
                            change: e.change,
                        };
                        (e, est.last_hold())
                    })
                    .unzip())
            }
        },
        Method::HsuGerdes => {
            let mut e = HsuGerdes::new(p).ok_or("the tyre gives no Hsu-Gerdes model")?;
            Ok((rows.iter().map(|r| e.update(r)).collect(), Vec::new()))
        }
        Method::SlipSlope => {
            let mut e = SlipSlope::new(p).ok_or("the tyre gives no slip-slope calibration")?;
            Ok((rows.iter().map(|r| e.update(r)).collect(), Vec::new()))
        }
    }
}
