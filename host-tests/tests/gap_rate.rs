//! Issue 40: the gap diagnosis's sim at the log rate is the continuous model, sampled. Logs are
//! made by an independent run of the core's transient tyre at 10 kHz (`TransientTyre` with the
//! first-order hold, the sim's damping speed), sampled at 100 Hz and 1 kHz with 1 % noise; the
//! sim must match them to the noise, the diagnosis must find nothing in them, and a log with
//! dropped rows is run with the filter restarted at the gaps.
use gough::math::Libm;
use gough::mf::{Options, Params};
use gough::relax::{DampingSpeed, Kinematics, Operating, TransientTyre};
use gough_host::gap::log::Log;
use gough_host::gap::sim::{Mods, Sim};
use gough_host::gap::{self as gap, stats};
use gough_host::rng::Rng;
use std::f64::consts::TAU;
use std::path::Path;

fn tyre(name: &str) -> Params<f64> {
    let p = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("data/tyres")
        .join(name);
    gough_host::tyre::load(&p).unwrap().params
}

/// The programme at time t: (Vx, α, κ, Fz). Fz oscillates ±30 % at 8 Hz around Fz0 while the
/// slip angle sits near 4° (the paper's Figs. 13–14) and a slow κ and α content gives Fx and Mz.
fn programme(p: &Params<f64>, t: f64) -> (f64, f64, f64, f64) {
    let vx = 15.0 + 3.0 * (TAU * 0.2 * t).sin();
    let alpha = 4f64.to_radians() + 1.5f64.to_radians() * (TAU * 0.7 * t).sin();
    let kappa = 0.03 * (TAU * 0.45 * t + 1.0).sin();
    let fz = p.fnomin * (1.0 + 0.3 * (TAU * 8.0 * t).sin());
    (vx, alpha, kappa, fz)
}

/// A none-case log: the core's transient tyre at 10 kHz over `secs`, sampled at `rate` Hz,
/// white noise of `noise` × each channel's RMS. Returns the log and the noise RMS per channel.
fn oscillating_log(
    p: &Params<f64>,
    rate: f64,
    secs: f64,
    noise: f64,
    seed: u64,
) -> (Log, [f64; 3]) {
    let dt = 1e-4;
    let every = (1.0 / rate / dt).round() as usize;
    let n = (secs / dt).round() as usize;
    let opts = Options {
        transient: true,
        ..Options::default()
    };
    let mut tt = TransientTyre::new(p);
    tt.config.damping = DampingSpeed::Forward;
    tt.hold = true;
    let mut lg = Log::default();
    let mut clean = Vec::new();
    let mut init = true;
    for i in 0..=n {
        let t = i as f64 * dt;
        let (vx, alpha, kappa, fz) = programme(p, t);
        let op = Operating {
            kin: Kinematics {
                vx,
                vsx: -kappa * vx,
                vsy: alpha.tan() * vx,
            },
            fz,
            gamma: 0.0,
            phit: 0.0,
            p: None,
        };
        if init {
            // Start in the steady state of the first row, as the sim does.
            let (o, _) = tt.step::<Libm>(p, &opts, dt, &op).unwrap();
            tt.state.v = o.sigma_y * alpha.tan();
            tt.state.u = o.sigma_x * kappa;
            init = false;
        }
        let (o, _) = tt.step::<Libm>(p, &opts, dt, &op).unwrap();
        if i % every == 0 {
            lg.t.push(t);
            lg.vx.push(vx);
            lg.alpha.push(alpha);
            lg.kappa.push(kappa);
            lg.gamma.push(0.0);
            lg.fz.push(fz);
            clean.push([o.fx, o.fy, o.mz]);
        }
    }
    let mut rng = Rng::new(seed);
    let mut sd = [0.0; 3];
    for (c, s) in sd.iter_mut().enumerate() {
        *s = noise * stats::rms(clean.iter().map(|m| m[c]));
    }
    lg.meas = clean
        .iter()
        .map(|m| [0, 1, 2].map(|c| m[c] + sd[c] * rng.normal()))
        .collect();
    (lg, sd)
}

