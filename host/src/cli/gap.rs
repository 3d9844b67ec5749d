//! `gough gap ...`: `diagnose` (the interface), `bench` (the withheld-effect
//! benchmark), `generate` (a log from the benchmark's truth model, e.g. the bundled examples).

use crate::gap::bench::{self, GenConfig};
use crate::gap::effects::Effect;
use std::path::{Path, PathBuf};

/// The `gap` subcommands.
#[derive(clap::Subcommand, Debug)]
pub enum GapCmd {
    /// Diagnose the gap between the sim of SIM.tir and a measured log; write a JSON report.
    ///
    /// Log: CSV with header, SI units, ISO-W; required t,vx,alpha,kappa,gamma,fz,fx,fy,mz;
    /// optional p (Pa), phit (1/m), mu (reference friction); other columns ignored.
    Diagnose {
        /// Tyre property file of the sim (.tir).
        #[arg(long, value_name = "SIM.tir")]
        tir: PathBuf,
        /// Measured log (CSV).
        #[arg(long, value_name = "LOG.csv")]
        log: PathBuf,
        /// Report (JSON, written atomically).
        #[arg(long, value_name = "REPORT.json")]
        report: PathBuf,
        /// Directory for PNG residual maps (created).
        #[arg(long, value_name = "DIR")]
        plots: Option<PathBuf>,
        /// Write the corrected tyre file: SIM.tir with the verdict's fitted effect(s) put into
        /// its coefficients (what the file format cannot hold is named; without a verdict,
        /// SIM.tir unchanged).
        #[arg(long, value_name = "FILE.tir")]
        write_tir: Option<PathBuf>,
        /// Evaluate the fits row by row with `mf::eval` (the reference, bit for bit the same in
        /// every build) instead of the lanes (about 1.5× faster; the last bits differ, and the
        /// μ section's discrete choices can amplify them).
        #[arg(long)]
        exact: bool,
    },
    /// Withheld-effect benchmark: generate logs with one effect, a pair or none on (2–3 decoy
    /// blocks out of every sim file), diagnose them from SIM.tir and the log only, print the
    /// issue-40 targets, the confusion matrix, false alarms, shrink achieved vs achievable and
    /// the pairs (Markdown).
    Bench {
        /// A smaller run for CI (m = 1 only, 1 noise level, 2 pairs, 1500-row logs).
        #[arg(long)]
        quick: bool,
        /// Worker threads.
        #[arg(long, default_value_t = 1)]
        jobs: usize,
        /// Directory with the tyre files (default: the bundled host-tests/data/tyres).
        #[arg(long, value_name = "DIR")]
        tyres: Option<PathBuf>,
        /// Also write the tables to this Markdown file.
        #[arg(long, value_name = "FILE")]
        markdown: Option<PathBuf>,
        /// Also write one CSV row per log (truth, verdict, shrinks, time) to this file.
        #[arg(long, value_name = "FILE")]
        cases: Option<PathBuf>,
        /// Log rates \[Hz\], comma-separated, taken in turn over the cases (default 100,200).
        #[arg(long, value_name = "HZ,...", value_delimiter = ',')]
        rates: Vec<f64>,
        #[command(flatten)]
        sampling: SamplingArgs,
        /// Only these effects' logs (comma-separated; the none logs always, pairs with one of
        /// them); default every effect.
        #[arg(long, value_name = "LIST")]
        effects: Option<String>,
        /// Effect magnitudes, comma-separated (default 1,0.3,0.1; `--quick` 1): e.g. `1,0.3`
        /// for the logs the targets are stated on.
        #[arg(long, value_name = "M,...", value_delimiter = ',')]
        magnitudes: Vec<f64>,
    },
    /// Generate a log from the benchmark's truth model (SIM.tir with one effect switched on).
    Generate {
        /// Tyre property file (.tir).
        #[arg(long, value_name = "SIM.tir")]
        tir: PathBuf,
        /// Output CSV.
        #[arg(long, value_name = "LOG.csv")]
        out: PathBuf,
        /// Effect switched on: none, camber, inflation_pressure, turn_slip, combined_slip,
        /// relaxation_length, speed_dependent_friction, thermal, sensor_lag, sensor_bias,
        /// conicity_plysteer; or two of them, comma-separated (a pair, both at --magnitude).
        #[arg(long, default_value = "none")]
        effect: String,
        /// Magnitude (1 large, 0.03 at the edge of detectability).
        #[arg(long, default_value_t = 1.0)]
        magnitude: f64,
        /// Rows.
        #[arg(long, default_value_t = 6000)]
        rows: usize,
        /// Sample rate (Hz).
        #[arg(long, default_value_t = 200.0)]
        rate: f64,
        /// Seed.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// White noise as a fraction of each channel's RMS.
        #[arg(long, default_value_t = 0.01)]
        noise: f64,
        /// Add a reference `mu` column.
        #[arg(long)]
        mu: bool,
        /// No `p` column (the pressure stays INFLPRES).
        #[arg(long)]
        no_p: bool,
        /// No `phit` column (no turn slip).
        #[arg(long)]
        no_phit: bool,
        /// Load oscillation bursts: Fz ±30 % at 2, 4, 8 Hz in the second half of every 5 s.
        #[arg(long)]
        load_oscillation: bool,
        #[command(flatten)]
        sampling: SamplingArgs,
        /// Also write the truth as a tyre file (SIM.tir with the effect's coefficient changes;
        /// for effects that are coefficient changes only): the tyre the log was measured on.
        #[arg(long, value_name = "FILE.tir")]
        truth_tir: Option<PathBuf>,
    },
}

