//! Host side of gough: wraps the core for the `gough` command-line tool and the tests.
//!
//! Nothing here re-implements a formula of the core: `mfrun` turns CSV rows into
//! [`gough::mf::Input`] and calls [`gough::mf::eval`]; `tolerance` holds the accuracy budgets.
pub mod csvio;
pub mod device;
pub mod fwcli;
pub mod gap;
pub mod mfrun;
pub mod mu;
pub mod replay;
pub mod sim;
pub mod tolerance;
pub mod tyre;
