//! The tyre on the car relative to its file: the few properties by which a real tyre differs
//! from its `.tir` (temperature, wear, pressure, production spread), estimated online by each
//! wheel's estimator and shared by all its surface hypotheses (they are the tyre's, not the
//! road's).
//!
//! ## The properties ([`Property`])
//! What moves the friction estimate when it is off (docs/estimator.md, "A tyre that is not its
//! file"), as the Magic Formula's load stage takes it ([`crate::mf::prepared::Adjust`]):
//! - **trail**: ln of the peak-trail scale (Dt, λt) — the aligning torque's arm; 10 % off moves
//!   μ read at utilisation 0.5 by up to 0.5 on a dry road;
//! - **trail shape**: ln of the scale of Bt — how fast the trail collapses towards the limit;
//! - **trail shift**: SHt − SHy \[rad\] — the trail's registration against the force (an offset
//!   of the Fy shift PHY1 acts as the opposite offset of QHZ1: the slip angle is not measured);
//! - **kx**: ln of the longitudinal slip stiffness scale (Kxκ, λKx) — braking reads μ from Fx
//!   against the measured κ.
//!
//! Not among them, measured and left out: the cornering stiffness scale (λKy) — without the slip
//! angle it only rescales the α′ each hypothesis fits, so the forces and the torque do not tell
//! it; pressure acts through the four above (on the bundled MF 6.1 file ±15 % moves the trail by
//! ∓13 % and Kxκ by ∓16 %, μy by < 1 %).
//!
//! ## The estimate
//! A Kalman filter over θ with a random-walk drift (each property may move by its prior σ over
//! `cal_tau`), one step per batch the bank's gates let through ([`crate::mu::bank`]): the
//! batch's normalised residuals at the likeliest hypothesis, their slopes in θ, and in the
//! nuisances of that batch — its slips α′, κ′ (free) and its surface μ (the identification's σ,
//! or anything on the grid) — processed row by row over the state (θ, α′, κ′, μ); the nuisances
//! are dropped after the step. So only what the batch says of the tyre beyond its slips and
//! beyond the surface it may be on moves the calibration.
//!
//! Exported and imported ([`Calibration::export`], [`Calibration::import`]) as values and σ, so
//! that a device starts warm after power-up.

use crate::math::{Backend, Float};
use crate::mf::prepared::Adjust;

/// Number of calibrated properties.
pub const PROPERTIES: usize = 4;

/// A calibrated property (the index into [`Calibration::theta`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Property {
    /// ln of the peak-trail scale.
    Trail,
    /// ln of the scale of Bt.
    TrailShape,
    /// SHt − SHy \[rad\].
    TrailShift,
    /// ln of the longitudinal slip stiffness scale.
    Kx,
}

impl Property {
    /// All, in index order.
    pub const ALL: [Property; PROPERTIES] = [
        Property::Trail,
        Property::TrailShape,
        Property::TrailShift,
        Property::Kx,
    ];
    /// Name as in logs and files: `trail`, `trail_shape`, `trail_shift`, `kx`.
    pub const fn name(self) -> &'static str {
        match self {
            Property::Trail => "trail",
            Property::TrailShape => "trail_shape",
            Property::TrailShift => "trail_shift",
            Property::Kx => "kx",
        }
    }
    /// Whether the property is a scale (stored as its logarithm) rather than a shift.
    pub const fn is_scale(self) -> bool {
        !matches!(self, Property::TrailShift)
    }
}

/// The calibration: the properties' values θ (logarithms of scales, the shift in rad) and
/// their covariance.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Calibration<F> {
    /// Values, by [`Property`] index.
    pub theta: [F; PROPERTIES],
    /// Covariance of θ.
    pub cov: [[F; PROPERTIES]; PROPERTIES],
    /// Batches that moved it since it was made (saturating).
    pub batches: u32,
}

