//! The bank: one wheel's friction estimator, tying the batches ([`crate::mu::batch`]), the
//! cells' fits ([`crate::mu::fit`]), their likelihoods ([`crate::mu::likelihood`]) and the
//! estimate ([`crate::mu::estimate`]) together, with the scheduler that spreads a batch's fit
//! over the next batch's samples.
//!
//! ## Scheduling
//! A batch's cells are fitted over the next batch's samples, `⌈active cells/batch⌉` per sample
//! (at least [`SLOTS`] slots of a cell's fit per sample), so that the work per sample is
//! bounded. Which cells (`Bank::select`): none without excitation (the batch is no evidence,
//! and the slips need not follow); otherwise every cell still in contention (ℓ below the
//! switching cap), the best cell's neighbours, and every [`VISIT`]th of the others in turn (so
//! that a surface excluded long ago is looked at again within [`VISIT`] batches; in between its
//! last χ² stands).
//!
//! Each batch's fit starts with the likeliest cell: when it no longer explains the new batch
//! (χ² above `chi2_identifiable`), an identifiable estimate is withdrawn then (its value held),
//! on the first sample of the fit rather than when the batch's fit is finished, and every cell
//! is fitted on that batch, as on a cold start: a cell out of contention is otherwise fitted on
//! every [`VISIT`]th batch, its last χ² standing in between, and after a change of surface those
//! χ² and its slips describe the old road (`gough mu bench`: the slalom onto μ 0.3 read on the
//! front-left in 93 ms instead of 251 ms, the rear-left in 209 ms instead of 389 ms).
//!
//! A reading from ahead ([`Bank::preview`], [`crate::mu::preview`]) takes a slot of a sample's
//! work as a cell's fit does: it waits for the first the batch's fit can spare, a sample at most.
//!
//! The calibration's slopes at the likeliest cell (the variance of μ its σ leaves, and its step,
//! each at most every `cal_period`: as much work as two cells' fits) are taken in pieces — the
//! residuals, then one property's column each — in the slots the batch's fit leaves free, from
//! the sample that fits that cell on, when the finish will want them (`Bank::wants_slopes`);
//! the cell's slips and the load stage do not change until the finish, so the pieces are what
//! the finish would compute. Those the slots had no room for, the finish takes — or, when a
//! sample before the next batch closes is left, that sample, with the variance and the step
//! (the variance then reaches the estimate a batch later; only on the device's rates, 10
//! samples a batch: at 200 Hz the finish is on the sample that closes the next batch).
//!
//! ## Cost
//! Bounded per sample, no allocation: each fit is one Magic Formula evaluation with the slip
//! derivatives and one without (the trial; none for a small step), plus one more for a poorly
//! fitting cell (at most [`RESEEDS`](crate::mu::RESEEDS) per batch, and those in contention).
//! M4F, `Fast`: see docs/estimator.md ("Cost on the device") for the figures the firmware
//! bench measures.

use super::batch::{Batch, Batcher, Sample, MAX_GAP_US};
use super::calibration::{
    mu_slopes, Calibration, CalibrationError, Exported, Surface, NUISANCES, PROPERTIES,
};
use super::config::{mu_y0, Config, Grid, CELLS};
use super::estimate::State;
use super::estimate::{Estimate, Report};
use super::fit::Fit;
use super::likelihood::Likelihood;
use super::preview::Reading;
use crate::math::{Backend, Float};
use crate::mf::{Params, Side};

/// The calibration's slopes at the likeliest cell ([`crate::mu::fit::Fit::calibration_slopes`]):
/// the normalised residuals, their slopes in the properties and in the nuisances.
type Slopes<F> = ([F; 4], [[F; PROPERTIES]; 4], [[F; NUISANCES]; 4]);

/// A cell out of contention is fitted on every `VISIT`th batch (and on every batch the likeliest
/// cell does not explain).
pub const VISIT: usize = 4;

/// A sample's work ([`Bank::update`]): at least this many slots of a cell's fit (one for a
/// reading from ahead, one for the load stage on a sample that closes a batch).
pub const SLOTS: usize = 3;

/// Why an estimator could not be built.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum BuildError {
    /// The model's μy0 at FNOMIN is not a positive number (nonsense parameters).
    NoFriction,
    /// The grid of hypotheses is empty or not positive (`mu_lo`, `mu_step`, `mu_hi_rel`),
    /// `batch_us` is 0, or the calibration's σ, time or bound are not positive.
    BadConfig,
}

impl core::fmt::Display for BuildError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            BuildError::NoFriction => "the tyre model has no positive friction at FNOMIN",
            BuildError::BadConfig => "the estimator's grid or batch is not positive",
        })
    }
}

impl core::error::Error for BuildError {}

/// What one [`Bank::update`]'s calls of `work` did (tests of the per-sample budget).
#[cfg(test)]
#[derive(Debug, Clone, Copy, PartialEq, Default)]
struct WorkTrace {
    /// Cells fitted over the update.
    fits: usize,
    /// Cells fitted by the calls that finish a batch that did not end before the next closed.
    forced_fits: usize,
    /// The most cells fitted (and readings mixed in) by one call.
    load: usize,
    /// The same, over the calls that also finished their batch.
    load_finishing: usize,
    /// A call refitted every cell (the likeliest did not explain the batch).
    refit: bool,
    /// A reading that had waited a sample was mixed in, in a slot of its own.
    own_slot: bool,
}

