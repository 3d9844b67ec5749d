//! The staged Magic Formula: a load stage built once per (Fz, γ, p, Vx, scalings), a friction
//! stage per road-friction scaling λμ, and a slip stage evaluated at any (κ, α) — with the
//! derivatives of Fx, Fy, Mz in κ, α and λμ from forward-mode dual numbers over the same code.
//!
//! [`crate::mf::eval`] is these three stages in a row, so the stages compute exactly what it
//! computes: every formula is written once (in the crate's `mf::pure`, `mf::combined` and
//! `mf::limits`), split by what it depends on:
//!
//! | stage | depends on | computes (paper / MF 5.2–6.1 equation numbers) |
//! |---|---|---|
//! | load ([`Prepared::new`]) | Fz, γ, p, Vx, φt, the λ's but λμ | conditioning of Fz, γ, p, Vx (4.E1)–(4.E2b), (4.E4); Kxκ (28), (4.E15); Kyα (39), (4.E25) and Kyα' (4.E39); Kyγ0 (4.E30); Cx, Cy, Ct; SHx (30); SHt (54); Dt (52), (A60); the polynomial parts of Ex, Ey, Et (27), (38), (53); the combined-slip weights' Cxα, Exα, SHxα, Cyκ, Eyκ, SHyκ and the load parts of Bxα, Byκ, DVyκ (4.E54)–(4.E67); the arm s's coefficients (73) |
//! | friction ([`Prepared::with_mu`]) | λμx*, λμy* (4.E7), (4.E8) | μx, μy (26), (37); Dx, Dy (25), (36); Bx, By (29), (40); SVx, SVy, SHy (31), (41), (42), (4.E27)–(4.E29); Bt (50); Br (55); SHf (48); Dr but its cos α* (56), (4.E47) — arithmetic only |
//! | slip ([`Prepared::eval`]) | κ, α | conditioning of κ, α (limits, low speed, α*, cos α*, cos α') (4.E3), (4.E6); κx, αy, αt, αr (23), (33), (45), (47); Ex, Ey, Et (27), (38), (53); Fx0, Fy0 (22), (32); Gxα, Gyκ with Bxα, Byκ (14), (15), (4.E51)–(4.E62); SVyκ (16), (68); Fx, Fy (13); αt,eq, αr,eq (74), (75); t, Mzr, s, Mz (69)–(73), (4.E71)–(4.E75) |
//!
//! Turn slip has no load-only stage (its ζ factors depend on κ and α, (4.78), (4.105),
//! (4.106)): [`Prepared::new`] refuses it and `mf::eval` runs all stages at each point.
//! Mx, My and the relaxation lengths are `mf::eval`'s, not the slip stage's.
//!
//! ## Derivatives
//! [`Prepared::eval_d`] gives ∂(Fx, Fy, Mz)/∂κ and ∂/∂α of the inputs κ, α (through the
//! conditioning: a clipped slip has derivative 0); [`Prepared::eval_d_mu`] adds ∂/∂λμ with
//! λμx* = λμy* = λμ moved together (the road-friction scaling of the estimator). At the
//! model's kinks (sign switches: κx = 0 and αy = 0 in Ex, Ey; αt = 0, αr = 0 in Mz; the clips)
//! the derivative is the one-sided one of the branch taken.

use super::combined::{self, Arm, MzIn, MzLoad, WeightsLoad};
use super::limits::{
    self, check_finite, condition_load_checked, digressive, slips, Cond, Conditioned,
};
use super::pure::{self, Fx0Load, Fx0Mu, Fy0Load, Fy0Mu, Mz0Load, Mz0Mu};
use super::FlagSet;
use super::{clip_e, EvalError, Flags, Input, InputField, Options, Params, Version};
use crate::math::{Backend, Dual, Float, Lift, Mask, Real};

/// The operating point without the slips: what the load stage depends on. SI units, ISO-W.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Operating<F> {
    /// Vertical load Fz \[N\]; ≤ 0 means no contact (all forces zero).
    pub fz: F,
    /// Inclination (camber) angle γ \[rad\].
    pub gamma: F,
    /// Turn slip φt \[1/m\] (read only with turn slip on, which the stages do not support).
    pub phit: F,
    /// Longitudinal speed of the wheel centre Vx \[m/s\].
    pub vx: F,
    /// Inflation pressure p \[Pa\]; `None` takes `INFLPRES`.
    pub p: Option<F>,
}