/// RMS of (log − sim) per channel over the rows after the first second, over the noise RMS.
fn miss_over_noise(p: &Params<f64>, lg: &Log, sd: [f64; 3]) -> [f64; 3] {
    let sim = Sim::new(p.clone(), lg);
    assert!(sim.filters, "the file must give relaxation lengths");
    let run = sim.run(lg, &sim.params, &Mods::default()).unwrap();
    let rows: Vec<usize> = (0..lg.len()).filter(|&i| lg.t[i] >= 1.0).collect();
    [0, 1, 2].map(|c| stats::rms(rows.iter().map(|&i| lg.meas[i][c] - run.out[i][c])) / sd[c])
}

/// Fz ±30 % at 8 Hz, sampled at 100 Hz and at 1 kHz: the sim misses the log by the noise alone
/// (ratio ≈ 1 in Fx, Fy and Mz), and the diagnosis of the 100 Hz log finds no effect.
/// Figures print with `--nocapture`.
#[test]
fn a_none_log_with_load_oscillation_is_matched_to_the_noise_at_100_hz_and_1_khz() {
    for file in ["MagicFormula61_Parameters.tir", "reference_tire_tvd3.tir"] {
        let p = tyre(file);
        for rate in [100.0, 1000.0] {
            let (lg, sd) = oscillating_log(&p, rate, 4.0, 0.01, 7);
            let r = miss_over_noise(&p, &lg, sd);
            println!(
                "{file} at {rate} Hz: sim miss / noise = Fx {:.3}, Fy {:.3}, Mz {:.3}",
                r[0], r[1], r[2]
            );
            for (c, x) in r.iter().enumerate() {
                assert!(*x < 1.1, "{file} {rate} Hz channel {c}: miss {x} × noise");
            }
        }
    }
    let p = tyre("MagicFormula61_Parameters.tir");
    let (lg, _) = oscillating_log(&p, 100.0, 4.0, 0.01, 11);
    let d = gap::diagnose(
        p,
        &lg,
        "SIM.tir",
        "oscillating",
        &gap::Options {
            fit_rows: Some(100),
            ..gap::Options::default()
        },
    )
    .unwrap();
    assert_eq!(d.verdict, None, "verdict {:?}", d.report.verdict);
}

/// Dropped rows: the sim restarts its filter at each gap (steady state of that row) instead of
/// bridging it; a log with 3 gaps of 0.2 s is counted as such, matches to the noise once the
/// restarts have settled, and gets no verdict (the diagnosis leaves the settling rows out of its
/// fits and scores; without that, the restarts' transients drew a `combined_slip` verdict).
#[test]
fn gaps_in_time_restart_the_filter_instead_of_bridging_it() {
    let p = tyre("MagicFormula61_Parameters.tir");
    let (full, sd) = oscillating_log(&p, 100.0, 5.0, 0.01, 3);
    let keep: Vec<usize> = (0..full.len())
        .filter(|&i| {
            !(120..140).contains(&i) && !(250..270).contains(&i) && !(380..400).contains(&i)
        })
        .collect();
    let pick = |v: &[f64]| keep.iter().map(|&i| v[i]).collect::<Vec<f64>>();
    let lg = Log {
        t: pick(&full.t),
        vx: pick(&full.vx),
        alpha: pick(&full.alpha),
        kappa: pick(&full.kappa),
        gamma: pick(&full.gamma),
        fz: pick(&full.fz),
        meas: keep.iter().map(|&i| full.meas[i]).collect(),
        ..Log::default()
    };
    assert_eq!(lg.gaps(), 3);
    let restarts = lg.restarts();
    assert!(restarts[0] && restarts[120] && restarts[230] && restarts[340] && !restarts[121]);
    let sim = Sim::new(p.clone(), &lg);
    let run = sim.run(&lg, &sim.params, &Mods::default()).unwrap();
    // Right after a gap the slips are the row's own (steady state), not a bridged transient.
    for &i in &[120usize, 230, 340] {
        assert_eq!(run.slips[i], [lg.kappa[i], lg.alpha[i]]);
    }
    let slips = sim.slips(&lg, &run.sigma).unwrap();
    assert_eq!(slips, run.slips);
    // The restart's steady state is not the oscillating tyre's state: the rows within 0.3 s
    // (≥ 4 relaxation lengths σκ ≈ 1 m of travel) after a restart may miss; the rest match to the noise.
    let settled: Vec<usize> = (0..lg.len())
        .filter(|&i| {
            lg.t[i] >= 1.0
                && [120usize, 230, 340]
                    .iter()
                    .all(|&g| i < g || lg.t[i] - lg.t[g] > 0.3)
        })
        .collect();
    let r = [0, 1, 2]
        .map(|c| stats::rms(settled.iter().map(|&i| lg.meas[i][c] - run.out[i][c])) / sd[c]);
    let all = miss_over_noise(&p, &lg, sd);
    println!("3 gaps: sim miss / noise = {r:?} settled, {all:?} all rows");
    assert!(r.iter().all(|&x| x < 1.15), "{r:?}");
    let d = gap::diagnose(
        p,
        &lg,
        "SIM.tir",
        "gaps",
        &gap::Options {
            fit_rows: Some(100),
            ..gap::Options::default()
        },
    )
    .unwrap();
    // The restarts' transients do not make a verdict.
    assert_eq!(d.verdict, None, "verdict {:?}", d.report.verdict);
}