/// The surface the calibration's steps share ([`Calibration::step_joint`]): one road under the
/// batches, its μ, variance and covariance with θ, forgotten when the road may have changed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Surface<F> {
    /// μ \[-\].
    pub mu: F,
    /// Its variance.
    pub var: F,
    /// Its covariance with θ.
    pub cross: [F; PROPERTIES],
    /// Whether it holds anything (false: the next step starts it at the batch's surface).
    pub known: bool,
}

impl<F: Float> Surface<F> {
    /// Nothing known.
    pub fn unknown() -> Self {
        Surface {
            mu: F::ZERO,
            var: F::ZERO,
            cross: [F::ZERO; PROPERTIES],
            known: false,
        }
    }

    /// Starts at `mu` with variance `var`, uncorrelated with θ.
    pub fn start(&mut self, mu: F, var: F) {
        *self = Surface {
            mu,
            var,
            cross: [F::ZERO; PROPERTIES],
            known: true,
        };
    }
}

/// A calibration as it crosses a boundary (the protocol, the C API, files): values and σ, the
/// scales as factors (1 = the file), the shift in rad.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Exported {
    /// Trail scale, trail-shape scale, trail shift \[rad\], Kxκ scale.
    pub value: [f32; PROPERTIES],
    /// Their σ (of the scale's logarithm: a relative σ; of the shift in rad).
    pub sigma: [f32; PROPERTIES],
    /// Batches that moved it.
    pub batches: u32,
}

/// Why a calibration was refused on import.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum CalibrationError {
    /// A value or σ is not a finite number, a scale is not positive, or a σ is negative.
    NotFinite,
    /// A value lies beyond the bound the estimator keeps it in (`cal_bound` prior σ).
    OutOfBounds,
}

impl core::fmt::Display for CalibrationError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            CalibrationError::NotFinite => "a calibration value or σ is not a finite, valid number",
            CalibrationError::OutOfBounds => "a calibration value lies beyond its bound",
        })
    }
}

impl core::error::Error for CalibrationError {}

/// Nuisances of one calibration step: the batch's slips α′, κ′ and its surface μ.
pub const NUISANCES: usize = 3;
const STATE: usize = PROPERTIES + NUISANCES;

impl<F: Float> Calibration<F> {
    /// The file as it is, with prior σ `sigma` of each property.
    pub fn file(sigma: &[F; PROPERTIES]) -> Self {
        let mut cov = [[F::ZERO; PROPERTIES]; PROPERTIES];
        for (i, (row, s)) in cov.iter_mut().zip(sigma.iter()).enumerate() {
            if let Some(x) = row.get_mut(i) {
                *x = *s * *s;
            }
        }
        Calibration {
            theta: [F::ZERO; PROPERTIES],
            cov,
            batches: 0,
        }
    }

    /// The load stage's adjustment this calibration stands for.
    pub fn adjust<M: Backend<F>>(&self) -> Adjust<F> {
        let [trail, shape, shift, kx] = self.theta;
        Adjust {
            kx: M::exp(kx),
            trail: M::exp(trail),
            trail_shape: M::exp(shape),
            trail_shift: shift,
        }
    }

    /// σ of property `p`.
    pub fn sigma<M: Backend<F>>(&self, p: Property) -> F {
        let i = p as usize;
        M::sqrt(
            self.cov
                .get(i)
                .and_then(|r| r.get(i))
                .copied()
                .unwrap_or(F::ZERO)
                .max(F::ZERO),
        )
    }

    /// The drift over `dt` seconds: each variance grows by its prior's over `tau`, up to it.
    pub fn drift(&mut self, dt: F, tau: F, prior: &[F; PROPERTIES]) {
        let q = dt / tau.max(F::from_f64(1e-3));
        for (i, s) in prior.iter().enumerate() {
            if let Some(x) = self.cov.get_mut(i).and_then(|r| r.get_mut(i)) {
                *x = (*x + *s * *s * q).min(*s * *s);
            }
        }
    }