/// How a generated log samples its truth (`gap::bench::Sampling`).
#[derive(clap::Args, Debug, Clone, Copy)]
pub struct SamplingArgs {
    /// Run the truth at this rate \[Hz\] between the log's rows and take it at the rows (the
    /// continuous model as a logger samples it); default: the truth at the rows themselves.
    #[arg(long, value_name = "HZ")]
    truth_rate: Option<f64>,
    /// Jitter each row's time by up to ± this fraction of the step (uniform, < 0.5).
    #[arg(long, value_name = "FRACTION", default_value_t = 0.0)]
    jitter: f64,
    /// Drop this fraction of the rows at random (≤ 0.5).
    #[arg(long, value_name = "FRACTION", default_value_t = 0.0)]
    drop: f64,
}

impl SamplingArgs {
    fn sampling(&self) -> Result<bench::Sampling, String> {
        let s = bench::Sampling {
            truth_rate: self.truth_rate,
            jitter: self.jitter,
            drop: self.drop,
        };
        s.check().map_err(|e| format!("--{e}"))?;
        Ok(s)
    }
}

fn effect_arg(s: &str) -> Result<Vec<Effect>, String> {
    if s == "none" {
        return Ok(vec![]);
    }
    s.split(',')
        .map(|x| {
            Effect::from_name(x.trim()).ok_or_else(|| {
                format!(
                    "--effect '{s}': expected none, or one or two (comma-separated) of {}",
                    crate::gap::effects::ALL.map(|e| e.name()).join(", ")
                )
            })
        })
        .collect()
}