/// The calibration's slopes at the pending batch's likeliest cell, taken in pieces in the
/// slots the batch's fit leaves free ([`Bank::work`]) when its finish will want them: the
/// residuals and their slopes in the nuisances, then one property's column per piece. The
/// cell's slips and the batch's load stage do not change after the cell's fit until the batch
/// is finished, so the pieces give what the finish would have computed.
#[derive(Debug, Clone, Copy)]
struct SlopeJob<F> {
    /// Pieces taken: 0 none, 1 the residuals, 1 + j + 1 the column of property j too.
    pieces: u8,
    /// A piece failed (no load stage, an evaluation that failed): no slopes.
    failed: bool,
    r0: [F; 4],
    h_cal: [[F; PROPERTIES]; 4],
    h_nuis: [[F; NUISANCES]; 4],
}

/// What a batch's finish leaves to the next sample when the calibration's slopes it wants are
/// not all taken yet and a sample before the next batch closes can take them
/// ([`Bank::calibrate_deferred`]): the rest of the slopes at the likeliest cell, the variance of
/// μ they give (`sys`) and the calibration's drift and Kalman step (`step`: the nuisances' prior
/// variances). The cell's slips and the batch's load stage stay those of the finish until the
/// next batch closes.
#[derive(Debug, Clone, Copy)]
struct Deferred<F> {
    /// The likeliest cell and its batch.
    k: u8,
    b: Batch<F>,
    /// Whether to take the variance of μ the calibration's σ leaves (`sys_var`).
    sys: bool,
    /// The drift's time \[s\] (the drift comes between the variance and the step, as on a
    /// finish).
    drift: F,
    /// The step, when one is due.
    step: Option<CalStep<F>>,
}

/// A calibration step that is due: with the batch's road a nuisance of its own (the prior
/// variances of α′, κ′, μ), or with the road the calibration's state (`Config::cal_joint`: the
/// slips' prior variances and the surface the residuals are taken at).
#[derive(Debug, Clone, Copy)]
enum CalStep<F> {
    Apart([F; NUISANCES]),
    Joint { slips: [F; 2], mu_lin: F },
}

/// A [`SlopeJob`]'s pieces: the residuals, then a column per property.
const SLOPE_PIECES: u8 = 1 + PROPERTIES as u8;

/// One wheel's friction estimator. A few hundred bytes of state and a reference to the tyre's
/// parameters; no allocation; bounded work per sample.
#[derive(Debug, Clone)]
pub struct Bank<F> {
    cfg: Config<F>,
    batches: Batcher<F>,
    fit: Fit<F>,
    likelihood: Likelihood<F>,
    report: Report<F>,
    /// The batch being fitted, the next cell to fit.
    pending: Option<Batch<F>>,
    next: usize,
    /// Where the round robin of re-seeds starts.
    reseed_from: usize,
    /// The cells fitted in the pending batch, and how many (see [`Bank::select`]).
    active: [bool; CELLS],
    n_active: usize,
    /// Batches so far (modulo [`VISIT`]), for the visits of far cells.
    round: usize,
    /// The cell fitted first in the pending batch (the likeliest), if not yet fitted.
    first: Option<u8>,
    /// The cell fitted first, skipped in the rotation.
    skip: Option<u8>,
    /// Cells of the pending batch fitted so far.
    fitted: usize,
    /// A reading from ahead ([`Bank::preview`]) not yet mixed in: it takes one of a sample's
    /// slots in [`Bank::work`], as a cell's fit does.
    mixing: Option<Reading<F>>,
    /// Whether that reading has waited a sample for a slot.
    mix_waited: bool,
    /// The tyre on the car relative to its file ([`crate::mu::calibration`]).
    cal: Calibration<F>,
    /// The road under the calibration's steps (its own state, shared across batches).
    surface: Surface<F>,
    /// A road whose μ the user knows ([`Bank::set_known_surface`]): its nearest cell and μ.
    known: Option<(u8, F)>,
    /// On a known road: excited batches, and those it explained (χ² ≤ `chi2_explain`).
    known_batches: (u32, u32),
    /// Running maximum and minimum of |F|/Fz over the last `cal_sweep_time` (the sweep that
    /// lets a batch away from the linear range calibrate).
    f_hi: F,
    f_lo: F,
    /// Time the estimate has been identifiable without a change \[s\].
    ident_s: F,
    /// Time since the calibration's last step \[s\].
    cal_wait: F,
    /// The variance of μ the calibration's σ leaves at the latest operating point (its slopes
    /// there, at most every `cal_period`), and the time since they were last taken \[s\].
    sys_var: F,
    sys_wait: F,
    /// The likeliest surface's χ², averaged over the recent excited batches (the mismatch
    /// indication).
    fit_avg: F,
    /// The calibration's slopes the pending batch's finish will want, as far as taken.
    slope_job: Option<SlopeJob<F>>,
    /// The calibration's work a finish left to the next sample.
    deferred: Option<Deferred<F>>,
    /// What the last [`Bank::update`]'s work did (tests of the per-sample budget).
    #[cfg(test)]
    trace: WorkTrace,
}

