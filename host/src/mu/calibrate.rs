//! Calibration of the tyre on a log of a road whose μ is known (`gough mu calibrate`): the
//! online calibration of the friction estimator (`gough::mu::calibration`), run by the core's
//! own bank at each wheel of the log with the road held at the known μ
//! (`gough::mu::Bank::set_known_surface`). Nothing of the calibration is re-implemented here:
//! the same properties (peak trail, trail shape, trail shift SHt − SHy, Kxκ), the same Kalman
//! step with each batch's slips free, the same σ — only the road is no longer a nuisance, so
//! every excited batch the known road explains takes a step ([`config`]).
//!
//! The result is what `gough mu estimate --calibration-in` and the device's `SetCalibration`
//! take (a `gough-calibration-1` file, [`super::calfile`]), and a `.tir` file with the
//! calibration put into its coefficients ([`write_tir`]): λt (`LTR`) for the peak trail,
//! `QBZ1`–`QBZ3` for the trail's shape, `QHZ1` for the trail's shift, λKx (`LKX`) for Kxκ —
//! the coefficients by which `gough::mf::prepared::Adjust` applies it, so that the written file
//! evaluates as the calibrated tyre does.
use super::banks::Banks;
use super::estimator::{Estimator, Precision, Sample, Setup};
use crate::tyre::set_or_add_in_tir;
use gough::mf::{Key, Params, Side};
use gough::mu::calibration::{Exported, Property, PROPERTIES};
use gough::mu::Config;
use gough::proto::Wheel;

/// The bank's configuration for a calibration on a known road: the default estimator's,
/// with a step allowed on every batch (`cal_period` one batch: the device's budget rule, not
/// the calibration's) and no drift over the log (`cal_tau` 10⁹ s: one log is one tyre).
pub fn config() -> Config<f64> {
    let d = Config::<f64>::default();
    Config {
        cal_period: d.batch_us as f64 * 1e-6,
        cal_tau: 1e9,
        ..d
    }
}

/// One wheel's calibration on a known road.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WheelCalibration {
    /// The wheel.
    pub wheel: Wheel,
    /// Its calibration.
    pub cal: Exported,
    /// Its excited batches, and those the known road explained.
    pub excited: u32,
    pub explained: u32,
}

/// Least share of a wheel's excited batches the known road must explain (χ² ≤
/// `chi2_explain`, a tail noise reaches about once in 10⁵ batches) for its calibration to be
/// the tyre's: below it the log is not of that road (or the tyre is further from its file than
/// the calibration reaches), and what the explained batches — the lightest: any road explains
/// a force well below its limit — would calibrate is not the tyre. (On the right road every
/// test log here has 99.9–100 % explained, the tyre off its file in every property; 0.2 off,
/// 77–80 %.)
pub const EXPLAINED_MIN: f64 = 0.9;

/// Each wheel's calibration (in wheel order, the wheels of `log` only) after the log, rows
/// `(wheel, sample)` in time order, on a road of friction `mu` (on the file's scale, as the
/// estimator reports it); each wheel mounted as `mounted` says. An error for a μ outside the
/// estimator's surfaces, for a wheel of whose excited batches the road explains less than
/// [`EXPLAINED_MIN`], or when no wheel's batch was explained.
pub fn calibrate(
    p: &Params<f64>,
    mu: f64,
    log: &[(Wheel, Sample)],
    mounted: [Option<Side>; 4],
) -> Result<Vec<WheelCalibration>, String> {
    let setup = Setup {
        precision: Precision::F64,
        mounted,
        preview: None,
    };
    let mut banks = Banks::<f64>::with_config(p, &setup, config())?;
    banks.set_known_surface(Some(mu))?;
    for (w, s) in log {
        banks.update(*w, s);
    }
    let out: Vec<(Wheel, Exported)> = Wheel::ALL
        .iter()
        .filter(|w| log.iter().any(|(x, _)| x == *w))
        .filter_map(|w| banks.calibration(*w).map(|c| (*w, c)))
        .collect();
    let out: Vec<WheelCalibration> = out
        .into_iter()
        .map(|(wheel, cal)| {
            let (excited, explained) = banks.known_surface_batches(wheel);
            WheelCalibration {
                wheel,
                cal,
                excited,
                explained,
            }
        })
        .collect();
    for &WheelCalibration {
        wheel: w,
        excited,
        explained,
        ..
    } in &out
    {
        if excited > 0 && f64::from(explained) < EXPLAINED_MIN * f64::from(excited) {
            return Err(format!(
                "wheel {w:?}: a road of μ {mu} explains {explained} of its {excited} excited \
                 batches (χ² ≤ {}; at least {:.0} % needed): is μ the road's, on the file's \
                 scale?",
                config().chi2_explain,
                100.0 * EXPLAINED_MIN
            ));
        }
    }
    if out.iter().all(|c| c.cal.batches == 0) {
        return Err(format!(
            "no batch of the log is one a road of μ {mu} explains (excited, χ² ≤ {}): \
             is μ the road's, on the file's scale?",
            config().chi2_explain
        ));
    }
    Ok(out)
}

