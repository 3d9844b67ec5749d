//! `gough sim`: runs a manoeuvre and writes `DIR/log.csv`, `DIR/signals.png`, `DIR/gough.png`.
//!
//! Numbers are taken as text and parsed here into the library's `sim::Spec`, so every bad
//! argument gives one line naming it.

use crate::sim::{plot, simulate, Spec, MANOEUVRES};
use std::path::PathBuf;

/// Arguments of `gough sim`.
#[derive(clap::Args, Debug)]
pub struct SimArgs {
    /// Manoeuvre: step-steer, sine-dwell, brake-in-turn, abs-split, constant-radius, slalom,
    /// coast-down.
    #[arg(long, value_name = "NAME")]
    pub manoeuvre: Option<String>,
    /// Tyre property file (.tir), fitted at every wheel (mirrored on the side it is not for).
    #[arg(long, value_name = "FILE")]
    pub tir: Option<PathBuf>,
    /// Road: e.g. `mu=0.9`, `split=0.9/0.2`, `step=0.9@0,0.3@50`, `patch=0.3@40..60[:left]`,
    /// joined with `+`, plus `uneven=AMP@WAVELENGTH` or `rough=RMS@SEED` (metres). Default: the
    /// tyre file's own surface (abs-split: split=0.9/0.2).
    #[arg(long, value_name = "SPEC")]
    pub road: Option<String>,
    /// Entry speed in m/s (default per manoeuvre).
    #[arg(long, value_name = "V", allow_hyphen_values = true)]
    pub speed: Option<String>,
    /// Simulated time in s (default per manoeuvre; braking runs end at standstill).
    #[arg(long, value_name = "T", allow_hyphen_values = true)]
    pub duration: Option<String>,
    /// Fixed step in s (default 0.001, at most 0.002).
    #[arg(long, value_name = "DT", allow_hyphen_values = true)]
    pub dt: Option<String>,
    /// Steering-wheel angle or amplitude in degrees (step-steer 40, sine-dwell 120).
    #[arg(long, value_name = "DEG", allow_hyphen_values = true)]
    pub steer: Option<String>,
    /// Circle radius in m (brake-in-turn, constant-radius; default 100).
    #[arg(long, value_name = "R", allow_hyphen_values = true)]
    pub radius: Option<String>,
    /// Deceleration demand in m/s² (brake-in-turn 5, abs-split 11.8 = 1.2 g).
    #[arg(long, value_name = "D", allow_hyphen_values = true)]
    pub decel: Option<String>,
    /// No ABS: the brake torque goes straight to the wheels, which may lock.
    #[arg(long)]
    pub no_abs: bool,
    /// Log every n-th step (default 1).
    #[arg(long, value_name = "N")]
    pub log_every: Option<String>,
    /// Skip the PNG plots.
    #[arg(long)]
    pub no_plots: bool,
    /// Size of signals.png in pixels, WIDTHxHEIGHT (gough.png is 0.6 times as wide).
    #[arg(long, value_name = "WxH")]
    pub plot_size: Option<String>,
    /// Output directory (created).
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
}

fn number(flag: &str, s: &Option<String>) -> Result<Option<f64>, String> {
    match s {
        None => Ok(None),
        Some(t) => match t.trim().parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(Some(v)),
            _ => Err(format!("{flag} '{t}' is not a finite number")),
        },
    }
}

/// The run these arguments ask for (`--tir`, `--out` and the plots' arguments are not read):
/// their text parsed into the library's [`Spec`], which Python's `gough.simulate` builds from
/// numbers.
pub fn spec(a: &SimArgs) -> Result<Spec, String> {
    let manoeuvre = a.manoeuvre.as_deref().ok_or_else(|| {
        format!(
            "--manoeuvre NAME is required (one of: {})",
            MANOEUVRES.join(", ")
        )
    })?;
    let log_every = match &a.log_every {
        None => None,
        Some(n) => Some(
            n.trim()
                .parse::<usize>()
                .ok()
                .filter(|&n| n >= 1)
                .ok_or_else(|| format!("--log-every '{n}' is not an integer ≥ 1"))?,
        ),
    };
    Ok(Spec {
        manoeuvre: manoeuvre.to_string(),
        road: a.road.clone(),
        speed: number("--speed", &a.speed)?,
        duration: number("--duration", &a.duration)?,
        dt: number("--dt", &a.dt)?,
        steer_deg: number("--steer", &a.steer)?,
        radius: number("--radius", &a.radius)?,
        decel: number("--decel", &a.decel)?,
        abs: !a.no_abs,
        log_every,
    })
}

/// Runs `gough sim`.
pub fn run(a: SimArgs) -> Result<(), String> {
    let cfg = spec(&a)?.config()?;
    let man = cfg.manoeuvre;
    let tir = a.tir.as_ref().ok_or("--tir FILE is required")?;
    let out = a.out.as_ref().ok_or("--out DIR is required")?;
    let (pw, ph) = match &a.plot_size {
        None => (1800, 1350),
        Some(s) => s
            .split_once('x')
            .and_then(|(w, h)| Some((w.trim().parse::<u32>().ok()?, h.trim().parse::<u32>().ok()?)))
            .filter(|&(w, h)| (300..=8000).contains(&w) && (200..=8000).contains(&h))
            .ok_or_else(|| {
                format!("--plot-size '{s}': expected WIDTHxHEIGHT, 300x200 to 8000x8000")
            })?,
    };
    let tyre = crate::tyre::load(tir)?;
    let start = std::time::Instant::now();
    let log = simulate(&cfg, &tyre.params, true)?;
    let wall = start.elapsed().as_secs_f64();
    std::fs::create_dir_all(out).map_err(|e| format!("{}: cannot create: {e}", out.display()))?;
    log.write_csv(&out.join("log.csv"))?;
    let simulated = log.t_end;
    if !a.no_plots {
        let road = a
            .road
            .clone()
            .or(man.default_road().map(str::to_string))
            .unwrap_or_else(|| format!("file surface, mu={:.3}", log.mu_y0));
        let title = format!(
            "{} at {:.1} m/s, road {}, {}",
            man.name(),
            man.speed(),
            road,
            if cfg.abs.is_some() { "ABS" } else { "no ABS" }
        );
        plot::signals(&log, &title, &out.join("signals.png"), (pw, ph))?;
        plot::gough(
            &log,
            &title,
            &out.join("gough.png"),
            (pw * 3 / 5, ph * 2 / 3),
        )?;
    }
    let peak_ay = log
        .records
        .iter()
        .map(|r| r.vehicle.ay.abs())
        .fold(0.0, f64::max);
    eprintln!(
        "{}: {} rows, {:.3} s simulated in {:.3} s ({:.0}x real time); peak |ay| {:.2} m/s²{} -> {}",
        man.name(),
        log.records.len(),
        simulated,
        wall,
        simulated / wall.max(1e-9),
        peak_ay,
        match log.stop {
            Some(s) => format!(
                "; stopped in {:.2} s over {:.1} m from the start of braking",
                s.time, s.distance
            ),
            None => String::new(),
        },
        out.display()
    );
    Ok(())
}
