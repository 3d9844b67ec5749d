//! Calibration of the tyre file's registration of Mz against Fy on a surface of known μ
//! (`gough mu calibrate`).
//!
//! The bank reads μ where the trail collapses against where the force saturates; a file whose
//! horizontal shifts of the force (SHy, `PHY1`) and of the trail (SHt, `QHZ1`) are 1–2 mrad off
//! for the tyre on the car breaks its safety figures (`gough mu bench --model-error`,
//! docs/estimator.md). Online the offset acts as another surface does; on a log of a surface
//! whose μ is known it is fitted here: the log in batches of [`BATCH`] rows (means), those at
//! utilisation ≥ [`UTIL_MIN`] of the known surface (where the trail collapses), each batch's
//! slip angle α′ fitted for every trial offset δ of one parameter, and δ the minimum of the
//! summed χ² of (Fy, Mz) over a grid, refined by a parabola; its σ from the parabola's
//! curvature (χ² = −2 log-likelihood). The model is the core's Magic Formula (`mf::eval`),
//! surfaces scaled as the bank scales them (λμ = λμ,file·μ/μy0, docs/architecture.md).
//!
//! What it needs: κ in the log, or no longitudinal force to speak of (a batch whose |Fx| is more
//! than a tenth of its horizontal force is left out without κ); the known μ; enough batches
//! near the limit ([`MIN_BATCHES`]).
use super::estimator::Sample;
use gough::math::Libm;
use gough::mf::{self, Input, Key, Options, Params, Side};

/// Rows per batch.
pub const BATCH: usize = 10;
/// Fewest batches near the limit the fit takes.
pub const MIN_BATCHES: usize = 20;
/// Smallest utilisation |F|/(μ·Fz) of a batch the fit uses \[-\].
pub const UTIL_MIN: f64 = 0.5;
/// Below this |Vx| \[m/s\] (when logged) a batch is left out.
pub const VX_MIN: f64 = 3.0;
/// Largest χ² one batch adds (a batch the model cannot explain at any α′ counts no more).
pub const CHI2_CAP: f64 = 25.0;
/// Grid points on each side of δ = 0.
const STEPS: usize = 20;

/// The sensors' noise the χ² is weighted with.
#[derive(Debug, Clone, Copy)]
pub struct Noise {
    /// Fx, Fy, Fz rms as a fraction of Fz \[-\].
    pub f_rel: f64,
    /// Mz rms \[N·m\].
    pub mz: f64,
}

impl Default for Noise {
    fn default() -> Self {
        Noise {
            f_rel: 0.01,
            mz: 2.0,
        }
    }
}

/// One wheel's samples (in time order; camber where not logged: 0) and how the tyre is mounted
/// (`None`: as the file describes it, as `gough mu estimate` takes a log).
pub struct WheelLog<'a> {
    /// Samples, time increasing.
    pub rows: &'a [Sample],
    /// Mounting side (mirroring), `None` for the file's own.
    pub mounted: Option<Side>,
}

/// The fitted offset of one parameter.
#[derive(Debug, Clone)]
pub struct Fit {
    /// The parameter.
    pub key: Key,
    /// Its offset from the file's value.
    pub delta: f64,
    /// 1σ of `delta` from the curvature of χ².
    pub sigma: f64,
    /// χ² at `delta` (the parabola's minimum).
    pub chi2: f64,
    /// χ² at the file's own value (δ = 0).
    pub chi2_file: f64,
    /// Batches used.
    pub batches: usize,
}

struct Batch {
    fz: f64,
    fy: f64,
    mz: f64,
    kappa: f64,
    gamma: f64,
    vx: f64,
    sf: f64,
    sm: f64,
    mounted: Option<Side>,
}

fn mean(x: impl Iterator<Item = f64>) -> f64 {
    let (s, n) = x.fold((0.0, 0usize), |(s, n), v| (s + v, n + 1));
    if n == 0 {
        f64::NAN
    } else {
        s / n as f64
    }
}