/// The wheels' calibrations as one tyre's: per property, the information each wheel's data
/// added to the prior (`prior`: the configuration's `cal_sigma`) summed, on the properties'
/// own scales (logarithms of the scales, the shift in rad); the covariances between
/// properties are not exported and not used. For a `.tir` that describes the tyre of all
/// those wheels (a car's front and rear tyres differ: calibrate a log of each).
pub fn combine(cals: &[Exported], prior: &[f64; PROPERTIES]) -> Exported {
    let mut out = Exported::default();
    for (k, p) in Property::ALL.iter().enumerate() {
        let s0 = prior[k];
        let (mut info, mut sum) = (1.0 / (s0 * s0), 0.0);
        for c in cals {
            let s = f64::from(c.sigma[k]).max(1e-12);
            let theta = theta_of(c)[k];
            // Each wheel's posterior carries the prior once; counted once in all.
            let i = (1.0 / (s * s) - 1.0 / (s0 * s0)).max(0.0);
            info += i;
            sum += theta / (s * s);
        }
        // The prior's mean is the file's (θ = 0), counted once: Σ θᵢ/σᵢ² is each wheel's
        // posterior mean times its precision, whose prior part is 0.
        let theta = sum / info;
        out.value[k] = (if p.is_scale() { theta.exp() } else { theta }) as f32;
        out.sigma[k] = (1.0 / info.sqrt()) as f32;
    }
    out.batches = cals.iter().fold(0u32, |a, c| a.saturating_add(c.batches));
    out
}

/// Tyre `p` with the calibration θ (`gough::mu::calibration::Calibration::theta`: ln of the
/// trail scale, ln of the trail-shape scale, the trail shift in rad, ln of the Kxκ scale) in
/// its coefficients: `LTR` × trail, `QBZ1`–`QBZ3` × trail shape, `QHZ1` + trail shift, `LKX` ×
/// Kxκ — the coefficients through which the estimator applies it
/// (`gough::mf::prepared::Adjust`).
pub fn apply(p: &Params<f64>, theta: &[f64; PROPERTIES]) -> Params<f64> {
    let [trail, shape, shift, kx] = *theta;
    let mut q = p.clone();
    q.ltr = p.ltr * trail.exp();
    q.qbz1 = p.qbz1 * shape.exp();
    q.qbz2 = p.qbz2 * shape.exp();
    q.qbz3 = p.qbz3 * shape.exp();
    q.qhz1 = p.qhz1 + shift;
    q.lkx = p.lkx * kx.exp();
    q
}

/// The θ of an exported calibration (logarithms of its scales, the shift as it is).
pub fn theta_of(c: &Exported) -> [f64; PROPERTIES] {
    let mut t = [0.0; PROPERTIES];
    for (k, p) in Property::ALL.iter().enumerate() {
        let v = f64::from(c.value[k]);
        t[k] = if p.is_scale() { v.ln() } else { v };
    }
    t
}

