//! One wheel's per-sample pipeline: measurement → transient slips → Magic Formula → `Forces`,
//! and measurement → friction estimator → `Estimate`.
//!
//! `no_std`, no allocation, no panics: the firmware runs it in its 1 kHz tick, and the host's
//! replay check (`gough replay --check`) runs the same code on the host, in f32 with the same
//! math backend, so "device = host f32 run" compares one piece of code built for two targets,
//! bit for bit.
//!
//! ## Forces
//! - A measurement **with kinematics** (Vx, plus α, κ or ω) goes through the relaxation-length
//!   filter ([`crate::relax::Transient`], eq. 20 solved exactly over the step between this
//!   wheel's timestamps): slip speeds Vsy = |Vx|·tan α and Vsx = −|Vx|·κ, or Vsx = Vx − ω·Re when ω
//!   is given without κ ([`effective_radius`]); the Magic Formula is evaluated at the transient
//!   α', κ' (`Options::transient`). The relaxation lengths of a step are those of the previous
//!   evaluation (σ varies with Fz, which changes little over one step), as in
//!   [`crate::relax::TransientTyre`]. The damping speed is |Vx|
//!   ([`crate::relax::DampingSpeed::Forward`], TNO's form): a constant input settles on
//!   exactly the steady-state Magic Formula at the measured α, κ — the slips the Magic Formula
//!   was fitted with.
//! - **Start** (a wheel's first sample; after a gap longer than [`MAX_STEP_US`], a timestamp that
//!   does not advance, a parameter upload, or a sample without kinematics): the deflections start
//!   in the steady state of the measured slips (v = σα·tan α, u = σκ·κ) and the forces are the
//!   steady-state Magic Formula — a stream that starts mid-manoeuvre does not start from an
//!   undeflected tyre.
//! - **Without kinematics** (no Vx, or neither α, κ nor ω): the steady-state Magic Formula at the
//!   measured α, κ ([`Measurement::mf_input`](crate::proto::Measurement::mf_input),
//!   Vx = LONGVL), see [`steady`].
//!
//! ## Estimate
//! The friction estimator is the exact-model bank ([`crate::mu::bank::Bank`], `f32`), started
//! with [`Wheel::start_estimator`] when parameters are loaded (the device does it on every
//! parameter load and every `Settings`). [`Wheel::estimate`] feeds it what was **measured**: Fz,
//! Fy, Mz, and Fx, κ, Vx, γ when the sample carries them ([`sample`]) — never α and never the
//! model's forces — with the sample's wrapping `u32` µs timestamp as it is (the bank uses only
//! wrapping differences, so the estimates do not depend on when the clock started). κ is the
//! measured κ, or, without it, the one the wheel speed gives as the filter computes it,
//! (ω·Re − Vx)/|Vx| clamped to ±1 ([`effective_radius`]).
//!
//! Of the protocol's [`Settings`]: `fallback_mu` is the bank's prior `mu_prior` (the μ of a
//! `Fallback` estimate; when it is a positive number, [`estimator_config`]); `limits` applies
//! to the forces only; `wheelbase` starts the front-to-rear preview between a [`Car`]'s axles.
//! A [`Car`] mounts each wheel's tyre on its side ([`Wheel::on`]), for the forces and the
//! estimate alike; a lone [`Wheel::new`] takes it as its file describes it.
use crate::math::Backend;
use crate::mf::{self, Input, Options, Output, Params, Side};
use crate::mu::preview::{self, Preview};
use crate::mu::{self as bank, Bank, BuildError};
use crate::proto::Wheel as WheelId;
use crate::proto::{AckCode, Estimate, Forces, Measurement, Settings};
use crate::relax::{self, DampingSpeed, Kinematics, Sigma, Transient};

/// Longest step the filter takes \[µs\] (`relax::MAX_DT`); a longer gap restarts it.
pub const MAX_STEP_US: i32 = 1_000_000;

/// The filter's state between samples.
#[derive(Debug, Clone, Copy)]
struct Deflection {
    tr: Transient<f32>,
    cfg: relax::Config<f32>,
    /// σκ, σα of the last evaluation \[m\].
    sigma: Sigma<f32>,
    /// Timestamp of the last sample \[µs\].
    t_us: u32,
}

