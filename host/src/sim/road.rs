//! The road: friction by position (μ-split, steps, patches) and an optional uneven profile.
//!
//! ## Friction
//! μ is the tyre–road peak friction on the scale of the tyre file's own test surface
//! (`docs/architecture.md`): a road of friction μ scales the Magic Formula by
//! λμx = λμy = μ / μy0, μy0 the file's μy at Fz = FNOMIN, γ = 0, nominal pressure. This module
//! only says which μ lies under a contact point; [`super::vehicle`] applies the scaling.
//!
//! μ at a world position (X, Y) is decided in this order, the later winning:
//! 1. the base: `mu=M` everywhere, or `split=L/R` (M = L where Y ≥ 0, the left of the start
//!    line, R where Y < 0); without either, the file's own surface (λμ = 1, μ = μy0);
//! 2. `step=M0@X0,M1@X1,...`: from X ≥ Xk on, μ = Mk (before X0 the base holds);
//! 3. `patch=M@A..B[:left|:right]`: μ = M for A ≤ X < B (on one side of Y = 0 only, if given);
//!    patches later in the spec win over earlier ones.
//!
//! ## Unevenness (vertical load fluctuation)
//! A road height z_r(X) under each track (left and right wheels), fed to a quarter-car at each
//! wheel in [`super::vehicle`] (the unsprung mass on the tyre's vertical stiffness, body held
//! still). Two profiles, which add:
//! - `uneven=AMP@WAVELENGTH`: z_r = AMP·sin(2π·X/WAVELENGTH), the same under both tracks
//!   (a heave/pitch excitation; paper Figs. 13–14 use a sinusoidal load);
//! - `rough=RMS@SEED`: a seeded random profile, a sum of [`ROUGH_WAVES`] sines between
//!   wavelengths 0.5 m and 30 m with amplitudes for a displacement PSD ∝ n⁻² (ISO 8608 shape,
//!   n the spatial frequency), random phases per track, scaled to the given RMS height.
//!
//! ## Spec grammar
//! ```text
//! SPEC  := TERM ('+' TERM)*
//! TERM  := 'mu=' M | 'split=' M '/' M | 'step=' M '@' X (',' M '@' X)*
//!        | 'patch=' M '@' X '..' X [':left' | ':right']
//!        | 'uneven=' AMP '@' WAVELENGTH | 'rough=' RMS '@' SEED
//! ```
//! M in (0, 2], X in metres along the world X axis (the start heading), AMP and RMS in metres
//! (≤ 0.2), WAVELENGTH > 0 in metres, SEED an unsigned integer. Examples: `mu=0.3`,
//! `split=0.9/0.2`, `step=0.9@0,0.5@40,0.1@80`, `mu=0.9+patch=0.2@30..45:right`,
//! `mu=0.8+uneven=0.01@2`.
//!
//! ## What it leaves out
//! Friction varying with Y except across the split line; banking, grade; the road's own
//! compliance; a different profile under each wheel of the same track (the rear wheels run over
//! what the front wheels ran over, delayed by the wheelbase, as on a real road).

use std::f64::consts::PI;

/// Number of sine components of the `rough` profile.
pub const ROUGH_WAVES: usize = 32;

/// A friction patch: μ over `x0 ≤ X < x1`, on one side or both.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Patch {
    /// Friction μ \[-\].
    pub mu: f64,
    /// Start X \[m\].
    pub x0: f64,
    /// End X \[m\] (exclusive), > `x0`.
    pub x1: f64,
    /// `Some(true)`: left of Y = 0 only; `Some(false)`: right only; `None`: both.
    pub left: Option<bool>,
}

/// One sine of a road profile: height a·sin(k·X + phase).
#[derive(Debug, Clone, Copy, PartialEq)]
struct Wave {
    a: f64,
    k: f64,
    phase: [f64; 2],
}

/// The road: friction map and height profile. Build with [`Road::parse`] or the fields.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Road {
    /// Base friction; `None`: the tyre file's own surface (μ = μy0).
    pub mu: Option<f64>,
    /// μ-split base (left of Y = 0, right of Y = 0); overrides `mu`.
    pub split: Option<(f64, f64)>,
    /// Steps (μ, from X) in increasing X.
    pub steps: Vec<(f64, f64)>,
    /// Patches, the later winning.
    pub patches: Vec<Patch>,
    /// Sinusoidal unevenness (amplitude \[m\], wavelength \[m\]).
    pub uneven: Option<(f64, f64)>,
    /// Random unevenness (RMS height \[m\], seed).
    pub rough: Option<(f64, u64)>,
    waves: Vec<Wave>,
}

/// Road height under one wheel: z_r \[m\] and its slope dz_r/dX \[-\].
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Height {
    /// Height z_r \[m\], up.
    pub z: f64,
    /// Slope dz_r/dX \[-\].
    pub slope: f64,
}

