//! The brush tyre model of the paper ("Simple steady-state slip considerations", Figs. 2–5):
//! physical Gough curves when no `.tir` file is at hand.
//!
//! Elastic bristles on a rigid carcass, isotropic stiffness, Coulomb friction μ, a symmetric
//! parabolic pressure distribution over a contact length 2a. For pure side slip, with
//! θ = Cα/(3·μ·Fz) and ψ = θ·|tan α| (Pacejka 2006, §3.2.2, eqs. 3.43–3.45):
//!
//! ```text
//! |Fy| = μ·Fz·(3ψ − 3ψ² + ψ³),   |Mz| = μ·Fz·a·ψ·(1 − ψ)³     for ψ < 1 (adhesion left)
//! |Fy| = μ·Fz,                   Mz = 0                       for ψ ≥ 1 (full sliding)
//! ```
//!
//! so the pneumatic trail t = |Mz/Fy| starts at a/3 and collapses to 0 as the force saturates —
//! "the pneumatic trail decreases with increasing side slip" (Fig. 4) — and the curves for
//! different μ are the same curve scaled radially by μ: the Gough plot's spread with friction.
//! Signs are ISO-W: α > 0 gives Fy < 0 and Mz > 0.
//!
//! Load dependence: a = a0·√(Fz/Fz0) (Hertz-like contact length), Cα = 2·cp·a² ∝ Fz, so
//! Cα(Fz) = Cα0·Fz/Fz0 with Cα0 the cornering stiffness at Fz0.
//!
//! Leaves out: carcass compliance, anisotropic stiffness, load-dependent friction, camber and
//! turn slip — the reasons the paper turns to the Magic Formula.

use gough::math::{Backend, Float};

/// A brush tyre. SI units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Brush<F> {
    /// Cornering stiffness Cα0 at the reference load \[N/rad\] (> 0).
    pub c_alpha0: F,
    /// Half contact length a0 at the reference load \[m\] (> 0).
    pub a0: F,
    /// Reference load Fz0 \[N\] (> 0).
    pub fz0: F,
    /// Friction coefficient μ of the surface the curves describe \[-\] (> 0).
    pub mu: F,
}

impl<F: Float> Brush<F> {
    /// (Fy, Mz) \[N, N·m\] at slip angle `alpha` \[rad\] and load `fz` \[N\]; zero for Fz ≤ 0 or
    /// non-positive parameters.
    pub fn fy_mz<M: Backend<F>>(&self, alpha: F, fz: F) -> (F, F) {
        if fz <= F::ZERO || self.fz0 <= F::ZERO || self.mu <= F::ZERO || self.c_alpha0 <= F::ZERO {
            return (F::ZERO, F::ZERO);
        }
        let a = self.a0 * M::sqrt(fz / self.fz0);
        let c_alpha = self.c_alpha0 * fz / self.fz0;
        let theta = c_alpha / (F::from_f64(3.0) * self.mu * fz);
        let psi = theta * M::tan(alpha).abs();
        let sgn = alpha.sign();
        let mufz = self.mu * fz;
        if psi >= F::ONE {
            return (-sgn * mufz, F::ZERO);
        }
        let three = F::from_f64(3.0);
        let fy = mufz * (three * psi - three * psi * psi + psi * psi * psi);
        let one_m = F::ONE - psi;
        let mz = mufz * a * psi * one_m * one_m * one_m;
        (-sgn * fy, sgn * mz)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use gough::math::Libm;

    const B: Brush<f64> = Brush {
        c_alpha0: 80_000.0,
        a0: 0.08,
        fz0: 4000.0,
        mu: 1.0,
    };

    #[test]
    fn small_slip_stiffness_and_trail_a_over_3() {
        let (fy, mz) = B.fy_mz::<Libm>(1e-7, 4000.0);
        assert!((fy / 1e-7 + 80_000.0).abs() < 0.1, "Cα: {}", fy / 1e-7);
        assert!((mz / -fy - 0.08 / 3.0).abs() < 1e-6, "t = a/3");
    }

    #[test]
    fn saturates_at_mu_fz_with_zero_torque_and_odd() {
        for a in [0.2, 0.5, 1.0] {
            let (fy, mz) = B.fy_mz::<Libm>(a, 4000.0);
            assert_eq!((fy, mz), (-4000.0, 0.0));
            let (fyn, mzn) = B.fy_mz::<Libm>(-a, 4000.0);
            assert_eq!((fyn, mzn), (4000.0, -0.0));
        }
        assert_eq!(B.fy_mz::<Libm>(0.1, 0.0), (0.0, 0.0));
    }

    /// The paper: "for larger value of the friction coefficient the curves tend to spread in
    /// radial direction": (Fy, Mz)(α; μ) = μ·(Fy, Mz)(α/μ'; 1) with tan scaling, exactly.
    #[test]
    fn gough_curves_scale_radially_with_mu() {
        let lo = Brush { mu: 0.3, ..B };
        for ta in [0.01f64, 0.03, 0.05, 0.08] {
            let (fy, mz) = lo.fy_mz::<Libm>(ta.atan(), 4000.0);
            let (fy1, mz1) = B.fy_mz::<Libm>((ta / 0.3).atan(), 4000.0);
            assert!((fy - 0.3 * fy1).abs() < 1e-9 && (mz - 0.3 * mz1).abs() < 1e-9);
        }
    }

    #[test]
    fn trail_decreases_monotonically() {
        let mut last = f64::INFINITY;
        for i in 1..100 {
            let (fy, mz) = B.fy_mz::<Libm>(i as f64 * 0.0015, 4000.0);
            let t = mz / -fy;
            assert!(t < last);
            last = t;
        }
    }
}