impl<F: Copy> From<&Input<F>> for Operating<F> {
    fn from(i: &Input<F>) -> Self {
        Operating {
            fz: i.fz,
            gamma: i.gamma,
            phit: i.phit,
            vx: i.vx,
            p: i.p,
        }
    }
}

/// The friction stage: the coefficients that scale with λμx*, λμy*. Cheap to make
/// ([`Prepared::with_mu`]: arithmetic only) for one surface hypothesis after another.
#[derive(Debug, Clone, Copy, Default)]
pub struct Mu<F> {
    fx0: Fx0Mu<F>,
    fy0: Fy0Mu<F>,
    fy0_g0: Fy0Mu<F>,
    mz0: Mz0Mu<F>,
}

impl<F: Real> Mu<F> {
    /// μx \[-\] (26), (4.E13) at this load and friction scaling.
    pub fn mu_x(&self) -> F {
        self.fx0.mu_x
    }
    /// μy \[-\] (37), (4.E23), as a magnitude.
    pub fn mu_y(&self) -> F {
        self.fy0.mu_y.abs()
    }
    /// The largest |Fx0| and |Fy0| the pure-slip formulas can give at this load and friction
    /// scaling \[N\]: |Dx| + |SVx| ((25), (31)) and |Dy| + |SVy| ((36), (42)) — the peak and
    /// the vertical shift, which scales with λμ′ (4.E8), not λμ*, and so weighs more on a
    /// slippery surface.
    pub fn f_peak(&self) -> (F, F) {
        (
            self.fx0.d_x.abs() + self.fx0.s_vx.abs(),
            self.fy0.d_y.abs() + self.fy0.s_vy.abs(),
        )
    }
}

/// Fx, Fy, Mz and what goes with them, as [`super::Output`] has them.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Forces<F, L = Flags> {
    /// Longitudinal force Fx \[N\].
    pub fx: F,
    /// Lateral force Fy \[N\].
    pub fy: F,
    /// Aligning moment Mz \[N·m\].
    pub mz: F,
    /// Pneumatic trail t \[m\] (4.E73).
    pub t: F,
    /// Residual aligning torque Mzr \[N·m\] (4.E75).
    pub m_zr: F,
    /// κ after the low-speed reduction \[-\].
    pub kappa: F,
    /// What was clipped or regularised (load and slip stages; per lane for lanes).
    pub flags: L,
}

/// ∂Fx, ∂Fy, ∂Mz along one direction.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Partials<F> {
    /// ∂Fx \[N per unit of the direction\].
    pub fx: F,
    /// ∂Fy.
    pub fy: F,
    /// ∂Mz \[N·m per unit\].
    pub mz: F,
}

/// The slopes of Fx, Fy, Mz in the input slips.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Slopes<F> {
    /// ∂/∂κ \[N, N·m\].
    pub kappa: Partials<F>,
    /// ∂/∂α \[N/rad, N·m/rad\].
    pub alpha: Partials<F>,
}

/// The slopes in the slips and in the road-friction scaling λμ.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SlopesMu<F> {
    /// ∂/∂κ, ∂/∂α.
    pub slip: Slopes<F>,
    /// ∂/∂λμ with λμx* = λμy* = λμ \[N, N·m per unit λμ\] ([`Prepared::eval_d_mu`]), or
    /// ∂/∂s with both scaled by s ([`Prepared::eval_d_scale`]).
    pub lmu: Partials<F>,
}

/// How the tyre on the car differs from its file, as the load stage takes it
/// ([`Prepared::adjusted`]): scales of Kxκ, of the peak trail Dt and of Bt, and a shift of SHt
/// \[rad\]. [`Adjust::NONE`] is the file.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Adjust<F> {
    /// Scale of the longitudinal slip stiffness Kxκ (as λKx).
    pub kx: F,
    /// Scale of the peak trail Dt (as λt).
    pub trail: F,
    /// Scale of the trail's stiffness factor Bt (as QBZ1–QBZ3 together): its shape.
    pub trail_shape: F,
    /// Shift of the trail's SHt \[rad\] (as QHZ1), in the file's side's axes.
    pub trail_shift: F,
}

