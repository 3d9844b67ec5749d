//! The sim of the diagnosis: our tyre model from SIM.tir driven by the log's inputs.
//!
//! - Steady state: [`gough::mf::eval`] of the file's version at each row's (Fz, κ, α, γ, φt,
//!   Vx, p), limits on (the file's ranges; each clip is the model's, as in `gough mf eval`).
//! - Relaxation: when the file gives what the filters need (MF 6.x `LATERAL_STIFFNESS` and
//!   `LONGITUDINAL_STIFFNESS`; MF 5.2 / Delft 96 `PTX1` and `PTY1`), the core's transient tyre
//!   runs ([`gough::relax::TransientTyre`]: the filter of eq. 20, exact discretisation, then
//!   the Magic Formula at its slips with `Options::transient`, no steady-state low-speed
//!   reductions).
//! - Turn slip is on when the log has a `phit` column and the file carries turn-slip
//!   coefficients (MF 6.x); otherwise φt is not used.
//!
//! ## First-order hold: the continuous model, sampled
//! A log samples continuous signals, so between two rows the inputs are taken as linear in
//! time, and the step is the core's [`TransientTyre::step_between`] ([`Transient::step_hold`],
//! then the Magic Formula): the kinematics **and** the
//! relaxation lengths (σ at each row's load, γ, p) are linear between the two rows, and with them
//! the damping speed and the decay rate V/σ; the forcing is integrated exactly; the core takes
//! sub-steps where V/σ moves faster than one step resolves (the load oscillating at several Hz
//! in a 100 Hz log); the slips of row i are formed with row i's own σ (a σ held from the step's
//! start misses the continuous model by several times the noise on a 100 Hz log with Fz ±30 %
//! at 8 Hz). σ does not depend on the slips, so each row's σ comes from one extra Magic Formula evaluation
//! at the log's slips (moments off) before the row's own. Steps longer than
//! [`gough::relax::MAX_DT`] are gaps.
//!
//! ## Gaps
//! A log with dropped rows has gaps in time; the filter is not bridged over them: after a step
//! longer than 1.5 × the log's median step ([`Log::restarts`]) it restarts in the steady state
//! of that row's slips, as at row 0.
//!
//! The damping speed is |Vx| ([`DampingSpeed::Forward`], TNO's linear transient model): a
//! `.tir` file is fitted on steady-state data, and with this choice the transient sim reproduces
//! that fit exactly in steady state (α' → α, κ' → κ), also under braking.
//!
//! The first row (and the first after a gap) starts in steady state (deflections equal to
//! σ·tan α and σ·κ, with σ floored as the filter floors it: [`Transient::steady`]), so a log
//! that begins mid-manoeuvre does not show a start-up transient that the tyre never had.
//!
//! Nothing of the tyre is re-implemented here. The one formula typed here is the sensor model of
//! [`lag`] (a first-order low-pass, exact for a first-order hold), which is not the tyre's.

use super::log::Log;
use gough::math::Libm;
use gough::mf::{self, Input, Options, Params};
use gough::relax::{
    Config, DampingSpeed, Kinematics, Operating, Sample, Sigma, Transient, TransientTyre,
};

/// Fx, Fy \[N\], Mz \[N·m\] of one row.
pub type Out = [f64; 3];

/// Per-row multipliers on the Magic Formula's scaling factors λ (1 = unchanged).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Lambda {
    /// On λμx (LMUX).
    pub mux: f64,
    /// On λμy (LMUY).
    pub muy: f64,
    /// On λKx (LKX).
    pub kx: f64,
    /// On λKy (LKY).
    pub ky: f64,
}

impl Lambda {
    /// No change.
    pub const ONE: Lambda = Lambda {
        mux: 1.0,
        muy: 1.0,
        kx: 1.0,
        ky: 1.0,
    };
    /// Both friction factors times `m`.
    pub fn mu(m: f64) -> Lambda {
        Lambda {
            mux: m,
            muy: m,
            ..Lambda::ONE
        }
    }
}

/// Where the relaxation lengths of a run come from; `[σκ, σα]` \[m\] per row.
#[derive(Debug, Clone, Copy, Default)]
pub enum SigmaMode<'a> {
    /// The model's (σx, σy of [`gough::mf::Output`]).
    #[default]
    Model,
    /// The model's, times a per-row multiplier.
    Scaled(&'a [[f64; 2]]),
    /// Given per row (filters run even when the file has none).
    Given(&'a [[f64; 2]]),
}

/// Per-row modifications of the sim (what an effect changes).
#[derive(Debug, Clone, Copy, Default)]
pub struct Mods<'a> {
    /// λ multipliers per row.
    pub lambda: Option<&'a [Lambda]>,
    /// Added to the outputs per row.
    pub add: Option<&'a [Out]>,
    /// Relaxation lengths.
    pub sigma: SigmaMode<'a>,
}