impl<F: Float> Bank<F> {
    /// An estimator for a wheel with tyre `params` mounted on `side` (mirrored as `mf::eval`
    /// mirrors with `Options::mounted`; `None`: as the file describes it).
    ///
    /// The bank keeps no reference to `params`: [`Bank::update`] takes them with each sample
    /// (so that a device can own its parameters and its estimators side by side). Pass the same
    /// parameters every time; after loading others, build a new bank.
    pub fn new<M: Backend<F>>(
        params: &Params<F>,
        side: Option<Side>,
        cfg: Config<F>,
    ) -> Result<Self, BuildError> {
        if !cfg.usable() {
            return Err(BuildError::BadConfig);
        }
        let mu_y0 = mu_y0::<F, M>(params).ok_or(BuildError::NoFriction)?;
        let r0 = if params.unloaded_radius > F::ZERO {
            params.unloaded_radius
        } else {
            // A file without a radius (not one the reader accepts): a car's.
            F::from_f64(0.3)
        };
        Ok(Bank {
            cfg,
            batches: Batcher::new(&cfg, params.fnomin, r0),
            fit: Fit::new(&cfg, params, side, mu_y0),
            likelihood: Likelihood::new(),
            report: Report::new(&cfg),
            pending: None,
            next: 0,
            reseed_from: 0,
            active: [false; CELLS],
            n_active: 0,
            round: 0,
            first: None,
            skip: None,
            fitted: 0,
            mixing: None,
            mix_waited: false,
            cal: Calibration::file(&cfg.cal_sigma),
            surface: Surface::unknown(),
            known: None,
            known_batches: (0, 0),
            f_hi: F::ZERO,
            f_lo: F::ZERO,
            ident_s: F::ZERO,
            cal_wait: F::ZERO,
            sys_var: F::ZERO,
            sys_wait: F::ZERO,
            fit_avg: F::ZERO,
            slope_job: None,
            deferred: None,
            #[cfg(test)]
            trace: WorkTrace::default(),
        })
    }

    /// The calibration of the tyre on the car ([`crate::mu::calibration`]).
    pub fn calibration(&self) -> &Calibration<F> {
        &self.cal
    }

    /// Starts from calibration `c` (one exported earlier, [`Bank::import_calibration`] for its
    /// values and σ): from the next batch on the surfaces are read relative to it. Refused,
    /// nothing changed, when a number is not finite or a value lies beyond its bound
    /// (`cal_bound` prior σ).
    pub fn set_calibration<M: Backend<F>>(
        &mut self,
        c: &Calibration<F>,
    ) -> Result<(), CalibrationError> {
        let ok = c.theta.iter().all(|x| x.is_finite())
            && c.cov.iter().all(|r| r.iter().all(|x| x.is_finite()))
            && c.cov
                .iter()
                .enumerate()
                .all(|(i, r)| r.get(i).is_some_and(|d| *d >= F::ZERO));
        if !ok {
            return Err(CalibrationError::NotFinite);
        }
        // The last finish's step first: `c` replaces the calibration it moved.
        self.calibrate_deferred::<M>();
        for (t, s) in c.theta.iter().zip(self.cfg.cal_sigma.iter()) {
            if t.abs() > self.cfg.cal_bound * *s {
                return Err(CalibrationError::OutOfBounds);
            }
        }
        self.cal = *c;
        Ok(())
    }

    /// Calibrates on a road whose μ is known (`Some(μ)`, on the file's scale, as the estimate
    /// reports it), e.g. a log of a test track: the surface each calibration step takes is that
    /// road, held exactly ([`Calibration::step_joint`] with the road's variance zero), the cell
    /// nearest it is fitted first on every batch and linearised at, and a step is due on every
    /// excited batch that cell explains (χ² ≤ `chi2_explain`), at most every `cal_period`.
    /// The sweep and identification gates of the online calibration are not needed: the road
    /// is not a nuisance. `None` (the default) returns to the online calibration. Refused
    /// (`false`, nothing changed) for a μ that is not finite or outside the bank's grid.
    ///
    /// The estimate is reported as always; what `gough mu calibrate` reads is
    /// [`Bank::calibration`].
    pub fn set_known_surface(&mut self, mu: Option<F>) -> bool {
        self.known_batches = (0, 0);
        let Some(mu) = mu else {
            self.known = None;
            return true;
        };
        let grid = self.fit.grid();
        let top = grid.mu_of(CELLS - 1);
        if !(mu.is_finite() && mu > F::ZERO && mu <= top) {
            return false;
        }
        match u8::try_from(grid.cell_of(mu)) {
            Ok(k) => {
                self.known = Some((k, mu));
                true
            }
            Err(_) => false,
        }
    }

    /// On a known road ([`Bank::set_known_surface`], since it was set): the excited batches,
    /// and how many of them the road explained (χ² ≤ `chi2_explain` at its cell). A log that is
    /// not of that road shows as a small share explained.
    pub fn known_surface_batches(&self) -> (u32, u32) {
        self.known_batches
    }

    /// Starts from a calibration exported earlier as values and σ ([`Calibration::export`]);
    /// see [`Bank::set_calibration`].
    pub fn import_calibration<M: Backend<F>>(
        &mut self,
        e: &Exported,
    ) -> Result<(), CalibrationError> {
        let c = Calibration::import::<M>(e, &self.cfg.cal_sigma, self.cfg.cal_bound)?;
        self.calibrate_deferred::<M>();
        self.cal = c;
        Ok(())
    }

    /// The sensors' noise as the bank tracks it (Fx/Fz, Fy/Fz, Mz \[N·m\], κ), beside the
    /// configured start in `Config` (the online check of `sigma_f_rel`, `sigma_mz_rel`,
    /// `sigma_kappa`).
    pub fn noise<M: Backend<F>>(&self) -> [F; 4] {
        let n = self.batches.noise();
        [
            n.sigma::<M>(0),
            n.sigma::<M>(1),
            n.sigma::<M>(2),
            n.sigma::<M>(3),
        ]
    }

    /// The grid of surface hypotheses of this tyre.
    pub fn grid(&self) -> &Grid<F> {
        self.fit.grid()
    }

    /// μy0 of the tyre: μ of its test surface.
    pub fn mu0(&self) -> F {
        self.fit.mu_y0()
    }

    /// The settings.
    pub fn config(&self) -> &Config<F> {
        &self.cfg
    }

    /// Samples refused so far (not finite, Fz ≤ 0, a timestamp that does not advance).
    pub fn bad_samples(&self) -> u32 {
        self.batches.bad()
    }

