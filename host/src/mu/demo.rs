//! `gough mu demo`: the product's main job on one command — a manoeuvre on a road whose
//! friction changes, the estimator at every wheel (with the bench's sensor model), a short table
//! on the terminal, the estimates, a log and plots.

use super::bench::plots::{plot_gough, plot_mu};
use super::bench::tables::{fmt, WHEELS};
use super::bench::{
    measure, metrics, run_method, sim_wheelbase, simulate_case, Case, Sensors, WheelTrace,
};
use super::{Estimate, Method, Setup};
use gough::mu::State;
use std::fmt::Write as _;
use std::path::PathBuf;

/// What `gough mu demo` runs, and where it writes.
#[derive(Debug, Clone, PartialEq)]
pub struct Config {
    /// Tyre property file (.tir).
    pub tir: PathBuf,
    /// Manoeuvre (one of the simulation's).
    pub manoeuvre: String,
    /// Road (the simulation's spec grammar).
    pub road: String,
    /// Output directory (estimates.csv, log_fl.csv, mu.png, gough.png).
    pub out: PathBuf,
    /// Noise seed.
    pub seed: u64,
}

impl Default for Config {
    /// The README's demo: the bundled MF 6.1 tyre, the sine with dwell from a dry road onto a
    /// wet patch (μ 1.0 → 0.4), seed 1.
    fn default() -> Self {
        Config {
            tir: "host-tests/data/tyres/MagicFormula61_Parameters.tir".into(),
            manoeuvre: "sine-dwell".into(),
            road: "mu=1.0+patch=0.4@45..300".into(),
            out: "out/demo".into(),
            seed: 1,
        }
    }
}

/// The product's main job on one command: a manoeuvre on a road whose friction changes, the
/// estimator at every wheel, a short table, plots.
pub fn run(a: &Config) -> Result<(), String> {
    let t = crate::tyre::load(&a.tir)?;
    let p = t.params;
    let case = Case::new(&a.manoeuvre, &a.road)?;
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
    let mut first: Option<(WheelTrace, Vec<Estimate>)> = None;
    let traces: Vec<WheelTrace> = (0..4).map(|w| measure(&log, w, &sensors, a.seed)).collect();
    let preview = gough::mu::preview::Config::with_wheelbase(sim_wheelbase());
    let ests = run_method(Method::Bank, &p, &Setup::car(Some(preview)), &traces)?;
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
            state: State::Fallback,
            change: false,
            mismatch: false,
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
            // Its `alpha` column is the slip sensor's (the bank never reads it).
            let v = |x: Option<f64>| x.unwrap_or(f64::NAN);
            let rows: Vec<Vec<f64>> = tr
                .rows
                .iter()
                .zip(&tr.slip_sensor)
                .zip(&tr.mu_true)
                .map(|((r, &(alpha, _)), &m)| {
                    vec![
                        r.t,
                        r.fz,
                        s * r.fy,
                        s * r.mz,
                        v(r.fx),
                        v(r.vx),
                        v(r.kappa),
                        s * alpha,
                        s * v(r.gamma),
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