/// Runs a `gap` subcommand.
pub fn run(cmd: GapCmd) -> Result<(), String> {
    match cmd {
        GapCmd::Diagnose {
            tir,
            log,
            report,
            plots,
            write_tir,
            exact,
        } => {
            let tyre = crate::tyre::load(&tir)?;
            let lg = crate::gap::log::read(&log)?;
            let start = std::time::Instant::now();
            let d = crate::gap::diagnose(
                tyre.params,
                &lg,
                &tir.display().to_string(),
                &log.display().to_string(),
                &crate::gap::Options {
                    progress: true,
                    plots,
                    fit_rows: None,
                    exact,
                },
            )?;
            let json = serde_json::to_string_pretty(&d.report)
                .map_err(|e| format!("cannot encode the report: {e}"))?;
            crate::gap::write_atomic(&report, &(json + "\n"))?;
            let v = &d.report.verdict;
            let mut line = format!("verdict: {}", v.effect);
            if let (Some(s), Some(c)) = (v.shrink, &v.channel) {
                line += &format!(" (held-out shrink {s:.3}, mostly {c})");
            }
            if !v.indistinguishable_from.is_empty() {
                line += &format!(
                    "; indistinguishable from {}",
                    v.indistinguishable_from.join(", ")
                );
            }
            for e in v.effects.iter().skip(1) {
                line += &format!(
                    "; plus {} (adds {:.3}, mostly {}",
                    e.effect, e.shrink_added, e.channel
                );
                if !e.indistinguishable_from.is_empty() {
                    line += &format!(
                        "; indistinguishable from {}",
                        e.indistinguishable_from.join(", ")
                    );
                }
                line += ")";
            }
            println!("{line}");
            if let Some(out) = &write_tir {
                let text = std::fs::read_to_string(&tir)
                    .map_err(|e| format!("{}: cannot read: {e}", tir.display()))?;
                println!(
                    "{}",
                    crate::gap::tirfile::write_corrected(&text, out, d.corrected.as_ref())?
                );
            }
            eprintln!(
                "{} rows diagnosed in {:.1} s -> {}",
                lg.len(),
                start.elapsed().as_secs_f64(),
                report.display()
            );
            Ok(())
        }
        GapCmd::Bench {
            quick,
            jobs,
            tyres,
            markdown,
            cases,
            rates,
            sampling,
            effects,
            magnitudes,
        } => {
            let dir = tyres.unwrap_or_else(|| {
                Path::new(env!("CARGO_MANIFEST_DIR"))
                    .join("../host-tests/data")
                    .join("tyres")
            });
            let mut cfg = bench::default_config(&dir, quick);
            cfg.jobs = jobs.max(1);
            cfg.sampling = sampling.sampling()?;
            if let Some(r) = rates.iter().find(|r| !(r.is_finite() && **r > 0.0)) {
                return Err(format!("--rates: {r} is not a rate (> 0 Hz)"));
            }
            let rates_given = !rates.is_empty();
            if rates_given {
                cfg.rates = rates;
            }
            if let Some(list) = &effects {
                cfg.effects = effect_arg(list)?;
            }
            if let Some(m) = magnitudes.iter().find(|m| !(m.is_finite() && **m > 0.0)) {
                return Err(format!("--magnitudes: {m} is not a magnitude (> 0)"));
            }
            let magnitudes_given = !magnitudes.is_empty();
            if magnitudes_given {
                cfg.magnitudes = magnitudes;
            }
            let start = std::time::Instant::now();
            let res = bench::run(&cfg)?;
            let mut text = bench::table(&cfg, &res);
            let mut flags = String::new();
            if quick {
                flags += " --quick";
            }
            if jobs > 1 {
                flags += &format!(" --jobs {jobs}");
            }
            if rates_given {
                let r: Vec<String> = cfg.rates.iter().map(|r| r.to_string()).collect();
                flags += &format!(" --rates {}", r.join(","));
            }
            let smp = cfg.sampling;
            if let Some(r) = smp.truth_rate {
                flags += &format!(" --truth-rate {r}");
            }
            if smp.jitter > 0.0 {
                flags += &format!(" --jitter {}", smp.jitter);
            }
            if smp.drop > 0.0 {
                flags += &format!(" --drop {}", smp.drop);
            }
            if let Some(l) = &effects {
                flags += &format!(" --effects {l}");
            }
            if magnitudes_given {
                let m: Vec<String> = cfg.magnitudes.iter().map(|m| m.to_string()).collect();
                flags += &format!(" --magnitudes {}", m.join(","));
            }
            text += &format!(
                "\nCommand: `cargo run --release --bin gough -- gap bench{}` ({:.0} s wall with {} job(s)).\n",
                flags,
                start.elapsed().as_secs_f64(),
                cfg.jobs
            );
            print!("{text}");
            if let Some(m) = markdown {
                crate::gap::write_atomic(&m, &text)?;
            }
            if let Some(c) = cases {
                crate::gap::write_atomic(&c, &bench::cases_csv(&res))?;
            }
            Ok(())
        }
        GapCmd::Generate {
            tir,
            out,
            effect,
            magnitude,
            rows,
            rate,
            seed,
            noise,
            mu,
            no_p,
            no_phit,
            load_oscillation,
            sampling,
            truth_tir,
        } => {
            let truth = effect_arg(&effect)?;
            if truth.len() > 2 {
                return Err(format!("--effect '{effect}': at most two effects (A,B)"));
            }
            if rows < crate::gap::log::MIN_ROWS {
                return Err(format!(
                    "--rows {rows}: at least {}",
                    crate::gap::log::MIN_ROWS
                ));
            }
            if !(rate > 0.0 && rate.is_finite()) {
                return Err(format!("--rate {rate}: must be > 0"));
            }
            if !(noise >= 0.0 && noise.is_finite() && magnitude.is_finite()) {
                return Err("--noise must be >= 0 and --magnitude finite".into());
            }
            let tyre = crate::tyre::load(&tir)?;
            let g = bench::generate(
                &tyre.params,
                &GenConfig {
                    rows,
                    rate,
                    seed,
                    truth: truth.first().copied(),
                    truth2: truth.get(1).copied(),
                    magnitude,
                    noise,
                    mu,
                    p: !no_p,
                    phit: !no_phit,
                    load_oscillation,
                    sampling: sampling.sampling()?,
                },
            )?;
            crate::gap::log::write(&out, &g.log)
                .map_err(|e| format!("{}: cannot write: {e}", out.display()))?;
            if let Some(path) = &truth_tir {
                let text = std::fs::read_to_string(&tir)
                    .map_err(|e| format!("{}: cannot read: {e}", tir.display()))?;
                let t = bench::truth_tir(&text, &tyre.params, &g.log, &truth, magnitude)?;
                crate::gap::write_atomic(path, &t)?;
                eprintln!("the truth's tyre -> {}", path.display());
            }
            eprintln!(
                "{rows} rows ({} on, magnitude {magnitude}) -> {}",
                effect,
                out.display()
            );
            Ok(())
        }
    }
}