impl<F: Real> Adjust<F> {
    /// No adjustment: the file.
    pub const NONE: Adjust<F> = Adjust {
        kx: F::ONE,
        trail: F::ONE,
        trail_shape: F::ONE,
        trail_shift: F::ZERO,
    };
}

/// The load stage of the Magic Formula at one (Fz, γ, p, Vx), with the friction stage at the
/// file's λμx, λμy. See the [module doc](self).
///
/// ```
/// use gough::{math::Libm, mf::{self, Input, Options, Params, Version}};
/// use gough::mf::prepared::{Operating, Prepared};
/// let mut p = Params::<f64>::zeroed(Version::Mf52); // a made-up tyre, for the example
/// p.fnomin = 4000.0; p.unloaded_radius = 0.3; p.longvl = 16.7; p.vxlow = 1.0;
/// p.pcy1 = 1.3; p.pdy1 = 1.0; p.pky1 = -20.0; p.pky2 = 2.0; p.pcx1 = 1.6; p.pdx1 = 1.0;
/// p.pkx1 = 20.0; p.qcz1 = 1.2; p.qbz1 = 10.0; p.qdz1 = 0.1;
/// let opts = Options { limits: false, ..Options::default() };
/// let op = Operating { fz: 4000.0, vx: 20.0, ..Default::default() };
/// let load = Prepared::new::<Libm>(&p, &op, &opts).unwrap();
/// let f = load.eval::<Libm>(0.02, 0.05).unwrap();
/// let i = Input { fz: 4000.0, kappa: 0.02, alpha: 0.05, vx: 20.0, ..Default::default() };
/// assert_eq!(f.fy, mf::eval::<f64, Libm>(&p, &i, &opts).unwrap().fy);
/// // Another road: λμ = 0.5, then the slopes there.
/// let wet = load.with_mu(0.5, 0.5);
/// let (g, d) = load.eval_d::<Libm>(&wet, 0.02, 0.05).unwrap();
/// assert!(g.fy.abs() < f.fy.abs() && d.alpha.fy < 0.0);
/// ```
#[derive(Debug, Clone, Copy)]
pub struct Prepared<F> {
    c: Conditioned<F>,
    contact: bool,
    mirrored: bool,
    fx0: Fx0Load<F>,
    fy0: Fy0Load<F>,
    /// Fy0 at γ = 0 (MF 6.x's F'y (4.E74)); `None` at γ* = 0.
    fy0_g0: Option<Fy0Load<F>>,
    mz0: Mz0Load<F>,
    w: WeightsLoad<F>,
    mz: MzLoad<F>,
    mu: Mu<F>,
}

impl<F: Float> Prepared<F> {
    /// The load stage (and the friction stage at the file's λμ) of `p` at `op`, with the
    /// options of `mf::eval` (limits, α*, mounted side, transient; `moments` is not read).
    /// Errors: non-finite input, pressure ≤ 0, and turn slip (which has no load stage:
    /// [`EvalError::TurnSlipUnavailable`]).
    #[inline(always)]
    pub fn new<M: Backend<F>>(
        p: &Params<F>,
        op: &Operating<F>,
        opts: &Options,
    ) -> Result<Self, EvalError> {
        if opts.turn_slip {
            return Err(EvalError::TurnSlipUnavailable);
        }
        let input = Input {
            fz: op.fz,
            kappa: F::ZERO,
            alpha: F::ZERO,
            gamma: op.gamma,
            phit: op.phit,
            vx: op.vx,
            p: op.p,
        };
        check_finite(&input)?;
        let (c, mirrored, _) = for_eval::<F, M>(p, &input, opts)?;
        /// The load stage kept.
        struct Keep;
        impl<F: Float> Then<F> for Keep {
            type Out = Prepared<F>;
            #[inline(always)]
            fn then(self, v: View<'_, F>) -> Prepared<F> {
                Prepared::from_view(v)
            }
        }
        Ok(stages::<F, M, _>(p, c, mirrored, None, Keep))
    }

    /// The load stage's parts copied into a `Prepared`, with the friction stage at the file's λμ.
    #[inline(always)]
    fn from_view(v: View<'_, F>) -> Self {
        Prepared {
            c: *v.c,
            contact: v.contact,
            mirrored: v.mirrored,
            fx0: *v.fx0,
            fy0: *v.fy0,
            fy0_g0: v.fy0_g0.copied(),
            mz0: *v.mz0,
            w: *v.w,
            mz: *v.mz,
            mu: v.mu_stage::<F>(v.c.lmux_star, v.c.lmuy_star),
        }
    }

