//! Host vehicle simulation: the plant the ABS/ESC and friction-estimator work runs against.
//!
//! A two-track vehicle ([`vehicle`]) with a transient Magic Formula tyre at each wheel
//! ([`gough::relax::TransientTyre`] over [`gough::mf::eval`]: nothing of the tyre is
//! re-implemented here), on a road with friction by position and an optional uneven profile
//! ([`road`]), flown through standard manoeuvres by a driver model ([`manoeuvre`]), with a
//! slip-controlling ABS ([`abs`]). [`simulate`] runs it at a fixed step and returns a [`Log`];
//! `plot` (feature `plot`) draws it.
//!
//! μ follows `docs/architecture.md`: a road of friction μ scales the tyre by
//! λμx = λμy = μ/μy0, so a log's `mu_true` column means what the estimator reports.
//!
//! Deterministic: the same [`SimConfig`] and tyre give bit-identical logs (no threads, no
//! clocks, seeded road roughness). The inner loop allocates nothing beyond the log, whose
//! capacity is reserved up front.

pub mod abs;
pub mod manoeuvre;
#[cfg(feature = "plot")]
pub mod plot;
pub mod road;
pub mod spec;
pub mod vehicle;

pub use abs::{Abs, AbsParams};
pub use manoeuvre::{Driver, Manoeuvre, Overrides, MANOEUVRES};
pub use road::Road;
pub use spec::Spec;
pub use vehicle::{
    Commands, Initial, Record, Vehicle, VehicleParams, VehicleRecord, WheelRecord, G, MAX_DT,
    WHEELS,
};

use gough::mf::Params;
use std::path::Path;

/// Everything a run needs besides the tyre.
#[derive(Debug, Clone, PartialEq)]
pub struct SimConfig {
    /// The vehicle.
    pub vehicle: VehicleParams,
    /// The road.
    pub road: Road,
    /// The manoeuvre.
    pub manoeuvre: Manoeuvre,
    /// The ABS (`None`: the brake torque goes straight to the wheels, which may lock).
    pub abs: Option<AbsParams>,
    /// Fixed step h \[s\], in \[1e-5, [`MAX_DT`]\]; default 1 ms.
    pub dt: f64,
    /// Simulated time \[s\] (runs that end at standstill may stop earlier).
    pub duration: f64,
    /// Log every n-th step (1: every step).
    pub log_every: usize,
}

impl SimConfig {
    /// The manoeuvre with the default vehicle, its default road (or the file's surface), the
    /// default ABS, 1 ms step, the manoeuvre's default duration, every step logged.
    pub fn new(manoeuvre: Manoeuvre) -> SimConfig {
        let road = manoeuvre
            .default_road()
            .and_then(|s| Road::parse(s).ok())
            .unwrap_or_default();
        SimConfig {
            vehicle: VehicleParams::default(),
            road,
            manoeuvre,
            abs: Some(AbsParams::default()),
            dt: 1e-3,
            duration: manoeuvre.default_duration(),
            log_every: 1,
        }
    }
}

/// Most rows a log may hold (each row is about 560 bytes in memory, 1.3 kB of CSV).
pub const MAX_ROWS: usize = 1_000_000;

/// Speed below which a run that ends at standstill stops \[m/s\].
pub const STOP_SPEED: f64 = 0.5;

/// The result of a run: one [`Record`] per logged step.
#[derive(Debug, Clone, PartialEq)]
pub struct Log {
    /// Step h \[s\].
    pub dt: f64,
    /// The tyre file's μy0 (docs/architecture.md).
    pub mu_y0: f64,
    /// Records in time order.
    pub records: Vec<Record>,
    /// Time and distance travelled when the vehicle came to a stop (runs that end at standstill).
    pub stop: Option<Stop>,
    /// Mass times gravity m·g \[N\] (what the four Fz sum to on a flat road).
    pub weight: f64,
    /// Time simulated \[s\] (the end of the last step).
    pub t_end: f64,
}

/// Where a braking run stopped.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stop {
    /// Time from the start of braking \[s\].
    pub time: f64,
    /// Distance travelled from the start of braking \[m\].
    pub distance: f64,
}

