//! `gough mu ...` subcommands.
pub mod bench;

use crate::mu::{read_log, Method, Precision, Setup};
use crate::tyre;
use clap::{Args, Subcommand};
use gough::proto::Wheel;
use std::io::Write;
use std::path::PathBuf;

/// `gough mu` subcommands.
#[derive(Subcommand)]
pub enum MuCmd {
    /// Run a friction estimator over a log: one wheel's, or (the bank) a car's.
    ///
    /// LOG columns: t,fz,fy,mz required; fx,vx,kappa,alpha,gamma optional (SI, ISO-W); with
    /// `wheel` (0–3 = FL, FR, RL, RR) a car's log. The bank never reads alpha. EST columns:
    /// t,mu,sigma,state (identifiable, not_identifiable, fallback), with `wheel` for a car's log.
    Estimate(EstimateArgs),
    /// Benchmark the estimator (the bank) and its peers on the simulation's manoeuvre suite, then
    /// the bank on every tyre of a folder, on tyres that are not their file, at 100, 200 and
    /// 1000 Hz (the wheel cases).
    Bench(bench::BenchArgs),
    /// The main job: a simulated manoeuvre on a road whose friction changes, the estimator at
    /// every wheel, a table on the terminal, plots and estimates written.
    Demo(bench::DemoArgs),
    /// From which utilisation the bank reads μ on a tyre: steady, noise-free points of its own
    /// Magic Formula on surfaces μ 1.0 … 0.1 at 0.5, 1 and 1.5·Fz0, each held for 150 ms, and
    /// the trail gap between neighbouring surfaces.
    Map(MapArgs),
    /// How soon any estimator could know μ on the benchmark's data: the Cramér–Rao bound of
    /// its rows (exact model, the bench's noise) 150 ms after the utilisation reaches 0.5, beside
    /// the bank's latency (as `gough mu bench` runs it), wheel by wheel.
    Bound(bench::BoundArgs),
    /// Calibrate the tyre on a log of a road whose μ is known: the estimator's online
    /// calibration (peak trail, trail shape, trail shift, Kxκ; each with its σ) run with the
    /// road held at that μ, written as the file `gough mu estimate --calibration-in` reads,
    /// and as a `.tir` with the calibration in its coefficients.
    ///
    /// LOG columns as `gough mu estimate` reads them (with `wheel` for several wheels, each
    /// mounted on its side; one wheel's log as `--side` says).
    Calibrate(CalibrateArgs),
}

/// Arguments of `gough mu calibrate`.
#[derive(Args)]
pub struct CalibrateArgs {
    /// Tyre property file (.tir).
    #[arg(long)]
    pub tir: PathBuf,
    /// Measurement log (CSV) on one road.
    #[arg(long)]
    pub log: PathBuf,
    /// The road's friction μ, on the file's scale (as the estimator reports it).
    #[arg(long)]
    pub mu: f64,
    /// The side of a one-wheel log's wheel (as `gough mu estimate --side`).
    #[arg(long, value_enum, default_value = "file")]
    pub side: SideArg,
    /// Write each wheel's calibration here (JSON; `gough mu estimate --calibration-in`).
    #[arg(long)]
    pub calibration_out: Option<PathBuf>,
    /// Write the tyre file with the calibration (the log's wheels combined) in its
    /// coefficients here.
    #[arg(long)]
    pub out: Option<PathBuf>,
}

/// Arguments of `gough mu map`.
#[derive(Args)]
pub struct MapArgs {
    /// Tyre property file (.tir).
    #[arg(long)]
    pub tir: PathBuf,
    /// Also write the map as CSV here.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// The samples carry no Fx (a wheel without a longitudinal force sensor; by default they
    /// carry the model's free-rolling Fx, as a wheel that measures Fx would).
    #[arg(long)]
    pub no_fx: bool,
    /// Inclination γ of the wheel \[rad\] (ISO-W; the samples carry it). The sweep is α > 0,
    /// where Fy < 0; whether γ's camber thrust adds to that force or works against it is the
    /// tyre's (on the bundled MF 6.1 tyre γ > 0 adds to it): compare ±γ.
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub gamma: f64,
}

