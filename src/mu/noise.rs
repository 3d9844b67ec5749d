//! The sensors' noise, estimated from the data: each channel's white noise from the second
//! differences of successive samples, x₂ − 2x₁ + x₀, whose variance is 6σ² for a white noise
//! of σ and which a smooth signal (the manoeuvre, at the sample rate) barely moves. The median
//! of their squares is tracked in the log domain (a step up or down by [`RATE`] per sample),
//! so that the manoeuvre's own steps and outliers do not inflate it; for a Gaussian noise the
//! median of a χ²₁ is 0.4549 of its mean ([`MEDIAN_SQ2`] = 6·0.4549).
//!
//! The forces are tracked relative to Fz (the bench's and most sensors' noise grows with the
//! load), Mz in N·m, κ as it is. The configured noise (`Config::sigma_f_rel`, `sigma_mz_rel`
//! of FNOMIN·R0, `sigma_kappa`) is the start; after a few hundred samples the data's estimate
//! has replaced it ([`Bank::noise`](crate::mu::Bank::noise) reports both, the online check).
//!
//! At low sample rates a fast manoeuvre moves the second differences too (a 10 Hz ripple at
//! 20 Hz): the estimate is then larger than the sensor's, and the estimator more cautious.

use crate::math::{Backend, Float};

/// The channels tracked, in order: Fx/Fz, Fy/Fz, Mz \[N·m\], κ.
pub const CHANNELS: usize = 4;
/// 6·0.4549: the median of (x₂ − 2x₁ + x₀)² over σ² for a white Gaussian noise of σ.
pub const MEDIAN_SQ2: f64 = 2.7294;
/// Relative step of the median tracker per sample.
pub const RATE: f64 = 0.02;

/// Running noise estimates of one wheel's channels.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Noise<F> {
    /// The last two samples of each channel (NaN: not measured) and how many there are (≤ 2).
    prev: [[F; CHANNELS]; 2],
    n: u8,
    /// Tracked medians of the squared second differences.
    med: [F; CHANNELS],
}

impl<F: Float> Noise<F> {
    /// Starts from σ of each channel (Fx/Fz, Fy/Fz, Mz \[N·m\], κ).
    pub fn new(sigma: [F; CHANNELS]) -> Self {
        let m = F::from_f64(MEDIAN_SQ2);
        let mut med = [F::ZERO; CHANNELS];
        for (o, s) in med.iter_mut().zip(sigma.iter()) {
            *o = *s * *s * m;
        }
        Noise {
            prev: [[F::ZERO; CHANNELS]; 2],
            n: 0,
            med,
        }
    }

    /// Forgets the last samples (a gap in the stream: a second difference across it is no
    /// noise).
    pub fn restart(&mut self) {
        self.n = 0;
    }

    /// One sample's channels; a channel that is not measured is NaN and left as it is.
    pub fn push(&mut self, x: [F; CHANNELS]) {
        let up = F::ONE + F::from_f64(RATE);
        if self.n >= 2 {
            let [p0, p1] = self.prev;
            for (((m, a), b), c) in self
                .med
                .iter_mut()
                .zip(x.iter())
                .zip(p1.iter())
                .zip(p0.iter())
            {
                let e = *a - F::TWO * *b + *c;
                if !e.is_finite() {
                    continue;
                }
                *m = if e * e > *m { *m * up } else { *m / up };
            }
        }
        let [_, last] = self.prev;
        self.prev = [last, x];
        self.n = (self.n + 1).min(2);
    }

    /// σ of channel `k` (0 Fx/Fz, 1 Fy/Fz, 2 Mz \[N·m\], 3 κ).
    pub fn sigma<M: Backend<F>>(&self, k: usize) -> F {
        let m = self.med.get(k).copied().unwrap_or(F::ZERO);
        M::sqrt((m / F::from_f64(MEDIAN_SQ2)).max(F::ZERO))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Libm;
    extern crate std;

    /// A deterministic Gaussian stream (Box–Muller on a small LCG) for the tests.
    fn gauss(seed: u64) -> impl FnMut() -> f64 {
        let mut s = seed;
        let mut u = move || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((s >> 11) as f64 + 0.5) / (1u64 << 53) as f64
        };
        move || (-2.0 * u().ln()).sqrt() * (2.0 * core::f64::consts::PI * u()).cos()
    }

    #[test]
    fn the_tracked_sigma_finds_the_noise_on_top_of_a_smooth_manoeuvre() {
        let mut n = Noise::<f64>::new([0.05, 0.05, 10.0, 0.05]);
        let mut g = gauss(3);
        for i in 0..5000 {
            let t = i as f64 * 1e-3;
            let fy = 0.8 * (2.0 * core::f64::consts::PI * 0.5 * t).sin();
            n.push([
                f64::NAN,
                fy + 0.01 * g(),
                40.0 * fy + 2.0 * g(),
                0.005 * g(),
            ]);
        }
        let s = [n.sigma::<Libm>(1), n.sigma::<Libm>(2), n.sigma::<Libm>(3)];
        assert!((s[0] / 0.01 - 1.0).abs() < 0.15, "{s:?}");
        assert!((s[1] / 2.0 - 1.0).abs() < 0.15, "{s:?}");
        assert!((s[2] / 0.005 - 1.0).abs() < 0.15, "{s:?}");
        // Fx never measured: its start value stands.
        assert!((n.sigma::<Libm>(0) - 0.05).abs() < 1e-12);
    }

    #[test]
    fn steps_of_the_manoeuvre_and_outliers_barely_move_it() {
        let mut n = Noise::<f64>::new([0.01; CHANNELS]);
        let mut g = gauss(5);
        for i in 0..4000 {
            // A step of 50σ every 200 samples, and a single wild sample every 300.
            let step = if (i / 200) % 2 == 0 { 0.0 } else { 0.5 };
            let wild = if i % 300 == 150 { 10.0 } else { 0.0 };
            n.push([step + 0.01 * g() + wild; CHANNELS]);
        }
        let s = n.sigma::<Libm>(1);
        assert!((s / 0.01 - 1.0).abs() < 0.2, "{s}");
    }
}
