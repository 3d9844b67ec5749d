//! A car's wheels: their positions ([`Wheel`]: front left, front right, rear left, rear right,
//! each with its side), and each one's per-sample pipeline ([`Corner`]): measurement →
//! transient slips → Magic Formula → forces, and measurement → friction estimator → estimate;
//! the four of a [`Car`], with the front-to-rear preview between their estimators.
//!
//! `no_std`, no allocation, no panics, generic over the number type: the firmware runs it in
//! `f32` in its 1 kHz tick, and the host's replay check (`gough replay --check`) runs the same
//! code on the host, in f32 with the same math backend, so "device = host f32 run" compares one
//! piece of code built for two targets, bit for bit; the host can run it in f64 as well. The
//! pipeline takes and gives domain types ([`Measurement`], [`mf::Output`],
//! [`crate::mu::Estimate`]); the protocol's messages convert to and from them
//! ([`crate::proto`]).
//!
//! ## Forces
//! - A measurement **with kinematics** (Vx, plus α, κ or ω) goes through the transient tyre
//!   ([`crate::relax::TransientTyre`]: the relaxation-length filter, eq. 20 solved exactly over
//!   the step between this wheel's timestamps, then the Magic Formula at the transient α', κ',
//!   `Options::transient`): slip speeds Vsy = |Vx|·tan α and Vsx = −|Vx|·κ, or Vsx = Vx − ω·Re
//!   when ω is given without κ ([`effective_radius`]). The relaxation lengths of a step are
//!   those of the previous evaluation (σ varies with Fz, which changes little over one step).
//!   The damping speed is |Vx|
//!   ([`crate::relax::DampingSpeed::Forward`], TNO's form): a constant input settles on
//!   exactly the steady-state Magic Formula at the measured α, κ — the slips the Magic Formula
//!   was fitted with.
//! - **Start** (a wheel's first sample; after a gap longer than [`MAX_STEP_US`], a timestamp that
//!   does not advance, a parameter upload, or a sample without kinematics): the deflections start
//!   in the steady state of the measured slips (v = σα·tan α, u = σκ·κ,
//!   [`crate::relax::TransientTyre::start`]) and the forces are the steady-state Magic Formula — a stream that starts mid-manoeuvre does not start from an
//!   undeflected tyre.
//! - **Without kinematics** (no Vx, or neither α, κ nor ω): the steady-state Magic Formula at the
//!   measured α, κ ([`Measurement::mf_input`], Vx = LONGVL), see [`steady`].
//!
//! ## Estimate
//! The friction estimator is the exact-model bank ([`crate::mu::Bank`]), started with
//! [`Corner::start_estimator`] when parameters are loaded (the device does it on every
//! parameter load and every `Settings`). [`Corner::estimate`] feeds it what was **measured**:
//! Fz, Fy, Mz, and Fx, κ, Vx, γ when the sample carries them ([`sample`]) — never α and never
//! the model's forces — with the sample's wrapping `u32` µs timestamp as it is (the bank uses
//! only wrapping differences, so the estimates do not depend on when the clock started). κ is
//! the measured κ, or, without it, the one the wheel speed gives as the filter computes it,
//! (ω·Re − Vx)/|Vx| clamped to ±1 ([`effective_radius`]).
//!
//! A [`Car`] mounts each wheel's tyre on its side ([`Corner::on`], [`Wheel::side`]), for the
//! forces and the estimate alike, and runs the front-to-rear preview between its axles when it
//! is given one; a lone [`Corner::new`] takes the tyre as its file describes it.
use crate::math::{Backend, Float};
use crate::mf::{self, Input, Options, Output, Params, Side};
use crate::mu::preview::{self, Preview, PreviewError};
use crate::mu::{self, Bank, BuildError};
use crate::relax::{DampingSpeed, Kinematics, Operating, TransientTyre, TyreError};
use postcard::experimental::max_size::MaxSize;
use serde::{Deserialize, Serialize};

/// Longest step the filter takes \[µs\] (`relax::MAX_DT`); a longer gap restarts it.
pub const MAX_STEP_US: i32 = 1_000_000;

/// A wheel's position on the car. The protocol carries it as one byte, 0..=3.
#[derive(Serialize, Deserialize, MaxSize, Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Wheel {
    /// Front left (0).
    #[default]
    FrontLeft,
    /// Front right (1).
    FrontRight,
    /// Rear left (2).
    RearLeft,
    /// Rear right (3).
    RearRight,
}