/// Issue 40, item 2: the sim file lacks the combined-slip block entirely (tvd3 with RBX1, RBX3,
/// RBY1, RBY4 and RVY1–6 zero, so the weights are flat at the file's values); the log is the
/// full file's. The extension's coarse scan leaves the flat point: the verdict is combined slip
/// with a held-out shrink ≥ 0.8 of the achievable. Figures print with `--nocapture`.
#[test]
fn combined_slip_is_found_from_a_file_without_its_block() {
    use gough_host::gap::bench::{self, GenConfig};
    use gough_host::gap::cv;
    use gough_host::gap::effects::Effect;
    let truth = tyre("reference_tire_tvd3.tir");
    let mut simp = truth.clone();
    for k in [
        "RBX1", "RBX3", "RBY1", "RBY4", "RVY1", "RVY2", "RVY3", "RVY4", "RVY5", "RVY6",
    ] {
        simp.set(gough::mf::Key::from_name(k).unwrap(), 0.0);
    }
    let cfg = GenConfig {
        rows: 1500,
        rate: 100.0,
        seed: 21,
        p: false,
        phit: false,
        ..GenConfig::default()
    };
    let mut lg = bench::inputs(&truth, &cfg);
    let sim = Sim::new(truth.clone(), &lg);
    let clean = sim.run(&lg, &truth, &Mods::default()).unwrap().out;
    let mut rng = Rng::new(5);
    let sd = [0, 1, 2].map(|c| 0.01 * stats::rms(clean.iter().map(|m| m[c])));
    lg.meas = clean
        .iter()
        .map(|m| [0, 1, 2].map(|c| m[c] + sd[c] * rng.normal()))
        .collect();
    let d = gap::diagnose(
        simp,
        &lg,
        "SIM.tir",
        "no-combined-block",
        &gap::Options {
            fit_rows: Some(200),
            ..gap::Options::default()
        },
    )
    .unwrap();
    let achievable = cv::shrink(&d.rmse_before, &sd, &d.noise);
    let got = d
        .shrinks
        .iter()
        .find(|s| s.0 == Effect::CombinedSlip)
        .map(|s| s.1)
        .unwrap();
    println!(
        "combined slip from nothing: verdict {:?}, shrink {got:.3} of achievable {achievable:.3}",
        d.report.verdict.effect
    );
    assert_eq!(
        d.verdict,
        Some(Effect::CombinedSlip),
        "{:?}",
        d.report.verdict
    );
    assert!(got >= 0.8 * achievable, "{got} of {achievable}");
}

