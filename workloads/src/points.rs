//! The inputs of the Magic Formula benches (the M4F bench, the no-FPU bench and its build
//! script's f64 reference): a grid over the operating range, Fz 0.5..1.5 FNOMIN, κ −0.2..0.2,
//! α −0.15..0.15 rad (γ 0, Vx 16.6 m/s).

/// Evaluations per workload.
pub const N: usize = 256;

/// Point `i`: (Fz \[N\], kappa, alpha \[rad\]).
pub fn inputs(i: usize) -> (f64, f64, f64) {
    let a = (i % 16) as f64 / 15.0;
    let b = ((i / 16) % 16) as f64 / 15.0;
    (
        6752.0 * (0.5 + a),
        -0.2 + 0.4 * b,
        -0.15 + 0.3 * ((i * 7 % 16) as f64 / 15.0),
    )
}

/// Point `i` as the Magic Formula's input in `F` (γ 0, Vx 16.6 m/s).
pub fn input<F: gough::math::Float>(i: usize) -> gough::mf::Input<F> {
    let (fz, k, a) = inputs(i);
    gough::mf::Input {
        fz: F::from_f64(fz),
        kappa: F::from_f64(k),
        alpha: F::from_f64(a),
        gamma: F::ZERO,
        phit: F::ZERO,
        vx: F::from_f64(16.6),
        p: None,
    }
}