impl Wheel {
    /// All wheels, by index.
    pub const ALL: [Wheel; 4] = [
        Wheel::FrontLeft,
        Wheel::FrontRight,
        Wheel::RearLeft,
        Wheel::RearRight,
    ];
    /// 0..=3.
    pub const fn index(self) -> usize {
        self as usize
    }
    /// The wheel of an index 0..=3.
    pub fn from_index(i: usize) -> Option<Wheel> {
        Wheel::ALL.get(i).copied()
    }
    /// The side of the car the wheel is on: front and rear left on the left, the others on
    /// the right (the side a tyre is mounted on, `mf::Options::mounted`).
    pub const fn side(self) -> Side {
        match self {
            Wheel::FrontLeft | Wheel::RearLeft => Side::Left,
            Wheel::FrontRight | Wheel::RearRight => Side::Right,
        }
    }
}

/// One sample of one wheel's measured forces (from a force-sensing hub or bearing, or from a
/// vehicle observer), with what the vehicle knows of its motion. ISO-W at the contact point,
/// SI units.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Measurement<F> {
    /// Sample time \[µs\], the sender's clock, wrapping.
    pub t_us: u32,
    /// Vertical load Fz \[N\], ≥ 0 in contact.
    pub fz: F,
    /// Lateral force Fy \[N\].
    pub fy: F,
    /// Aligning moment Mz \[N·m\].
    pub mz: F,
    /// Longitudinal force Fx \[N\], if measured.
    pub fx: Option<F>,
    /// Longitudinal speed of the wheel centre Vx \[m/s\], if known.
    pub vx: Option<F>,
    /// Wheel spin speed ω \[rad/s\], if known.
    pub omega: Option<F>,
    /// Slip angle α \[rad\], if the vehicle estimates it (the forces use it; the estimator never).
    pub alpha: Option<F>,
    /// Longitudinal slip κ \[-\], if the vehicle estimates it.
    pub kappa: Option<F>,
    /// Inclination (camber) angle γ \[rad\], if known (default 0).
    pub gamma: Option<F>,
}

impl<F: Float> Measurement<F> {
    /// The Magic Formula operating point of this sample, or `None` when neither α nor κ is
    /// given (nothing to predict). Absent α, κ, γ are 0; absent Vx is the tyre's `LONGVL`;
    /// the pressure is the parameter set's `INFLPRES`.
    pub fn mf_input(&self, p: &Params<F>) -> Option<Input<F>> {
        if self.alpha.is_none() && self.kappa.is_none() {
            return None;
        }
        Some(Input {
            fz: self.fz,
            kappa: self.kappa.unwrap_or(F::ZERO),
            alpha: self.alpha.unwrap_or(F::ZERO),
            gamma: self.gamma.unwrap_or(F::ZERO),
            phit: F::ZERO,
            vx: self.vx.unwrap_or(p.longvl),
            p: None,
        })
    }
}

/// Why a measurement got no forces.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Error {
    /// Neither α, κ nor (with Vx) ω: no slip to predict the forces of.
    NoSlip,
    /// The transient tyre refused the sample: its filter the step (non-finite kinematics), or
    /// the Magic Formula the operating point.
    Tyre(TyreError),
}

impl core::fmt::Display for Error {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Error::NoSlip => f.write_str("the measurement carries no slip"),
            Error::Tyre(e) => write!(f, "{e}"),
        }
    }
}

impl core::error::Error for Error {}

/// The filter between samples: the transient tyre and the time of the last sample \[µs\].
#[derive(Debug, Clone)]
struct Filter<F> {
    tyre: TransientTyre<F>,
    t_us: u32,
}

/// A measurement's kinematics.
#[derive(Debug, Clone, Copy)]
struct Kin<F> {
    kin: Kinematics<F>,
    /// Steady-state slips: the measured α (0 if absent) and κ (measured, or from ω).
    alpha: F,
    kappa: F,
}