    /// Per cell: μ, α′, κ′, ℓ and the last batch's χ² (for diagnosis and the bench).
    pub fn cells(&self) -> [(F, F, F, F, F); CELLS] {
        let mut out = [(F::ZERO, F::ZERO, F::ZERO, F::ZERO, F::ZERO); CELLS];
        let cells = self.fit.cells().iter().zip(self.fit.chi2().iter());
        for (k, ((o, (c, x)), l)) in out
            .iter_mut()
            .zip(cells)
            .zip(self.likelihood.nll.iter())
            .enumerate()
        {
            *o = (self.fit.mu_c(k), c.alpha, c.kappa, *l, *x);
        }
        out
    }

    /// The estimate of the last [`Bank::update`] (its `change` set only on that update).
    pub fn current(&self) -> Estimate<F> {
        self.report.current()
    }

    /// Distance \[m\] rolled between the last identifiable estimate before the current one and
    /// the current one: on a change of surface ([`Estimate::change`]), about how far back the
    /// old surface's reading ended — where this wheel met the new one.
    pub fn identification_gap(&self) -> F {
        self.report.identification_gap()
    }

    /// The likelihood profile: ℓ per cell, the likeliest at 0 — what a wheel that follows this
    /// one on its track takes in ([`crate::mu::preview`]) when it gets here.
    pub fn profile(&self) -> [F; CELLS] {
        self.likelihood.nll
    }

    /// Takes in a reading of the surface this wheel is running onto ([`crate::mu::preview`]:
    /// another wheel's [`Bank::profile`] where it ran over the same place, with the probability
    /// that it applies here). Its own batches then confirm or overrule it; the estimate follows
    /// at the end of the batch being fitted.
    ///
    /// The reading is not mixed in here: it waits for a slot in the next samples' work (it
    /// costs about half a cell's fit; [`Bank::update`] gives it a slot of its own, or the first
    /// it can spare without pushing the batch's last fits onto the sample that closes the next
    /// batch — within a few samples, all mixed before the batch's estimate). While one waits
    /// ([`Bank::previewing`]) a second one first mixes the waiting one in, at once: hand one
    /// per sample, as [`crate::mu::preview::Preview::rear`] does.
    pub fn preview<M: Backend<F>>(&mut self, reading: Reading<F>) {
        self.mix_waiting::<M>();
        self.mixing = Some(reading);
    }

    /// Whether a reading from ahead ([`Bank::preview`]) waits to be mixed in.
    pub fn previewing(&self) -> bool {
        self.mixing.is_some()
    }

    /// Takes one sample of a wheel with tyre `params` (those the bank was built with) and
    /// returns the current estimate.
    pub fn update<M: Backend<F>>(&mut self, params: &Params<F>, s: &Sample<F>) -> Estimate<F> {
        self.report.begin_sample();
        #[cfg(test)]
        {
            self.trace = WorkTrace::default();
        }
        // Spread the pending batch's fit over this sample.
        self.work::<M>();
        let Some(dt_us) = self.batches.admit(&self.cfg, s) else {
            return self.report.current();
        };
        if dt_us > MAX_GAP_US {
            // The batch restarted: the evidence ages by the gap.
            self.age::<M>(F::from_micros(dt_us), F::ZERO);
        }
        if !self.batches.push::<M>(&self.cfg, s, dt_us) {
            return self.report.current();
        }
        let f_rel = self.batches.noise().sigma::<M>(1);
        self.report
            .check_force::<M>(&self.cfg, self.batches.sums(), f_rel);
        if let Some(b) = self.batches.close::<M>(&self.cfg) {
            if self.pending.is_some() {
                // The previous batch's fit did not finish (cannot happen with ⌈CELLS/batch⌉
                // cells per sample); finish it now rather than lose it.
                while self.pending.is_some() {
                    #[cfg(test)]
                    let before = self.trace.fits;
                    self.work::<M>();
                    #[cfg(test)]
                    {
                        self.trace.forced_fits += self.trace.fits - before;
                    }
                }
            }
            // The last finish's calibration work, if no sample since took it (before the cells'
            // slips move and the next load stage takes the calibration).
            self.calibrate_deferred::<M>();
            // Every cell's κ′ follows the measured κ′ from batch to batch (its own offset kept).
            if let Some(d) = self.batches.kappa_step::<M>(&b) {
                self.fit.follow_kappa(d);
            }
            self.select(&b);
            self.slope_job = None;
            let adjust = self.cal.adjust::<M>();
            let sx = self
                .fit
                .prepare::<M>(params, &adjust, (self.n_active > 0).then_some(&b));
            if let Some(sx) = sx {
                self.batches.set_sigma_kappa(sx);
            }
            // The next batches' σ in this load's scales and the calibration's trail.
            let trail_var = self.cal.cov.first().and_then(|r| r.first()).copied();
            self.batches
                .set_scales(self.fit.kappa_scale(), trail_var.unwrap_or(F::ZERO));
            if self.fit.prepared() {
                self.pending = Some(b);
            } else {
                // Nothing to fit (no excitation, or no contact): the evidence only ages.
                self.finish::<M>(&b);
            }
            self.next = 0;
            self.fitted = 0;
        }
        self.report.current()
    }

