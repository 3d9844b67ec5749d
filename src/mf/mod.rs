//! Magic Formula steady-state tyre forces and moments.
pub mod params;
pub use params::{Key, Need, Params, Side, Since, Version, IGNORED_KEYS};
