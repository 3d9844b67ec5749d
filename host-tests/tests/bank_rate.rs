//! Issue 39 item 6: the friction estimator at 100 Hz, as the Cortex-M0/M3 bench runs it
//! (`gough_workloads::streams`: the M4F bench's 1 kHz slalom decimated to every 10th sample, the
//! bank with one sample per batch), against the product's configuration (the 1 kHz stream, ten
//! samples per batch: also a 100 Hz estimator) on the same signal, in f32 with `math::Fast` as
//! both devices run it; and the Q31.32 bank (`Fix` + `FixMath`, the M0/M3 bench's fixed-point
//! build) against the f32 one at 100 Hz. The figures are printed (`cargo test -p
//! gough-host-tests --test bank_rate -- --nocapture`) and quoted in docs/backends.md.
use gough::fixed::{Fix, FixMath};
use gough::math::{Backend, Fast, Float};
use gough::mf::Params;
use gough::mu::{self, Bank, State};
use gough_workloads::slalom::Slalom;
use gough_workloads::streams::{bank_sample, config, stream, DECIMATE, SAMPLES};
use std::path::Path;

fn tyre() -> Params<f64> {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("data/tyres/MagicFormula61_Parameters.tir");
    gough::tir::parse(&std::fs::read_to_string(p).unwrap())
        .unwrap()
        .params
}

/// (μ, identifiable) after every sample of `samples`, with bank settings `cfg`.
fn run<F: Float, M: Backend<F>>(
    p: &Params<f64>,
    cfg: mu::Config<F>,
    samples: impl Iterator<Item = gough::proto::Measurement>,
) -> Vec<(f64, bool)> {
    let pf = p.cast::<F>();
    let mut b = Bank::new::<M>(&pf, None, cfg).unwrap();
    samples
        .map(|m| {
            let e = b.update::<M>(&pf, &bank_sample::<F>(&m));
            (e.mu.to_f64(), e.state == State::Identifiable)
        })
        .collect()
}

fn quantile(mut xs: Vec<f64>, q: f64) -> f64 {
    if xs.is_empty() {
        return f64::NAN;
    }
    xs.sort_by(f64::total_cmp);
    xs[((xs.len() - 1) as f64 * q).round() as usize]
}

/// How two runs' estimates at the same instants compare: both identifiable (share), |Δμ| where
/// both are (median, p95, max, share above 0.05), and each run's |μ − λμ·μy0| p95 and largest
/// while identifiable (the true surface: the stream's λμ times the tyre's own μy0, 1.0184 for
/// the MF 6.1 file).
struct Cmp {
    both: f64,
    /// Both identifiable, of the instants at which either is.
    agree: f64,
    d_med: f64,
    d_p95: f64,
    d_max: f64,
    d_over: f64,
    ident: [usize; 2],
    err_p95: [f64; 2],
    err_max: [f64; 2],
}

fn compare(a: &[(f64, bool)], b: &[(f64, bool)], truth: f64) -> Cmp {
    assert_eq!(a.len(), b.len());
    let d: Vec<f64> = a
        .iter()
        .zip(b)
        .filter(|(x, y)| x.1 && y.1)
        .map(|(x, y)| (x.0 - y.0).abs())
        .collect();
    let err = |r: &[(f64, bool)]| -> Vec<f64> {
        r.iter()
            .filter(|x| x.1)
            .map(|x| (x.0 - truth).abs())
            .collect()
    };
    let (ea, eb) = (err(a), err(b));
    let either = a.iter().zip(b).filter(|(x, y)| x.1 || y.1).count();
    Cmp {
        both: d.len() as f64 / a.len() as f64,
        agree: d.len() as f64 / either.max(1) as f64,
        d_med: quantile(d.clone(), 0.5),
        d_p95: quantile(d.clone(), 0.95),
        d_max: d.iter().copied().fold(0.0, f64::max),
        d_over: d.iter().filter(|&&x| x > 0.05).count() as f64 / d.len().max(1) as f64,
        ident: [ea.len(), eb.len()],
        err_p95: [quantile(ea.clone(), 0.95), quantile(eb.clone(), 0.95)],
        err_max: [
            ea.iter().copied().fold(0.0, f64::max),
            eb.iter().copied().fold(0.0, f64::max),
        ],
    }
}

const CASES: [(f32, f32, &str); 4] = [
    (1.0, 0.02, "dry, camber"),
    (1.0, 0.0, "dry, no camber"),
    (0.5, 0.02, "wet, camber"),
    (0.2, 0.02, "ice, camber"),
];