    /// The stages as references (what the slip stage reads).
    #[inline(always)]
    fn view(&self) -> View<'_, F> {
        View {
            c: &self.c,
            contact: self.contact,
            mirrored: self.mirrored,
            fx0: &self.fx0,
            fy0: &self.fy0,
            fy0_g0: self.fy0_g0.as_ref(),
            mz0: &self.mz0,
            w: &self.w,
            mz: &self.mz,
        }
    }

    /// The load stage adjusted to a tyre that differs from its file ([`Adjust`]): Kxκ (28),
    /// (4.E15) and Dt (52), (A60) scaled, Bt's load part (50), (A58) scaled, SHt (54), (4.E35)
    /// shifted — what scaling λKx, λt, QBZ1–QBZ3 and adding to QHZ1 in the file would give,
    /// without building the load stage again (a few multiplications). The friction stage at the
    /// file's own λμ is made again.
    pub fn adjusted(&self, a: &Adjust<F>) -> Self {
        let mut p = *self;
        p.fx0.k_xk = self.fx0.k_xk * a.kx;
        p.mz.k_ratio = self.mz.k_ratio * a.kx;
        p.mz0.d_t = self.mz0.d_t * a.trail;
        p.mz.d_t = self.mz.d_t * a.trail;
        p.mz0.b_t1 = self.mz0.b_t1 * a.trail_shape;
        p.mz0.s_ht = self.mz0.s_ht + a.trail_shift;
        p.mu = p.view().mu_stage::<F>(p.c.lmux_star, p.c.lmuy_star);
        p
    }

    /// The friction stage at λμx* = `lmu_x`, λμy* = `lmu_y` (4.E7) (these replace the file's
    /// LMUX, LMUY; the estimator's road scaling moves both together). Arithmetic only: a few
    /// dozen operations, no kernel.
    pub fn with_mu(&self, lmu_x: F, lmu_y: F) -> Mu<F> {
        self.view().mu_stage::<F>(lmu_x, lmu_y)
    }

    /// The friction stage at the file's λμx, λμy (what [`Prepared::eval`] uses).
    pub fn mu(&self) -> &Mu<F> {
        &self.mu
    }

    /// Vertical load used \[N\] (after clipping).
    pub fn fz(&self) -> F {
        self.c.fz
    }
    /// The conditioned load-stage inputs (for the relaxation lengths, `mf::sigma`).
    pub(crate) fn conditioned(&self) -> &Cond<F> {
        &self.c
    }
    /// Kxκ \[N\] (28), (4.E15).
    pub fn k_xk(&self) -> F {
        self.fx0.k_xk
    }
    /// Kyα \[N/rad\] (39), (4.E25).
    pub fn k_ya(&self) -> F {
        self.fy0.k_ya
    }
    /// Whether the tyre touches the road (Fz > 0).
    pub fn contact(&self) -> bool {
        self.contact
    }
    /// Whether the tyre is mirrored (mounted side differs from TYRESIDE).
    pub fn mirrored(&self) -> bool {
        self.mirrored
    }

    /// The slip stage at the file's λμ: Fx, Fy, Mz at (κ, α), equal to `mf::eval`'s.
    #[inline(always)]
    pub fn eval<M: Backend<F>>(&self, kappa: F, alpha: F) -> Result<Forces<F>, EvalError> {
        self.eval_with::<M>(&self.mu, kappa, alpha)
    }

    /// The slip stage with the friction stage `mu` (from [`Prepared::with_mu`]).
    #[inline(always)]
    pub fn eval_with<M: Backend<F>>(
        &self,
        mu: &Mu<F>,
        kappa: F,
        alpha: F,
    ) -> Result<Forces<F>, EvalError> {
        check_slips(kappa, alpha)?;
        finite(self.view().slip::<F, F, M>(mu, kappa, alpha))
    }

    /// The slip stage and the slopes ∂/∂κ, ∂/∂α of Fx, Fy, Mz (dual numbers, two directions).
    pub fn eval_d<M: Backend<F>>(
        &self,
        mu: &Mu<F>,
        kappa: F,
        alpha: F,
    ) -> Result<(Forces<F>, Slopes<F>), EvalError> {
        check_slips(kappa, alpha)?;
        let f = self
            .view()
            .slip::<F, Dual<F, 2>, M>(mu, Dual::var(kappa, 0), Dual::var(alpha, 1));
        let (v, d) = split(f)?;
        Ok((
            v,
            Slopes {
                kappa: d(0),
                alpha: d(1),
            },
        ))
    }

    /// The friction stage at λμx* = λμy* = `lmu` and the slip stage, with the slopes in κ, α
    /// and ∂/∂λμ (both scalings moved together).
    pub fn eval_d_mu<M: Backend<F>>(
        &self,
        lmu: F,
        kappa: F,
        alpha: F,
    ) -> Result<(Forces<F>, SlopesMu<F>), EvalError> {
        let l = Dual::<F, 3>::var(lmu, 2);
        self.eval_d3::<M>(l, l, kappa, alpha)
    }

    /// The friction stage at λμx* = `lmux_star`·s, λμy* = `lmuy_star`·s and the slip stage at
    /// s = 1, with the slopes in κ, α and, in [`SlopesMu::lmu`], ∂/∂s: the slope in a road's
    /// friction relative to its value (a surface μ scales both λμx and λμy, docs/architecture.md:
    /// ∂/∂μ = ∂/∂s / μ), where the file's λμx and λμy differ.
    pub fn eval_d_scale<M: Backend<F>>(
        &self,
        lmux_star: F,
        lmuy_star: F,
        kappa: F,
        alpha: F,
    ) -> Result<(Forces<F>, SlopesMu<F>), EvalError> {
        let scaled = |l: F| Dual::<F, 3> {
            v: l,
            d: [F::ZERO, F::ZERO, l],
        };
        self.eval_d3::<M>(scaled(lmux_star), scaled(lmuy_star), kappa, alpha)
    }

    /// The friction stage at dual λμx*, λμy* (direction 2) and the slip stage with κ, α as
    /// directions 0 and 1.
    fn eval_d3<M: Backend<F>>(
        &self,
        lmux_star: Dual<F, 3>,
        lmuy_star: Dual<F, 3>,
        kappa: F,
        alpha: F,
    ) -> Result<(Forces<F>, SlopesMu<F>), EvalError> {
        check_slips(kappa, alpha)?;
        if !(lmux_star.v.is_finite() && lmuy_star.v.is_finite()) {
            return Err(EvalError::NonFinite(InputField::P));
        }
        let mu = self.view().mu_stage::<Dual<F, 3>>(lmux_star, lmuy_star);
        let f = self.view().slip::<Dual<F, 3>, Dual<F, 3>, M>(
            &mu,
            Dual::var(kappa, 0),
            Dual::var(alpha, 1),
        );
        let (v, d) = split(f)?;
        Ok((
            v,
            SlopesMu {
                slip: Slopes {
                    kappa: d(0),
                    alpha: d(1),
                },
                lmu: d(2),
            },
        ))
    }
}

