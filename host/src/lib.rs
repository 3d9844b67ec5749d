//! Host side of gough: the `gough` command-line tool and the libraries behind it.
//!
//! Nothing here re-implements a formula of the core:
//! - `cli` — the `gough` command line, one module per command group (feature `plot`, on by
//!   default: the commands draw their plots).
//! - [`mfrun`] — CSV rows → [`gough::mf::Input`] → [`gough::mf::eval`] (`gough mf eval`).
//! - [`sim`] — the vehicle simulation (`gough sim`).
//! - [`gap`] — the sim-to-real gap diagnosis (`gough gap`).
//! - [`mu`] — the friction estimators behind one interface (the core's bank, the published
//!   peers), their bench, bound, map and the tyre file's calibration (`gough mu`).
//! - [`replay`], [`device`] — the firmware under QEMU over SLCAN/TCP (`gough replay`,
//!   `gough firmware`); `xtask` runs its QEMU images through [`device::qemu`].
//! - `plot` — fonts, ranges and labels of every PNG (feature `plot`).
//! - [`csvio`], [`tyre`] — reading logs and tyre files with one-line errors; [`rng`] — the
//!   seeded random generator.
pub mod busload;
#[cfg(feature = "plot")]
pub mod cli;
pub mod csvio;
pub mod device;
pub mod gap;
pub mod mfrun;
pub mod mu;
#[cfg(feature = "plot")]
pub mod plot;
pub mod replay;
pub mod rng;
pub mod sim;
pub mod tyre;