/// Batch 1 at 100 Hz against batch 10 at 1 kHz, f32 `Fast`, over the bench's 2 s: the 1 kHz run
/// is read at the 100 Hz samples' instants (its estimate after the 1 kHz sample taken at the
/// same time), so both have seen the signal up to the same instant.
#[test]
fn batch_1_at_100_hz_is_the_1_khz_estimator() {
    let p = tyre();
    let p32 = p.cast::<f32>();
    let mu0 = mu::mu_y0::<f64, gough::math::Libm>(&p).unwrap();
    println!("bank f32 math::Fast, {SAMPLES} instants 10 ms apart: batch 1 at 100 Hz (a) against batch 10 at 1 kHz (b)");
    println!("| stream | both identifiable | abs(Δμ) median / p95 / max | share > 0.05 | identifiable a / b | abs(μ − λμ·μy0) p95 a / b | max a / b |");
    for (mu, camber, name) in CASES {
        let a = run::<f32, Fast>(&p, config(), stream(&p32, mu, camber));
        let fine = run::<f32, Fast>(
            &p,
            mu::Config::default(),
            Slalom::new(&p32, mu, camber).take(SAMPLES * DECIMATE),
        );
        let b: Vec<_> = fine.iter().step_by(DECIMATE).copied().collect();
        let c = compare(&a, &b, f64::from(mu) * mu0);
        // Where the two differ by more than 0.05 while both are identifiable [s].
        let apart: Vec<f64> = a
            .iter()
            .zip(&b)
            .enumerate()
            .filter(|(_, (x, y))| x.1 && y.1 && (x.0 - y.0).abs() > 0.05)
            .map(|(i, _)| i as f64 * 0.01)
            .collect();
        if let (Some(first), Some(last)) = (apart.first(), apart.last()) {
            println!(
                "{name}: apart by more than 0.05 at {} instants, t = {first:.2} … {last:.2} s",
                apart.len()
            );
        }
        println!(
            "| {name} | {:.1} % | {:.4} / {:.4} / {:.4} | {:.1} % | {} / {} | {:.4} / {:.4} | {:.3} / {:.3} |",
            100.0 * c.both,
            c.d_med,
            c.d_p95,
            c.d_max,
            100.0 * c.d_over,
            c.ident[0],
            c.ident[1],
            c.err_p95[0],
            c.err_p95[1],
            c.err_max[0],
            c.err_max[1],
        );
        // The same estimator: identifiable together most of the time, the same value to a
        // fraction of the ±0.1 target where both are. (Not its largest difference: on ice, the
        // 1 kHz run reports μ 1.1–1.3 as identifiable for about 0.2 s of the second period, near
        // t = 1.55–1.75 s; the 100 Hz run does not. Both are printed.)
        // From a cold start the dry streams are identifiable on about half of the instants
        // (the calibration's σ of the trail is in μ's σ until the sweeps pin it down), so
        // "together" is counted among the instants at which either run is.
        assert!(
            c.agree >= 0.8,
            "{name}: both identifiable on {:.2} of the instants either is",
            c.agree
        );
        assert!(c.d_med <= 0.01, "{name}: median |Δμ| {}", c.d_med);
        // The 100 Hz run meets the accuracy target wherever it is identifiable.
        assert!(
            c.err_p95[0] <= 0.08,
            "{name}: 100 Hz p95 error {}",
            c.err_p95[0]
        );
    }
}

/// The Q31.32 bank at 100 Hz (the M0/M3 bench's fixed-point build) against the f32 one.
#[test]
fn fixed_point_bank_at_100_hz() {
    let p = tyre();
    let p32 = p.cast::<f32>();
    let mu0 = mu::mu_y0::<f64, gough::math::Libm>(&p).unwrap();
    println!("bank at 100 Hz (batch 1), {SAMPLES} samples: Q31.32 Fix + FixMath (a) against f32 math::Fast (b)");
    println!("| stream | both identifiable | abs(Δμ) median / p95 / max | share > 0.05 | identifiable a / b | abs(μ − λμ·μy0) p95 a / b | max a / b |");
    for (mu, camber, name) in CASES {
        let a = run::<Fix, FixMath>(&p, config(), stream(&p32, mu, camber));
        let b = run::<f32, Fast>(&p, config(), stream(&p32, mu, camber));
        let c = compare(&a, &b, f64::from(mu) * mu0);
        println!(
            "| {name} | {:.1} % | {:.1e} / {:.1e} / {:.1e} | {:.1} % | {} / {} | {:.4} / {:.4} | {:.3} / {:.3} |",
            100.0 * c.both,
            c.d_med,
            c.d_p95,
            c.d_max,
            100.0 * c.d_over,
            c.ident[0],
            c.ident[1],
            c.err_p95[0],
            c.err_p95[1],
            c.err_max[0],
            c.err_max[1],
        );
        // The normal equations are scaled into Q31.32's range (bank.rs, `fit_cell`): the
        // fixed-point bank then follows the f32 one (unscaled, its determinant saturated on
        // most steps and it strayed by up to 0.1).
        assert!(c.d_max <= 0.01, "{name}: max |Δμ| Fix vs f32 {}", c.d_max);
        assert!(
            c.ident[0].abs_diff(c.ident[1]) <= 4,
            "{name}: identifiable Fix {} vs f32 {}",
            c.ident[0],
            c.ident[1]
        );
        assert!(
            c.err_p95[0] <= 0.08,
            "{name}: Fix p95 error {}",
            c.err_p95[0]
        );
    }
}