/// The sim: a parameter set, the evaluation options and whether the filters run.
#[derive(Debug, Clone)]
pub struct Sim {
    /// SIM.tir's parameters.
    pub params: Params<f64>,
    /// Evaluation options (limits on; `transient` when the filters run; turn slip if used).
    pub opts: Options,
    /// The relaxation-length filters run.
    pub filters: bool,
    /// Turn slip is evaluated (log has `phit`, file has turn-slip coefficients).
    pub turn_slip: bool,
    /// Transient-model settings (|Vx| damping, the file's DAMP_VLOW/VXLOW, σ floor 1 % R0).
    pub cfg: Config<f64>,
}

/// The result of a full run.
#[derive(Debug, Clone, Default)]
pub struct Run {
    /// Outputs per row.
    pub out: Vec<Out>,
    /// Relaxation lengths `[σκ, σα]` used from each row on \[m\] (0 without filters).
    pub sigma: Vec<[f64; 2]>,
    /// Slips fed to the Magic Formula `[κ', α']` per row.
    pub slips: Vec<[f64; 2]>,
}

/// Does the file give what the relaxation filters need?
pub fn has_filters(p: &Params<f64>) -> bool {
    if p.version.is_mf6() {
        p.lateral_stiffness > 0.0 && p.longitudinal_stiffness > 0.0
    } else {
        p.pty1 != 0.0 && p.ptx1 != 0.0
    }
}

/// An error at a row: (row index, message).
pub type RowError = (usize, String);

impl Sim {
    /// The sim of `params` for `log`.
    pub fn new(params: Params<f64>, log: &Log) -> Sim {
        let filters = has_filters(&params);
        let turn_slip = log.phit.is_some() && mf::turnslip::available(&params);
        let opts = Options {
            transient: filters,
            turn_slip,
            ..Options::default()
        };
        let mut cfg = Config::from_params(&params);
        cfg.damping = DampingSpeed::Forward;
        Sim {
            params,
            opts,
            filters,
            turn_slip,
            cfg,
        }
    }

    fn input(&self, log: &Log, i: usize, kappa: f64, alpha: f64) -> Input<f64> {
        Input {
            fz: log.fz[i],
            kappa,
            alpha,
            gamma: log.gamma[i],
            phit: if self.turn_slip { log.phit_at(i) } else { 0.0 },
            vx: log.vx[i],
            p: log.p_at(i),
        }
    }

    /// The kinematics of row `i`.
    fn kinematics(log: &Log, i: usize) -> Kinematics<f64> {
        let (vsx, vsy) = log.slip_velocity(i);
        Kinematics {
            vx: log.vx[i],
            vsx,
            vsy,
        }
    }

    /// The inputs of eq. (20) at row `i` with relaxation lengths `sigma` = `[σκ, σα]`.
    fn sample(log: &Log, i: usize, sigma: [f64; 2]) -> Sample<f64> {
        Sample {
            kin: Sim::kinematics(log, i),
            sigma: sigma_of(sigma),
        }
    }

    /// The operating point of row `i` (what [`Sim::input`] gives the Magic Formula, but for
    /// the slips).
    fn operating(&self, log: &Log, i: usize) -> Operating<f64> {
        Operating {
            kin: Sim::kinematics(log, i),
            fz: log.fz[i],
            gamma: log.gamma[i],
            phit: if self.turn_slip { log.phit_at(i) } else { 0.0 },
            p: log.p_at(i),
        }
    }

    /// Advances the deflection states from row `i − 1` to row `i`: the core's first-order hold
    /// ([`Transient::step_hold`]) between the two rows' kinematics and relaxation lengths `s0`,
    /// `s1`, sub-stepped by the core where σ moves fast; the slips at row `i` with its own σ.
    fn advance(
        &self,
        st: &mut Transient<f64>,
        log: &Log,
        i: usize,
        s0: [f64; 2],
        s1: [f64; 2],
    ) -> Result<[f64; 2], RowError> {
        let h = log.t[i] - log.t[i - 1];
        let (a, b) = (Sim::sample(log, i - 1, s0), Sim::sample(log, i, s1));
        let s = st
            .step_hold::<Libm>(&self.cfg, h, &a, &b)
            .map_err(|e| (i, format!("relaxation step: {e}")))?;
        Ok([s.kappa, s.alpha])
    }

