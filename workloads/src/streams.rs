//! The friction estimator's streams of the no-FPU bench (Cortex-M0 and Cortex-M3) at 100 Hz: its
//! build script runs them on the host for the expected outcome, the bench runs them on the
//! device. Each is the M4F bench's 1 kHz [`crate::slalom`] on a road of friction λμ with roll
//! camber amplitude `camber` \[rad\], decimated to every [`DECIMATE`]th sample (10 ms apart),
//! [`SAMPLES`] of them (two slalom periods). The estimator is [`gough::mu::bank::Bank`] with
//! [`config`]: one 10 ms sample per batch, the same 100 Hz estimator as the default batch of 10
//! samples at 1 kHz.

use gough::math::Float;
use gough::mf::Params;
use gough::mu::{Config, Estimate, Sample};
use gough::proto::Measurement;

use crate::slalom::Slalom;

/// 1 kHz samples per 100 Hz sample.
pub const DECIMATE: usize = 10;
/// Samples per stream (100 Hz: 2 s, two slalom periods).
pub const SAMPLES: usize = 200;
/// (λμ, camber amplitude \[rad\], short name, description) per stream.
pub const STREAMS: [(f32, f32, &str, &str); 2] = [
    (1.0, 0.02, "dry", "λμ 1 (dry), camber measured"),
    (0.2, 0.02, "ice", "λμ 0.2 (ice), camber measured"),
];
/// FNV-1a offset basis: the hash of no estimate.
pub const HASH0: u32 = 0x811c_9dc5;

/// The 100 Hz stream on a road of friction `mu` with roll camber amplitude `camber`: every
/// [`DECIMATE`]th sample of [`Slalom`] (the first at t = 0), [`SAMPLES`] of them.
pub fn stream(p: &Params<f32>, mu: f32, camber: f32) -> impl Iterator<Item = Measurement> {
    Slalom::new(p, mu, camber).step_by(DECIMATE).take(SAMPLES)
}

/// The bank's settings for the 100 Hz streams: the defaults (a batch is 10 ms: one sample).
pub fn config<F: Float>() -> Config<F> {
    Config::default()
}

/// A stream's measurement (f32, as the proto carries it) as the bank's sample in `F`.
pub fn bank_sample<F: Float>(m: &Measurement) -> Sample<F> {
    let c = |x: f32| F::from_f64(f64::from(x));
    Sample {
        t_us: m.t_us,
        fz: c(m.fz),
        fy: c(m.fy),
        mz: c(m.mz),
        fx: m.fx.map(c),
        kappa: m.kappa.map(c),
        vx: m.vx.map(c),
        gamma: m.gamma.map(c),
    }
}

/// A value's bits fed into an FNV-1a hash (f32: its 4 bytes; Q31.32: its 8).
pub trait Feed: Copy {
    /// `h` with the value's bytes hashed in.
    fn feed(self, h: u32) -> u32;
}

fn fnv(mut h: u32, bytes: &[u8]) -> u32 {
    for &byte in bytes {
        h ^= u32::from(byte);
        h = h.wrapping_mul(0x0100_0193);
    }
    h
}

impl Feed for f32 {
    fn feed(self, h: u32) -> u32 {
        fnv(h, &self.to_bits().to_le_bytes())
    }
}

#[cfg(feature = "fixed")]
impl Feed for gough::fixed::Fix {
    fn feed(self, h: u32) -> u32 {
        fnv(h, &self.to_bits().to_le_bytes())
    }
}

/// FNV-1a over an estimate's μ, σ and μ_min bits, its state and its change flag.
pub fn hash<F: Feed>(h: u32, e: &Estimate<F>) -> u32 {
    let h = e.mu_min.feed(e.sigma.feed(e.mu.feed(h)));
    let h = fnv(h, &(e.state as u32).to_le_bytes());
    fnv(h, &u32::from(e.change).to_le_bytes())
}