/// A measurement's kinematics.
#[derive(Debug, Clone, Copy)]
struct Kin {
    kin: Kinematics<f32>,
    /// Steady-state slips: the measured α (0 if absent) and κ (measured, or from ω).
    alpha: f32,
    kappa: f32,
    tan_alpha: f32,
}

/// One wheel: transient filter and friction estimator (about 1.5 KB, nearly all of it the
/// bank). Keeps no reference to the parameters: each call takes them (pass the same ones the
/// estimator was started with).
#[derive(Debug, Clone)]
pub struct Wheel {
    defl: Option<Deflection>,
    est: Option<Bank<f32>>,
    mounted: Option<Side>,
}

impl Default for Wheel {
    fn default() -> Self {
        Self::new()
    }
}

/// The estimator's settings from the protocol's: the bank's defaults with the prior
/// `mu_prior` = `fallback_mu` (when it is a positive number).
pub fn estimator_config(s: &Settings) -> bank::Config<f32> {
    let mut c = bank::Config::default();
    if s.fallback_mu.is_finite() && s.fallback_mu > 0.0 {
        c.mu_prior = s.fallback_mu;
    }
    c
}

/// Effective rolling radius Re \[m\] at load `fz` \[N\] for slip from the wheel speed ω: MF 6.x,
/// `Re = R0·Q_RE0 − ρFz0·(DREFF·atan(BREFF·ρd) + FREFF·ρd)` with the vertical deflection taken
/// linear (ρFz0 = FNOMIN/Cz, ρd = Fz/FNOMIN) and the speed growth of the free radius (Q_V1) left
/// out; R0 when the file has no vertical stiffness.
pub fn effective_radius<M: Backend<f32>>(p: &Params<f32>, fz: f32) -> f32 {
    let r0 = p.unloaded_radius;
    if !(p.vertical_stiffness > 0.0 && p.fnomin > 0.0) {
        return r0;
    }
    let q = if p.q_re0 > 0.0 { p.q_re0 } else { 1.0 };
    let rho0 = p.fnomin / p.vertical_stiffness;
    let d = fz.max(0.0) / p.fnomin;
    r0 * q - rho0 * (p.dreff * M::atan(p.breff * d) + p.freff * d)
}

fn kinematics<M: Backend<f32>>(p: &Params<f32>, m: &Measurement) -> Option<Kin> {
    let vx = m.vx?;
    if m.alpha.is_none() && m.kappa.is_none() && m.omega.is_none() {
        return None;
    }
    let speed = vx.abs();
    let alpha = m.alpha.unwrap_or(0.0);
    let tan_alpha = M::tan(alpha);
    let (vsx, kappa) = match (m.kappa, m.omega) {
        (Some(k), _) => (-k * speed, k),
        (None, Some(w)) => {
            let vsx = vx - w * effective_radius::<M>(p, m.fz);
            let k = if speed > 0.0 {
                (-vsx / speed).clamp(-1.0, 1.0)
            } else {
                0.0
            };
            (vsx, k)
        }
        (None, None) => (0.0, 0.0),
    };
    Some(Kin {
        kin: Kinematics {
            vx,
            vsx,
            vsy: tan_alpha * speed,
        },
        alpha,
        kappa,
        tan_alpha,
    })
}

