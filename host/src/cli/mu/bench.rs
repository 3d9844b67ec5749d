//! The arguments of `gough mu bench`, `gough mu demo` and `gough mu bound`, each turned into its
//! library configuration (`mu::bench::Config`, `mu::demo::Config`, `mu::bound::Config`); every
//! bad value is a one-line error naming its flag.
use crate::mu::{bench, bound, demo};
use clap::Args;
use std::path::PathBuf;

/// Arguments of `gough mu bench`.
#[derive(Args)]
pub struct BenchArgs {
    /// Tyre property file (.tir) of the vehicle suite.
    #[arg(long, default_value_os_t = bench::Config::default().tir)]
    pub tir: PathBuf,
    /// Output directory for the table (table.md; the vehicle suite's table.csv, wheels.csv and
    /// plots; the wheel cases' wheel_cases.csv).
    #[arg(long, default_value_os_t = bench::Config::default().out)]
    pub out: PathBuf,
    /// Noise seed (and, for the wheel cases, the seed of the envelope's draws).
    #[arg(long, default_value_t = bench::Config::default().seed)]
    pub seed: u64,
    /// Run once per seed, each into OUT/seed-N, and write OUT/seeds.md: per seed and the worst
    /// over them. A range A-B (`1-5`), a list (`1,3,5`) or one seed.
    #[arg(long, value_name = "SEEDS", conflicts_with = "seed")]
    pub seeds: Option<String>,
    /// Only the first N cases of the vehicle suite (for a quick look).
    #[arg(long)]
    pub cases: Option<usize>,
    /// Only one group of cases: the vehicle simulation's suite on `--tir`, or the wheel cases
    /// on every tyre of `--tyres`. Default: both, the vehicle suite first.
    #[arg(long, value_enum)]
    pub only: Option<bench::Only>,
    /// The folder of tyre files for the wheel cases: every `.tir` the estimator accepts (the
    /// others are listed as skipped, with why).
    #[arg(long, value_name = "DIR", default_value_os_t = bench::Config::default().tyres)]
    pub tyres: PathBuf,
    /// The quick subset (CI): the wheel cases on three tyres (MF 6.1 car, FSAE, MF 5.2 truck) ×
    /// four scenarios, exact and at 1× the envelope, at 200 Hz, one of them at 100 Hz and 1 kHz;
    /// the vehicle suite's first three cases (unless `--cases`).
    #[arg(long)]
    pub quick: bool,
    /// Run every wheel case twice in a row on one estimator, and report the second run (the
    /// estimator warm from the first) beside the first (cold).
    #[arg(long)]
    pub warm: bool,
    /// Threads running the wheel cases (the results do not depend on it).
    #[arg(long, value_name = "N", default_value_t = bench::Config::default().jobs)]
    pub jobs: usize,
    /// Aligning-torque sensor noise, rms \[N·m\], added to every row the estimators see. The
    /// sensors, not the estimators: what the bank assumes is its own configuration's.
    #[arg(long, value_name = "NM", allow_negative_numbers = true, default_value_t = bench::Sensors::default().sigma_mz)]
    pub noise_mz: f64,
    /// Force sensor noise (Fy, Fx, Fz), rms, as a fraction of Fz \[-\] (the sensors, not the
    /// estimators' assumption).
    #[arg(long, value_name = "FRACTION", allow_negative_numbers = true, default_value_t = bench::Sensors::default().sigma_rel)]
    pub noise_f: f64,
    /// Pure delay of every measured channel \[s\] (rounded to the simulation's step, 1 ms).
    #[arg(long, value_name = "S", allow_negative_numbers = true, default_value_t = bench::Sensors::default().delay)]
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
    /// Give the estimators this tyre file instead of the simulated tyre's (`--tir`'s in the
    /// vehicle suite; in the wheel cases every tyre's of `--tyres`, on the exact level only):
    /// the car's tyre is simulated, the estimator has this file of it (docs/gap.md's loop: the
    /// file and the corrected file of `gough gap diagnose --write-tir`).
    #[arg(long, value_name = "FILE.tir")]
    pub estimator_tir: Option<PathBuf>,
}