/// Effective rolling radius Re \[m\] at load `fz` \[N\] for slip from the wheel speed ω: MF 6.x,
/// `Re = R0·Q_RE0 − ρFz0·(DREFF·atan(BREFF·ρd) + FREFF·ρd)` with the vertical deflection taken
/// linear (ρFz0 = FNOMIN/Cz, ρd = Fz/FNOMIN) and the speed growth of the free radius (Q_V1) left
/// out; R0 when the file has no vertical stiffness.
pub fn effective_radius<F: Float, M: Backend<F>>(p: &Params<F>, fz: F) -> F {
    let r0 = p.unloaded_radius;
    if !(p.vertical_stiffness > F::ZERO && p.fnomin > F::ZERO) {
        return r0;
    }
    let q = if p.q_re0 > F::ZERO { p.q_re0 } else { F::ONE };
    let rho0 = p.fnomin / p.vertical_stiffness;
    let d = fz.max(F::ZERO) / p.fnomin;
    r0 * q - rho0 * (p.dreff * M::atan(p.breff * d) + p.freff * d)
}

fn kinematics<F: Float, M: Backend<F>>(p: &Params<F>, m: &Measurement<F>) -> Option<Kin<F>> {
    let vx = m.vx?;
    if m.alpha.is_none() && m.kappa.is_none() && m.omega.is_none() {
        return None;
    }
    let speed = vx.abs();
    let alpha = m.alpha.unwrap_or(F::ZERO);
    let tan_alpha = M::tan(alpha);
    let (vsx, kappa) = match (m.kappa, m.omega) {
        (Some(k), _) => (-k * speed, k),
        (None, Some(w)) => {
            let vsx = vx - w * effective_radius::<F, M>(p, m.fz);
            let k = if speed > F::ZERO {
                (-vsx / speed).clamp_flag(-F::ONE, F::ONE).0
            } else {
                F::ZERO
            };
            (vsx, k)
        }
        (None, None) => (F::ZERO, F::ZERO),
    };
    Some(Kin {
        kin: Kinematics {
            vx,
            vsx,
            vsy: tan_alpha * speed,
        },
        alpha,
        kappa,
    })
}

/// What the estimator reads of a measurement (see the module doc): Fz, Fy, Mz, and Fx, κ, Vx, γ
/// when measured, at the sample's own timestamp; κ from the wheel speed when only ω is given.
/// Never α.
pub fn sample<F: Float, M: Backend<F>>(p: &Params<F>, m: &Measurement<F>) -> mu::Sample<F> {
    let kappa = match (m.kappa, m.omega, m.vx) {
        (Some(k), _, _) => Some(k),
        (None, Some(_), Some(_)) => kinematics::<F, M>(p, m).map(|k| k.kappa),
        _ => None,
    };
    mu::Sample {
        t_us: m.t_us,
        fz: m.fz,
        fy: m.fy,
        mz: m.mz,
        fx: m.fx,
        kappa,
        vx: m.vx,
        gamma: m.gamma,
    }
}

fn eval<F: Float, M: Backend<F>>(
    p: &Params<F>,
    input: &Input<F>,
    opts: &Options,
) -> Result<Output<F>, Error> {
    mf::eval::<F, M>(p, input, opts).map_err(|e| Error::Tyre(TyreError::Eval(e)))
}

/// The steady-state answer (no filter): the Magic Formula at the measured slips
/// ([`Measurement::mf_input`]), Fx, Fy, Mz (and μ, K, σ) without Mx, My.
/// `mounted`: the side the tyre is on (`None`: as the file describes it), see
/// [`Corner::mounted`].
pub fn steady<F: Float, M: Backend<F>>(
    p: &Params<F>,
    limits: bool,
    mounted: Option<Side>,
    m: &Measurement<F>,
) -> Result<Output<F>, Error> {
    let input = m.mf_input(p).ok_or(Error::NoSlip)?;
    let opts = Options {
        limits,
        mounted,
        moments: false, // the forces are Fx, Fy, Mz
        ..Options::default()
    };
    eval::<F, M>(p, &input, &opts)
}

/// One corner of the car: a wheel's transient filter and friction estimator (about 1.5 KB in
/// `f32`, nearly all of it the bank). Keeps no reference to the parameters: each call takes
/// them (pass the same ones the estimator was started with).
#[derive(Debug, Clone)]
pub struct Corner<F> {
    filter: Option<Filter<F>>,
    est: Option<Bank<F>>,
    mounted: Option<Side>,
}

impl<F: Float> Default for Corner<F> {
    fn default() -> Self {
        Self::new()
    }
}

impl<F: Float> Corner<F> {
    /// No filter state, no estimator; the tyre as its file describes it (see
    /// [`Corner::mounted`]).
    pub const fn new() -> Self {
        Corner::on(None)
    }

