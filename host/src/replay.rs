//! `gough replay`: a measurement log → the device (as CAN frames) → the device's answers.
//!
//! LOG columns: `t,fz,fy,mz` required; `fx,vx,alpha,kappa,gamma,wheel,omega` optional (SI, rad,
//! ISO-W; `t` in s, `wheel` 0..3 = FL, FR, RL, RR, default 0, `omega` the wheel speed in rad/s).
//! RESULTS columns: `t,wheel,fx,fy,mz,flags,ack` then `mu,sigma,state,mu_min,change`. `ack` is
//! empty when the device answered with forces, else the reason it did not (`NoSlip`,
//! `EvalError`, ...); `mu,sigma,state,mu_min,change` are the device's friction estimate after
//! that sample (state `identifiable`, `not_identifiable` or `fallback`; `change` 1 on the
//! estimate at which a change of surface was declared, else 0), empty when it sent none.
//!
//! The check ([`host_f32`], [`compare`]) runs the device's own per-wheel pipeline
//! ([`gough::wheel`]) on the host, in f32 with the same math backend, over the same measurement
//! stream: transient filter, Magic Formula, and the friction estimator (`mu::bank::Bank<f32>`).
use crate::csvio::{self, CsvError, WheelRow};
use crate::device::Device;
use gough::math::{Backend, Fast, Libm};
use gough::mf::Params;
use gough::proto::{
    AckCode, CalibrationState, Command, Estimate, Forces, Measurement, Msg, MsgType, Settings,
    Wheel,
};
use gough::wheel;
use std::collections::VecDeque;
use std::fmt::Write as _;
use std::path::Path;
use std::time::Duration;

/// Result columns.
pub const RESULT_COLUMNS: [&str; 12] = [
    "t", "wheel", "fx", "fy", "mz", "flags", "ack", "mu", "sigma", "state", "mu_min", "change",
];

/// The log's rows as the protocol's measurements.
pub fn read_log(path: &Path) -> Result<Vec<Measurement>, CsvError> {
    let t = csvio::read::<WheelRow>(path)?;
    let mut out = Vec::with_capacity(t.rows.len());
    for (r, &line) in t.rows.iter().zip(&t.lines) {
        let err = |column: &str, msg: String| CsvError {
            file: path.to_path_buf(),
            line,
            column: Some(column.into()),
            msg,
        };
        if !(0.0..=4294.967295).contains(&r.t) {
            return Err(err(
                "t",
                format!(
                    "t = {} s is outside 0..4294.967295 s (a u32 of microseconds)",
                    r.t
                ),
            ));
        }
        let w = r.wheel.unwrap_or(0.0);
        let wheel = Wheel::from_index(w as usize)
            .filter(|_| w.fract() == 0.0 && w >= 0.0)
            .ok_or_else(|| err("wheel", format!("wheel = {w}: expected 0, 1, 2 or 3")))?;
        let f = |x: Option<f64>| x.map(|v| v as f32);
        out.push(Measurement {
            wheel,
            t_us: (r.t * 1e6).round() as u32,
            fz: r.fz as f32,
            fy: r.fy as f32,
            mz: r.mz as f32,
            fx: f(r.fx),
            vx: f(r.vx),
            omega: f(r.omega),
            delta: None,
            alpha: f(r.alpha),
            kappa: f(r.kappa),
            gamma: f(r.gamma),
        });
    }
    Ok(out)
}

/// The device's answer to one measurement.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Answer {
    /// Predicted forces.
    Forces(Forces),
    /// No forces, and why.
    Ack(AckCode),
}

/// Everything the device sent for one measurement.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Reply {
    /// Forces, or why none.
    pub answer: Answer,
    /// The friction estimate after this sample (none while the device has no estimator).
    pub estimate: Option<Estimate>,
}

/// Attaches an `Estimate` to the row it follows (the device sends it right after that row's
/// forces or acknowledgement).
fn attach(out: &mut [Reply], log: &[Measurement], e: Estimate) -> Result<(), String> {
    let i = out.len();
    let (Some(r), Some(m)) = (out.last_mut(), i.checked_sub(1).and_then(|k| log.get(k))) else {
        return Err("an estimate arrived before any answer".into());
    };
    if (e.wheel, e.t_us) != (m.wheel, m.t_us) || r.estimate.is_some() {
        return Err(format!(
            "estimate for wheel {:?} t_us {} does not follow its row (row {i}: wheel {:?} t_us {})",
            e.wheel, e.t_us, m.wheel, m.t_us
        ));
    }
    r.estimate = Some(e);
    Ok(())
}