    /// Chooses the cells to fit on batch `b` (see the module's "Scheduling"); [`Bank::work`]
    /// adds the others when the likeliest cell does not explain the batch.
    fn select(&mut self, b: &Batch<F>) {
        let excited = b.excited(&self.cfg);
        self.round = (self.round + 1) % VISIT;
        let best = match self.known {
            Some((k, _)) => usize::from(k),
            None => self.likelihood.best(),
        };
        let cap = self.cfg.switch_nll - F::HALF;
        self.n_active = 0;
        for (k, (a, l)) in self
            .active
            .iter_mut()
            .zip(self.likelihood.nll.iter())
            .enumerate()
        {
            *a = excited && (*l < cap || k.abs_diff(best) <= 2 || k % VISIT == self.round);
            self.n_active += usize::from(*a);
        }
        self.first = u8::try_from(best).ok().filter(|_| excited);
        self.skip = None;
    }

    /// Fits cell `k` on batch `b`; returns its χ².
    fn fit_cell<M: Backend<F>>(&mut self, k: usize, b: &Batch<F>) -> F {
        let nll = self.likelihood.get(k).unwrap_or(F::ZERO);
        self.fit.fit_cell::<M>(&self.cfg, k, nll, b)
    }

    /// Fits the next cells of the pending batch (and mixes in a waiting reading from ahead);
    /// finishes the batch after the last.
    ///
    /// A sample has `per` = ⌈active cells/batch⌉ slots of a cell's fit, at least [`SLOTS`]; the
    /// sample that closes a batch spends one on the load stage of the next, and the batch's
    /// finish takes one (a sample whose fits filled its slots leaves it to the next sample).
    /// The batch's first sample fits the likeliest cell before it plans the mixture: that
    /// cell's χ² may call for every cell (and ⌈CELLS/batch⌉ fits per sample). A waiting reading
    /// takes a free slot, or one of this sample's fits if the samples before the closing one
    /// have room for it; otherwise it waits for the next sample, and no longer (then it takes a
    /// slot of its own: with one sample per batch every sample closes one).
    fn work<M: Backend<F>>(&mut self) {
        // The last finish's calibration work first (the batch's fit ended before).
        self.calibrate_deferred::<M>();
        let batch = usize::from(self.batches.per_batch().max(1));
        let Some(b) = self.pending else {
            self.mix_waiting::<M>();
            return;
        };
        let mut per = self.n_active.div_ceil(batch).max(1);
        let mut fits = per;
        let mut done = 0;
        // The likeliest cell first: when it no longer explains the new batch, an identifiable
        // estimate is withdrawn on the batch's first fitted sample instead of after the last.
        if let Some(k8) = self.first.take() {
            let k = usize::from(k8);
            done += 1;
            self.fitted += 1;
            self.skip = Some(k8);
            let chi2 = self.fit_cell::<M>(k, &b);
            // (NaN counts as not explained.)
            let explains = chi2 <= self.cfg.chi2_identifiable;
            if !explains {
                self.report.withdraw();
            }
            if self.wants_slopes::<M>(&b, chi2) {
                self.slope_job = Some(SlopeJob {
                    pieces: 0,
                    failed: false,
                    r0: [F::ZERO; 4],
                    h_cal: [[F::ZERO; PROPERTIES]; 4],
                    h_nuis: [[F::ZERO; NUISANCES]; 4],
                });
            }
            // Nor are the other cells' last χ² evidence any longer (a cell out of contention
            // keeps its last one between visits, and its slips are as old): the road may have
            // changed, so every cell is fitted on this batch, as on a cold start — this sample
            // and the next ones take ⌈CELLS/batch⌉ fits each, so that the batch's fit ends
            // before the next batch closes (the mixture below plans with them).
            if !explains && self.n_active < CELLS {
                self.active = [true; CELLS];
                self.n_active = CELLS;
                per = CELLS.div_ceil(batch);
                fits = per;
                #[cfg(test)]
                {
                    self.trace.refit = true;
                }
            }
        }
        let slots = per.max(SLOTS);
        let mut mixed = false;
        if self.mixing.is_some() {
            let n = usize::from(self.batches.sums().n);
            let closing = usize::from(n + 1 >= batch);
            // Cells still to fit (the likeliest, if fitted above, is counted in `done`).
            let left = self.n_active.saturating_sub(self.fitted);
            let planned = fits.saturating_sub(done).min(left);
            let room = slots > done + planned + closing;
            // One fit fewer now: the samples after this one, short of the closing one, take it.
            let later = batch.saturating_sub(n + 2);
            let spare = closing == 0 && done + planned > 1 && per * later > left - planned;
            // (A reading that waited a sample already is mixed in now, in a slot of its own:
            // with one sample per batch every sample closes one, and no later one has room.)
            if room || spare || self.mix_waited {
                if !room && spare {
                    fits = done + planned - 1;
                }
                #[cfg(test)]
                {
                    self.trace.own_slot |= !room && !spare;
                }
                mixed = true;
                self.mix_waiting::<M>();
            } else {
                self.mix_waited = true;
            }
        }
        while self.next < CELLS && done < fits {
            // Rotated order, so that the re-seeds of successive batches go to different cells.
            let k = (self.next + self.reseed_from) % CELLS;
            self.next += 1;
            if self.skip.map(usize::from) != Some(k) && self.active.get(k).copied().unwrap_or(false)
            {
                done += 1;
                self.fitted += 1;
                self.fit_cell::<M>(k, &b);
            }
        }
        // The batch's finish takes a slot too: a sample whose fits (and mixture) filled its
        // slots leaves it to the next sample.
        let finish = self.next >= CELLS && done + usize::from(mixed) < slots;
        // The slots left (the finish keeps its own, the sample that closes a batch one for the
        // load stage) take pieces of the calibration's slopes, two per slot (a piece is one
        // evaluation, a fit two or three).
        let closing = usize::from(self.batches.sums().n) + 1 >= batch;
        let used = done + usize::from(mixed) + usize::from(finish) + usize::from(closing);
        let free = slots.saturating_sub(used);
        self.slope_pieces::<M>(&b, 2 * free);
        #[cfg(test)]
        {
            let load = done + usize::from(mixed);
            self.trace.fits += done;
            self.trace.load = self.trace.load.max(load);
            if finish {
                self.trace.load_finishing = self.trace.load_finishing.max(load);
            }
        }
        if finish {
            self.pending = None;
            self.reseed_from = (self.reseed_from + 7) % CELLS;
            self.finish::<M>(&b);
        }
    }