impl BenchArgs {
    /// The bench's configuration: the sensors' values each finite and ≥ 0 (the delay at most
    /// 1 s), the preview's weight inside (0, 1) or 0, each model error a `.tir` key and a
    /// finite number.
    pub fn config(&self) -> Result<bench::Config, String> {
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
        let w = self.preview;
        let preview = if w == 0.0 {
            None
        } else if w > 0.0 && w < 1.0 {
            Some(gough::mu::preview::Config {
                wheelbase: bench::sim_wheelbase(),
                weight: w,
            })
        } else {
            return Err(format!(
                "--preview {w}: a weight inside (0, 1), or 0 for none"
            ));
        };
        Ok(bench::Config {
            tir: self.tir.clone(),
            out: self.out.clone(),
            seed: self.seed,
            cases: self.cases,
            sensors: bench::Sensors {
                sigma_mz: self.noise_mz,
                sigma_rel: self.noise_f,
                delay: self.delay,
                ..bench::Sensors::default()
            },
            preview,
            mu_shift: self.mu_shift,
            model_error: self
                .model_error
                .iter()
                .map(|kv| model_error(kv))
                .collect::<Result<_, _>>()?,
            only: self.only,
            tyres: self.tyres.clone(),
            quick: self.quick,
            warm: self.warm,
            jobs: if self.jobs == 0 {
                return Err("--jobs 0: expected at least one thread".into());
            } else {
                self.jobs
            },
            estimator_tir: self.estimator_tir.clone(),
        })
    }

    /// The seeds of `--seeds` (`None`: one run, `--seed`).
    pub fn seeds(&self) -> Result<Option<Vec<u64>>, String> {
        self.seeds.as_deref().map(bench::parse_seeds).transpose()
    }
}

/// One `--model-error NAME=DELTA`: a `.tir` key (any case, spaces trimmed) and a finite delta.
fn model_error(kv: &str) -> Result<(gough::mf::Key, f64), String> {
    let (name, v) = kv
        .split_once('=')
        .ok_or_else(|| format!("--model-error {kv}: expected NAME=DELTA"))?;
    let key = gough::mf::Key::from_name(name.trim())
        .ok_or_else(|| format!("--model-error {kv}: no .tir parameter '{}'", name.trim()))?;
    let d = v
        .trim()
        .parse::<f64>()
        .ok()
        .filter(|d| d.is_finite())
        .ok_or_else(|| format!("--model-error {kv}: '{}' is not a finite number", v.trim()))?;
    Ok((key, d))
}

/// Arguments of `gough mu demo`.
#[derive(Args)]
pub struct DemoArgs {
    /// Tyre property file (.tir).
    #[arg(long, default_value_os_t = demo::Config::default().tir)]
    pub tir: PathBuf,
    /// Manoeuvre (one of the simulation's).
    #[arg(long, default_value_t = demo::Config::default().manoeuvre)]
    pub manoeuvre: String,
    /// Road (the simulation's spec grammar).
    #[arg(long, default_value_t = demo::Config::default().road)]
    pub road: String,
    /// Output directory (estimates.csv, log_fl.csv, mu.png, gough.png).
    #[arg(long, default_value_os_t = demo::Config::default().out)]
    pub out: PathBuf,
    /// Noise seed.
    #[arg(long, default_value_t = demo::Config::default().seed)]
    pub seed: u64,
}

impl DemoArgs {
    /// The demo's configuration.
    pub fn config(&self) -> demo::Config {
        demo::Config {
            tir: self.tir.clone(),
            manoeuvre: self.manoeuvre.clone(),
            road: self.road.clone(),
            out: self.out.clone(),
            seed: self.seed,
        }
    }
}

/// Arguments of `gough mu bound`.
#[derive(Args)]
pub struct BoundArgs {
    /// Tyre property file (.tir).
    #[arg(long, default_value_os_t = bound::Config::default().bench.tir)]
    pub tir: PathBuf,
    /// Output directory (bound.md, bound.csv).
    #[arg(long, default_value_os_t = bound::Config::default().bench.out)]
    pub out: PathBuf,
    /// Noise seed of the bank's run (the bound itself needs no noise).
    #[arg(long, default_value_t = bound::Config::default().bench.seed)]
    pub seed: u64,
    /// Only the first N cases of the bench's suite.
    #[arg(long)]
    pub cases: Option<usize>,
    /// Also run the maximum-likelihood reference (`WindowMl`) on every wheel and surface: about
    /// 1,000 Magic Formula evaluations per row, a few minutes for the suite.
    #[arg(long)]
    pub ml: bool,
    /// The reference's window \[s\], in (0, 10] (implies `--ml`): how much of the run-up it
    /// may use. Default 1 s (`ML_WINDOW`).
    #[arg(long)]
    pub ml_window: Option<f64>,
    /// Bound the wheel cases instead (every tyre of `--tyres`, every scenario, exact and drawn
    /// from the envelope, 200 Hz), beside the bank's wheel-surfaces within 150 ms: per tyre,
    /// with the tyre exact and with its calibration unknown. Writes bound_wheel.md.
    #[arg(long)]
    pub wheel_cases: bool,
    /// The tyre files of `--wheel-cases`.
    #[arg(long, default_value = "host-tests/data/tyres")]
    pub tyres: PathBuf,
}