/// The friction stage from the load stage's parts (λμx*, λμy* (4.E7), λμ' (4.E8)).
#[inline(always)]
fn mu_of<F: Real, G: Lift<F>>(
    c: &Cond<F>,
    fx0_l: &Fx0Load<F>,
    fy0_l: &Fy0Load<F>,
    fy0_g0_l: Option<&Fy0Load<F>>,
    mz0_l: &Mz0Load<F>,
    lmux_star: G,
    lmuy_star: G,
) -> Mu<G> {
    let (lmux_prime, lmuy_prime) = (digressive(lmux_star), digressive(lmuy_star)); // (4.E8)
    let fx0 = pure::fx0_mu::<F, G>(fx0_l, c, lmux_star, lmux_prime);
    let fy0 = pure::fy0_mu::<F, G>(fy0_l, c, lmuy_star, lmuy_prime);
    let fy0_g0 = match fy0_g0_l {
        Some(l) => pure::fy0_mu::<F, G>(l, c, lmuy_star, lmuy_prime),
        None => fy0,
    };
    let mz0 = pure::mz0_mu::<F, G>(mz0_l, fy0_l, &fy0, c, lmuy_star);
    Mu {
        fx0,
        fy0,
        fy0_g0,
        mz0,
    }
}

/// The load stage's parts, borrowed: what the friction and slip stages read. `mf::eval` makes
/// one over its locals ([`stages`]), [`Prepared`] over its fields: no copy of the load stage
/// on `mf::eval`'s path.
#[derive(Clone, Copy)]
pub(crate) struct View<'a, F: Real> {
    pub(crate) c: &'a Cond<F>,
    pub(crate) contact: bool,
    pub(crate) mirrored: bool,
    pub(crate) fx0: &'a Fx0Load<F>,
    pub(crate) fy0: &'a Fy0Load<F>,
    /// Fy0 at γ = 0 (MF 6.x's F'y (4.E74)); `None` at γ* = 0.
    pub(crate) fy0_g0: Option<&'a Fy0Load<F>>,
    pub(crate) mz0: &'a Mz0Load<F>,
    pub(crate) w: &'a WeightsLoad<F>,
    pub(crate) mz: &'a MzLoad<F>,
}