    /// One Kalman step on a batch: `r` its normalised residuals (measured − model)/σ at the
    /// linearisation point, `h_cal[i][j]` the slope of row i's model part (over its σ) in θj,
    /// `h_nuis[i][k]` in the nuisances (α′, κ′, μ) and `nuis_var` their prior variances. θ moves
    /// by what the batch says beyond the nuisances; each value is kept within `bound`·its prior
    /// σ. Rows whose slopes are all zero (not measured) are skipped. A step that is not finite
    /// is not taken.
    pub fn step(
        &mut self,
        r: &[F; 4],
        h_cal: &[[F; PROPERTIES]; 4],
        h_nuis: &[[F; NUISANCES]; 4],
        nuis_var: &[F; NUISANCES],
        prior: &[F; PROPERTIES],
        bound: F,
    ) {
        let [va, vk, vm] = *nuis_var;
        let mut s = Surface {
            mu: F::ZERO,
            var: vm,
            cross: [F::ZERO; PROPERTIES],
            known: true,
        };
        self.step_joint(r, h_cal, h_nuis, [va, vk], F::ZERO, &mut s, prior, bound);
    }

    /// [`Calibration::step`] with the surface a state of its own ([`Surface`]), kept from batch
    /// to batch with its cross-covariance with θ: the batch's slips are nuisances, dropped
    /// after the step, but the surface is one over the batches, so that batches at different
    /// operating points on one road tell the tyre and the road apart. `mu_lin` is the surface
    /// at which the residuals were linearised.
    #[allow(
        clippy::indexing_slicing,
        clippy::needless_range_loop,
        clippy::too_many_arguments
    )] // constant sizes: i, j < STATE (the arrays' own lengths)
    pub fn step_joint(
        &mut self,
        r: &[F; 4],
        h_cal: &[[F; PROPERTIES]; 4],
        h_nuis: &[[F; NUISANCES]; 4],
        slip_var: [F; 2],
        mu_lin: F,
        surface: &mut Surface<F>,
        prior: &[F; PROPERTIES],
        bound: F,
    ) {
        const M: usize = PROPERTIES + 2;
        let mut p = [[F::ZERO; STATE]; STATE];
        for i in 0..PROPERTIES {
            for j in 0..PROPERTIES {
                p[i][j] = self.cov[i][j];
            }
            p[i][M] = surface.cross[i];
            p[M][i] = surface.cross[i];
        }
        p[PROPERTIES][PROPERTIES] = slip_var[0];
        p[PROPERTIES + 1][PROPERTIES + 1] = slip_var[1];
        p[M][M] = surface.var;
        // The state's surface against the one the residuals were taken at.
        let off = surface.mu - mu_lin;
        let mut dx = [F::ZERO; STATE];
        for i in 0..4 {
            let mut h = [F::ZERO; STATE];
            h[..PROPERTIES].copy_from_slice(&h_cal[i]);
            h[PROPERTIES..].copy_from_slice(&h_nuis[i]);
            if h.iter().all(|x| *x == F::ZERO) {
                continue;
            }
            let mut ph = [F::ZERO; STATE];
            for a in 0..STATE {
                for b in 0..STATE {
                    ph[a] += p[a][b] * h[b];
                }
            }
            let mut s = F::ONE;
            let mut pred = h[M] * off;
            for a in 0..STATE {
                s += h[a] * ph[a];
                pred += h[a] * dx[a];
            }
            let inn = r[i] - pred;
            for a in 0..STATE {
                dx[a] += ph[a] * inn / s;
            }
            for a in 0..STATE {
                for b in 0..STATE {
                    p[a][b] -= ph[a] * ph[b] / s;
                }
            }
        }
        let finite = dx.iter().all(|x| x.is_finite())
            && p.iter().all(|row| row.iter().all(|x| x.is_finite()));
        if !finite {
            return;
        }
        for i in 0..PROPERTIES {
            let lim = bound * prior[i];
            self.theta[i] = (self.theta[i] + dx[i]).max(-lim).min(lim);
            for j in 0..PROPERTIES {
                self.cov[i][j] = p[i][j];
            }
            // Never below zero on the diagonal (rounding).
            self.cov[i][i] = self.cov[i][i].max(F::ZERO);
            surface.cross[i] = p[i][M];
        }
        surface.mu += dx[M];
        surface.var = p[M][M].max(F::ZERO);
        self.batches = self.batches.saturating_add(1);
    }

    /// Values and σ for a boundary ([`Exported`]).
    pub fn export<M: Backend<F>>(&self) -> Exported {
        let mut out = Exported {
            batches: self.batches,
            ..Exported::default()
        };
        for (k, p) in Property::ALL.iter().enumerate() {
            let t = self.theta.get(k).copied().unwrap_or(F::ZERO);
            let v = if p.is_scale() { M::exp(t) } else { t };
            if let (Some(o), Some(s)) = (out.value.get_mut(k), out.sigma.get_mut(k)) {
                *o = v.to_f64() as f32;
                *s = self.sigma::<M>(*p).to_f64() as f32;
            }
        }
        out
    }

    /// A calibration from values and σ ([`Exported`]), the covariance diagonal; refused when a
    /// number is not valid or a value lies beyond `bound`·its prior σ.
    pub fn import<M: Backend<F>>(
        e: &Exported,
        prior: &[F; PROPERTIES],
        bound: F,
    ) -> Result<Self, CalibrationError> {
        let mut c = Calibration::file(prior);
        c.batches = e.batches;
        for (k, p) in Property::ALL.iter().enumerate() {
            let (Some(v), Some(s), Some(pr)) = (e.value.get(k), e.sigma.get(k), prior.get(k))
            else {
                return Err(CalibrationError::NotFinite);
            };
            let (v, s) = (F::from_f64(f64::from(*v)), F::from_f64(f64::from(*s)));
            if !(v.is_finite() && s.is_finite() && s >= F::ZERO) || (p.is_scale() && v <= F::ZERO) {
                return Err(CalibrationError::NotFinite);
            }
            let t = if p.is_scale() { M::ln(v) } else { v };
            if t.abs() > bound * *pr {
                return Err(CalibrationError::OutOfBounds);
            }
            if let (Some(x), Some(row)) = (c.theta.get_mut(k), c.cov.get_mut(k)) {
                *x = t;
                if let Some(d) = row.get_mut(k) {
                    *d = s * s;
                }
            }
        }
        Ok(c)
    }
}

