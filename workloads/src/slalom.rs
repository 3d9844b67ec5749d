//! The friction estimator's measurement stream: a noisy slalom, generated one sample at a time.
//! The M4F `bench` and `profile` binaries and the no-FPU bench run it, so a profile measures
//! what the bench reports.

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

/// A slalom at 20 m/s sampled at 1 kHz on a road of friction `mu` (λμx = λμy = `mu` times the
/// file's: 1 is the tyre's own test surface), one measurement per `next`, without end:
/// α = 0.1 rad·sin(2π·1 Hz·t), Fz = Fz0·(1 + 0.15·sin), light
/// braking κ = −0.02·sin², roll camber γ = `camber`·sin, sent when `camber` ≠ 0 (then γ lies
/// between the table's camber nodes: the estimator interpolates over twice the curves; without
/// γ the estimator takes its static camber 0, a node); "measured" Fx, Fy, Mz = the f32 Magic
/// Formula (`Libm`) plus noise (uniform: Mz ±3.5 N·m ≈ 2 N·m rms, Fy ±1.7 % Fz ≈ 1 % rms).
/// Generated one by one, so that a device with little RAM need not hold the stream; the same bits on every target (IEEE f32, no FMA contraction).
pub struct Slalom {
    road: Params<f32>,
    fnomin: f32,
    camber: f32,
    /// xorshift32 state of the noise.
    x: u32,
    i: u32,
}

impl Slalom {
    /// The slalom on a road of friction `mu` with roll camber amplitude `camber` \[rad\].
    pub fn new(p: &Params<f32>, mu: f32, camber: f32) -> Self {
        let mut road = p.clone();
        road.lmuy = p.lmuy * mu;
        road.lmux = p.lmux * mu;
        Slalom {
            road,
            fnomin: p.fnomin,
            camber,
            x: 0x2545_f491,
            i: 0,
        }
    }

    fn rnd(&mut self) -> f32 {
        let x = &mut self.x;
        *x ^= *x << 13;
        *x ^= *x >> 17;
        *x ^= *x << 5;
        (*x >> 8) as f32 / (1u32 << 24) as f32 * 2.0 - 1.0
    }
}

impl Iterator for Slalom {
    type Item = Measurement;

    fn next(&mut self) -> Option<Measurement> {
        let i = self.i;
        self.i = i.wrapping_add(1);
        let t = i as f32 * 1e-3;
        let s = <Libm as Backend<f32>>::sin(core::f32::consts::TAU * t);
        let (alpha, kappa, fz) = (0.1 * s, -0.02 * s * s, self.fnomin * (1.0 + 0.15 * s));
        let gamma = self.camber * s;
        let input = Input {
            fz,
            kappa,
            alpha,
            gamma,
            phit: 0.0,
            vx: 20.0,
            p: None,
        };
        let (fx, fy, mz) = match mf::eval::<f32, Libm>(&self.road, &input, &Options::default()) {
            Ok(o) => (o.fx, o.fy, o.mz),
            Err(_) => (0.0, 0.0, 0.0),
        };
        let (nf, nm) = (self.rnd(), self.rnd());
        Some(Measurement {
            wheel: WheelId::FrontLeft,
            t_us: 1_000u32.wrapping_mul(i),
            fz,
            fy: fy + 0.017 * fz * nf,
            mz: mz + 3.5 * nm,
            fx: Some(fx),
            vx: Some(20.0),
            omega: None,
            delta: None,
            alpha: Some(alpha),
            kappa: Some(kappa),
            gamma: (self.camber != 0.0).then_some(gamma),
        })
    }
}

/// [`Slalom`]'s first `out.len()` measurements (the bench takes 1 s).
pub fn slalom(p: &Params<f32>, mu: f32, camber: f32, out: &mut [Measurement]) {
    for (m, x) in out.iter_mut().zip(Slalom::new(p, mu, camber)) {
        *m = x;
    }
}