/// The batches of `wheels` at utilisation ≥ [`UTIL_MIN`] on surface `mu`.
fn batches(wheels: &[WheelLog], mu: f64, noise: &Noise) -> Vec<Batch> {
    let mut out = Vec::new();
    for w in wheels {
        for r in w.rows.chunks_exact(BATCH) {
            let (fz, fy, mz) = (
                mean(r.iter().map(|x| x.fz)),
                mean(r.iter().map(|x| x.fy)),
                mean(r.iter().map(|x| x.mz)),
            );
            let fx = mean(r.iter().filter_map(|x| x.fx).filter(|v| v.is_finite()));
            let kappa = mean(r.iter().filter_map(|x| x.kappa).filter(|v| v.is_finite()));
            let vx = mean(r.iter().filter_map(|x| x.vx).filter(|v| v.is_finite()));
            let gamma = mean(r.iter().filter_map(|x| x.gamma).filter(|v| v.is_finite()));
            if !(fz.is_finite() && fz > 0.0 && fy.is_finite() && mz.is_finite()) {
                continue;
            }
            if vx.is_finite() && vx.abs() < VX_MIN {
                continue;
            }
            let fx = if fx.is_finite() { fx } else { 0.0 };
            let f = fx.hypot(fy);
            // Without κ the longitudinal slip is taken as 0: only where Fx says little.
            if !kappa.is_finite() && fx.abs() > 0.1 * f {
                continue;
            }
            if f < UTIL_MIN * mu * fz {
                continue;
            }
            let n = (BATCH as f64).sqrt();
            out.push(Batch {
                fz,
                fy,
                mz,
                kappa: if kappa.is_finite() { kappa } else { 0.0 },
                gamma: if gamma.is_finite() { gamma } else { 0.0 },
                // Without Vx, any speed well above VXLOW: the transient evaluation skips the
                // low-speed reductions, the only place the speed enters.
                vx: if vx.is_finite() { vx } else { 20.0 },
                // The batch mean's noise plus the bank's model-error terms (Config's defaults).
                sf: noise.f_rel * fz / n + 0.01 * fy.abs() + 0.005 * fz,
                sm: noise.mz / n + 0.03 * mz.abs() + 1.0,
                mounted: w.mounted,
            });
        }
    }
    out
}

/// χ² of batch `b` at slip angle `a` on the surface `p`.
fn chi2_at(p: &Params<f64>, b: &Batch, a: f64) -> f64 {
    let opts = Options {
        transient: true,
        mounted: b.mounted,
        moments: false,
        ..Options::default()
    };
    let input = Input {
        fz: b.fz,
        kappa: b.kappa,
        alpha: a,
        gamma: b.gamma,
        vx: b.vx,
        ..Input::default()
    };
    match mf::eval::<f64, Libm>(p, &input, &opts) {
        Ok(o) if o.fy.is_finite() && o.mz.is_finite() => {
            (((b.fy - o.fy) / b.sf).powi(2) + ((b.mz - o.mz) / b.sm).powi(2)).min(CHI2_CAP)
        }
        _ => CHI2_CAP,
    }
}

/// The α′ in `lo..hi` of least χ² (golden section) and that χ².
fn fit_alpha(p: &Params<f64>, b: &Batch, mut lo: f64, mut hi: f64) -> (f64, f64) {
    const G: f64 = 0.381_966_011_250_105;
    let (mut x1, mut x2) = (lo + G * (hi - lo), hi - G * (hi - lo));
    let (mut f1, mut f2) = (chi2_at(p, b, x1), chi2_at(p, b, x2));
    for _ in 0..40 {
        if f1 <= f2 {
            hi = x2;
            (x2, f2) = (x1, f1);
            x1 = lo + G * (hi - lo);
            f1 = chi2_at(p, b, x1);
        } else {
            lo = x1;
            (x1, f1) = (x2, f2);
            x2 = hi - G * (hi - lo);
            f2 = chi2_at(p, b, x2);
        }
    }
    let a = 0.5 * (lo + hi);
    (a, chi2_at(p, b, a))
}

/// The surface `mu` of the file `p` with `key` moved by `d`.
fn surface(p: &Params<f64>, key: Key, d: f64, mu: f64, mu_y0: f64) -> Params<f64> {
    let mut q = p.clone();
    q.set(key, p.get(key) + d);
    q.lmux = p.lmux * mu / mu_y0;
    q.lmuy = p.lmuy * mu / mu_y0;
    q
}