/// What [`stages`] hands its [`View`] of locals to: a closure written by hand, whose `then` is
/// `#[inline(always)]`. (A closure is compiled as a function of its own, without the target
/// features of `mf::eval_batch_lanes`'s AVX functions: measured, three quarters of a lane
/// batch's time went to SSE2 code. Returning the stages by value instead cost the M4F's
/// combined evaluation 5 % more instructions.)
pub(crate) trait Then<F: Real> {
    /// What the continuation gives.
    type Out;
    /// The continuation, at the load stage's view.
    fn then(self, v: View<'_, F>) -> Self::Out;
}

/// The load stage from a conditioned load (with turn slip, `turn` is (κ, α*) of `c`'s point),
/// handed to `k` as a [`View`] of locals.
#[inline(always)]
pub(crate) fn stages<F: Real, M: Backend<F>, K: Then<F>>(
    p: &Params<F>,
    mut c: Cond<F>,
    mirrored: bool,
    turn: Option<(F, F)>,
    k: K,
) -> K::Out {
    if mirrored {
        c.flags.insert(Flags::MIRRORED);
    }
    // No contact (Fz ≤ 0). Lanes reach here all in contact or all not (`mf::lanes` evaluates
    // a chunk that mixes them point by point).
    if c.fz.mask_le(F::ZERO).all() {
        let (fx0, fy0, mz0) = (Fx0Load::default(), Fy0Load::default(), Mz0Load::default());
        let (w, mz) = (WeightsLoad::default(), MzLoad::default());
        return k.then(View {
            c: &c,
            contact: false,
            mirrored,
            fx0: &fx0,
            fy0: &fy0,
            fy0_g0: None,
            mz0: &mz0,
            w: &w,
            mz: &mz,
        });
    }
    let fx0 = pure::fx0_load::<F, M>(p, &c);
    let turn_on = c.turn.is_some();
    let gamma_star = c.gamma_star;
    let fy0 = pure::fy0_load::<F, M>(p, &mut c, gamma_star, turn_on);
    // Fy0 at γ = 0 for F'y (4.E74) (MF 6.x; MF 5.2's Mz takes the actual Fy − SVyκ and does
    // not read it, but testing the version here cost the M4F bench's MF 6.1 load stage 5
    // instructions, `mf_load_stage_fast` 2,211 → 2,216: MF 5.2 computes it unused).
    // (In lanes: skipped when γ* = 0 in every lane; Fy0 at γ = 0 of a lane whose γ* is 0 is
    // its Fy0, the same arithmetic.)
    let fy0_g0 = if gamma_star.mask_eq(F::ZERO).all() {
        None
    } else {
        Some(pure::fy0_load::<F, M>(p, &mut c, F::ZERO, turn_on))
    };
    let w = combined::weights_load(p, &mut c);
    let turn_g_yk = turn.map(|(kappa, alpha_star)| {
        let m = pure::fy0_mu::<F, F>(&fy0, &c, c.lmuy_star, c.lmuy_prime);
        let mut flags = c.flags;
        let g = combined::g_yk::<F, F, M>(&w, kappa, alpha_star, &mut flags);
        c.flags = flags;
        (m.mu_y, g)
    });
    let mz0 = pure::mz0_load::<F, M>(p, &mut c, turn_g_yk);
    let mz = MzLoad {
        k_ratio: fx0.k_xk / fy0.k_ya_prime,
        d_t: mz0.d_t,
        c_t: mz0.c_t,
        c_r: mz0.c_r,
        arm: Arm::from_params(p),
    };
    k.then(View {
        c: &c,
        contact: true,
        mirrored,
        fx0: &fx0,
        fy0: &fy0,
        fy0_g0: fy0_g0.as_ref(),
        mz0: &mz0,
        w: &w,
        mz: &mz,
    })
}

impl<F: Real> View<'_, F> {
    #[inline(always)]
    pub(crate) fn mu_stage<G: Lift<F>>(&self, lmux_star: G, lmuy_star: G) -> Mu<G> {
        if !self.contact {
            return Mu::default();
        }
        mu_of::<F, G>(
            self.c,
            self.fx0,
            self.fy0,
            self.fy0_g0,
            self.mz0,
            lmux_star,
            lmuy_star,
        )
    }

