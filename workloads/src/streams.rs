//! The friction estimator's streams of the no-FPU bench: its build script runs them on the host
//! for the expected outcome, the bench runs them on the device. Each is the [`crate::slalom`]
//! on a road of friction λμ with roll camber amplitude `camber` \[rad\], as the M4F bench's dry
//! and icy streams.

/// Samples per stream (1 kHz: one slalom period).
pub const SAMPLES: usize = 1000;
/// (λμ, camber amplitude \[rad\], name) per stream.
pub const STREAMS: [(f32, f32, &str); 2] = [
    (1.0, 0.02, "λμ 1 (dry), camber measured"),
    (0.2, 0.02, "λμ 0.2 (ice), camber measured"),
];
/// FNV-1a offset basis: the hash of no estimate.
pub const HASH0: u32 = 0x811c_9dc5;

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

/// FNV-1a over an estimate's μ and σ bits, its state and its change flag.
pub fn hash<F: Feed>(h: u32, e: &gough::mu::Estimate<F>) -> u32 {
    let h = e.sigma.feed(e.mu.feed(h));
    let h = fnv(h, &(e.state as u32).to_le_bytes());
    fnv(h, &u32::from(e.change).to_le_bytes())
}

/// A stream's sample (f32, as the proto carries it) in the estimator's number type `F`.
pub fn cast_sample<F: gough::math::Float>(s: &gough::mu::Sample<f32>) -> gough::mu::Sample<F> {
    let c = |x: f32| F::from_f64(f64::from(x));
    gough::mu::Sample {
        t: c(s.t),
        fz: c(s.fz),
        fy: c(s.fy),
        mz: c(s.mz),
        fx: s.fx.map(c),
        vx: s.vx.map(c),
        gamma: s.gamma.map(c),
    }
}