    /// [`Corner::new`] for a wheel on side `mounted`: where it differs from the file's
    /// `TYRESIDE` the Magic Formula and the estimator mirror the tyre (α, γ in, Fy, Mz out:
    /// `Options::mounted`, `Bank::new`), so that the wheel takes and gives its signals in its own
    /// ISO-W axes. `None`: as the file describes it (the other side's signals arrive mirrored).
    pub const fn on(mounted: Option<Side>) -> Self {
        Corner {
            filter: None,
            est: None,
            mounted,
        }
    }

    /// The side the tyre is mounted on (`None`: as its file describes it).
    pub fn mounted(&self) -> Option<Side> {
        self.mounted
    }

    /// Forgets the filter's deflections (the next sample starts it in the steady state).
    pub fn reset_filter(&mut self) {
        self.filter = None;
    }

    /// (Re)starts the estimator for tyre `p` with settings `cfg`; it forgets what it learnt. On
    /// an error (a tyre without friction, settings without a grid) no estimator runs.
    pub fn start_estimator<M: Backend<F>>(
        &mut self,
        p: &Params<F>,
        cfg: mu::Config<F>,
    ) -> Result<(), BuildError> {
        self.est = None;
        self.est = Some(Bank::new::<M>(p, self.mounted, cfg)?);
        Ok(())
    }

    /// Drops the estimator.
    pub fn stop_estimator(&mut self) {
        self.est = None;
    }

    /// The estimator, if one runs.
    pub fn estimator(&self) -> Option<&Bank<F>> {
        self.est.as_ref()
    }

    /// The estimator, if one runs, to hand it a reading of the road ahead
    /// ([`crate::mu::preview::Preview::rear`]).
    pub fn estimator_mut(&mut self) -> Option<&mut Bank<F>> {
        self.est.as_mut()
    }

    /// The filter's deflections (v lateral, u longitudinal) \[m\], if it runs.
    pub fn deflection(&self) -> Option<(F, F)> {
        self.filter
            .as_ref()
            .map(|f| (f.tyre.state.v, f.tyre.state.u))
    }

    /// The predicted forces of one sample (see the module doc): Fx, Fy, Mz (with μ, K, σ and the
    /// flags; Mx, My not evaluated), or why there are none. The filter's state moves on only
    /// when the evaluation succeeds.
    pub fn forces<M: Backend<F>>(
        &mut self,
        p: &Params<F>,
        limits: bool,
        m: &Measurement<F>,
    ) -> Result<Output<F>, Error> {
        let Some(k) = kinematics::<F, M>(p, m) else {
            self.filter = None;
            return steady::<F, M>(p, limits, self.mounted, m);
        };
        let op = Operating {
            kin: k.kin,
            fz: m.fz,
            gamma: m.gamma.unwrap_or(F::ZERO),
            phit: F::ZERO,
            p: None,
        };
        if let Some(f) = self.filter.as_mut() {
            let dt = m.t_us.wrapping_sub(f.t_us) as i32;
            if dt > 0 && dt <= MAX_STEP_US {
                let opts = Options {
                    limits,
                    transient: true,
                    mounted: self.mounted,
                    moments: false, // the forces are Fx, Fy, Mz
                    ..Options::default()
                };
                let (o, _) = f
                    .tyre
                    .step::<M>(p, &opts, F::from_micros(dt as u32), &op)
                    .map_err(Error::Tyre)?;
                f.t_us = m.t_us;
                return Ok(o);
            }
        }
        // Start: steady state of the measured slips.
        self.filter = None;
        let opts = Options {
            limits,
            mounted: self.mounted,
            moments: false, // the forces are Fx, Fy, Mz
            ..Options::default()
        };
        let mut tyre = TransientTyre::new(p);
        tyre.config.damping = DampingSpeed::Forward;
        let o = tyre
            .start::<M>(p, &opts, &op, k.kappa, k.alpha)
            .map_err(Error::Tyre)?;
        self.filter = Some(Filter { tyre, t_us: m.t_us });
        Ok(o)
    }

    /// Runs the estimator on one sample of tyre `p` (the parameters it was started with): the
    /// estimate, whose `change` is set on the one estimate at which the estimator declared a
    /// change of surface. `None` when no estimator runs.
    pub fn estimate<M: Backend<F>>(
        &mut self,
        p: &Params<F>,
        m: &Measurement<F>,
    ) -> Option<mu::Estimate<F>> {
        let est = self.est.as_mut()?;
        Some(est.update::<M>(p, &sample::<F, M>(p, m)))
    }
}