    /// The slip stage, computed in `G` from the load stage (`F`) and a friction stage (`H`).
    #[inline(always)]
    pub(crate) fn slip<H: Lift<F>, G: Lift<F> + Lift<H>, M: Backend<G>>(
        &self,
        mu: &Mu<H>,
        kappa: G,
        alpha: G,
    ) -> Forces<G, G::Flags> {
        let c = &self.c;
        let alpha = if self.mirrored { -alpha } else { alpha };
        let s = slips::<F, G, M>(c, kappa, alpha);
        let mut flags = c.flags;
        flags.merge(s.flags);
        if !self.contact {
            // No contact: no force, no moment (MFeval gives the same, see the `load` sweep).
            return Forces {
                kappa: s.kappa_out,
                flags,
                ..Forces::default()
            };
        }
        let fx0 = pure::fx0_slip::<F, H, G, M>(self.fx0, &mu.fx0, c, s.kappa, &mut flags);
        let fy0 = pure::fy0_slip::<F, H, G, M>(self.fy0, &mu.fy0, c, s.alpha_star, &mut flags);
        // t and Mzr at pure slip: (45), (47), (53), (56) / (4.E34), (4.E37), (4.E44), (4.E47).
        let m0 = self.mz0;
        let alpha_r = s.alpha_star + mu.mz0.s_hf; // (47), (4.E37)
        let alpha_t = s.alpha_star + m0.s_ht; // (45), (4.E34)
        let b_t = mu.mz0.b_t;
        let e_t = (M::atan(alpha_t * (b_t * m0.c_t)) * m0.e_t2 + F::ONE) * m0.e_t1; // (53), (4.E44)
        let e_t = clip_e(e_t, c.limits, &mut flags);
        let d_r = s.cos_alpha_star * mu.mz0.d_r1 + m0.zeta8 - F::ONE; // (56), (4.E47)

        let fx = combined::fx_slip::<F, G, M>(self.w, s.kappa, s.alpha_star, fx0, &mut flags);
        let mu_y = mu.fy0.mu_y;
        let fy = combined::fy_slip::<F, H, G, M>(
            self.w,
            c,
            (s.kappa, s.alpha_star),
            fy0,
            mu_y,
            self.fy0.zeta2,
            &mut flags,
        );
        // Fy0 at γ = 0 for MF 6.x's F'y; at γ* = 0 the Fy0 already computed (the common case
        // on a car).
        let fy0_g0 = match &self.fy0_g0 {
            None => fy0,
            Some(l) => pure::fy0_slip::<F, H, G, M>(l, &mu.fy0_g0, c, s.alpha_star, &mut flags),
        };
        let fy_arm = match c.version {
            // MF-Tyre 5.2 (and the paper's (17), (69)): Mz = −t·(Fy − SVyκ) + Mzr + s·Fx, with
            // the Fy and the SVyκ (4.E66) of this point — the actual γ, so that Fy − SVyκ is
            // Gyκ·Fy0: the κ-induced side force acts at the contact centre, without trail.
            // DIFFERS FROM MFeval 4.0: 4.0 subtracts an SVyκ at μy(γ = 0) (its γ = 0 evaluation's
            // μy), which leaves (μy(γ) − μy(0))·SVyκ/μy(γ) under the trail; MFeval 4.3.1 follows
            // the manual, as we do. Tests: `mf::tests::mf52_mz_subtracts_its_own_svyk`, the
            // oracle's MF 5.2 Mz with camber (docs/magic-formula.md).
            Version::Delft96 | Version::Mf52 => fy.fy - fy.s_vyk,
            // F'y (4.E74): Fy at γ = 0 (MF 6.x); the weighting Gyκ keeps the actual γ* (TNO,
            // MFeval) and is taken without the turn-slip ζ2 (MFeval's `internalParams_sub0`).
            Version::Mf61 | Version::Mf62 => fy.g_yk * fy0_g0, // (4.E74)
        };
        let mz = combined::mz_slip::<F, H, G, M>(
            self.mz,
            c,
            &MzIn {
                kappa: s.kappa,
                alpha_t,
                alpha_r,
                b_t,
                e_t,
                d_r,
                b_r: mu.mz0.b_r,
                cos_alpha_prime: s.cos_alpha_prime,
                fx,
                fy: fy.fy,
                fy_arm,
            },
        );
        let sgn = |x: G| if self.mirrored { -x } else { x };
        Forces {
            fx,
            fy: sgn(fy.fy),
            mz: sgn(mz.mz),
            t: mz.t,
            m_zr: sgn(mz.m_zr),
            kappa: s.kappa_out,
            flags,
        }
    }
}