/// Fits the offset of `key` (e.g. `PHY1`, `QHZ1`) within ±`range` on `wheels`, logged on a
/// surface of friction `mu` (the file's scale). Errors: μ, the range or a noise not positive
/// and finite, fewer than [`MIN_BATCHES`] batches near the limit, the minimum at the grid's edge
/// (the offset lies beyond ±`range`), a χ² without curvature there.
pub fn calibrate(
    p: &Params<f64>,
    key: Key,
    mu: f64,
    wheels: &[WheelLog],
    noise: &Noise,
    range: f64,
) -> Result<Fit, String> {
    if !(mu.is_finite() && mu > 0.0) {
        return Err(format!("μ {mu}: expected a positive number"));
    }
    if !(range.is_finite() && range > 0.0 && range <= 0.1) {
        return Err(format!("range {range}: expected a value in (0, 0.1]"));
    }
    if !(noise.f_rel.is_finite() && noise.f_rel > 0.0 && noise.mz.is_finite() && noise.mz > 0.0) {
        return Err(format!(
            "noise {} of Fz, {} N·m: expected positive numbers",
            noise.f_rel, noise.mz
        ));
    }
    let mu_y0 = crate::sim::vehicle::mu_y0(p)?;
    let bs = batches(wheels, mu, noise);
    if bs.len() < MIN_BATCHES {
        return Err(format!(
            "{} batches of {BATCH} rows at utilisation ≥ {UTIL_MIN} of μ {mu} (at least {MIN_BATCHES} needed): the log does not come near the limit of that surface",
            bs.len()
        ));
    }
    // Each batch's α′ at the file's value: a scan, then golden section about the best point.
    let p0 = surface(p, key, 0.0, mu, mu_y0);
    let start: Vec<f64> = bs
        .iter()
        .map(|b| {
            let mut best = (f64::MAX, 0.0);
            for i in 0..=300 {
                let a = -0.3 + 0.002 * i as f64;
                let c = chi2_at(&p0, b, a);
                if c < best.0 {
                    best = (c, a);
                }
            }
            fit_alpha(&p0, b, best.1 - 0.002, best.1 + 0.002).0
        })
        .collect();
    // χ² over the grid of δ; each batch's α′ refitted near its start (a shift of δ moves it by
    // about δ).
    let win = 0.004 + 2.0 * range;
    let h = range / STEPS as f64;
    let curve: Vec<(f64, f64)> = (0..=2 * STEPS)
        .map(|i| {
            let d = -range + h * i as f64;
            let q = surface(p, key, d, mu, mu_y0);
            let c: f64 = bs
                .iter()
                .zip(&start)
                .map(|(b, &a)| fit_alpha(&q, b, a - win, a + win).1)
                .sum();
            (d, c)
        })
        .collect();
    let (i, _) = curve
        .iter()
        .enumerate()
        .min_by(|a, b| a.1 .1.total_cmp(&b.1 .1))
        .ok_or("no grid")?;
    if i == 0 || i == curve.len() - 1 {
        return Err(format!(
            "{}: the best offset lies at the edge of ±{range} (χ² still falling there): widen the range or check μ",
            key.name()
        ));
    }
    let (c0, c1, c2) = (curve[i - 1].1, curve[i].1, curve[i + 1].1);
    let curv = (c0 - 2.0 * c1 + c2) / (h * h);
    if !(curv.is_finite() && curv > 0.0) {
        return Err(format!(
            "{}: χ² has no curvature at its minimum",
            key.name()
        ));
    }
    let shift = 0.5 * h * (c0 - c2) / (c0 - 2.0 * c1 + c2);
    Ok(Fit {
        key,
        delta: curve[i].0 + shift,
        sigma: (2.0 / curv).sqrt(),
        chi2: c1 - 0.25 * (c0 - c2) * shift / h,
        chi2_file: curve[STEPS].1,
        batches: bs.len(),
    })
}