fn num(term: &str, s: &str, what: &str) -> Result<f64, String> {
    let v: f64 = s
        .trim()
        .parse()
        .map_err(|_| format!("road term '{term}': {what} '{s}' is not a number"))?;
    if !v.is_finite() {
        return Err(format!("road term '{term}': {what} '{s}' is not finite"));
    }
    Ok(v)
}

fn mu_of(term: &str, s: &str) -> Result<f64, String> {
    let m = num(term, s, "friction")?;
    if !(m > 0.0 && m <= 2.0) {
        return Err(format!("road term '{term}': friction {m} outside (0, 2]"));
    }
    Ok(m)
}

fn split2<'a>(term: &str, s: &'a str, sep: &str, what: &str) -> Result<(&'a str, &'a str), String> {
    s.split_once(sep)
        .ok_or_else(|| format!("road term '{term}': expected {what}"))
}

impl Road {
    /// A uniform road of friction `mu`.
    pub fn uniform(mu: f64) -> Road {
        Road {
            mu: Some(mu),
            ..Road::default()
        }
    }

    /// Parses a road spec (grammar in the module doc). Errors are one line naming the term.
    pub fn parse(spec: &str) -> Result<Road, String> {
        let mut r = Road::default();
        if spec.trim().is_empty() {
            return Err("road spec is empty".into());
        }
        for term in spec.split('+') {
            let term = term.trim();
            let (key, val) = term
                .split_once('=')
                .ok_or_else(|| format!("road term '{term}': expected KEY=VALUE"))?;
            match key.trim() {
                "mu" => {
                    if r.mu.is_some() || r.split.is_some() {
                        return Err(format!(
                            "road term '{term}': a base friction is already given"
                        ));
                    }
                    r.mu = Some(mu_of(term, val)?);
                }
                "split" => {
                    if r.mu.is_some() || r.split.is_some() {
                        return Err(format!(
                            "road term '{term}': a base friction is already given"
                        ));
                    }
                    let (l, rt) = split2(term, val, "/", "LEFT/RIGHT")?;
                    r.split = Some((mu_of(term, l)?, mu_of(term, rt)?));
                }
                "step" => {
                    if !r.steps.is_empty() {
                        return Err(format!("road term '{term}': steps are already given"));
                    }
                    for part in val.split(',') {
                        let (m, x) = split2(term, part, "@", "MU@X")?;
                        let (m, x) = (mu_of(term, m)?, num(term, x, "position")?);
                        if let Some(&(_, last)) = r.steps.last() {
                            if x <= last {
                                return Err(format!(
                                    "road term '{term}': step positions must increase"
                                ));
                            }
                        }
                        r.steps.push((m, x));
                    }
                }
                "patch" => {
                    let (body, side) = match val.split_once(':') {
                        Some((b, "left")) => (b, Some(true)),
                        Some((b, "right")) => (b, Some(false)),
                        Some((_, s)) => {
                            return Err(format!(
                                "road term '{term}': side '{s}' is not 'left' or 'right'"
                            ))
                        }
                        None => (val, None),
                    };
                    let (m, range) = split2(term, body, "@", "MU@A..B")?;
                    let (a, b) = split2(term, range, "..", "MU@A..B")?;
                    let (a, b) = (num(term, a, "start")?, num(term, b, "end")?);
                    if b <= a {
                        return Err(format!(
                            "road term '{term}': patch end must exceed its start"
                        ));
                    }
                    r.patches.push(Patch {
                        mu: mu_of(term, m)?,
                        x0: a,
                        x1: b,
                        left: side,
                    });
                }
                "uneven" => {
                    if r.uneven.is_some() {
                        return Err(format!("road term '{term}': unevenness is already given"));
                    }
                    let (a, w) = split2(term, val, "@", "AMP@WAVELENGTH")?;
                    let (a, w) = (num(term, a, "amplitude")?, num(term, w, "wavelength")?);
                    if !(0.0..=0.2).contains(&a) || w <= 0.0 {
                        return Err(format!(
                            "road term '{term}': need 0 ≤ AMP ≤ 0.2 m and WAVELENGTH > 0"
                        ));
                    }
                    r.uneven = Some((a, w));
                }
                "rough" => {
                    if r.rough.is_some() {
                        return Err(format!("road term '{term}': roughness is already given"));
                    }
                    let (a, s) = split2(term, val, "@", "RMS@SEED")?;
                    let a = num(term, a, "RMS")?;
                    let s: u64 = s.trim().parse().map_err(|_| {
                        format!("road term '{term}': seed '{s}' is not an unsigned integer")
                    })?;
                    if !(0.0..=0.2).contains(&a) {
                        return Err(format!("road term '{term}': need 0 ≤ RMS ≤ 0.2 m"));
                    }
                    r = r.with_rough(a, s);
                }
                k => {
                    return Err(format!(
                    "road term '{term}': unknown key '{k}' (mu, split, step, patch, uneven, rough)"
                ))
                }
            }
        }
        Ok(r)
    }