/// The `.tir` text `text` of tyre `p` with calibration `c` put into its coefficients: `LTR`
/// times the trail scale, `QBZ1`–`QBZ3` times the trail's shape scale, `QHZ1` plus the trail's
/// shift, `LKX` times the Kxκ scale. A coefficient the text lacks is added to its section
/// (`[SCALING_COEFFICIENTS]`, `[ALIGNING_COEFFICIENTS]`) unless its new value is the
/// reader's default for a missing key.
pub fn write_tir(text: &str, p: &Params<f64>, c: &Exported) -> Result<String, String> {
    let q = apply(p, &theta_of(c));
    let sets = [
        (Key::LTR, q.ltr),
        (Key::QBZ1, q.qbz1),
        (Key::QBZ2, q.qbz2),
        (Key::QBZ3, q.qbz3),
        (Key::QHZ1, q.qhz1),
        (Key::LKX, q.lkx),
    ];
    let mut out = text.to_string();
    for (key, value) in sets {
        out = set_or_add_in_tir(&out, key, value, "gough mu calibrate")?;
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The written file evaluates as the calibrated tyre does: `mf::eval` on it equals the
    /// file's load stage adjusted by the calibration (`Prepared::adjusted`, what the estimator
    /// evaluates) to 1e-9 relative, over loads, slips and camber; a file without LTR, LKX gets
    /// them in `[SCALING_COEFFICIENTS]`.
    #[test]
    fn the_written_file_is_the_calibrated_tyre() {
        use gough::math::Libm;
        use gough::mf::prepared::{Adjust, Prepared};
        use gough::mf::{Input, Options};
        let (text, p) = crate::tyre::bundled_text();
        let c = Exported {
            value: [1.07, 0.94, 0.0012, 0.91],
            sigma: [0.01; 4],
            batches: 1,
        };
        // Without the scaling factors the adjustment needs (a file may lack them: 1).
        let bare: String = text
            .lines()
            .filter(|l| {
                let k = l.split('=').next().unwrap_or("").trim();
                !(k.eq_ignore_ascii_case("LTR") || k.eq_ignore_ascii_case("LKX"))
            })
            .map(|l| format!("{l}\n"))
            .collect();
        for t in [text.as_str(), bare.as_str()] {
            let q = gough::tir::parse(&write_tir(t, &p, &c).unwrap())
                .unwrap()
                .params;
            let a = Adjust {
                trail: f64::from(c.value[0]),
                trail_shape: f64::from(c.value[1]),
                trail_shift: f64::from(c.value[2]),
                kx: f64::from(c.value[3]),
            };
            let opts = Options::default();
            for fz in [0.5, 1.0, 1.6].map(|x| x * p.fnomin) {
                for (kappa, alpha, gamma) in
                    [(0.0, 0.03, 0.0), (-0.04, 0.08, 0.02), (0.02, -0.01, -0.03)]
                {
                    let i = Input {
                        fz,
                        kappa,
                        alpha,
                        gamma,
                        vx: 20.0,
                        ..Input::default()
                    };
                    let got = gough::mf::eval::<f64, Libm>(&q, &i, &opts).unwrap();
                    let want = Prepared::new::<Libm>(&p, &(&i).into(), &opts)
                        .unwrap()
                        .adjusted(&a)
                        .eval::<Libm>(kappa, alpha)
                        .unwrap();
                    for (g, w) in [(got.fx, want.fx), (got.fy, want.fy), (got.mz, want.mz)] {
                        assert!((g - w).abs() <= 1e-9 * w.abs().max(1.0), "{g} against {w}");
                    }
                }
            }
        }
        // A file without the sections gets them (appended, each with its key).
        let bare = write_tir("[MODEL]\nFITTYP = 61\n", &p, &c).unwrap();
        assert!(bare.contains("[SCALING_COEFFICIENTS]\n"), "{bare}");
        assert!(bare.contains("\nLTR "), "{bare}");
    }

    /// Two wheels that each learnt as much as the prior knew: the combination knows three
    /// times the prior's information (the prior counted once), and its value is the two
    /// wheels' data without the prior's pull counted twice: 4/3 of their common θ.
    #[test]
    fn wheels_combine_by_information() {
        let prior = config().cal_sigma;
        let s = |k: usize| (prior[k] / 2f64.sqrt()) as f32;
        let a = Exported {
            value: [1.1, 1.0, 0.001, 0.9],
            sigma: [s(0), s(1), s(2), s(3)],
            batches: 3,
        };
        let b = Exported {
            value: [1.1, 1.0, 0.003, 0.9],
            ..a
        };
        let c = combine(&[a, b], &prior);
        assert_eq!(c.batches, 6);
        let th = |v: f64| (4.0 / 3.0 * v.ln()).exp();
        assert!((f64::from(c.value[0]) - th(1.1)).abs() < 1e-5, "{c:?}");
        assert!((f64::from(c.value[3]) - th(0.9)).abs() < 1e-5, "{c:?}");
        assert!(
            (f64::from(c.value[2]) - 4.0 / 3.0 * 0.002).abs() < 1e-6,
            "{c:?}"
        );
        for (k, p) in prior.iter().enumerate() {
            let want = p / 3f64.sqrt();
            assert!((f64::from(c.sigma[k]) - want).abs() < 1e-4 * want, "{c:?}");
        }
    }
}