    /// Forgets evidence over `dt` seconds and `dist` metres: the likelihoods and the fitted
    /// offsets' information alike.
    fn age<M: Backend<F>>(&mut self, dt: F, dist: F) {
        let d = self.likelihood.age::<M>(&self.cfg, dt, dist);
        self.fit.forget(d);
    }

    /// Folds a fitted batch into the likelihoods and updates the calibration and the estimate.
    fn finish<M: Backend<F>>(&mut self, b: &Batch<F>) {
        self.age::<M>(b.dt, b.dist);
        let best = self.fit.best_of_batch();
        self.report.roll(&self.cfg, b);
        let excited = b.excited(&self.cfg);
        // The likeliest cell, fitted first on this batch: how well it explains it.
        let first = self.skip.map(usize::from);
        let chi2_first = first
            .and_then(|k| self.fit.chi2().get(k).copied())
            .filter(|x| x.is_finite());
        if excited {
            let c = &self.cfg;
            let w = (b.dt / c.mismatch_time.max(F::from_f64(1e-3))).min(F::ONE);
            let x = chi2_first.unwrap_or(c.chi2_explain).min(c.chi2_explain);
            self.fit_avg += (x - self.fit_avg) * w;
        }
        if let (Some(k), Some(x)) = (first, chi2_first) {
            // The calibration's slopes at the likeliest cell, at most every `cal_period` of
            // excited batches: what its σ leaves unknown of μ here, and its own step.
            self.sys_wait += b.dt;
            let sys = excited && self.sys_wait >= self.cfg.cal_period;
            if sys {
                self.sys_wait = F::ZERO;
            }
            let step = self.calibrate::<M>(b, k, x);
            // Slopes still to take, and a sample before the next batch closes: that sample
            // takes them, the variance and the step (this one has fitted cells already).
            let ready = self
                .slope_job
                .as_ref()
                .is_some_and(|j| j.pieces >= SLOPE_PIECES || j.failed);
            let batch = usize::from(self.batches.per_batch().max(1));
            let spare = usize::from(self.batches.sums().n) + 1 < batch;
            match u8::try_from(k) {
                Ok(k8) if (sys || step.is_some()) && !ready && spare => {
                    self.deferred = Some(Deferred {
                        k: k8,
                        b: *b,
                        sys,
                        drift: b.dt,
                        step,
                    });
                }
                _ => self.calibration_work::<M>(k, b, sys, b.dt, step),
            }
        }
        if excited && best <= self.cfg.chi2_explain {
            // A model that does not explain the data (the mismatch indication's χ², averaged, above
            // its threshold) says that much less: its χ² differences are scaled down by how far
            // above (the Birge ratio).
            let scale = self.fit_avg / self.cfg.mismatch_chi2.max(F::from_f64(1e-3));
            self.likelihood
                .fold(&self.cfg, self.fit.chi2(), best, scale);
        }
        self.likelihood.normalise(&self.cfg);
        let at_bound = self
            .cal
            .theta
            .iter()
            .zip(self.cfg.cal_sigma.iter())
            .any(|(t, s)| *s > F::ZERO && t.abs() >= self.cfg.cal_bound * *s * F::from_f64(0.999));
        let mismatch = self.fit_avg > self.cfg.mismatch_chi2 || at_bound;
        // What the calibration's σ leaves unknown of μ where the batches are: a steady operating
        // point cannot tell a trail a few per cent off from another surface, however many
        // batches it lasts (the likelihoods take each batch as independent evidence).
        // The evidence from ahead (the preview) is not this tyre's: only the wheel's own share
        // of ℓ carries its calibration's σ.
        let sys_var = if excited {
            self.sys_var * (F::ONE - self.likelihood.external).max(F::ZERO)
        } else {
            F::ZERO
        };
        self.report
            .update::<M>(&self.cfg, &self.likelihood, &self.fit, mismatch, sys_var);
        let r = self.fit.peak_ratio::<M>(self.report.current().mu);
        self.report.set_peak_ratio(r);
    }