/// The `.tir` text `text` with the value of `key` set to `value` (the rest of the line — its
/// alignment, a `$` comment — kept). Errors when the key is not in the text.
pub fn set_in_tir(text: &str, key: Key, value: f64) -> Result<String, String> {
    let mut found = false;
    let mut out = String::with_capacity(text.len() + 16);
    for line in text.split_inclusive('\n') {
        let body = line.trim_end_matches(['\n', '\r']);
        let end = &line[body.len()..];
        let hit = body
            .split_once('=')
            .filter(|(k, _)| k.trim().eq_ignore_ascii_case(key.name()));
        match hit {
            Some((k, v)) if !found => {
                let comment = v.find('$').map_or("", |i| &v[i..]);
                out.push_str(&format!("{k}= {value:<15}\t {comment}"));
                out.push_str(end);
                found = true;
            }
            _ => out.push_str(line),
        }
    }
    if found {
        Ok(out)
    } else {
        Err(format!("{} is not in the file", key.name()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mu::bench::{self, measure, simulate_case, Sensors, WheelTrace};

    fn file() -> (String, Params<f64>) {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../host-tests/data/tyres/MagicFormula61_Parameters.tir"
        );
        let text = std::fs::read_to_string(path).unwrap();
        let p = crate::tyre::load(std::path::Path::new(path))
            .unwrap()
            .params;
        (text, p)
    }

    /// The bench's step steer on μ 1.0, four wheels (mounted left, right), noise seed 1.
    fn traces(p: &Params<f64>) -> Vec<WheelTrace> {
        let case = &bench::suite()[0];
        assert_eq!(
            (case.manoeuvre, case.road.as_str()),
            ("step-steer", "mu=1.0")
        );
        let log = simulate_case(p, case).unwrap();
        (0..4)
            .map(|w| measure(&log, w, &Sensors::default(), 1))
            .collect()
    }

    /// Each wheel's samples with the exact slips (κ of a slip sensor, as the calibration's
    /// tests have always taken them).
    fn samples(tr: &[WheelTrace]) -> Vec<Vec<Sample>> {
        tr.iter()
            .map(|t| (0..t.rows.len()).map(|i| t.sample(i, true)).collect())
            .collect()
    }

    fn wheels(samples: &[Vec<Sample>]) -> Vec<WheelLog<'_>> {
        samples
            .iter()
            .enumerate()
            .map(|(w, rows)| WheelLog {
                rows,
                mounted: gough::proto::Wheel::from_index(w).map(|x| x.side()),
            })
            .collect()
    }

    /// A file whose force shift is 2 mrad off is put right: PHY1's offset found within 3σ and
    /// 0.5 mrad of −0.002; QHZ1's (the trail's shift, which acts alike) the other way; on the
    /// simulated tyre's own file no offset beyond 3σ.
    #[test]
    fn a_shifted_file_is_put_right_on_a_known_surface() {
        let (_, p) = file();
        let tr = samples(&traces(&p));
        let ws = wheels(&tr);
        let mut wrong = p.clone();
        wrong.phy1 += 0.002;
        let n = Noise::default();
        let f = calibrate(&wrong, Key::PHY1, 1.0, &ws, &n, 0.005).unwrap();
        assert!(
            (f.delta + 0.002).abs() < (3.0 * f.sigma).max(0.0005) && f.sigma < 0.001,
            "{f:?}"
        );
        assert!(f.chi2 < f.chi2_file && f.batches >= 500, "{f:?}");
        let g = calibrate(&wrong, Key::QHZ1, 1.0, &ws, &n, 0.005).unwrap();
        assert!(g.delta > 0.0005 && g.delta < 0.003, "{g:?}");
        let h = calibrate(&p, Key::PHY1, 1.0, &ws, &n, 0.005).unwrap();
        assert!(h.delta.abs() < 3.0 * h.sigma, "{h:?}");
    }

    /// Too little near the limit, a range too narrow for the offset, a bad μ: errors that say so.
    #[test]
    fn what_cannot_be_calibrated_is_refused() {
        let (_, p) = file();
        let tr = samples(&traces(&p));
        let ws = wheels(&tr);
        let n = Noise::default();
        // On μ 1.0 data called μ 2.0, hardly a batch reaches utilisation 0.5.
        let e = calibrate(&p, Key::PHY1, 2.0, &ws, &n, 0.005).unwrap_err();
        assert!(e.contains("near the limit"), "{e}");
        let mut wrong = p.clone();
        wrong.phy1 += 0.004;
        let e = calibrate(&wrong, Key::PHY1, 1.0, &ws, &n, 0.002).unwrap_err();
        assert!(e.contains("edge"), "{e}");
        for mu in [0.0, f64::NAN, -1.0] {
            assert!(calibrate(&p, Key::PHY1, mu, &ws, &n, 0.005).is_err());
        }
        assert!(calibrate(&p, Key::PHY1, 1.0, &ws, &n, f64::INFINITY).is_err());
        for bad in [(0.0, 2.0), (0.01, -1.0), (f64::NAN, 2.0)] {
            let noise = Noise {
                f_rel: bad.0,
                mz: bad.1,
            };
            let e = calibrate(&p, Key::PHY1, 1.0, &ws, &noise, 0.005).unwrap_err();
            assert!(e.contains("noise"), "{e}");
        }
    }

    /// The value is replaced on its own line, the comment kept, and the file reads back with
    /// it and nothing else changed; a key the text lacks is an error.
    #[test]
    fn a_value_is_set_in_the_file_text() {
        let (text, p) = file();
        let out = set_in_tir(&text, Key::PHY1, -0.000811411).unwrap();
        let q = gough::tir::parse(&out).unwrap().params;
        let mut back = q.clone();
        assert_eq!(q.phy1, -0.000811411);
        back.phy1 = p.phy1;
        assert_eq!(back, p);
        assert!(out.contains("$Horizontal shift Shy at Fznom"));
        assert_eq!(out.lines().count(), text.lines().count());
        assert!(set_in_tir("[MODEL]\nFITTYP = 61\n", Key::PHY1, 0.0).is_err());
    }
}