/// How far the surface μ moves per unit of each calibrated property where a batch is, the
/// slips left free: for each property's column of `h_cal` (the residuals' model part's slopes,
/// as [`Calibration::step`] takes them), the least-squares (α′, κ′, μ) over `h_nuis` that
/// stand in for it, and of those the μ. What an error of the calibration does to the surface
/// read at this operating point (a steady one cannot tell them apart). A column no row sees
/// (κ′ without κ) or two alike get a small ridge (the least-norm share); `None` when no row
/// sees any nuisance or a number is not finite.
#[allow(clippy::indexing_slicing, clippy::needless_range_loop)] // constant sizes: 3×3, 4×3, 4×4
pub(crate) fn mu_slopes<F: Float>(
    h_cal: &[[F; PROPERTIES]; 4],
    h_nuis: &[[F; NUISANCES]; 4],
) -> Option<[F; PROPERTIES]> {
    let mut a = [[F::ZERO; NUISANCES]; NUISANCES];
    for row in h_nuis.iter() {
        for r in 0..NUISANCES {
            for c in 0..NUISANCES {
                a[r][c] += row[r] * row[c];
            }
        }
    }
    // Scaled so that the largest diagonal entry is 1 (the determinants stay in range), and a
    // little ridge for the columns no row sees (κ′ without κ).
    let top = a[0][0].max(a[1][1]).max(a[2][2]);
    if top.partial_cmp(&F::ZERO) != Some(core::cmp::Ordering::Greater) || !top.is_finite() {
        return None;
    }
    let inv = F::ONE / top;
    for r in 0..NUISANCES {
        for c in 0..NUISANCES {
            a[r][c] *= inv;
        }
        a[r][r] = a[r][r] * F::from_f64(1.0 + 1e-9) + F::from_f64(1e-9);
    }
    let det3 = |m: &[[F; 3]; 3]| {
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    };
    let d = det3(&a);
    if d.abs().partial_cmp(&F::ZERO) != Some(core::cmp::Ordering::Greater) || !d.is_finite() {
        return None;
    }
    let mut out = [F::ZERO; PROPERTIES];
    for j in 0..PROPERTIES {
        // The nuisances' change that cancels the property's: −(HₙᵀHₙ)⁻¹Hₙᵀhⱼ; its μ by
        // Cramer's rule.
        let mut a2 = a;
        for r in 0..NUISANCES {
            let mut g = F::ZERO;
            for i in 0..4 {
                g -= h_nuis[i][r] * h_cal[i][j];
            }
            a2[r][2] = g * inv;
        }
        let x = det3(&a2) / d;
        if !x.is_finite() {
            return None;
        }
        out[j] = x;
    }
    Some(out)
}

