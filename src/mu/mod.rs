//! The road-friction estimator: μ from measured Fy, Mz and Fz (and Fx, κ, Vx, γ when given),
//! never the slip angle.
//!
//! The estimator is a bank of surface hypotheses ("cells"), each the wheel's own Magic Formula
//! on its surface, fitted to the recent past ([`Bank`]). It is the product's estimator: the
//! per-wheel pipeline [`crate::wheel`], and with it the firmware and the C API, runs it. One
//! concept per module:
//!
//! - [`config`] — the settings ([`Config`]) and the grid of hypotheses on the tyre file's scale
//!   (λμx = λμy = μ/μy0, [`mu_y0`]).
//! - [`batch`] — the samples ([`Sample`]) gathered into batches: means, their σ, κ′ from the
//!   measured κ; the time base.
//! - [`fit`] — each cell's fit to a batch: its transient slips α′, κ′ by damped Gauss–Newton,
//!   its surface within its interval by recursive least squares, the seeds.
//! - [`likelihood`] — each cell's ℓ with memory: dead zone, cap, forgetting, switching cap.
//! - [`estimate`] — the [`Estimate`] read from ℓ, its [`State`], the held value and its ageing,
//!   the change flag.
//! - [`bank`] — the [`Bank`] that ties them together, with its per-sample work scheduler.
//! - [`preview`] — the front-to-rear hand-over: what a front wheel read, carried to the rear
//!   wheel on its side a wheelbase later and mixed into its likelihoods.

pub mod bank;
pub mod batch;
pub mod calibration;
pub mod config;
pub mod estimate;
pub mod fit;
pub mod likelihood;
pub mod noise;
pub mod preview;

pub use bank::{Bank, BuildError, SLOTS, VISIT};
pub use batch::{Sample, MAX_GAP_US};
pub use config::{mu_y0, Config, CELLS};
pub use estimate::{Estimate, State};
pub use fit::{RESEEDS, TRUST_GAIN, TRUST_STEP};
pub use preview::Reading;
