//! Return codes: every function returns `GOUGH_OK` (0) or one of these negative codes.

/// Success.
pub const GOUGH_OK: i32 = 0;
/// A required pointer was null.
pub const GOUGH_E_NULL: i32 = -1;
/// An argument is out of its domain (unknown `use_mode`, wheel index above 3, negative
/// pressure, a message kind that cannot be sent, a zero-length frame, ...).
pub const GOUGH_E_ARG: i32 = -2;
/// An input was NaN or infinite.
pub const GOUGH_E_NONFINITE: i32 = -3;
/// The `.tir` text is not valid (its line in `*err_line`).
pub const GOUGH_E_PARSE: i32 = -4;
/// An output buffer is too small.
pub const GOUGH_E_BUFFER: i32 = -5;
/// The model cannot answer: an evaluation overflowed (limits off, inputs far outside the
/// model's range), turn slip asked of a file without it, or the tyre gives no usable friction
/// (an estimator cannot be built).
pub const GOUGH_E_MODEL: i32 = -6;
/// A storage struct was used before its `*_init`/`*_parse`/`*_build` call succeeded.
pub const GOUGH_E_UNINIT: i32 = -7;
/// A measurement carries neither α, κ nor ω (with Vx): no forces to predict.
pub const GOUGH_E_NOSLIP: i32 = -8;
/// A CAN frame or message was dropped by the reassembler (bad header, CRC, order, timeout,
/// version, type or body); counted as the Rust `proto::Counters` count it.
pub const GOUGH_E_PROTO: i32 = -9;
/// A calibration was refused (`gough_*_set_calibration`): a value or σ is not a finite number, a
/// scale is not positive or a σ is negative (`gough::mu::calibration::CalibrationError::NotFinite`).
/// The calibration in use stays.
pub const GOUGH_E_CAL_INVALID: i32 = -10;
/// A calibration was refused: a value lies beyond the bound the estimator keeps it in (4 prior
/// σ: `CalibrationError::OutOfBounds`). The calibration in use stays.
pub const GOUGH_E_CAL_BOUNDS: i32 = -11;
/// A message was refused by its verifier (`gough_rx_feed_secured`): not secured, a MAC that does
/// not verify (forged, altered, another key or epoch) or a stale counter; counted in the
/// verifier (`gough_verifier_counts`). Nothing of it is returned.
pub const GOUGH_E_AUTH: i32 = -12;