/// Why [`Car::start_estimators`] did not start every estimator.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum StartError {
    /// The preview's settings are out of range (its wheelbase not a positive number); nothing
    /// changed.
    Preview(PreviewError),
    /// The tyre has no friction to estimate, or the estimator's settings no grid
    /// ([`BuildError`]); no estimator runs (the preview, if any, idles).
    Tyre(BuildError),
}

impl core::fmt::Display for StartError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            StartError::Preview(e) => write!(f, "{e}"),
            StartError::Tyre(e) => write!(f, "{e}"),
        }
    }
}

impl core::error::Error for StartError {}

/// A car's four corners ([`Wheel`]: FL, FR, RL, RR) and, when started with one, the front-to-rear
/// preview between their estimators ([`crate::mu::preview`]: what the front-left wheel read is
/// handed to the rear-left one when it gets there, front-right to rear-right). The firmware's
/// pipeline and the host's replay check run this.
///
/// Each corner is mounted on its side ([`Corner::on`], [`Wheel::side`]: FL, RL left, FR, RR
/// right): the tyre file describes one side's tyre (`TYRESIDE`), the other side's is its mirror
/// image, and every wheel's signals are taken and given in its own ISO-W axes.
#[derive(Debug, Clone)]
pub struct Car<F> {
    corners: [Corner<F>; 4],
    preview: Option<[Preview<F>; 2]>,
}

impl<F: Float> Default for Car<F> {
    fn default() -> Self {
        Self::new()
    }
}

impl<F: Float> Car<F> {
    /// No filter state, no estimators, no preview; each corner on its side.
    pub const fn new() -> Self {
        Car {
            corners: [
                Corner::on(Some(Wheel::FrontLeft.side())),
                Corner::on(Some(Wheel::FrontRight.side())),
                Corner::on(Some(Wheel::RearLeft.side())),
                Corner::on(Some(Wheel::RearRight.side())),
            ],
            preview: None,
        }
    }

    /// The corner of wheel `w`.
    pub fn corner(&self, w: Wheel) -> &Corner<F> {
        let [fl, fr, rl, rr] = &self.corners;
        match w {
            Wheel::FrontLeft => fl,
            Wheel::FrontRight => fr,
            Wheel::RearLeft => rl,
            Wheel::RearRight => rr,
        }
    }

    /// The corner of wheel `w`, mutable.
    fn corner_mut(&mut self, w: Wheel) -> &mut Corner<F> {
        let [fl, fr, rl, rr] = &mut self.corners;
        match w {
            Wheel::FrontLeft => fl,
            Wheel::FrontRight => fr,
            Wheel::RearLeft => rl,
            Wheel::RearRight => rr,
        }
    }

    /// The estimator of wheel `w`, if one runs (to hand it a calibration,
    /// [`Bank::import_calibration`]).
    pub fn estimator_mut(&mut self, w: Wheel) -> Option<&mut Bank<F>> {
        self.corner_mut(w).estimator_mut()
    }

    /// The preview of side `i` (0 left, 1 right), if one runs.
    pub fn preview(&self, i: usize) -> Option<&Preview<F>> {
        self.preview.as_ref().and_then(|p| p.get(i))
    }

    /// Forgets every filter's deflections.
    pub fn reset_filters(&mut self) {
        for c in self.corners.iter_mut() {
            c.reset_filter();
        }
    }

    /// (Re)starts the four estimators for tyre `p` with settings `cfg`, and the preview with
    /// settings `preview` when given; all forget what they learnt. Preview settings out of
    /// range are refused ([`StartError::Preview`]) and nothing changes; on a tyre without
    /// friction no estimator runs ([`StartError::Tyre`]).
    pub fn start_estimators<M: Backend<F>>(
        &mut self,
        p: &Params<F>,
        cfg: mu::Config<F>,
        preview: Option<preview::Config<F>>,
    ) -> Result<(), StartError> {
        let preview = preview
            .map(Preview::new)
            .transpose()
            .map_err(StartError::Preview)?;
        self.preview = preview.map(|pv| [pv.clone(), pv]);
        let mut out = Ok(());
        for c in self.corners.iter_mut() {
            if let Err(e) = c.start_estimator::<M>(p, cfg) {
                out = Err(StartError::Tyre(e));
            }
        }
        out
    }