/// What the estimator reads of a measurement (see the module doc): Fz, Fy, Mz, and Fx, κ, Vx, γ
/// when measured, at the sample's own timestamp; κ from the wheel speed when only ω is given.
/// Never α.
pub fn sample<M: Backend<f32>>(p: &Params<f32>, m: &Measurement) -> bank::Sample<f32> {
    let kappa = match (m.kappa, m.omega, m.vx) {
        (Some(k), _, _) => Some(k),
        (None, Some(_), Some(_)) => kinematics::<M>(p, m).map(|k| k.kappa),
        _ => None,
    };
    bank::Sample {
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

fn eval<M: Backend<f32>>(
    p: &Params<f32>,
    input: &Input<f32>,
    opts: &Options,
) -> Result<Output<f32>, AckCode> {
    mf::eval::<f32, M>(p, input, opts).map_err(|_| AckCode::EvalError)
}

fn forces_of(m: &Measurement, o: &Output<f32>) -> Forces {
    Forces {
        wheel: m.wheel,
        t_us: m.t_us,
        fx: o.fx,
        fy: o.fy,
        mz: o.mz,
        flags: o.flags.0,
    }
}

/// The steady-state answer (no filter): the Magic Formula at the measured slips.
/// `mounted`: the side the tyre is on (`None`: as the file describes it), see [`Wheel::mounted`].
pub fn steady<M: Backend<f32>>(
    p: &Params<f32>,
    limits: bool,
    mounted: Option<Side>,
    m: &Measurement,
) -> Result<Forces, AckCode> {
    let input = m.mf_input(p).ok_or(AckCode::NoSlip)?;
    let opts = Options {
        limits,
        mounted,
        moments: false, // the Forces message carries Fx, Fy, Mz
        ..Options::default()
    };
    eval::<M>(p, &input, &opts).map(|o| forces_of(m, &o))
}

impl Wheel {
    /// No filter state, no estimator; the tyre as its file describes it (see [`Wheel::mounted`]).
    pub const fn new() -> Self {
        Wheel::on(None)
    }

    /// [`Wheel::new`] for a wheel on side `mounted`: where it differs from the file's
    /// `TYRESIDE` the Magic Formula and the estimator mirror the tyre (α, γ in, Fy, Mz out:
    /// `Options::mounted`, `Bank::new`), so that the wheel takes and gives its signals in its own
    /// ISO-W axes. `None`: as the file describes it (the other side's signals arrive mirrored).
    pub const fn on(mounted: Option<Side>) -> Self {
        Wheel {
            defl: None,
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
        self.defl = None;
    }

    /// (Re)starts the estimator for tyre `p` with the prior of `s` ([`estimator_config`]); it
    /// forgets what it learnt. On an error (a tyre without friction) no estimator runs.
    pub fn start_estimator<M: Backend<f32>>(
        &mut self,
        p: &Params<f32>,
        s: &Settings,
    ) -> Result<(), BuildError> {
        self.est = None;
        self.est = Some(Bank::new::<M>(p, self.mounted, estimator_config(s))?);
        Ok(())
    }

    /// Drops the estimator.
    pub fn stop_estimator(&mut self) {
        self.est = None;
    }

    /// The estimator, if one runs.
    pub fn estimator(&self) -> Option<&Bank<f32>> {
        self.est.as_ref()
    }

    /// The estimator, if one runs, to hand it a reading of the road ahead
    /// ([`crate::mu::preview::Preview::rear`]).
    pub fn estimator_mut(&mut self) -> Option<&mut Bank<f32>> {
        self.est.as_mut()
    }

    /// The filter's deflections (v lateral, u longitudinal) \[m\], if it runs.
    pub fn deflection(&self) -> Option<(f32, f32)> {
        self.defl.map(|d| (d.tr.v, d.tr.u))
    }

    /// The predicted forces of one sample (see the module doc), or why there are none. The
    /// filter's state moves on only when the evaluation succeeds.
    pub fn forces<M: Backend<f32>>(
        &mut self,
        p: &Params<f32>,
        limits: bool,
        m: &Measurement,
    ) -> Result<Forces, AckCode> {
        let Some(k) = kinematics::<M>(p, m) else {
            self.defl = None;
            return steady::<M>(p, limits, self.mounted, m);
        };
        let gamma = m.gamma.unwrap_or(0.0);
        let input = |kappa: f32, alpha: f32| Input {
            fz: m.fz,
            kappa,
            alpha,
            gamma,
            phit: 0.0,
            vx: k.kin.vx,
            p: None,
        };
        if let Some(d) = self.defl {
            let dt = m.t_us.wrapping_sub(d.t_us) as i32;
            if dt > 0 && dt <= MAX_STEP_US {
                let mut tr = d.tr;
                let s = tr
                    .step::<M>(&d.cfg, dt as f32 / 1.0e6, &k.kin, &d.sigma)
                    .map_err(|_| AckCode::EvalError)?;
                let opts = Options {
                    limits,
                    transient: true,
                    mounted: self.mounted,
                    moments: false, // the Forces message carries Fx, Fy, Mz
                    ..Options::default()
                };
                let o = eval::<M>(p, &input(s.kappa, s.alpha), &opts)?;
                self.defl = Some(Deflection {
                    tr,
                    cfg: d.cfg,
                    sigma: Sigma {
                        sigma_kappa: o.sigma_x,
                        sigma_alpha: o.sigma_y,
                    },
                    t_us: m.t_us,
                });
                return Ok(forces_of(m, &o));
            }
        }
        // Start: steady state of the measured slips.
        self.defl = None;
        let opts = Options {
            limits,
            mounted: self.mounted,
            moments: false, // the Forces message carries Fx, Fy, Mz
            ..Options::default()
        };
        let o = eval::<M>(p, &input(k.kappa, k.alpha), &opts)?;
        let cfg = relax::Config {
            damping: DampingSpeed::Forward,
            ..relax::Config::from_params(p)
        };
        // The floor `Transient::step` puts on σ.
        let floor = |s: f32| {
            let s = s.abs();
            if s < cfg.sigma_min {
                cfg.sigma_min.max(1e-6)
            } else {
                s
            }
        };
        let (s_a, s_k) = (floor(o.sigma_y), floor(o.sigma_x));
        let (v_max, u_max) = (cfg.max_tan_alpha * s_a, cfg.max_kappa * s_k);
        let tr = Transient {
            v: (s_a * k.tan_alpha).max(-v_max).min(v_max),
            u: (s_k * k.kappa).max(-u_max).min(u_max),
        };
        self.defl = Some(Deflection {
            tr,
            cfg,
            sigma: Sigma {
                sigma_kappa: o.sigma_x,
                sigma_alpha: o.sigma_y,
            },
            t_us: m.t_us,
        });
        Ok(forces_of(m, &o))
    }

    /// Runs the estimator on one sample of tyre `p` (the parameters it was started with): the
    /// estimate, whose `change` is set on the one estimate at which the estimator declared a
    /// change of surface. `None` when no estimator runs.
    pub fn estimate<M: Backend<f32>>(
        &mut self,
        p: &Params<f32>,
        m: &Measurement,
    ) -> Option<Estimate> {
        let est = self.est.as_mut()?;
        Some(estimate_of(m, &est.update::<M>(p, &sample::<M>(p, m))))
    }
}

/// The bank's estimate after measurement `m` as the protocol's.
fn estimate_of(m: &Measurement, e: &bank::Estimate<f32>) -> Estimate {
    Estimate {
        wheel: m.wheel,
        t_us: m.t_us,
        mu: e.mu,
        sigma: e.sigma,
        state: e.state,
        mu_min: e.mu_min,
        change: e.change,
    }
}

/// Why [`Car::start_estimators`] did not start every estimator.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum StartError {
    /// The settings' wheelbase is out of range ([`Settings::wheelbase`]); nothing changed.
    Settings,
    /// The tyre has no friction to estimate ([`BuildError`]); no estimator runs (the preview,
    /// if any, idles).
    Tyre(BuildError),
}

impl core::fmt::Display for StartError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            StartError::Settings => {
                f.write_str("the settings' wheelbase is not 0 or a positive number")
            }
            StartError::Tyre(e) => write!(f, "{e}"),
        }
    }
}

