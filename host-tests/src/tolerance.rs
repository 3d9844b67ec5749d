//! Accuracy budgets against the MFeval oracle, each with its reason (one table for all tests).
use gough_host::mfrun::Precision;

/// Allowed max |error| for forces \[N\]: 1e-6·FNOMIN in f64 (the formulas are the same; what is
/// left is rounding and the order of operations), 1e-4·FNOMIN in f32 (f32 has 6e-8 relative
/// precision; a dozen chained transcendental steps, and inputs such as dfz computed from
/// rounded Fz, amplify it near the peak).
pub fn force(fnomin: f64, prec: Precision) -> f64 {
    match prec {
        Precision::F64 => 1e-6 * fnomin,
        Precision::F32 => 1e-4 * fnomin,
    }
}

/// Allowed max |error| for moments [N·m]: the force budget times R0.
pub fn moment(fnomin: f64, r0: f64, prec: Precision) -> f64 {
    force(fnomin, prec) * r0
}
