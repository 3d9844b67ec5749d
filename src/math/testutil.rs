//! Shared helpers of the kernel tests (`math::fast`, `math::micro`, `fixed`): sweeps against
//! `f64` std and the error metric.

use std::vec::Vec;

/// Below this |reference| the error is taken as absolute, above as relative.
pub const NEAR_ZERO: f64 = 1.0 / 1024.0;

/// Max errors of a sweep: relative where |ref| ≥ NEAR_ZERO, absolute where below, absolute
/// over all points, and where the first two happened.
#[derive(Debug, Clone, Copy, Default)]
pub struct Errors {
    pub rel: f64,
    pub abs: f64,
    pub abs_all: f64,
    pub worst_rel_x: f32,
    pub worst_abs_x: f32,
}

impl Errors {
    pub fn add(&mut self, x: f32, got: f32, want: f64) {
        let got = got as f64;
        let e = (got - want).abs();
        if e.is_nan() || e > self.abs_all {
            self.abs_all = e;
        }
        if want.abs() >= NEAR_ZERO {
            let r = e / want.abs();
            if r.is_nan() || r > self.rel {
                self.rel = r;
                self.worst_rel_x = x;
            }
        } else if e.is_nan() || e > self.abs {
            self.abs = e;
            self.worst_abs_x = x;
        }
    }
}

/// `n` points evenly spread over [lo, hi], both ends included, rounded to f32.
pub fn linspace(lo: f64, hi: f64, n: usize) -> impl Iterator<Item = f32> {
    (0..n).map(move |i| (lo + (hi - lo) * (i as f64) / ((n - 1) as f64)) as f32)
}

/// `n` points log-spread over [lo, hi] (lo > 0), both ends included.
pub fn logspace(lo: f64, hi: f64, n: usize) -> impl Iterator<Item = f32> {
    let (a, b) = (lo.ln(), hi.ln());
    (0..n).map(move |i| (a + (b - a) * (i as f64) / ((n - 1) as f64)).exp() as f32)
}

/// Every f32 from `lo` upwards in steps of `step` ulps, up to `hi` (both positive).
pub fn ulp_walk(lo: f32, hi: f32, step: u32) -> impl Iterator<Item = f32> {
    let (a, b) = (lo.to_bits(), hi.to_bits());
    (a..=b).step_by(step as usize).map(f32::from_bits)
}

/// Sweeps `f` against `reference` over `xs`; prints and returns the max errors.
pub fn sweep(
    name: &str,
    f: impl Fn(f32) -> f32,
    reference: impl Fn(f64) -> f64,
    xs: impl Iterator<Item = f32>,
) -> Errors {
    let mut e = Errors::default();
    let mut n = 0usize;
    for x in xs {
        e.add(x, f(x), reference(x as f64));
        n += 1;
    }
    std::println!(
        "{name}: {n} points, max rel {:.2e} (at {:e}), max abs near 0 {:.2e} (at {:e}), max abs {:.2e}",
        e.rel,
        e.worst_rel_x,
        e.abs,
        e.worst_abs_x,
        e.abs_all
    );
    e
}

/// The edge inputs of libm's test generator, for f32: 0, ±1, subnormals, huge, ±∞, NaN.
pub fn edge_inputs() -> Vec<f32> {
    let mut v = std::vec![
        0.0,
        -0.0,
        f32::from_bits(1),
        -f32::from_bits(1),
        f32::MIN_POSITIVE,
        -f32::MIN_POSITIVE,
        f32::MIN_POSITIVE / 3.0,
        1e-30,
        -1e-30,
        1e-7,
        -1e-7,
        0.5,
        -0.5,
        1.0,
        -1.0,
        core::f32::consts::FRAC_PI_2,
        -core::f32::consts::FRAC_PI_2,
        core::f32::consts::PI,
        -core::f32::consts::PI,
        10.0,
        -10.0,
        1e5,
        -1e5,
        1.5e5,
        -1.5e5,
        1e10,
        -1e10,
        1e30,
        -1e30,
        f32::MAX,
        f32::MIN,
        f32::INFINITY,
        f32::NEG_INFINITY,
        f32::NAN,
    ];
    let extra: Vec<f32> = v.iter().map(|x| f32::from_bits(x.to_bits() + 1)).collect();
    v.extend(extra.into_iter().filter(|x| !x.is_nan()));
    v
}