/// Streams `log` to the device, at most `window` measurements in flight; one reply per row.
/// Ends with a status request as a fence, so that the last row's estimate is in.
pub fn stream(dev: &mut Device, log: &[Measurement], window: usize) -> Result<Vec<Reply>, String> {
    let mut out: Vec<Reply> = Vec::with_capacity(log.len());
    let mut in_flight: VecDeque<usize> = VecDeque::new();
    let mut next = 0usize;
    while out.len() < log.len() {
        while next < log.len() && in_flight.len() < window.max(1) {
            dev.send(&Msg::Measurement(log[next]))?;
            in_flight.push_back(next);
            next += 1;
        }
        let answer = match dev.recv(Duration::from_secs(10))? {
            Msg::Forces(f) => Answer::Forces(f),
            Msg::Ack(a) if a.of == MsgType::Measurement as u8 => Answer::Ack(a.code),
            Msg::Estimate(e) => {
                attach(&mut out, log, e)?;
                continue;
            }
            _ => continue,
        };
        let Some(i) = in_flight.pop_front() else {
            return Err("the device answered a measurement that was not sent".into());
        };
        if let Answer::Forces(f) = answer {
            if f.t_us != log[i].t_us || f.wheel != log[i].wheel {
                return Err(format!(
                    "answer out of order: row {} has t_us {}, the answer {}",
                    i + 1,
                    log[i].t_us,
                    f.t_us
                ));
            }
        }
        out.push(Reply {
            answer,
            estimate: None,
        });
    }
    // The device answers a status request in its poll, after the tick that sent the last
    // row's forces and estimate has finished.
    dev.send(&Msg::Command(Command::StatusRequest))?;
    loop {
        match dev.recv(Duration::from_secs(10))? {
            Msg::Estimate(e) => attach(&mut out, log, e)?,
            Msg::Status(_) => return Ok(out),
            _ => {}
        }
    }
}

/// Math backend of the device's pipeline (the firmware's `app::Math`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Backend32 {
    /// `gough::math::Fast` (the firmware's default build).
    Fast,
    /// `gough::math::Libm` (a firmware built without its `fast` feature).
    Libm,
}

impl Backend32 {
    /// Name as printed.
    pub fn name(self) -> &'static str {
        match self {
            Backend32::Fast => "math::Fast",
            Backend32::Libm => "math::Libm",
        }
    }
}

/// What the device must answer: its per-wheel pipeline run on the host in f32 with backend
/// `backend`, from the state right after a parameter upload and `settings` (filters at rest,
/// estimators started on `p` with `settings`: the prior, and the preview over the wheelbase if
/// it gives one). Settings the device would refuse are an error.
pub fn host_f32(
    p: &Params<f32>,
    settings: &Settings,
    log: &[Measurement],
    backend: Backend32,
) -> Result<Vec<Reply>, String> {
    host_f32_calibrated(p, settings, log, backend).map(|(r, _)| r)
}

/// [`host_f32`], and then each running estimator's calibration (wheel order) as the device
/// reports it ([`gough::proto::Msg::Calibration`]).
pub fn host_f32_calibrated(
    p: &Params<f32>,
    settings: &Settings,
    log: &[Measurement],
    backend: Backend32,
) -> Result<(Vec<Reply>, Vec<CalibrationState>), String> {
    match backend {
        Backend32::Fast => run::<Fast>(p, settings, log),
        Backend32::Libm => run::<Libm>(p, settings, log),
    }
}

fn run<M: Backend<f32>>(
    p: &Params<f32>,
    settings: &Settings,
    log: &[Measurement],
) -> Result<(Vec<Reply>, Vec<CalibrationState>), String> {
    let mut car = wheel::Car::new();
    // As the device: settings out of range are refused; a tyre without friction gets forces
    // and no estimates.
    let preview = settings.preview().map_err(|_| {
        format!(
            "wheelbase {} m: the settings' wheelbase is not 0 or a positive number",
            settings.wheelbase
        )
    })?;
    let cfg = settings.estimator_config();
    if let Err(e @ wheel::StartError::Preview(_)) = car.start_estimators::<M>(p, cfg, preview) {
        return Err(format!("wheelbase {} m: {e}", settings.wheelbase));
    }
    let replies = log
        .iter()
        .map(|m| {
            let x = wheel::Measurement::from(m);
            let answer = match car.forces::<M>(p, settings.limits, m.wheel, &x) {
                Ok(o) => Answer::Forces(Forces::new(m.wheel, m.t_us, &o)),
                Err(e) => Answer::Ack(AckCode::from(e)),
            };
            let estimate = car.estimate::<M>(p, m.wheel, &x);
            Reply {
                answer,
                estimate: estimate.map(|e| Estimate::new(m.wheel, m.t_us, &e)),
            }
        })
        .collect();
    let cals = Wheel::ALL
        .iter()
        .filter_map(|w| {
            let b = car.corner(*w).estimator()?;
            Some(CalibrationState::new(*w, &b.calibration().export::<M>()))
        })
        .collect();
    Ok((replies, cals))
}