/// Issue 56: a log without an effect, the truth (the sim of the file) run at 2 kHz between the
/// rows and taken at the rows as a logger samples it — 20, 50, 100, 200 and 1,000 Hz, the
/// timestamps jittered by ±10 % of the step, 2 % of the rows dropped, the bench's load bursts
/// (Fz ±30 % at 2, 4, 8 Hz) — and the sim at the log rate: its miss of the noise-free truth,
/// RMS over the noise's, per channel, on the rows the diagnosis scores, two tyres. From 50 Hz
/// on below 0.2 of the noise. At 20 Hz an 8 Hz burst has 2.5 rows a period (and 1.25 across a
/// dropped row): no interpolant of the rows has it, and the miss is printed, not bounded (the
/// diagnosis's verdict on such logs: `a_none_log_at_20_hz_gets_no_verdict`). Figures print
/// with `--nocapture`.
#[test]
fn a_none_log_at_any_rate_with_jitter_and_dropped_rows_is_matched_by_the_sim() {
    use gough_host::gap::bench::{self, GenConfig, Sampling};
    let mut worst = 0.0f64;
    for file in ["MagicFormula61_Parameters.tir", "reference_tire_tvd3.tir"] {
        let p = tyre(file);
        for rate in [20.0, 50.0, 100.0, 200.0, 1000.0] {
            let cfg = GenConfig {
                // 15 s of log at any rate: a burst at each of 2, 4, 8 Hz.
                rows: (15.0 * rate) as usize,
                rate,
                seed: 3,
                noise: 0.01,
                load_oscillation: true,
                sampling: Sampling {
                    truth_rate: Some(2000.0),
                    jitter: 0.1,
                    drop: 0.02,
                },
                ..GenConfig::default()
            };
            let g = bench::generate(&p, &cfg).unwrap();
            let lg = &g.log;
            let sim = Sim::new(p.clone(), lg);
            let ctx = gap::effects::Ctx::new(lg, &sim).unwrap();
            let run = &ctx.base;
            let sd: [f64; 3] =
                [0, 1, 2].map(|c| stats::rms((0..lg.len()).map(|i| lg.meas[i][c] - g.clean[i][c])));
            // The rows the diagnosis scores (not those settling after a restart: the filter
            // starts in steady state there, the truth did not stop), after the first second.
            let rows: Vec<usize> = (0..lg.len())
                .filter(|&i| lg.t[i] >= 1.0 && ctx.settled[i])
                .collect();
            let r = [0, 1, 2]
                .map(|c| stats::rms(rows.iter().map(|&i| g.clean[i][c] - run.out[i][c])) / sd[c]);
            println!(
                "{file} at {rate} Hz ({} rows, {} restarts): sim miss of the truth / noise = Fx {:.3}, Fy {:.3}, Mz {:.3}",
                lg.len(),
                lg.gaps(),
                r[0],
                r[1],
                r[2]
            );
            if rate >= 50.0 {
                worst = worst.max(r[0]).max(r[1]).max(r[2]);
            }
        }
    }
    assert!(worst < 0.2, "worst from 50 Hz on: {worst}");
}

/// Issue 56: at 20 Hz (2,000 rows, 100 s, bursts, jitter ±10 %, 2 % dropped), where the sim
/// cannot follow an 8 Hz burst, the diagnosis still names nothing on a log without an effect,
/// on two tyres (the linear hold before issue 56 named `relaxation_length` on the second, shrink
/// 0.013). Slow (two diagnoses): `cargo test --release -p gough-host-tests --test gap_rate
/// a_none_log_at_20 -- --ignored --nocapture`.
#[test]
#[ignore]
fn a_none_log_at_20_hz_gets_no_verdict() {
    use gough_host::gap::bench::{self, GenConfig, Sampling};
    for file in ["MagicFormula61_Parameters.tir", "reference_tire_tvd3.tir"] {
        let p = tyre(file);
        let cfg = GenConfig {
            rows: 2000,
            rate: 20.0,
            seed: 5,
            noise: 0.01,
            load_oscillation: true,
            sampling: Sampling {
                truth_rate: Some(5000.0),
                jitter: 0.1,
                drop: 0.02,
            },
            ..GenConfig::default()
        };
        let g = bench::generate(&p, &cfg).unwrap();
        let d = gap::diagnose(p, &g.log, file, "none_20hz", &gap::Options::default()).unwrap();
        println!("{file} at 20 Hz: verdict {:?}", d.verdict);
        assert_eq!(d.verdict, None, "{file}: {:?}", d.report.verdict);
    }
}