    /// The relaxation lengths `[σκ, σα]` of row `i` under `q` (λ of the row set) and `mods`:
    /// σ does not depend on the slips, so the Magic Formula runs once at the log's slips,
    /// without moments, for them (or not at all when they are given).
    pub fn sigma_at(
        &self,
        log: &Log,
        q: &Params<f64>,
        mods: &Mods,
        i: usize,
    ) -> Result<[f64; 2], RowError> {
        if let SigmaMode::Given(g) = mods.sigma {
            return Ok(g.get(i).copied().unwrap_or([0.0, 0.0]));
        }
        let opts = Options {
            moments: false,
            ..self.opts
        };
        let inp = self.input(log, i, log.kappa[i], log.alpha[i]);
        let o = mf::eval::<f64, Libm>(q, &inp, &opts)
            .map_err(|e| (i, format!("Magic Formula: {e}")))?;
        Ok(match mods.sigma {
            SigmaMode::Scaled(m) => {
                let m = m.get(i).copied().unwrap_or([1.0, 1.0]);
                [o.sigma_x * m[0], o.sigma_y * m[1]]
            }
            _ => [o.sigma_x, o.sigma_y],
        })
    }

    /// Steady-state deflections at row `i` for relaxation lengths `sigma` (the core's
    /// [`Transient::steady`]).
    fn init(&self, log: &Log, i: usize, sigma: [f64; 2]) -> Transient<f64> {
        Transient::steady(
            &self.cfg,
            &sigma_of(sigma),
            log.kappa[i],
            log.alpha[i].tan(),
        )
    }

    /// Runs the whole log with `params` (SIM.tir's or an effect's) and `mods`. The filters
    /// restart in steady state at row 0 and after every gap in time ([`Log::restarts`]).
    pub fn run(&self, log: &Log, params: &Params<f64>, mods: &Mods) -> Result<Run, RowError> {
        let n = log.len();
        let filters = self.filters || matches!(mods.sigma, SigmaMode::Given(_));
        let restart = log.restarts();
        let mut q = params.clone();
        let base = [q.lmux, q.lmuy, q.lkx, q.lky];
        let mut run = Run {
            out: Vec::with_capacity(n),
            sigma: Vec::with_capacity(n),
            slips: Vec::with_capacity(n),
        };
        // The core's transient tyre: the filter, then the Magic Formula at its slips.
        let mut tyre = TransientTyre::new(params);
        tyre.config = self.cfg;
        let mut prev = [0.0; 2];
        for i in 0..n {
            set_lambda(&mut q, &base, mods, i);
            let sigma = if filters {
                self.sigma_at(log, &q, mods, i)?
            } else {
                [0.0, 0.0]
            };
            let fresh = restart.get(i).copied().unwrap_or(true);
            let (o, slips) = if !filters || fresh {
                if filters {
                    tyre.restart(sigma_of(sigma), log.kappa[i], log.alpha[i].tan());
                }
                let inp = self.input(log, i, log.kappa[i], log.alpha[i]);
                let o = mf::eval::<f64, Libm>(&q, &inp, &self.opts)
                    .map_err(|e| (i, format!("Magic Formula: {e}")))?;
                (o, [log.kappa[i], log.alpha[i]])
            } else {
                // The first-order hold from row i − 1 to row i, each with its own σ.
                let h = log.t[i] - log.t[i - 1];
                let (a, b) = (Sim::sample(log, i - 1, prev), Sim::sample(log, i, sigma));
                let (o, s) = tyre
                    .step_between::<Libm>(&q, &self.opts, h, &a, &b, &self.operating(log, i))
                    .map_err(|e| (i, e.to_string()))?;
                (o, [s.kappa, s.alpha])
            };
            prev = sigma;
            let mut out = [o.fx, o.fy, o.mz];
            add(&mut out, mods, i);
            run.out.push(out);
            run.sigma.push(sigma);
            run.slips.push(slips);
        }
        Ok(run)
    }

    /// The filters alone with given relaxation lengths per row (the step from row i − 1 to i
    /// holds `sigma[i − 1]` → `sigma[i]` linearly, as in [`Sim::run`]): the slips `[κ', α']`
    /// per row; restarts as in [`Sim::run`]. Without filters (`sigma` all zero and the file has
    /// none) the log's slips.
    pub fn slips(&self, log: &Log, sigma: &[[f64; 2]]) -> Result<Vec<[f64; 2]>, RowError> {
        let n = log.len();
        let restart = log.restarts();
        let mut out = Vec::with_capacity(n);
        let s0 = sigma.first().copied().unwrap_or([0.0; 2]);
        let mut st = Transient::new(0.0);
        for i in 0..n {
            let s = sigma.get(i).copied().unwrap_or(s0);
            if restart.get(i).copied().unwrap_or(true) {
                st = self.init(log, i, s);
                out.push([log.kappa[i], log.alpha[i]]);
            } else {
                let p = sigma.get(i - 1).copied().unwrap_or(s0);
                out.push(self.advance(&mut st, log, i, p, s)?);
            }
        }
        Ok(out)
    }