    /// The predicted forces of one sample of wheel `w` ([`Corner::forces`]).
    pub fn forces<M: Backend<F>>(
        &mut self,
        p: &Params<F>,
        limits: bool,
        w: Wheel,
        m: &Measurement<F>,
    ) -> Result<Output<F>, Error> {
        self.corner_mut(w).forces::<M>(p, limits, m)
    }

    /// Runs the estimator of wheel `w` ([`Corner::estimate`]) with the previews between the
    /// axles ([`preview::update`]): a rear wheel first takes what its front wheel read that it
    /// has now reached, a front wheel's new identification is queued for the rear wheel behind
    /// it.
    pub fn estimate<M: Backend<F>>(
        &mut self,
        p: &Params<F>,
        w: Wheel,
        m: &Measurement<F>,
    ) -> Option<mu::Estimate<F>> {
        let bank = self.corners.get_mut(w.index())?.est.as_mut()?;
        let s = sample::<F, M>(p, m);
        Some(preview::update::<F, M>(
            self.preview.as_mut(),
            w.index(),
            bank,
            p,
            &s,
        ))
    }
}

#[cfg(test)]
mod tests {
    //! What never moves the tyre's calibration through the wheel pipeline: samples the
    //! estimator refuses (not finite, Fz ≤ 0) are held — the estimate and the calibration as
    //! they were — and counted (`Bank::bad_samples`); unexciting data (free rolling: no slip,
    //! no force, no torque) leaves θ and the batch count as they were, and the covariance moves
    //! only by the documented drift (`Calibration::drift`: each variance grows towards its
    //! prior's, never beyond; the off-diagonal terms untouched).
    use super::*;
    use crate::math::Libm;
    use crate::mu::calibration::{Calibration, Exported};
    use proptest::prelude::*;

    fn tyre() -> Params<f64> {
        let text = include_str!("../host-tests/data/tyres/MagicFormula61_Parameters.tir");
        crate::tir::parse(text).unwrap().params
    }

    /// A corner whose estimator starts from a calibration away from the file, with σ below the
    /// prior (so that the drift has room to show).
    fn warm_corner(p: &Params<f64>, side: Option<Side>) -> Corner<f64> {
        let mut c = Corner::on(side);
        c.start_estimator::<Libm>(p, mu::Config::default()).unwrap();
        let e = Exported {
            value: [1.05, 0.97, 0.0008, 1.04],
            sigma: [0.03, 0.04, 0.0007, 0.05],
            batches: 12,
        };
        c.estimator_mut()
            .unwrap()
            .import_calibration::<Libm>(&e)
            .unwrap();
        c
    }

    /// `after` is `before` moved by nothing but the drift: θ and the batches equal, the
    /// off-diagonal terms equal, each variance between its value before and its prior's.
    #[allow(clippy::needless_range_loop)] // i, j < 4: the 4×4 covariance
    fn only_drift(before: &Calibration<f64>, after: &Calibration<f64>, prior: &[f64; 4]) {
        assert_eq!(after.theta, before.theta);
        assert_eq!(after.batches, before.batches);
        for i in 0..4 {
            for j in 0..4 {
                if i == j {
                    let (b, a, top) = (before.cov[i][i], after.cov[i][i], prior[i] * prior[i]);
                    assert!(
                        a >= b && a <= top.max(b),
                        "var {i}: {b} -> {a} (prior {top})"
                    );
                } else {
                    assert_eq!(after.cov[i][j], before.cov[i][j], "cov {i}{j}");
                }
            }
        }
    }