    /// The calibration's step on batch `b`, linearised at cell `k` (the likeliest, which
    /// explains the batch with χ² `chi2`): whether it is due, and then the prior variances of
    /// its nuisances. Due when the batch is excited, the cell explains it, and either its force
    /// is in the linear range of every surface (`cal_util` of the lowest hypothesis) or the
    /// force has swept (`cal_sweep`) and the estimate has been identifiable for `cal_settle`,
    /// at most every `cal_period`: then a Kalman step ([`Calibration::step`],
    /// [`Bank::calibration_work`]) with the batch's slips free and its surface at the
    /// identification's μ (twice its σ) or, outside an identification, anywhere on the grid. A
    /// steady operating point tells μ and the tyre apart no better over many batches than over
    /// one, and right after a change of surface the old surface's cell with another trail
    /// explains the new road: neither calibrates.
    fn calibrate<M: Backend<F>>(&mut self, b: &Batch<F>, k: usize, chi2: F) -> Option<CalStep<F>> {
        let c = self.cfg;
        if !c.calibrate || b.fz <= F::ZERO {
            return None;
        }
        let f = M::sqrt(b.fy.0.sq() + b.fx.map_or(F::ZERO, |(v, _)| v.sq()));
        let fr = f / b.fz;
        let decay = M::exp(-b.dt / c.cal_sweep_time.max(F::from_f64(1e-3)));
        self.f_hi = fr.max(self.f_hi * decay + fr * (F::ONE - decay));
        self.f_lo = fr.min(self.f_lo * decay + fr * (F::ONE - decay));
        let est = self.report.current();
        if let Some((_, mu)) = self.known {
            return self.calibrate_known(b, k, chi2, mu);
        }
        if c.cal_joint {
            return self.calibrate_joint::<M>(b, k, chi2, &est);
        }
        if est.state == State::Identifiable && !est.change {
            self.ident_s += b.dt;
        } else {
            self.ident_s = F::ZERO;
        }
        let swept = self.f_hi - self.f_lo >= c.cal_sweep * self.f_hi;
        let settled = self.ident_s >= c.cal_settle;
        let linear = fr <= c.cal_util * self.fit.grid().lowest();
        self.cal_wait += b.dt;
        if !(b.excited(&c) && chi2 <= c.chi2_identifiable && (linear || (swept && settled))) {
            return None;
        }
        // At most one step per `cal_period`: the calibration drifts over minutes, and a step
        // costs five evaluations (on the device as much as several cells' fits).
        if self.cal_wait < c.cal_period {
            return None;
        }
        self.cal_wait = F::ZERO;
        // The slips free (ten times their scales), the surface as known.
        let (ua, uk) = self.fit.slip_units_of(k);
        let top = self.fit.grid().mu_of(CELLS - 1);
        let mu_var = if est.state == State::Identifiable {
            (F::TWO * est.sigma).sq()
        } else {
            top * top
        };
        let ten = F::from_f64(10.0);
        Some(CalStep::Apart([(ten * ua).sq(), (ten * uk).sq(), mu_var]))
    }

    /// The calibration's work on batch `b` at cell `k`: its slopes there (when `sys` or
    /// `step` wants them), the variance of μ its σ leaves there (`sys`), its drift over
    /// `drift` seconds, and its step (`step`: the nuisances' prior variances).
    fn calibration_work<M: Backend<F>>(
        &mut self,
        k: usize,
        b: &Batch<F>,
        sys: bool,
        drift: F,
        step: Option<CalStep<F>>,
    ) {
        let c = self.cfg;
        let slopes = if sys || step.is_some() {
            self.slopes::<M>(k, b)
        } else {
            None
        };
        if sys {
            if let Some(s) = slopes.as_ref().and_then(|(_, hc, hn)| mu_slopes(hc, hn)) {
                self.sys_var = self.cal.mu_var(&s);
            }
        }
        self.cal.drift(drift, c.cal_tau, &c.cal_sigma);
        match (step, slopes) {
            (Some(CalStep::Apart(nuis)), Some((r, h_cal, h_nuis))) => {
                self.cal
                    .step(&r, &h_cal, &h_nuis, &nuis, &c.cal_sigma, c.cal_bound);
            }
            (Some(CalStep::Joint { slips, mu_lin }), Some((r, h_cal, h_nuis))) => {
                self.cal.step_joint(
                    &r,
                    &h_cal,
                    &h_nuis,
                    slips,
                    mu_lin,
                    &mut self.surface,
                    &c.cal_sigma,
                    c.cal_bound,
                );
            }
            _ => {}
        }
    }

    /// The calibration's work a finish left ([`Deferred`]), if any: in the sample after the
    /// finish, before the next batch closes (its load stage takes the calibration).
    fn calibrate_deferred<M: Backend<F>>(&mut self) {
        // (Tested first: taking the `Option` moves the whole of it, every sample.)
        if self.deferred.is_none() {
            return;
        }
        if let Some(d) = self.deferred.take() {
            self.calibration_work::<M>(usize::from(d.k), &d.b, d.sys, d.drift, d.step);
        }
    }

    /// Whether the finish of the pending batch `b`, whose likeliest cell has χ² `chi2`, will
    /// most likely want the calibration's slopes ([`Bank::finish`], [`Bank::calibrate`]): the
    /// variance of μ is due, or a step of the calibration passes its gates (as far as they can
    /// be told before the finish: whether the estimate stays identifiable is read now).
    fn wants_slopes<M: Backend<F>>(&self, b: &Batch<F>, chi2: F) -> bool {
        let c = &self.cfg;
        let excited = b.excited(c);
        if !chi2.is_finite() || !excited {
            return false;
        }
        if self.sys_wait + b.dt >= c.cal_period {
            return true;
        }
        if !c.calibrate
            || b.fz <= F::ZERO
            || chi2 > c.chi2_identifiable
            || self.cal_wait + b.dt < c.cal_period
        {
            return false;
        }
        let f = M::sqrt(b.fy.0.sq() + b.fx.map_or(F::ZERO, |(v, _)| v.sq()));
        let fr = f / b.fz;
        if fr <= c.cal_util * self.fit.grid().lowest() {
            return true;
        }
        let decay = M::exp(-b.dt / c.cal_sweep_time.max(F::from_f64(1e-3)));
        let f_hi = fr.max(self.f_hi * decay + fr * (F::ONE - decay));
        let f_lo = fr.min(self.f_lo * decay + fr * (F::ONE - decay));
        let est = self.report.current();
        let ident = est.state == State::Identifiable && !est.change;
        let settled = ident && self.ident_s + b.dt >= c.cal_settle;
        f_hi - f_lo >= c.cal_sweep * f_hi && settled
    }

