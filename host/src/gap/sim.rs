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
//! ## The continuous model, sampled
//! A log samples continuous signals. Between two rows the inputs of eq. (20) — the kinematics
//! **and** the relaxation lengths (σ at each row's load, γ, p) — follow the natural cubic spline
//! through the rows (`Path`: each stretch between restarts its own), and the filter advances
//! along it in sub-steps of at most a quarter of the relaxation time σ/|Vx| (the shorter of σκ,
//! σα at the step's two rows, at most `MAX_SUBSTEPS`), each the core's first-order hold
//! [`Transient::step_hold`] (forcing linear within the sub-step, integrated exactly; the core
//! sub-steps further where V/σ moves fast), the last one the core's
//! [`TransientTyre::step_between`] to the row, whose slips are formed with the row's own σ. At
//! high log rates a step is shorter than a quarter relaxation time and this is issue 40's single
//! hold between the rows; at 50 Hz the hold alone missed a log sampled from a 5 kHz truth by half
//! the noise, the spline by a tenth (docs/gap.md, "Any log rate"). σ does not depend on the slips,
//! so each row's σ comes from the Magic Formula's load stage at the log's slips
//! ([`gough::mf::relaxation_lengths`]: `eval`'s σ without the forces),
//! and between rows from the spline. Steps longer than [`gough::relax::MAX_DT`] are gaps.
//!
//! ## Gaps
//! A log with dropped rows has gaps in time. One dropped row is bridged by the interpolant
//! below; after a longer gap (a step longer than [`BRIDGED_STEPS`](super::log::BRIDGED_STEPS) ×
//! the log's median step, [`Log::restarts`]) the filter restarts in the steady state of that
//! row's slips, as at row 0.
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
#[cfg(feature = "lanes")]
use gough::mf::{BatchError, Columns, Isa, Outputs, Scales};
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
    /// Evaluation options (limits on; `transient` when the filters run; turn slip if used; no
    /// Mx, My).
    pub opts: Options,
    /// The relaxation-length filters run.
    pub filters: bool,
    /// Turn slip is evaluated (log has `phit`, file has turn-slip coefficients).
    pub turn_slip: bool,
    /// Transient-model settings (|Vx| damping, the file's DAMP_VLOW/VXLOW, σ floor 1 % R0).
    pub cfg: Config<f64>,
    /// [`Sim::eval_rows`] in lanes (`gough_lanes`, with the `lanes` feature: without it this is
    /// ignored); else row by row with `mf::eval`, the reference. On in optimised builds with the
    /// feature (without `debug_assertions`): there the lanes took a
    /// 20,000-row diagnosis from 40.9 to 26.6 s; the test builds compile them at `opt-level = 1`,
    /// where they are slower than `mf::eval` (the gap tests 4.5 s → 144 s), and keep to the
    /// reference (`host-tests/tests/gap.rs` checks the two against each other).
    pub lanes: bool,
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
        // Mx and My are not in a log's channels: not computed (five of about fifty kernel
        // calls of an evaluation; Fx, Fy, Mz do not depend on them).
        let opts = Options {
            transient: filters,
            turn_slip,
            moments: false,
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
            lanes: cfg!(feature = "lanes") && !cfg!(debug_assertions),
        }
    }

    /// [`Sim::new`] of `params` for `log`, evaluating as this sim does ([`Sim::lanes`]): the
    /// diagnosis's other sims (a refit, the corrected file, the μ section) take its path.
    pub fn like(&self, params: Params<f64>, log: &Log) -> Sim {
        Sim {
            lanes: self.lanes,
            ..Sim::new(params, log)
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

    /// [`Sim::input`] of row `i` at its slips in `slips` (the log's where `slips` is short).
    fn input_at(&self, log: &Log, slips: &[[f64; 2]], i: usize) -> Input<f64> {
        let [kappa, alpha] = slips
            .get(i)
            .copied()
            .unwrap_or([log.kappa[i], log.alpha[i]]);
        self.input(log, i, kappa, alpha)
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

    /// The relaxation lengths `[σκ, σα]` of row `i` under `q` (λ of the row set) and `mods`:
    /// σ does not depend on the slips (but for turn slip's load parts, taken at the log's
    /// slips): the Magic Formula's load stage for them ([`mf::relaxation_lengths`], `eval`'s σ
    /// without the forces), or nothing when they are given.
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
        let inp = self.input(log, i, log.kappa[i], log.alpha[i]);
        let (sx, sy) = mf::relaxation_lengths::<f64, Libm>(q, &inp, &self.opts)
            .map_err(|e| (i, format!("Magic Formula: {e}")))?;
        Ok(match mods.sigma {
            SigmaMode::Scaled(m) => {
                let m = m.get(i).copied().unwrap_or([1.0, 1.0]);
                [sx * m[0], sy * m[1]]
            }
            _ => [sx, sy],
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
    /// restart in steady state at row 0 and after every gap in time ([`Log::restarts`]). With
    /// [`Sim::lanes`] the filters run first ([`Sim::slips`]) and the Magic Formula over every
    /// row in one lane batch (the same slips to the bit, the forces within 1e-9·FNOMIN);
    /// else row by row, the core's `TransientTyre::step_between` (the filter, then `mf::eval`).
    pub fn run(&self, log: &Log, params: &Params<f64>, mods: &Mods) -> Result<Run, RowError> {
        let n = log.len();
        let filters = self.filters || matches!(mods.sigma, SigmaMode::Given(_));
        let restart = log.restarts();
        let mut q = params.clone();
        let base = [q.lmux, q.lmuy, q.lkx, q.lky];
        // σ of every row first (it does not depend on the slips): the interpolant between two
        // rows needs the rows around them.
        let mut sigma = Vec::with_capacity(n);
        for i in 0..n {
            set_lambda(&mut q, &base, mods, i);
            sigma.push(if filters {
                self.sigma_at(log, &q, mods, i)?
            } else {
                [0.0, 0.0]
            });
        }
        #[cfg(feature = "lanes")]
        if self.lanes {
            // The filters do not depend on the forces: the slips of every row first (the
            // filters alone, as `step_between` runs them), then every row's forces in one lane
            // batch.
            let slips = if filters {
                self.slips(log, &sigma)?
            } else {
                (0..n).map(|i| [log.kappa[i], log.alpha[i]]).collect()
            };
            let rows: Vec<usize> = (0..n).collect();
            let out = self.eval_rows_lanes(log, params, &slips, &rows, mods)?;
            return Ok(Run { out, sigma, slips });
        }
        let path = Path::new(log, &sigma, &restart);
        let mut run = Run {
            out: Vec::with_capacity(n),
            sigma: Vec::with_capacity(n),
            slips: Vec::with_capacity(n),
        };
        // The core's transient tyre: the filter, then the Magic Formula at its slips.
        let mut tyre = TransientTyre::new(params);
        tyre.config = self.cfg;
        for (i, &sg) in sigma.iter().enumerate() {
            set_lambda(&mut q, &base, mods, i);
            let fresh = restart.get(i).copied().unwrap_or(true);
            let (o, slips) = if !filters || fresh {
                if filters {
                    tyre.restart(sigma_of(sg), log.kappa[i], log.alpha[i].tan());
                }
                let inp = self.input(log, i, log.kappa[i], log.alpha[i]);
                let o = mf::eval::<f64, Libm>(&q, &inp, &self.opts)
                    .map_err(|e| (i, format!("Magic Formula: {e}")))?;
                (o, [log.kappa[i], log.alpha[i]])
            } else {
                // The hold from row i − 1 to row i along the interpolant, each sub-step's σ
                // its own; the last sub-step ends at row i with the Magic Formula.
                let (h, a) = path.substeps(&mut tyre.state, &self.cfg, i)?;
                let b = Sim::sample(log, i, sg);
                let (o, s) = tyre
                    .step_between::<Libm>(&q, &self.opts, h, &a, &b, &self.operating(log, i))
                    .map_err(|e| (i, e.to_string()))?;
                (o, [s.kappa, s.alpha])
            };
            let mut out = [o.fx, o.fy, o.mz];
            add(&mut out, mods, i);
            run.out.push(out);
            run.sigma.push(sg);
            run.slips.push(slips);
        }
        Ok(run)
    }

    /// The filters alone with given relaxation lengths per row (between rows along the spline of
    /// the kinematics and of `sigma`, in sub-steps, as in [`Sim::run`]): the slips `[κ', α']`
    /// per row; restarts as in [`Sim::run`]. Without filters (`sigma` all zero and the file has
    /// none) the log's slips.
    pub fn slips(&self, log: &Log, sigma: &[[f64; 2]]) -> Result<Vec<[f64; 2]>, RowError> {
        let n = log.len();
        let restart = log.restarts();
        let s0 = sigma.first().copied().unwrap_or([0.0; 2]);
        let sig: Vec<[f64; 2]> = (0..n)
            .map(|i| sigma.get(i).copied().unwrap_or(s0))
            .collect();
        let path = Path::new(log, &sig, &restart);
        let mut out = Vec::with_capacity(n);
        let mut st = Transient::new(0.0);
        for (i, &sg) in sig.iter().enumerate() {
            if restart.get(i).copied().unwrap_or(true) {
                st = self.init(log, i, sg);
                out.push([log.kappa[i], log.alpha[i]]);
            } else {
                let (h, a) = path.substeps(&mut st, &self.cfg, i)?;
                let b = Sim::sample(log, i, sg);
                let s = st
                    .step_hold::<Libm>(&self.cfg, h, &a, &b)
                    .map_err(|e| (i, format!("relaxation step: {e}")))?;
                out.push([s.kappa, s.alpha]);
            }
        }
        Ok(out)
    }

    /// Evaluates the Magic Formula at the given slips on the selected rows only (the fast path
    /// of a fit: the slips are those of a run, or of [`Sim::slips`]). With [`Sim::lanes`] one
    /// lane batch over the rows (`gough_lanes`, the core's `mf::eval_batch_lanes_scaled`), each
    /// row's λ multipliers its scales: every row within 1e-9·FNOMIN of `mf::eval` on that row's
    /// parameters (4.3e-15 over the MFeval oracle); else `mf::eval` row by row.
    pub fn eval_rows(
        &self,
        log: &Log,
        params: &Params<f64>,
        slips: &[[f64; 2]],
        rows: &[usize],
        mods: &Mods,
    ) -> Result<Vec<Out>, RowError> {
        #[cfg(feature = "lanes")]
        if self.lanes {
            return self.eval_rows_lanes(log, params, slips, rows, mods);
        }
        let mut q = params.clone();
        let base = [q.lmux, q.lmuy, q.lkx, q.lky];
        let mut res = Vec::with_capacity(rows.len());
        for &i in rows {
            set_lambda(&mut q, &base, mods, i);
            let inp = self.input_at(log, slips, i);
            let o = mf::eval::<f64, Libm>(&q, &inp, &self.opts)
                .map_err(|e| (i, format!("Magic Formula: {e}")))?;
            let mut out = [o.fx, o.fy, o.mz];
            add(&mut out, mods, i);
            res.push(out);
        }
        Ok(res)
    }

    /// [`Sim::eval_rows`] in one lane batch (`gough_lanes`).
    #[cfg(feature = "lanes")]
    fn eval_rows_lanes(
        &self,
        log: &Log,
        params: &Params<f64>,
        slips: &[[f64; 2]],
        rows: &[usize],
        mods: &Mods,
    ) -> Result<Vec<Out>, RowError> {
        let m = rows.len();
        // The inputs: fz, κ, α, γ, Vx, φt, p; the factors on λμx, λμy, λKx, λKy.
        let mut c: [Vec<f64>; 7] = std::array::from_fn(|_| Vec::with_capacity(m));
        let mut l: [Vec<f64>; 4] = std::array::from_fn(|_| Vec::with_capacity(m));
        for &i in rows {
            let inp = self.input_at(log, slips, i);
            let values = [
                inp.fz,
                inp.kappa,
                inp.alpha,
                inp.gamma,
                inp.vx,
                inp.phit,
                inp.p.unwrap_or(params.inflpres), // None means INFLPRES
            ];
            for (col, v) in c.iter_mut().zip(values) {
                col.push(v);
            }
            if let Some(lambda) = mods.lambda {
                let f = lambda.get(i).copied().unwrap_or(Lambda::ONE);
                for (col, v) in l.iter_mut().zip([f.mux, f.muy, f.kx, f.ky]) {
                    col.push(v);
                }
            }
        }
        let [fz, kappa, alpha, gamma, vx, phit, p] = &c;
        let columns = Columns {
            fz,
            kappa,
            alpha,
            gamma,
            vx,
            phit: self.turn_slip.then_some(phit.as_slice()),
            p: log.p.is_some().then_some(p.as_slice()),
        };
        let lambda = |k: usize| mods.lambda.is_some().then(|| l[k].as_slice());
        let scales = Scales {
            lmux: lambda(0),
            lmuy: lambda(1),
            lkx: lambda(2),
            lky: lambda(3),
        };
        let mut o: [Vec<f64>; 3] = std::array::from_fn(|_| vec![0.0; m]);
        let [fx, fy, mz] = &mut o;
        let mut out = Outputs {
            fx: Some(fx),
            fy: Some(fy),
            mz: Some(mz),
            ..Outputs::default()
        };
        gough_lanes::eval_batch_lanes_scaled(
            Isa::Auto,
            params,
            &columns,
            &scales,
            &self.opts,
            &mut out,
        )
        .map_err(|e| match e {
            BatchError::Point { index, error } => (
                rows.get(index).copied().unwrap_or(0),
                format!("Magic Formula: {error}"),
            ),
            e => (rows.first().copied().unwrap_or(0), e.to_string()),
        })?;
        Ok(rows
            .iter()
            .enumerate()
            .map(|(k, &i)| {
                let mut out = [o[0][k], o[1][k], o[2][k]];
                add(&mut out, mods, i);
                out
            })
            .collect())
    }
}

/// Sub-steps per relaxation time at most: a sub-step is at most a quarter of the shorter of
/// σα/|Vx| and σκ/|Vx| at its two rows (the time in which the tyre forgets its deflection).
const SUBSTEPS_PER_RELAXATION_TIME: f64 = 4.0;

/// At most this many sub-steps between two rows.
const MAX_SUBSTEPS: usize = 64;

/// The inputs of eq. (20) between the rows: the kinematics (Vx, Vsx, Vsy) and the relaxation
/// lengths (σκ, σα), each the natural cubic spline through the rows of its stretch between
/// restarts ([`spline_slopes`], evaluated as the cubic Hermite interpolant [`hermite`] with the
/// spline's slopes).
struct Path<'a> {
    t: &'a [f64],
    /// Per row: Vx, Vsx, Vsy, σκ, σα.
    y: Vec<[f64; 5]>,
    /// Their slopes in time.
    d: Vec<[f64; 5]>,
}

impl<'a> Path<'a> {
    fn new(log: &'a Log, sigma: &[[f64; 2]], restart: &[bool]) -> Path<'a> {
        let n = log.len();
        let y: Vec<[f64; 5]> = (0..n)
            .map(|i| {
                let (vsx, vsy) = log.slip_velocity(i);
                let s = sigma.get(i).copied().unwrap_or([0.0; 2]);
                [log.vx[i], vsx, vsy, s[0], s[1]]
            })
            .collect();
        // Each stretch between restarts its own spline.
        let mut d = vec![[0.0; 5]; n];
        let mut a = 0;
        while a < n {
            let mut b = a + 1;
            while b < n && !restart.get(b).copied().unwrap_or(true) {
                b += 1;
            }
            for c in 0..5 {
                let yc: Vec<f64> = y[a..b].iter().map(|r| r[c]).collect();
                for (k, v) in spline_slopes(&log.t[a..b], &yc).into_iter().enumerate() {
                    d[a + k][c] = v;
                }
            }
            a = b;
        }
        Path { t: &log.t, y, d }
    }

    /// The interpolant at fraction `w` of the step from row `i − 1` to row `i`.
    fn at(&self, i: usize, w: f64) -> Sample<f64> {
        let h = self.t[i] - self.t[i - 1];
        let v: [f64; 5] = std::array::from_fn(|c| {
            hermite(
                self.y[i - 1][c],
                self.y[i][c],
                self.d[i - 1][c] * h,
                self.d[i][c] * h,
                w,
            )
        });
        Sample {
            kin: Kinematics {
                vx: v[0],
                vsx: v[1],
                vsy: v[2],
            },
            sigma: Sigma {
                // (A cubic may undershoot between two small σ; the core floors it.)
                sigma_kappa: v[3].max(0.0),
                sigma_alpha: v[4].max(0.0),
            },
        }
    }

    /// Sub-steps the deflections `st` along the interpolant from row `i − 1` to the start of
    /// the step's last sub-step (a quarter of the relaxation time each, [`MAX_SUBSTEPS`] at
    /// most); returns that last sub-step's length and its start's inputs, for the caller's
    /// final step to row `i`.
    fn substeps(
        &self,
        st: &mut Transient<f64>,
        cfg: &Config<f64>,
        i: usize,
    ) -> Result<(f64, Sample<f64>), RowError> {
        let h = self.t[i] - self.t[i - 1];
        let tau = |r: &[f64; 5]| {
            let v = r[0].abs();
            let s = r[3].min(r[4]).max(cfg.sigma_min);
            if v > 0.0 {
                s / v
            } else {
                f64::INFINITY
            }
        };
        let t_relax = tau(&self.y[i - 1]).min(tau(&self.y[i]));
        let m = if t_relax.is_finite() && t_relax > 0.0 {
            ((h * SUBSTEPS_PER_RELAXATION_TIME / t_relax).ceil() as usize).clamp(1, MAX_SUBSTEPS)
        } else {
            1
        };
        let hs = h / m as f64;
        let mut a = self.at(i, 0.0);
        for j in 1..m {
            let b = self.at(i, j as f64 / m as f64);
            st.step_hold::<Libm>(cfg, hs, &a, &b)
                .map_err(|e| (i, format!("relaxation step: {e}")))?;
            a = b;
        }
        Ok((hs, a))
    }
}

/// The slopes at the knots `t` of the natural cubic spline through `y` (twice differentiable;
/// zero second derivative at the ends): the tridiagonal system of the slopes' continuity
/// conditions, solved by elimination. One knot: slope 0; two: the secant.
fn spline_slopes(t: &[f64], y: &[f64]) -> Vec<f64> {
    let n = t.len().min(y.len());
    if n < 2 {
        return vec![0.0; n];
    }
    let h: Vec<f64> = (0..n - 1).map(|k| t[k + 1] - t[k]).collect();
    let del: Vec<f64> = (0..n - 1).map(|k| (y[k + 1] - y[k]) / h[k]).collect();
    // Rows: sub·d[k−1] + diag·d[k] + sup·d[k+1] = rhs.
    let (mut sub, mut diag, mut sup, mut rhs) =
        (vec![0.0; n], vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    diag[0] = 2.0;
    sup[0] = 1.0;
    rhs[0] = 3.0 * del[0];
    for k in 1..n - 1 {
        sub[k] = h[k];
        diag[k] = 2.0 * (h[k - 1] + h[k]);
        sup[k] = h[k - 1];
        rhs[k] = 3.0 * (h[k] * del[k - 1] + h[k - 1] * del[k]);
    }
    sub[n - 1] = 1.0;
    diag[n - 1] = 2.0;
    rhs[n - 1] = 3.0 * del[n - 2];
    // Thomas algorithm (the matrix is diagonally dominant).
    for k in 1..n {
        let m = sub[k] / diag[k - 1];
        diag[k] -= m * sup[k - 1];
        rhs[k] -= m * rhs[k - 1];
    }
    let mut d = vec![0.0; n];
    d[n - 1] = rhs[n - 1] / diag[n - 1];
    for k in (0..n - 1).rev() {
        d[k] = (rhs[k] - sup[k] * d[k + 1]) / diag[k];
    }
    d
}

/// The cubic Hermite interpolant between `y0` and `y1` with end slopes `m0`, `m1` (per unit of
/// the step) at fraction `w` of the step.
fn hermite(y0: f64, y1: f64, m0: f64, m1: f64, w: f64) -> f64 {
    let (w2, w3) = (w * w, w * w * w);
    (2.0 * w3 - 3.0 * w2 + 1.0) * y0
        + (w3 - 2.0 * w2 + w) * m0
        + (-2.0 * w3 + 3.0 * w2) * y1
        + (w3 - w2) * m1
}

/// Relaxation lengths `[σκ, σα]` as the core's.
fn sigma_of(sigma: [f64; 2]) -> Sigma<f64> {
    Sigma {
        sigma_kappa: sigma[0],
        sigma_alpha: sigma[1],
    }
}

/// Row `i`'s λ multipliers on `base` into `q`; a row past the end of `mods.lambda` has the
/// file's (1), as in the lanes' scales.
fn set_lambda(q: &mut Params<f64>, base: &[f64; 4], mods: &Mods, i: usize) {
    if let Some(lambda) = mods.lambda {
        let l = lambda.get(i).copied().unwrap_or(Lambda::ONE);
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The spline through a straight line is the line (every slope its slope), on an uneven
    /// grid; through a sine sampled at 5 rows a period (jittered) it is within 2 % of the sine's
    /// amplitude, where the straight line between rows misses by 19 %.
    #[test]
    fn the_spline_holds_a_line_and_follows_a_sine_between_rows() {
        let t: Vec<f64> = (0..40)
            .map(|i| i as f64 * 0.02 + 0.002 * ((i * 7 % 5) as f64 - 2.0))
            .collect();
        let line: Vec<f64> = t.iter().map(|x| 3.0 - 2.0 * x).collect();
        for d in spline_slopes(&t, &line) {
            assert!((d + 2.0).abs() < 1e-9, "{d}");
        }
        let w = std::f64::consts::TAU * 10.0; // 10 Hz at ~50 Hz: 5 rows a period
        let y: Vec<f64> = t.iter().map(|x| (w * x).sin()).collect();
        let d = spline_slopes(&t, &y);
        let (mut spline, mut linear) = (0.0f64, 0.0f64);
        // Away from the natural ends.
        for i in 6..34 {
            let h = t[i] - t[i - 1];
            for k in 1..10 {
                let f = k as f64 / 10.0;
                let truth = (w * (t[i - 1] + f * h)).sin();
                let s = hermite(y[i - 1], y[i], d[i - 1] * h, d[i] * h, f);
                spline = spline.max((s - truth).abs());
                linear = linear.max((y[i - 1] + f * (y[i] - y[i - 1]) - truth).abs());
            }
        }
        assert!(
            spline < 0.02 && linear > 0.15,
            "spline {spline}, linear {linear}"
        );
    }
}