impl<F: Float> Calibration<F> {
    /// The variance of μ that the calibration's covariance leaves at an operating point whose
    /// μ moves by `slopes` per unit of each property ([`mu_slopes`]): sᵀ·P·s.
    #[allow(clippy::indexing_slicing)] // constant sizes
    pub(crate) fn mu_var(&self, slopes: &[F; PROPERTIES]) -> F {
        let mut v = F::ZERO;
        for i in 0..PROPERTIES {
            for j in 0..PROPERTIES {
                v += slopes[i] * self.cov[i][j] * slopes[j];
            }
        }
        v.max(F::ZERO)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Libm;

    const PRIOR: [f64; PROPERTIES] = [0.1, 0.1, 0.002, 0.1];

    #[test]
    fn a_step_moves_theta_towards_what_explains_the_residual_and_shrinks_its_variance() {
        let mut c = Calibration::<f64>::file(&PRIOR);
        // One row whose model part grows with the trail: the data say +5 % (r = 5 at a slope
        // of 100 per unit ln-scale), the nuisances do not touch that row.
        let mut h = [[0.0; PROPERTIES]; 4];
        h[2][0] = 100.0;
        let r = [0.0, 0.0, 5.0, 0.0];
        let hn = [[0.0; NUISANCES]; 4];
        c.step(&r, &h, &hn, &[1.0; NUISANCES], &PRIOR, 4.0);
        assert!((c.theta[0] - 0.05).abs() < 1e-3, "{:?}", c.theta);
        assert!(c.sigma::<Libm>(Property::Trail) < 0.011);
        assert_eq!(c.theta[1], 0.0);
        assert_eq!(c.batches, 1);
    }

    #[test]
    fn a_nuisance_that_explains_the_row_as_well_takes_it() {
        // The same row, but a free nuisance (the surface) moves it alike: nothing is left for θ.
        let mut c = Calibration::<f64>::file(&PRIOR);
        let mut h = [[0.0; PROPERTIES]; 4];
        h[2][0] = 100.0;
        let mut hn = [[0.0; NUISANCES]; 4];
        hn[2][2] = 100.0;
        c.step(
            &[0.0, 0.0, 5.0, 0.0],
            &h,
            &hn,
            &[1e6, 1e6, 1e6],
            &PRIOR,
            4.0,
        );
        assert!(c.theta[0].abs() < 1e-4, "{:?}", c.theta);
        assert!(c.sigma::<Libm>(Property::Trail) > 0.099);
    }

    #[test]
    fn drift_grows_the_variance_up_to_the_prior_and_export_import_round_trips() {
        let mut c = Calibration::<f64>::file(&PRIOR);
        c.cov[0][0] = 1e-6;
        c.theta = [0.05, -0.02, 0.001, 0.03];
        c.drift(60.0, 120.0, &PRIOR);
        assert!((c.cov[0][0] - (1e-6 + 0.005)).abs() < 1e-12);
        c.drift(1e6, 120.0, &PRIOR);
        assert!((c.cov[0][0] - 0.01).abs() < 1e-15);
        let e = c.export::<Libm>();
        assert!((e.value[0] - 0.05f64.exp() as f32).abs() < 1e-6);
        assert!((e.value[2] - 0.001).abs() < 1e-9);
        let d = Calibration::<f64>::import::<Libm>(&e, &PRIOR, 4.0).unwrap();
        for k in 0..PROPERTIES {
            assert!((d.theta[k] - c.theta[k]).abs() < 1e-6);
            assert!((d.cov[k][k].sqrt() - c.cov[k][k].sqrt()).abs() < 1e-6);
        }
    }

    #[test]
    fn import_refuses_what_is_not_a_calibration() {
        let ok = Calibration::<f32>::file(&[0.1, 0.1, 0.002, 0.1]).export::<Libm>();
        let prior = [0.1f32, 0.1, 0.002, 0.1];
        for bad in [
            Exported {
                value: [f32::NAN, 1.0, 0.0, 1.0],
                ..ok
            },
            Exported {
                value: [0.0, 1.0, 0.0, 1.0],
                ..ok
            },
            Exported {
                value: [1.0, 1.0, 0.0, -1.0],
                ..ok
            },
            Exported {
                sigma: [0.1, -0.1, 0.0, 0.1],
                ..ok
            },
            Exported {
                sigma: [f32::INFINITY, 0.1, 0.0, 0.1],
                ..ok
            },
        ] {
            assert_eq!(
                Calibration::<f32>::import::<Libm>(&bad, &prior, 4.0),
                Err(CalibrationError::NotFinite)
            );
        }
        let far = Exported {
            value: [2.0, 1.0, 0.0, 1.0],
            ..ok
        };
        assert_eq!(
            Calibration::<f32>::import::<Libm>(&far, &prior, 4.0),
            Err(CalibrationError::OutOfBounds)
        );
        assert!(Calibration::<f32>::import::<Libm>(&ok, &prior, 4.0).is_ok());
    }

    #[test]
    fn a_step_on_non_finite_numbers_changes_nothing() {
        let mut c = Calibration::<f64>::file(&PRIOR);
        let before = c;
        let mut h = [[0.0; PROPERTIES]; 4];
        h[1][0] = f64::NAN;
        c.step(
            &[0.0, 1.0, 0.0, 0.0],
            &h,
            &[[0.0; NUISANCES]; 4],
            &[1.0; NUISANCES],
            &PRIOR,
            4.0,
        );
        assert_eq!(c, before);
    }

    #[test]
    fn mu_slopes_read_what_the_surface_stands_in_for() {
        // Four rows, three nuisances (α′, κ′, μ) of unequal scales, all seen.
        let hn = [
            [120.0, 3.0, 900.0],
            [-40.0, 800.0, 150.0],
            [7.0, -2.0, 60.0],
            [30.0, 5.0, -45.0],
        ];
        let mut h = [[0.0f64; PROPERTIES]; 4];
        for i in 0..4 {
            h[i][0] = 2.0 * hn[i][2]; // the trail moves the rows as +2 of μ does
            h[i][1] = hn[i][0]; // the shape as α′ does: the surface does not move
            h[i][2] = 0.5 * hn[i][2] - 3.0 * hn[i][1];
        }
        h[0][3] = 1.0; // and one the nuisances explain only in part
        let s = mu_slopes(&h, &hn).unwrap();
        assert!((s[0] + 2.0).abs() < 1e-6, "{s:?}");
        assert!(s[1].abs() < 1e-6, "{s:?}");
        assert!((s[2] + 0.5).abs() < 1e-6, "{s:?}");
        assert!(s[3].is_finite());
        // μ's variance from a diagonal covariance: Σ sₖ² σₖ².
        let c = Calibration::<f64>::file(&PRIOR);
        let v = c.mu_var(&s);
        let want: f64 = (0..PROPERTIES)
            .map(|k| s[k] * s[k] * PRIOR[k] * PRIOR[k])
            .sum();
        assert!((v - want).abs() < 1e-9 * want.max(1e-12), "{v} {want}");
        // A calibration known exactly leaves μ nothing.
        let exact = Calibration::<f64>::file(&[0.0; PROPERTIES]);
        assert_eq!(exact.mu_var(&s), 0.0);
    }

    #[test]
    fn mu_slopes_refuse_rows_that_do_not_determine_the_surface() {
        let h = [[1.0; PROPERTIES]; 4];
        assert_eq!(mu_slopes::<f64>(&h, &[[0.0; NUISANCES]; 4]), None);
        let mut nan = [[1.0, 2.0, 3.0]; 4];
        nan[1][2] = f64::NAN;
        assert_eq!(mu_slopes::<f64>(&h, &nan), None);
        // μ's column a copy of α′'s: the ridge shares the row between them, finite, and the
        // likelihood (flat along that line) does not identify the surface there anyway.
        let dup = [
            [1.0, 0.0, 1.0],
            [2.0, 1.0, 2.0],
            [3.0, 0.0, 3.0],
            [4.0, 1.0, 4.0],
        ];
        let s = mu_slopes::<f64>(&h, &dup).unwrap();
        assert!(s.iter().all(|x| x.is_finite() && x.abs() < 1.0), "{s:?}");
    }

    #[test]
    fn one_road_over_two_operating_points_tells_the_tyre_from_the_road() {
        // Two batches whose row sees θ₀ and the road: alike at the first operating point,
        // opposite at the second. Truth: θ₀ = 0.05, the road 0.02 above the cell's.
        let mut h = [[0.0; PROPERTIES]; 4];
        h[0][0] = 100.0;
        let hn = |sign: f64| {
            let mut x = [[0.0; NUISANCES]; 4];
            x[0][2] = 100.0 * sign;
            x
        };
        let r = |sign: f64| [100.0 * (0.05 + sign * 0.02), 0.0, 0.0, 0.0];
        // Each batch's road its own nuisance: neither batch alone tells θ₀.
        let mut apart = Calibration::<f64>::file(&PRIOR);
        for sign in [1.0, -1.0] {
            apart.step(&r(sign), &h, &hn(sign), &[1.0, 1.0, 1.0], &PRIOR, 4.0);
        }
        assert!(apart.theta[0].abs() < 0.005, "{:?}", apart.theta);
        assert!(apart.sigma::<Libm>(Property::Trail) > 0.09);
        // One road under both: θ₀ and the road are read.
        let mut joint = Calibration::<f64>::file(&PRIOR);
        let mut road = Surface::unknown();
        road.start(0.5, 1.0);
        for sign in [1.0, -1.0] {
            joint.step_joint(
                &r(sign),
                &h,
                &hn(sign),
                [1.0, 1.0],
                0.5,
                &mut road,
                &PRIOR,
                4.0,
            );
        }
        assert!((joint.theta[0] - 0.05).abs() < 0.002, "{:?}", joint.theta);
        assert!((road.mu - 0.52).abs() < 0.002, "{road:?}");
        assert!(joint.sigma::<Libm>(Property::Trail) < 0.02);
        assert_eq!(joint.batches, 2);
    }
}