    /// Takes up to `budget` pieces of the calibration's slopes at the pending batch's
    /// likeliest cell (the residuals count two, a column one).
    fn slope_pieces<M: Backend<F>>(&mut self, b: &Batch<F>, mut budget: usize) {
        let (Some(k), Some(job)) = (self.skip.map(usize::from), self.slope_job.as_mut()) else {
            return;
        };
        while job.pieces < SLOPE_PIECES && !job.failed {
            let cost = if job.pieces == 0 { 2 } else { 1 };
            if budget < cost {
                break;
            }
            budget -= cost;
            slope_piece::<F, M>(&self.fit, job, k, b);
        }
    }

    /// The calibration's slopes at cell `k` of batch `b`
    /// ([`crate::mu::fit::Fit::calibration_slopes`]): the pieces taken ahead for it, and the
    /// rest now.
    fn slopes<M: Backend<F>>(&mut self, k: usize, b: &Batch<F>) -> Option<Slopes<F>> {
        match self.slope_job.take() {
            Some(mut job) if self.skip.map(usize::from) == Some(k) => {
                while job.pieces < SLOPE_PIECES && !job.failed {
                    slope_piece::<F, M>(&self.fit, &mut job, k, b);
                }
                let ok = !job.failed
                    && job.h_cal.iter().all(|r| F::all_finite(r))
                    && F::all_finite(&job.r0);
                let out = ok.then_some((job.r0, job.h_cal, job.h_nuis));
                // Kept for the step that may want them after the variance did.
                self.slope_job = Some(job);
                out
            }
            _ => self.fit.calibration_slopes::<M>(k, b),
        }
    }

    /// The calibration's step with the road a state of its own (`Config::cal_joint`): the road
    /// ages as an unobserved μ does and starts afresh where it may have changed (a change flag,
    /// the fallback, or the likeliest cell beyond what its σ allows); a step is due on every
    /// excited batch the likeliest cell explains, at most every `cal_period`.
    fn calibrate_joint<M: Backend<F>>(
        &mut self,
        b: &Batch<F>,
        k: usize,
        chi2: F,
        est: &Estimate<F>,
    ) -> Option<CalStep<F>> {
        let c = self.cfg;
        let mu_lin = self.fit.mu_c(k);
        let (down, up) = self.fit.grid().half(k);
        let w = down + up;
        if self.surface.known {
            self.surface.var += c.age_q_time * b.dt + c.age_q_distance * b.dist;
        }
        let far =
            (self.surface.mu - mu_lin).abs() > F::from_f64(3.0) * M::sqrt(self.surface.var) + w;
        if !self.surface.known || est.change || est.state == State::Fallback || far {
            let s0 = est.sigma.max(w);
            self.surface.start(mu_lin, s0 * s0);
        }
        self.cal_wait += b.dt;
        self.joint_step(b.excited(&c) && chi2 <= c.chi2_identifiable, k)
    }

    /// A step with the road the calibration's state, when `due` and `cal_period` has passed
    /// since the last: the batch's slips free within ten of cell `k`'s slip units, the residuals
    /// linearised at its surface.
    fn joint_step(&mut self, due: bool, k: usize) -> Option<CalStep<F>> {
        if !due || self.cal_wait < self.cfg.cal_period {
            return None;
        }
        self.cal_wait = F::ZERO;
        let (ua, uk) = self.fit.slip_units_of(k);
        let ten = F::from_f64(10.0);
        Some(CalStep::Joint {
            slips: [(ten * ua).sq(), (ten * uk).sq()],
            mu_lin: self.fit.mu_c(k),
        })
    }

    /// The calibration's step on a known road ([`Bank::set_known_surface`]): batch `b` at cell
    /// `k` (the known road's, fitted first), whose χ² is `chi2`.
    fn calibrate_known(&mut self, b: &Batch<F>, k: usize, chi2: F, mu: F) -> Option<CalStep<F>> {
        let c = self.cfg;
        self.surface.start(mu, F::ZERO);
        self.cal_wait += b.dt;
        let excited = b.excited(&c);
        let explained = excited && chi2 <= c.chi2_explain;
        let (e, x) = self.known_batches;
        self.known_batches = (
            e.saturating_add(u32::from(excited)),
            x.saturating_add(u32::from(explained)),
        );
        self.joint_step(explained, k)
    }

    /// Mixes in the reading from ahead that waits, if any ([`Reading::mix_into`]); a held value
    /// the reading excludes (its ℓ′ above `hold_nll`) is dropped.
    fn mix_waiting<M: Backend<F>>(&mut self) {
        self.mix_waited = false;
        if let Some(r) = &self.mixing {
            r.mix_into::<M>(&mut self.likelihood);
            let c = &self.cfg;
            let grid = self.fit.grid();
            self.report
                .drop_held_if(|h| r.excludes(grid.cell_of(h), c.hold_nll));
            self.mixing = None;
        }
    }
}

/// The next piece of `job` at cell `k` of batch `b` ([`SlopeJob`]).
fn slope_piece<F: Float, M: Backend<F>>(
    fit: &Fit<F>,
    job: &mut SlopeJob<F>,
    k: usize,
    b: &Batch<F>,
) {
    if job.pieces == 0 {
        match fit.calibration_base::<M>(k, b) {
            Some((r0, h_nuis)) => {
                job.r0 = r0;
                job.h_nuis = h_nuis;
            }
            None => job.failed = true,
        }
    } else {
        let j = usize::from(job.pieces - 1);
        match fit.calibration_column::<M>(k, b, j, &job.r0) {
            Some(col) => {
                for (row, x) in job.h_cal.iter_mut().zip(col.iter()) {
                    if let Some(o) = row.get_mut(j) {
                        *o = *x;
                    }
                }
            }
            None => job.failed = true,
        }
    }
    job.pieces += 1;
}

#[cfg(test)]
pub(crate) mod tests;