/// Column names of the CSV log, in [`Log::row`] order.
pub fn columns() -> Vec<String> {
    let mut c: Vec<String> = ["t", "x", "y", "yaw", "vx", "vy", "r", "ax", "ay", "steer"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    for w in WHEELS {
        for f in WHEEL_COLUMNS {
            c.push(format!("{w}_{f}"));
        }
    }
    c
}

/// Per-wheel columns, each prefixed by the wheel name (`fl_fz`, ...).
pub const WHEEL_COLUMNS: [&str; 15] = [
    "vx", "vsx", "vsy", "alpha", "kappa", "alpha_t", "kappa_t", "gamma", "fz", "fx", "fy", "mz",
    "mu_true", "omega", "torque",
];

impl Log {
    /// One CSV row of record `r`, in [`columns`] order.
    pub fn row(r: &Record) -> Vec<f64> {
        let v = &r.vehicle;
        let mut row = vec![r.t, v.x, v.y, v.yaw, v.vx, v.vy, v.r, v.ax, v.ay, v.steer];
        for w in &r.wheels {
            row.extend_from_slice(&[
                w.vx, w.vsx, w.vsy, w.alpha, w.kappa, w.alpha_t, w.kappa_t, w.gamma, w.fz, w.fx,
                w.fy, w.mz, w.mu_true, w.omega, w.torque,
            ]);
        }
        row
    }

    /// Writes the log as CSV (atomically, via [`crate::csvio::write`]).
    pub fn write_csv(&self, path: &Path) -> Result<(), String> {
        let cols = columns();
        let header: Vec<&str> = cols.iter().map(String::as_str).collect();
        let rows: Vec<Vec<f64>> = self.records.iter().map(Log::row).collect();
        crate::csvio::write(path, &header, &rows)
            .map_err(|e| format!("{}: cannot write: {e}", path.display()))
    }
}

/// Runs `cfg` with the tyre `tyre` at every wheel. `progress`: draw a progress bar on stderr
/// once the run has taken more than a second of wall time.
pub fn simulate(cfg: &SimConfig, tyre: &Params<f64>, progress: bool) -> Result<Log, String> {
    if !(cfg.dt.is_finite() && (1e-5..=MAX_DT).contains(&cfg.dt)) {
        return Err(format!(
            "step {} s outside [1e-5, {MAX_DT}] s (the wheel-tyre coupling needs ≤ {MAX_DT} s)",
            cfg.dt
        ));
    }
    if !(cfg.duration.is_finite() && cfg.duration > 0.0 && cfg.duration <= 3600.0) {
        return Err(format!("duration {} s outside (0, 3600] s", cfg.duration));
    }
    if cfg.log_every == 0 {
        return Err("log_every must be ≥ 1".into());
    }
    cfg.manoeuvre.validate()?;
    let man = cfg.manoeuvre;
    let mut v = Vehicle::new(
        cfg.vehicle,
        tyre,
        &cfg.road,
        Initial {
            speed: man.speed(),
            yaw_rate: man.initial_yaw_rate(),
        },
    )?;
    let mut driver = Driver::new(man);
    let mut abs = cfg.abs.map(Abs::new);
    let steps = (cfg.duration / cfg.dt).round() as usize;
    let rows = steps / cfg.log_every + 1;
    if rows > MAX_ROWS {
        return Err(format!(
            "{rows} log rows (duration / (dt·log_every)) is more than {MAX_ROWS}: raise log_every (--log-every)"
        ));
    }
    let mut log = Log {
        dt: cfg.dt,
        mu_y0: v.mu_y0,
        records: Vec::with_capacity(rows),
        stop: None,
        weight: cfg.vehicle.m * G,
        t_end: 0.0,
    };
    let mut bar = Progress::new(progress, steps);
    let mut brake_start: Option<(f64, f64, f64)> = None; // (t, X, Y)
    let mut dist = 0.0;
    for k in 0..steps {
        let t = k as f64 * cfg.dt;
        let mut cmd = driver.command(t, &v, cfg.dt);
        if brake_start.is_none() && cmd.brake.iter().any(|&b| b > 0.0) {
            brake_start = Some((t, v.x, v.y));
            dist = 0.0;
        }
        if let Some(a) = abs.as_mut() {
            let kappa = v.wheel_slips(cmd.steer);
            let vx = v.wheel_speeds(cmd.steer);
            cmd.brake = a.update(&cmd.brake, &kappa, &vx, cfg.dt);
        }
        let (x0, y0) = (v.x, v.y);
        v.t = t; // k·h exactly, no accumulated rounding
        v.step(&cmd, &cfg.road, cfg.dt)?;
        dist += (v.x - x0).hypot(v.y - y0);
        if k % cfg.log_every == 0 {
            log.records.push(v.last);
        }
        bar.tick(k);
        if man.ends_at_standstill() && brake_start.is_some() && v.speed() < STOP_SPEED {
            if let Some((tb, _, _)) = brake_start {
                log.stop = Some(Stop {
                    time: v.t - tb,
                    distance: dist,
                });
            }
            break;
        }
    }
    bar.finish();
    log.t_end = v.t;
    Ok(log)
}

/// A progress bar that appears only when a run takes more than a second of wall time.
struct Progress {
    enabled: bool,
    steps: usize,
    start: std::time::Instant,
    bar: Option<indicatif::ProgressBar>,
}

impl Progress {
    fn new(enabled: bool, steps: usize) -> Progress {
        Progress {
            enabled,
            steps,
            start: std::time::Instant::now(),
            bar: None,
        }
    }

    fn tick(&mut self, k: usize) {
        if !self.enabled || !k.is_multiple_of(1000) {
            return;
        }
        match &self.bar {
            Some(b) => b.set_position(k as u64),
            None if self.start.elapsed().as_secs_f64() > 1.0 => {
                let b = indicatif::ProgressBar::with_draw_target(
                    Some(self.steps as u64),
                    indicatif::ProgressDrawTarget::stderr(),
                );
                if let Ok(style) = indicatif::ProgressStyle::with_template(
                    "sim {bar:40} {percent:>3}% {elapsed_precise} (eta {eta})",
                ) {
                    b.set_style(style);
                }
                b.set_position(k as u64);
                self.bar = Some(b);
            }
            None => {}
        }
    }

    fn finish(&mut self) {
        if let Some(b) = self.bar.take() {
            b.finish_and_clear();
        }
    }
}