impl core::error::Error for StartError {}

/// A car's four wheels (index = [`crate::proto::Wheel::index`]: FL, FR, RL, RR) and, when the
/// settings give a wheelbase ([`Settings::wheelbase`]), the front-to-rear preview between their
/// estimators ([`crate::mu::preview`]: what the front-left wheel read is handed to the
/// rear-left one when it gets there, front-right to rear-right). The firmware's pipeline and the
/// host's replay check run this.
///
/// The wheelbase comes with the protocol's `Settings` (v3); with `0` (the default) every wheel
/// estimates alone.
///
/// Each wheel is mounted on its side ([`Wheel::on`], [`WheelId::side`]: FL, RL left, FR, RR right): the tyre
/// file describes one side's tyre (`TYRESIDE`), the other side's is its mirror image, and every
/// wheel's signals are taken and given in its own ISO-W axes.
#[derive(Debug, Clone)]
pub struct Car {
    wheels: [Wheel; 4],
    preview: Option<[Preview<f32>; 2]>,
}

impl Default for Car {
    fn default() -> Self {
        Self::new()
    }
}

/// Wheels 0–3 (FL, FR, RL, RR) on their sides ([`WheelId::side`]).
const WHEELS_ON: [Wheel; 4] = [
    Wheel::on(Some(WheelId::FrontLeft.side())),
    Wheel::on(Some(WheelId::FrontRight.side())),
    Wheel::on(Some(WheelId::RearLeft.side())),
    Wheel::on(Some(WheelId::RearRight.side())),
];