impl BoundArgs {
    /// The bound's configuration: the default bench's rows with this tyre, seed and cases (the
    /// window is checked when it runs, before the tyre is read).
    pub fn config(&self) -> bound::Config {
        bound::Config {
            bench: bench::Config {
                tir: self.tir.clone(),
                out: self.out.clone(),
                seed: self.seed,
                cases: self.cases,
                ..bench::Config::default()
            },
            ml: self.ml_window.or(self.ml.then_some(bound::ML_WINDOW)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    #[derive(Parser)]
    struct Cli {
        #[command(flatten)]
        a: BenchArgs,
    }

    fn parse(extra: &[&str]) -> Result<bench::Config, String> {
        Cli::try_parse_from(["bench"].iter().chain(extra))
            .unwrap()
            .a
            .config()
    }

    /// `--seeds` reads a range, a list or one seed (each once, in order); anything else, and
    /// `--seeds` with `--seed`, is refused.
    #[test]
    fn the_seeds() {
        use bench::parse_seeds as p;
        assert_eq!(p("1-5"), Ok(vec![1, 2, 3, 4, 5]));
        assert_eq!(p("3"), Ok(vec![3]));
        assert_eq!(p("1,3, 5"), Ok(vec![1, 3, 5]));
        assert_eq!(p("1-3,2,7"), Ok(vec![1, 2, 3, 7]));
        for bad in ["", "5-1", "a", "1-", "-3", "1-b", "0-5000"] {
            let e = p(bad).unwrap_err();
            assert!(e.starts_with(&format!("--seeds {bad}:")), "{e}");
        }
        let seeds = |extra: &[&str]| {
            Cli::try_parse_from(["bench"].iter().chain(extra)).map(|c| c.a.seeds().unwrap())
        };
        assert_eq!(seeds(&["--seeds", "1-2"]).unwrap(), Some(vec![1, 2]));
        assert_eq!(seeds(&[]).unwrap(), None);
        assert!(seeds(&["--seeds", "1-2", "--seed", "3"]).is_err());
    }

    /// Without arguments, the bench's documented configuration; the sensors, the preview and the
    /// model errors are what the flags ask for, and a value out of range is refused naming its
    /// flag.
    #[test]
    fn the_arguments_are_the_configuration() {
        assert_eq!(parse(&[]).unwrap(), bench::Config::default());
        let c = parse(&[
            "--noise-mz",
            "5",
            "--noise-f",
            "0.02",
            "--delay",
            "0",
            "--preview",
            "0",
            "--model-error",
            "PHY1=0.002, pvy1 = -0.01",
        ])
        .unwrap();
        assert_eq!(
            (c.sensors.sigma_mz, c.sensors.sigma_rel, c.sensors.delay),
            (5.0, 0.02, 0.0)
        );
        assert_eq!(c.preview, None);
        assert_eq!(
            c.model_error,
            [(gough::mf::Key::PHY1, 0.002), (gough::mf::Key::PVY1, -0.01)]
        );
        let w = parse(&["--preview", "0.5"]).unwrap().preview.unwrap();
        assert_eq!((w.wheelbase, w.weight), (bench::sim_wheelbase(), 0.5));
        for bad in [
            &["--noise-mz", "-1"][..],
            &["--noise-f", "NaN"],
            &["--delay", "2"],
            &["--preview", "1"],
        ] {
            let e = parse(bad).unwrap_err();
            assert!(e.starts_with(bad[0]), "{e}");
        }
        let c = parse(&[
            "--only", "wheel", "--tyres", "/t", "--quick", "--warm", "--jobs", "1",
        ])
        .unwrap();
        assert_eq!(
            (c.only, c.tyres, c.quick, c.warm, c.jobs),
            (Some(bench::Only::Wheel), PathBuf::from("/t"), true, true, 1)
        );
        assert!(parse(&["--jobs", "0"]).unwrap_err().starts_with("--jobs 0"));
        for bad in ["PHY1", "NOPE=1", "PHY1=x", "PHY1=NaN"] {
            let e = parse(&["--model-error", bad]).unwrap_err();
            assert!(e.starts_with("--model-error"), "{bad}: {e}");
        }
    }
}
