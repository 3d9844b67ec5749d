//! The road-friction estimator: μ from measured Fy, Mz and Fz (and Fx, κ, Vx, γ when given),
//! never the slip angle.
//!
//! [`bank`] is the exact-model bank: surface hypotheses, each fitted to the recent past with the
//! wheel's own Magic Formula (see its module documentation). It is the product's estimator: the
//! per-wheel pipeline [`crate::wheel`], and with it the firmware and the C API, runs it.
//!
//! [`preview`] carries what a front wheel read to the rear wheel on its side, a wheelbase later.
//!
//! The previous estimator, a trail inversion on tabulated Gough curves (`MuEstimator` and
//! `GoughTable`, with the paper's brush model), moved to the host crate in issue 39
//! (`gough_host::mu::table_estimator`), where it stays as a peer in the bench
//! (`gough mu bench`, `gough mu estimate --method gough`).

pub mod bank;
pub mod preview;