/// Distance in units in the last place between two f32 (0 when equal; large across signs).
pub fn ulps(a: f32, b: f32) -> u64 {
    if a == b {
        return 0;
    }
    let key = |x: f32| {
        let i = x.to_bits() as i32;
        if i < 0 {
            i64::from(i32::MIN) - i64::from(i)
        } else {
            i64::from(i)
        }
    };
    (key(a) - key(b)).unsigned_abs()
}

/// The largest differences found by [`compare`], in ulps.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Worst {
    /// Over Fx, Fy, Mz.
    pub forces: u64,
    /// Over μ, σ and μ_min.
    pub estimates: u64,
    /// Rows with an estimate.
    pub n_estimates: usize,
}

/// Compares device replies with the host's f32 run ([`host_f32`]); the largest ulp distances,
/// or an error naming the first row that differs in kind (forces vs none, flags, estimate
/// present or not, estimator state, change flag).
pub fn compare(host: &[Reply], got: &[Reply]) -> Result<Worst, String> {
    let mut w = Worst::default();
    if host.len() != got.len() {
        return Err(format!(
            "{} host rows, {} device rows",
            host.len(),
            got.len()
        ));
    }
    for (i, (h, d)) in host.iter().zip(got).enumerate() {
        match (h.answer, d.answer) {
            (Answer::Forces(h), Answer::Forces(d)) => {
                w.forces = w
                    .forces
                    .max(ulps(h.fx, d.fx))
                    .max(ulps(h.fy, d.fy))
                    .max(ulps(h.mz, d.mz));
                if h.flags != d.flags {
                    return Err(format!(
                        "row {}: flags {} (host) vs {} (device)",
                        i + 1,
                        h.flags,
                        d.flags
                    ));
                }
            }
            (Answer::Ack(a), Answer::Ack(b)) if a == b => {}
            (h, d) => return Err(format!("row {}: host {h:?}, device {d:?}", i + 1)),
        }
        match (h.estimate, d.estimate) {
            (None, None) => {}
            (Some(h), Some(d)) if h.state == d.state && h.change == d.change => {
                w.n_estimates += 1;
                w.estimates = w
                    .estimates
                    .max(ulps(h.mu, d.mu))
                    .max(ulps(h.sigma, d.sigma))
                    .max(ulps(h.mu_min, d.mu_min));
            }
            (h, d) => {
                return Err(format!(
                    "row {}: host estimate {h:?}, device estimate {d:?}",
                    i + 1
                ))
            }
        }
    }
    Ok(w)
}

/// Writes the RESULTS file (atomically: temporary file, then rename).
pub fn write_results(path: &Path, log: &[Measurement], got: &[Reply]) -> std::io::Result<()> {
    let mut s = String::new();
    s.push_str(&RESULT_COLUMNS.join(","));
    s.push('\n');
    for (m, r) in log.iter().zip(got) {
        let t = f64::from(m.t_us) / 1e6;
        let _ = match r.answer {
            Answer::Forces(f) => write!(
                s,
                "{t},{},{:e},{:e},{:e},{},,",
                m.wheel.index(),
                f.fx,
                f.fy,
                f.mz,
                f.flags
            ),
            Answer::Ack(c) => write!(s, "{t},{},,,,,{c:?},", m.wheel.index()),
        };
        let _ = match r.estimate {
            Some(e) => writeln!(
                s,
                "{:e},{:e},{},{:e},{}",
                e.mu,
                e.sigma,
                e.state.name(),
                e.mu_min,
                u8::from(e.change)
            ),
            None => writeln!(s, ",,,,"),
        };
    }
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)?;
    }
    let tmp = path.with_extension("csv.tmp");
    std::fs::write(&tmp, s)?;
    std::fs::rename(&tmp, path)
}