/// Arguments of `gough mu estimate`.
#[derive(Args)]
pub struct EstimateArgs {
    /// Tyre property file (.tir).
    #[arg(long)]
    pub tir: PathBuf,
    /// Measurement log (CSV).
    #[arg(long)]
    pub log: PathBuf,
    /// Output CSV.
    #[arg(long)]
    pub out: PathBuf,
    /// Float path of the bank (the peers run in f64).
    #[arg(long, value_enum, default_value_t = Precision::F64)]
    pub precision: Precision,
    /// Estimator.
    #[arg(long, value_enum, default_value_t = Method::Bank)]
    pub method: Method,
    /// Wheelbase \[m\] of the car a four-wheel log comes from (a `wheel` column, 0–3 = FL, FR,
    /// RL, RR): each rear wheel's estimator is told what the front wheel on its side read when
    /// it gets there (`gough::mu::preview`). Bank method only.
    #[arg(long, value_name = "M")]
    pub wheelbase: Option<f64>,
    /// The side of a one-wheel log's wheel: `file` takes the signals as the tyre file describes
    /// the tyre (a wheel on the other side's signals mirrored: Fy, Mz, α, γ negated); `left` or
    /// `right` takes them in the wheel's own ISO-W axes and mirrors the tyre where the file's
    /// TYRESIDE differs. A car's log (a `wheel` column) mounts FL, RL left and FR, RR right.
    #[arg(long, value_enum, default_value_t = SideArg::File)]
    pub side: SideArg,
    /// Start each wheel's estimator from the calibration of the tyre in this file (JSON, as
    /// `--calibration-out` writes it: per wheel the properties trail, trail_shape, trail_shift,
    /// kx with value and σ, and the batches): a warm start. A file of another form, or values
    /// the estimator refuses (not finite, beyond its bounds), are an error. Bank method only.
    #[arg(long, value_name = "FILE")]
    pub calibration_in: Option<PathBuf>,
    /// Write each wheel's calibration of the tyre after the log to this file (JSON). Bank
    /// method only.
    #[arg(long, value_name = "FILE")]
    pub calibration_out: Option<PathBuf>,
}

/// `--side` of `gough mu estimate`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum SideArg {
    /// As the tyre file describes the tyre.
    File,
    /// A left-hand wheel, in its own axes.
    Left,
    /// A right-hand wheel, in its own axes.
    Right,
}

impl SideArg {
    fn side(self) -> Option<gough::mf::Side> {
        match self {
            SideArg::File => None,
            SideArg::Left => Some(gough::mf::Side::Left),
            SideArg::Right => Some(gough::mf::Side::Right),
        }
    }
}

/// Runs a `gough mu` subcommand.
pub fn run(cmd: MuCmd) -> Result<(), String> {
    match cmd {
        MuCmd::Estimate(a) => estimate(&a),
        MuCmd::Bench(b) => {
            let (cfg, seeds) = (b.config()?, b.seeds()?);
            let t0 = std::time::Instant::now();
            match seeds {
                Some(s) => crate::mu::bench::run_seeds(&cfg, &s)?,
                None => crate::mu::bench::run(&cfg)?,
            }
            eprintln!("({:.1} s)", t0.elapsed().as_secs_f64());
            Ok(())
        }
        MuCmd::Demo(d) => crate::mu::demo::run(&d.config()),
        MuCmd::Bound(b) if b.wheel_cases => {
            crate::mu::bound::run_wheel_cases(&b.tyres, b.seed, &b.out)
        }
        MuCmd::Bound(b) => crate::mu::bound::run(&b.config()),
        MuCmd::Calibrate(a) => calibrate(&a),
        MuCmd::Map(a) => {
            if !a.gamma.is_finite() {
                return Err(format!("--gamma {}: not a finite angle [rad]", a.gamma));
            }
            let t = tyre::load(&a.tir)?;
            let cells = crate::mu::map::map(&t.params, !a.no_fx, a.gamma)?;
            let name = a.tir.file_name().map_or_else(
                || a.tir.display().to_string(),
                |n| n.to_string_lossy().into_owned(),
            );
            print!(
                "{}",
                crate::mu::map::render(&cells, &name, t.params.fnomin, !a.no_fx, a.gamma)
            );
            if let Some(out) = &a.out {
                if let Some(dir) = out.parent().filter(|d| !d.as_os_str().is_empty()) {
                    std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
                }
                std::fs::write(out, crate::mu::map::csv(&cells))
                    .map_err(|e| format!("{}: cannot write: {e}", out.display()))?;
                eprintln!("-> {}", out.display());
            }
            Ok(())
        }
    }
}