    /// Evaluates the Magic Formula at the given slips on the selected rows only (the fast path
    /// of a fit: the slips are those of a run, or of [`Sim::slips`]).
    pub fn eval_rows(
        &self,
        log: &Log,
        params: &Params<f64>,
        slips: &[[f64; 2]],
        rows: &[usize],
        mods: &Mods,
    ) -> Result<Vec<Out>, RowError> {
        let mut q = params.clone();
        let base = [q.lmux, q.lmuy, q.lkx, q.lky];
        let mut res = Vec::with_capacity(rows.len());
        for &i in rows {
            set_lambda(&mut q, &base, mods, i);
            let s = slips
                .get(i)
                .copied()
                .unwrap_or([log.kappa[i], log.alpha[i]]);
            let inp = self.input(log, i, s[0], s[1]);
            let o = mf::eval::<f64, Libm>(&q, &inp, &self.opts)
                .map_err(|e| (i, format!("Magic Formula: {e}")))?;
            let mut out = [o.fx, o.fy, o.mz];
            add(&mut out, mods, i);
            res.push(out);
        }
        Ok(res)
    }
}

/// Relaxation lengths `[σκ, σα]` as the core's.
fn sigma_of(sigma: [f64; 2]) -> Sigma<f64> {
    Sigma {
        sigma_kappa: sigma[0],
        sigma_alpha: sigma[1],
    }
}

fn set_lambda(q: &mut Params<f64>, base: &[f64; 4], mods: &Mods, i: usize) {
    if let Some(l) = mods.lambda.and_then(|l| l.get(i)) {
        q.lmux = base[0] * l.mux;
        q.lmuy = base[1] * l.muy;
        q.lkx = base[2] * l.kx;
        q.lky = base[3] * l.ky;
    }
}

fn add(out: &mut Out, mods: &Mods, i: usize) {
    if let Some(a) = mods.add.and_then(|a| a.get(i)) {
        for c in 0..3 {
            out[c] += a[c];
        }
    }
}

/// φ1(x) = (1 − e^(−x))/x, with a series below 1e-3.
fn phi1(x: f64) -> f64 {
    if x < 1e-3 {
        1.0 - x * (0.5 - x * (1.0 / 6.0 - x / 24.0))
    } else {
        (1.0 - (-x).exp()) / x
    }
}

/// A first-order sensor lag τ·dy/dt + y = u over the log's time base, exact for an input that
/// is linear between samples (first-order hold): over a step h with x = h/τ,
/// `y1 = y0·e^(−x) + u0·(1 − e^(−x)) + (u1 − u0)·(1 − φ1(x))`, the ramp response. Starts in
/// steady state (y0 = u0). τ ≤ 0 returns the input.
pub fn lag(u: &[f64], t: &[f64], tau: f64) -> Vec<f64> {
    match u.first() {
        Some(&u0) if tau > 0.0 => lowpass_from(u, t, tau, u0),
        _ => u.to_vec(),
    }
}

/// The first-order low-pass of a signal, as [`lag`], but starting from `y0`.
pub fn lowpass_from(u: &[f64], t: &[f64], tau: f64, y0: f64) -> Vec<f64> {
    node_from(u, t, tau, None, y0)
}

/// A first-order node τ·dy/dt + h·y = u with a loss rate h per row (`None`: 1, [`lowpass_from`]),
/// from y0: over a step, h held at the mean of the step's two rows, x = h·dt/τ, the input
/// linear in time (exact for a first-order hold when h is constant):
/// `y1 = y0·e^(−x) + (u0/h)·(1 − e^(−x)) + ((u1 − u0)/h)·(1 − φ1(x))`. h is floored at 1e-6.
pub fn node_from(u: &[f64], t: &[f64], tau: f64, h: Option<&[f64]>, y0: f64) -> Vec<f64> {
    if u.is_empty() {
        return Vec::new();
    }
    let mut y = Vec::with_capacity(u.len());
    let mut yi = y0;
    y.push(yi);
    for i in 1..u.len().min(t.len()) {
        let hi = h.map_or(1.0, |h| 0.5 * (h[i - 1] + h[i])).max(1e-6);
        let x = hi * (t[i] - t[i - 1]) / tau.max(1e-9);
        let e = (-x).exp();
        yi = yi * e + u[i - 1] * (1.0 - e) / hi + (u[i] - u[i - 1]) * (1.0 - phi1(x)) / hi;
        y.push(yi);
    }
    y
}