    /// A value the estimator refuses: NaN, ±∞ or a load ≤ 0, in one of the measured fields.
    fn bad_value() -> impl Strategy<Value = (usize, f64)> {
        (
            0usize..4,
            prop_oneof![
                Just(f64::NAN),
                Just(f64::INFINITY),
                Just(f64::NEG_INFINITY),
                -1e6f64..=0.0,
            ],
        )
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(24))]

        /// Only refused samples, from a warm start: the calibration and the estimate are held
        /// to the bit, and every sample is counted.
        #[test]
        fn refused_samples_never_move_the_calibration(
            rows in proptest::collection::vec((bad_value(), 0u32..5000, -1e4f64..1e4, -0.5f64..0.5, 0.0f64..60.0), 1..200),
            side in prop_oneof![Just(None), Just(Some(Side::Left)), Just(Some(Side::Right))],
        ) {
            let p = tyre();
            let mut c = warm_corner(&p, side);
            let before = *c.estimator().unwrap().calibration();
            let est0 = c.estimator().unwrap().current();
            let mut t = 0u32;
            for (k, ((field, bad), dt, f, kappa, vx)) in rows.iter().enumerate() {
                t = t.wrapping_add(*dt);
                let mut m = Measurement {
                    t_us: t, fz: 4000.0, fy: *f, mz: f / 50.0, fx: Some(*f / 2.0),
                    vx: Some(*vx), omega: None, alpha: Some(0.02), kappa: Some(*kappa), gamma: None,
                };
                match field {
                    0 => m.fz = *bad,
                    1 => m.fy = if bad.is_finite() { f64::NAN } else { *bad },
                    2 => m.mz = if bad.is_finite() { f64::INFINITY } else { *bad },
                    _ => m.fx = Some(if bad.is_finite() { f64::NEG_INFINITY } else { *bad }),
                }
                let _ = c.forces::<Libm>(&p, true, &m);
                let e = c.estimate::<Libm>(&p, &m).unwrap();
                prop_assert_eq!(e, est0, "the estimate is held");
                let b = c.estimator().unwrap();
                prop_assert_eq!(b.calibration(), &before);
                prop_assert_eq!(b.bad_samples() as usize, k + 1);
            }
        }

        /// Free rolling (no slip, no force, no torque, a steady load and speed), from a warm
        /// start: θ and the batch count stay, the covariance only drifts.
        #[test]
        fn free_rolling_never_moves_the_calibration(
            fz in 1500f64..8000.0,
            vx in 1f64..60.0,
            n in 100usize..1500,
            side in prop_oneof![Just(None), Just(Some(Side::Left)), Just(Some(Side::Right))],
        ) {
            let p = tyre();
            let mut c = warm_corner(&p, side);
            let before = *c.estimator().unwrap().calibration();
            let prior = c.estimator().unwrap().config().cal_sigma;
            for i in 0..n {
                let m = Measurement {
                    t_us: 1000 * i as u32, fz, fy: 0.0, mz: 0.0, fx: Some(0.0), vx: Some(vx),
                    omega: None, alpha: Some(0.0), kappa: Some(0.0), gamma: Some(0.0),
                };
                let o = c.forces::<Libm>(&p, true, &m).unwrap();
                prop_assert!(o.fy.is_finite());
                c.estimate::<Libm>(&p, &m).unwrap();
                let b = c.estimator().unwrap();
                only_drift(&before, b.calibration(), &prior);
                prop_assert_eq!(b.bad_samples(), 0);
            }
        }
    }

    /// Refused samples between good ones: each is counted and the estimates stay finite. (The
    /// estimate is not frozen on a refused sample: `Bank::update` spends the sample's slots on
    /// the pending batch's fit before it checks the sample, so an estimate of earlier samples'
    /// evidence may come out on it; the refused values themselves are never taken in.)
    #[test]
    fn refused_samples_among_good_ones_are_held_and_counted() {
        let p = tyre();
        let mut c = Corner::on(None);
        c.start_estimator::<Libm>(&p, mu::Config::default())
            .unwrap();
        let mut last: Option<mu::Estimate<f64>> = None;
        let mut refused = 0;
        for i in 0..600u32 {
            let a = 0.06 * (f64::from(i) / 300.0).min(1.0);
            let mut m = Measurement {
                t_us: 1000 * i,
                fz: 4000.0,
                fy: -60_000.0 * a,
                mz: 1500.0 * a,
                fx: None,
                vx: Some(20.0),
                omega: None,
                alpha: Some(a),
                kappa: None,
                gamma: None,
            };
            let bad = i % 7 == 3;
            if bad {
                m.fz = if i % 2 == 0 { f64::NAN } else { -1.0 };
                refused += 1;
            }
            let e = c.estimate::<Libm>(&p, &m).unwrap();
            assert!(
                e.mu.is_finite() && e.sigma.is_finite() && e.mu_min.is_finite(),
                "{e:?}"
            );
            last = Some(e);
        }
        assert_eq!(c.estimator().unwrap().bad_samples(), refused);
        assert!(
            last.is_some_and(|e| e.state != mu::State::Fallback),
            "{last:?}"
        );
    }
}