/// `gough mu estimate`.
fn estimate(a: &EstimateArgs) -> Result<(), String> {
    let t = tyre::load(&a.tir)?;
    let log = read_log(&a.log)?;
    let wheels: Vec<Wheel> = log.iter().map(|(w, _)| *w).collect();
    let several = wheels.iter().any(|&w| w != Wheel::FrontLeft);
    if (several || a.wheelbase.is_some()) && !a.method.couples_wheels() {
        return Err(format!(
            "{}: the {} method reads one wheel's log{}",
            a.log.display(),
            a.method.name(),
            if several {
                " (this one has several wheels)"
            } else {
                "; --wheelbase is the bank's"
            }
        ));
    }
    if several && a.side != SideArg::File {
        return Err(format!(
            "{}: --side is a one-wheel log's; a car's log mounts each wheel on its side",
            a.log.display()
        ));
    }
    let preview = match a.wheelbase {
        Some(l) => {
            let c = gough::mu::preview::Config::with_wheelbase(l);
            gough::mu::preview::Preview::new(c).map_err(|e| format!("--wheelbase {l}: {e}"))?;
            Some(c)
        }
        None => None,
    };
    let setup = Setup {
        precision: a.precision,
        mounted: crate::mu::mounting(&wheels, a.side.side()),
        preview,
    };
    if (a.calibration_in.is_some() || a.calibration_out.is_some()) && !a.method.couples_wheels() {
        return Err(format!(
            "--calibration-in/--calibration-out are the bank's; the {} method keeps no calibration",
            a.method.name()
        ));
    }
    let mut estimator = a.method.estimator(&t.params, &setup)?;
    if let Some(path) = &a.calibration_in {
        crate::mu::calfile::load_into(estimator.as_mut(), path)?;
    }
    let est = estimator.run(&log);
    if let Some(path) = &a.calibration_out {
        crate::mu::calfile::save_from(estimator.as_ref(), &wheels, path)?;
        eprintln!("calibration -> {}", path.display());
    }
    if let Some(dir) = a.out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    }
    let tmp = a.out.with_extension("csv.tmp");
    let write = || -> std::io::Result<()> {
        let mut w = std::io::BufWriter::new(std::fs::File::create(&tmp)?);
        writeln!(w, "t,{}mu,sigma,state", if several { "wheel," } else { "" })?;
        for ((wheel, s), e) in log.iter().zip(&est) {
            write!(w, "{},", s.t)?;
            if several {
                write!(w, "{},", wheel.index())?;
            }
            writeln!(w, "{:.6},{:.6},{}", e.mu, e.sigma, e.state.name())?;
        }
        w.flush()?;
        std::fs::rename(&tmp, &a.out)
    };
    write().map_err(|e| format!("{}: cannot write: {e}", a.out.display()))?;
    let n_id = est
        .iter()
        .filter(|e| e.state == gough::mu::State::Identifiable)
        .count();
    let last = est.last().map(|e| (e.mu, e.sigma, e.state.name()));
    eprintln!(
        "{} rows, {} identifiable; last: {:?} -> {}",
        log.len(),
        n_id,
        last,
        a.out.display()
    );
    Ok(())
}

/// `gough mu calibrate`.
fn calibrate(a: &CalibrateArgs) -> Result<(), String> {
    use crate::mu::calibrate;
    use gough::mu::calibration::Property;
    let t = tyre::load(&a.tir)?;
    let log = read_log(&a.log)?;
    let wheels: Vec<Wheel> = log.iter().map(|(w, _)| *w).collect();
    if wheels.iter().any(|&w| w != Wheel::FrontLeft) && a.side != SideArg::File {
        return Err(format!(
            "{}: --side is a one-wheel log's; a car's log mounts each wheel on its side",
            a.log.display()
        ));
    }
    let mounted = crate::mu::mounting(&wheels, a.side.side());
    let cals = calibrate::calibrate(&t.params, a.mu, &log, mounted)
        .map_err(|e| format!("{}: {e}", a.log.display()))?;
    let prior = calibrate::config().cal_sigma;
    let show = |label: &str, c: &gough::mu::calibration::Exported| {
        println!("{label}: {} steps", c.batches);
        for (k, p) in Property::ALL.iter().enumerate() {
            let (v, s) = (c.value[k], c.sigma[k]);
            if p.is_scale() {
                println!(
                    "  {:<12} × {v:.4} ± {:.1} % (prior ± {:.1} %)",
                    p.name(),
                    100.0 * s,
                    100.0 * prior[k]
                );
            } else {
                println!(
                    "  {:<12} {:+.3} mrad ± {:.3} mrad (prior ± {:.3} mrad)",
                    p.name(),
                    1e3 * v,
                    1e3 * s,
                    1e3 * prior[k]
                );
            }
        }
    };
    for c in &cals {
        show(
            &format!(
                "wheel {:?} (the road explains {} of {} excited batches)",
                c.wheel, c.explained, c.excited
            ),
            &c.cal,
        );
    }
    let all: Vec<_> = cals.iter().map(|c| c.cal).collect();
    let one = calibrate::combine(&all, &prior);
    if cals.len() > 1 {
        show("the wheels combined", &one);
    }
    if let Some(path) = &a.calibration_out {
        let pairs: Vec<_> = cals.iter().map(|c| (c.wheel, c.cal)).collect();
        crate::mu::calfile::CalibrationFile::new(&pairs).write(path)?;
        println!("-> {}", path.display());
    }
    if let Some(out) = &a.out {
        let text = std::fs::read_to_string(&a.tir)
            .map_err(|e| format!("{}: cannot read: {e}", a.tir.display()))?;
        let new = calibrate::write_tir(&text, &t.params, &one)?;
        if let Some(dir) = out.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
        }
        std::fs::write(out, new).map_err(|e| format!("{}: {e}", out.display()))?;
        // What was written reads back.
        tyre::load(out).map_err(|e| format!("{}: does not read back: {e}", out.display()))?;
        println!("-> {}", out.display());
    }
    Ok(())
}