fn check_slips<F: Real>(kappa: F, alpha: F) -> Result<(), EvalError> {
    if !kappa.is_finite() {
        return Err(EvalError::NonFinite(InputField::Kappa));
    }
    if !alpha.is_finite() {
        return Err(EvalError::NonFinite(InputField::Alpha));
    }
    Ok(())
}

fn finite<F: Real, L>(f: Forces<F, L>) -> Result<Forces<F, L>, EvalError> {
    if F::all_finite(&[f.fx, f.fy, f.mz, f.t, f.m_zr]) {
        Ok(f)
    } else {
        Err(EvalError::Overflow)
    }
}

/// The values and a direction-`i` reader of a dual result; non-finite → [`EvalError::Overflow`].
#[allow(clippy::type_complexity)]
fn split<F: Float, const N: usize>(
    f: Forces<Dual<F, N>>,
) -> Result<(Forces<F>, impl Fn(usize) -> Partials<F>), EvalError> {
    finite(f)?;
    let v = Forces {
        fx: f.fx.v,
        fy: f.fy.v,
        mz: f.mz.v,
        t: f.t.v,
        m_zr: f.m_zr.v,
        kappa: f.kappa.v,
        flags: f.flags,
    };
    Ok((v, move |i| Partials {
        fx: f.fx.der(i),
        fy: f.fy.der(i),
        mz: f.mz.der(i),
    }))
}

/// What `mf::eval` builds its stages from: the conditioned load (with turn slip: of the whole
/// point, every stage's load part there), whether mirrored, and with turn slip (κ, α*).
/// Returned apart from the [`Prepared`] so that `mf::eval` builds that in place (no copy of it
/// through a `Result`). `input` must have been checked finite (`limits::check_finite`).
#[allow(clippy::type_complexity)]
#[inline(always)]
pub(crate) fn for_eval<F: Real, M: Backend<F>>(
    p: &Params<F>,
    input: &Input<F>,
    opts: &Options,
) -> Result<(Cond<F>, bool, Option<(F, F)>), EvalError> {
    let mirrored = p.mirrored_on(opts.mounted);
    let sgn = |x: F| if mirrored { -x } else { x };
    if !opts.turn_slip {
        let load = Input {
            fz: input.fz,
            kappa: F::ZERO,
            alpha: F::ZERO,
            gamma: sgn(input.gamma),
            phit: sgn(input.phit),
            vx: input.vx,
            p: input.p,
        };
        return Ok((
            condition_load_checked::<F, M>(p, &load, opts)?,
            mirrored,
            None,
        ));
    }
    let mut inp = *input;
    inp.alpha = sgn(inp.alpha);
    inp.gamma = sgn(inp.gamma);
    inp.phit = sgn(inp.phit);
    let mut c = limits::condition::<F, M>(p, &inp, opts)?;
    if c.fz > F::ZERO {
        super::turnslip::prepare::<F, M>(p, &mut c);
    }
    let turn = (c.kappa, c.alpha_star);
    Ok((c, mirrored, Some(turn)))
}
