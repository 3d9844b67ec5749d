//! Workloads shared by the `bench` and `profile` binaries, so that a profile measures what the
//! bench reports.

use gough::math::{Backend, Libm};
use gough::mf::{self, Input, Options, Params};
use gough::proto::{Measurement, Wheel as WheelId};

/// A measurement with nothing in it: the initialiser of a stream buffer.
pub const EMPTY: Measurement = Measurement {
    wheel: WheelId::FrontLeft,
    t_us: 0,
    fz: 0.0,
    fy: 0.0,
    mz: 0.0,
    fx: None,
    vx: None,
    omega: None,
    delta: None,
    alpha: None,
    kappa: None,
    gamma: None,
};

/// A slalom at 20 m/s sampled at 1 kHz (`out.len()` samples; the bench takes 1 s) on a road of
/// friction `mu` (λμx = λμy = `mu` times the file's: 1 is the tyre's own test surface):
/// α = 0.1 rad·sin(2π·1 Hz·t), Fz = Fz0·(1 + 0.15·sin), light
/// braking κ = −0.02·sin², roll camber γ = `camber`·sin, sent when `camber` ≠ 0 (then γ lies
/// between the table's camber nodes: the estimator interpolates over twice the curves; without
/// γ the estimator takes its static camber 0, a node); "measured" Fx, Fy, Mz = the f32 Magic
/// Formula plus noise (uniform: Mz ±3.5 N·m ≈ 2 N·m rms, Fy ±1.7 % Fz ≈ 1 % rms).
pub fn slalom(p: &Params<f32>, mu: f32, camber: f32, out: &mut [Measurement]) {
    let mut road = p.clone();
    road.lmuy = p.lmuy * mu;
    road.lmux = p.lmux * mu;
    let mut x = 0x2545_f491u32;
    let mut rnd = || {
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        (x >> 8) as f32 / (1u32 << 24) as f32 * 2.0 - 1.0
    };
    for (i, m) in out.iter_mut().enumerate() {
        let t = i as f32 * 1e-3;
        let s = <Libm as Backend<f32>>::sin(core::f32::consts::TAU * t);
        let (alpha, kappa, fz) = (0.1 * s, -0.02 * s * s, p.fnomin * (1.0 + 0.15 * s));
        let gamma = camber * s;
        let input = Input {
            fz,
            kappa,
            alpha,
            gamma,
            phit: 0.0,
            vx: 20.0,
            p: None,
        };
        let (fx, fy, mz) = match mf::eval::<f32, Libm>(&road, &input, &Options::default()) {
            Ok(o) => (o.fx, o.fy, o.mz),
            Err(_) => (0.0, 0.0, 0.0),
        };
        *m = Measurement {
            wheel: WheelId::FrontLeft,
            t_us: 1_000 * i as u32,
            fz,
            fy: fy + 0.017 * fz * rnd(),
            mz: mz + 3.5 * rnd(),
            fx: Some(fx),
            vx: Some(20.0),
            omega: None,
            delta: None,
            alpha: Some(alpha),
            kappa: Some(kappa),
            gamma: (camber != 0.0).then_some(gamma),
        };
    }
}