impl Car {
    /// No filter state, no estimators, no preview.
    pub const fn new() -> Self {
        Car {
            wheels: WHEELS_ON,
            preview: None,
        }
    }

    /// Wheel `i` (0..=3).
    pub fn wheel(&self, i: usize) -> Option<&Wheel> {
        self.wheels.get(i)
    }

    /// The preview of side `i` (0 left, 1 right), if one runs.
    pub fn preview(&self, i: usize) -> Option<&Preview<f32>> {
        self.preview.as_ref().and_then(|p| p.get(i))
    }

    /// Forgets every filter's deflections.
    pub fn reset_filters(&mut self) {
        for w in self.wheels.iter_mut() {
            w.reset_filter();
        }
    }

    /// (Re)starts the four estimators for tyre `p` with settings `s` ([`estimator_config`]),
    /// and the preview over `s`'s wheelbase when it gives one; all forget what they learnt.
    /// Settings whose wheelbase is out of range ([`Settings::wheelbase`]) are refused
    /// ([`StartError::Settings`]) and nothing changes; on a tyre without friction no estimator
    /// runs ([`StartError::Tyre`]).
    pub fn start_estimators<M: Backend<f32>>(
        &mut self,
        p: &Params<f32>,
        s: &Settings,
    ) -> Result<(), StartError> {
        let preview = s
            .wheelbase()
            .map_err(|_| StartError::Settings)?
            .map(|l| Preview::new(preview::Config::with_wheelbase(l)))
            .transpose()
            .map_err(|_| StartError::Settings)?;
        self.preview = preview.map(|pv| [pv.clone(), pv]);
        let mut out = Ok(());
        for w in self.wheels.iter_mut() {
            if let Err(e) = w.start_estimator::<M>(p, s) {
                out = Err(StartError::Tyre(e));
            }
        }
        out
    }

    /// The predicted forces of one sample ([`Wheel::forces`] of its wheel).
    pub fn forces<M: Backend<f32>>(
        &mut self,
        p: &Params<f32>,
        limits: bool,
        m: &Measurement,
    ) -> Result<Forces, AckCode> {
        match self.wheels.get_mut(m.wheel.index()) {
            Some(w) => w.forces::<M>(p, limits, m),
            None => Err(AckCode::EvalError),
        }
    }

    /// Runs the estimator of the sample's wheel ([`Wheel::estimate`]) with the previews between
    /// the axles ([`preview::update`]): a rear wheel first takes what its front wheel read that
    /// it has now reached, a front wheel's new identification is queued for the rear wheel
    /// behind it.
    pub fn estimate<M: Backend<f32>>(
        &mut self,
        p: &Params<f32>,
        m: &Measurement,
    ) -> Option<Estimate> {
        let i = m.wheel.index();
        let bank = self.wheels.get_mut(i)?.est.as_mut()?;
        let e = preview::update::<f32, M>(self.preview.as_mut(), i, bank, p, &sample::<M>(p, m));
        Some(estimate_of(m, &e))
    }
}