    /// Sets the random profile (RMS height \[m\], seed) and draws its phases.
    pub fn with_rough(mut self, rms: f64, seed: u64) -> Road {
        self.rough = Some((rms, seed));
        let mut rng = crate::rng::Rng::new(seed);
        let (n_lo, n_hi): (f64, f64) = (1.0 / 30.0, 1.0 / 0.5); // spatial frequency n [cycles/m]
        let ratio = (n_hi / n_lo).powf(1.0 / (ROUGH_WAVES - 1) as f64);
        let mut waves = Vec::with_capacity(ROUGH_WAVES);
        let mut power = 0.0f64;
        for i in 0..ROUGH_WAVES {
            let n = n_lo * ratio.powi(i as i32);
            // PSD Gd(n) ∝ n⁻², band Δn ∝ n (log spacing): amplitude² ∝ Gd·Δn ∝ 1/n.
            let a = (1.0 / n).sqrt();
            power += a * a / 2.0;
            let mut ph = [0.0; 2];
            for p in &mut ph {
                *p = 2.0 * PI * rng.uniform();
            }
            waves.push(Wave {
                a,
                k: 2.0 * PI * n,
                phase: ph,
            });
        }
        let scale = rms / power.sqrt();
        for w in &mut waves {
            w.a *= scale;
        }
        self.waves = waves;
        self
    }

    /// Is the road flat (no unevenness)?
    pub fn is_flat(&self) -> bool {
        self.uneven.is_none_or(|(a, _)| a == 0.0) && self.rough.is_none_or(|(a, _)| a == 0.0)
    }

    /// Friction μ at world position (X, Y) \[m\]; `mu_file` is the tyre file's μy0 (the base
    /// when the spec gives none).
    pub fn mu(&self, x: f64, y: f64, mu_file: f64) -> f64 {
        let left = y >= 0.0;
        let mut m = match (self.split, self.mu) {
            (Some((l, r)), _) => {
                if left {
                    l
                } else {
                    r
                }
            }
            (None, Some(m)) => m,
            (None, None) => mu_file,
        };
        for &(sm, sx) in &self.steps {
            if x >= sx {
                m = sm;
            }
        }
        for p in &self.patches {
            if x >= p.x0 && x < p.x1 && p.left.is_none_or(|l| l == left) {
                m = p.mu;
            }
        }
        m
    }

    /// Road height and slope at X under the left (`left = true`) or right track.
    pub fn height(&self, x: f64, left: bool) -> Height {
        let mut h = Height::default();
        if let Some((a, w)) = self.uneven {
            let k = 2.0 * PI / w;
            h.z += a * (k * x).sin();
            h.slope += a * k * (k * x).cos();
        }
        let track = usize::from(!left);
        for w in &self.waves {
            let arg = w.k * x + w.phase[track];
            h.z += w.a * arg.sin();
            h.slope += w.a * w.k * arg.cos();
        }
        h
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn friction_map_order() {
        let r = Road::parse("split=0.9/0.2+step=0.5@50+patch=0.1@60..70:left").unwrap();
        assert_eq!(r.mu(0.0, 1.0, 1.0), 0.9);
        assert_eq!(r.mu(0.0, -1.0, 1.0), 0.2);
        assert_eq!(r.mu(55.0, -1.0, 1.0), 0.5);
        assert_eq!(r.mu(65.0, 1.0, 1.0), 0.1);
        assert_eq!(r.mu(65.0, -1.0, 1.0), 0.5);
        assert_eq!(Road::default().mu(3.0, 0.0, 1.07), 1.07);
    }

    #[test]
    fn rough_profile_has_the_rms() {
        let r = Road::parse("rough=0.01@7").unwrap();
        let n = 50_000;
        let (mut s2, mut s2r) = (0.0, 0.0);
        for i in 0..n {
            let x = i as f64 * 0.04;
            s2 += r.height(x, true).z.powi(2);
            s2r += r.height(x, false).z.powi(2);
        }
        let (rms, rms_r) = ((s2 / n as f64).sqrt(), (s2r / n as f64).sqrt());
        assert!((rms - 0.01).abs() < 1.5e-3, "{rms}");
        assert!((rms_r - 0.01).abs() < 1.5e-3, "{rms_r}");
        assert_ne!(r.height(3.0, true).z, r.height(3.0, false).z);
        // Slope is the derivative of the height.
        let (x, e) = (12.3, 1e-6);
        let d = (r.height(x + e, true).z - r.height(x - e, true).z) / (2.0 * e);
        assert!((d - r.height(x, true).slope).abs() < 1e-6);
    }
}
