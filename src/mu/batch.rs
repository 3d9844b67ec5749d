//! Batches: the samples a bank takes, gathered into means with their σ.
//!
//! - **Samples** ([`Sample`]): Fz, Fy, Mz and, when measured, Fx, κ, Vx, γ of one wheel at a
//!   `u32` microsecond timestamp — never the slip angle. A sample that is not finite, whose
//!   timestamp does not advance, or whose Fz is outside (`fz_min_rel`·FNOMIN, 10·FNOMIN\] is not
//!   used (the first two, and Fz ≤ 0, are counted as bad); below `vx_min` (when Vx is measured)
//!   the batch restarts.
//! - **κ′ from the measured κ**: the transient slip κ′ lags the measured κ by the relaxation
//!   length σκ (eq. 20 for a constant σκ: a first-order lag over σκ/|Vx|), with σκ of the last
//!   batch's load; its batch mean is one more residual of the fit.
//! - **Batches**: the estimator works on means over `batch_us` of samples (10 ms: a 100 Hz
//!   estimator at any sample rate — 10 samples at 1 kHz, 2 at 200 Hz, 1 at 100 Hz or less).
//!   Each batch's Fz, Fx, Fy, Mz, γ, Vx and κ′ are averaged; their σ is the sensors' noise
//!   ([`crate::mu::noise`], tracked from the data) over √n, plus a model-error term stated in
//!   the tyre's scales (shares of |F| and Fz, of |Mz| and Fz·R0, of the slip μy0·Fz/Kxκ at
//!   which the linear range ends; the calibration's σ of the trail as a share of |Mz|), plus a
//!   share (`spread`) of the channel's spread within the batch beyond its noise (where the
//!   point moves along a bent curve within the batch, the mean of the forces is not the force
//!   at the mean slips).
//! - **From batch to batch** the measured κ′ moves every cell's κ′ (`Batcher::kappa_step`):
//!   by the change shrunk towards 0 by three times the noise of a difference of two batch
//!   means.
//!
//! ## Time
//! Only wrapping differences of the timestamps are used, so the estimator behaves identically
//! whatever the clock read at its start, for as long as it runs. A difference of 0, a backward
//! step, or one over [`MAX_GAP_US`] restarts the batch (the evidence ages by the gap).

use super::config::Config;
use super::noise::Noise;
use crate::math::{Backend, Float};

/// The longest sample interval \[µs\] inside a batch; a longer one restarts it.
pub const MAX_GAP_US: u32 = 200_000;

/// One measurement of one wheel. ISO-W at the contact point, SI units.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Sample<F> {
    /// Timestamp \[µs\], wrapping: only differences between samples are used.
    pub t_us: u32,
    /// Vertical load Fz \[N\].
    pub fz: F,
    /// Lateral force Fy \[N\].
    pub fy: F,
    /// Aligning torque Mz \[N·m\].
    pub mz: F,
    /// Longitudinal force Fx \[N\], when measured (without it, κ′ is taken as the measured κ, or 0).
    pub fx: Option<F>,
    /// Longitudinal slip κ \[-\] (wheel speed against vehicle speed), when measured. Never α.
    pub kappa: Option<F>,
    /// Forward speed Vx \[m/s\], when measured.
    pub vx: Option<F>,
    /// Inclination γ \[rad\], when known; `Config::gamma` otherwise.
    pub gamma: Option<F>,
}

/// Sums of the batch being collected.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Sums<F> {
    pub(crate) n: u16,
    pub(crate) n_fx: u16,
    n_kappa: u16,
    n_vx: u16,
    pub(crate) fz: F,
    pub(crate) fx: F,
    pub(crate) fy: F,
    mz: F,
    gamma: F,
    vx: F,
    kappa: F,
    /// Sums of squares of Fx, Fy, Mz, κ′ (the spread within the batch).
    sq: [F; 4],
    /// Duration \[µs\] and distance \[m\] the batch covers.
    us: u32,
    dist: F,
}

impl<F: Float> Sums<F> {
    fn new() -> Self {
        Sums {
            n: 0,
            n_fx: 0,
            n_kappa: 0,
            n_vx: 0,
            fz: F::ZERO,
            fx: F::ZERO,
            fy: F::ZERO,
            mz: F::ZERO,
            gamma: F::ZERO,
            vx: F::ZERO,
            kappa: F::ZERO,
            sq: [F::ZERO; 4],
            us: 0,
            dist: F::ZERO,
        }
    }

    /// The means and σ of a full batch: the sensors' noise `noise` (tracked), the model's
    /// error at the tyre's scales `scale`.
    fn batch<M: Backend<F>>(&self, c: &Config<F>, noise: &Noise<F>, scale: &Scales<F>) -> Batch<F> {
        let a = self;
        let n = F::from_index(a.n);
        let fz = a.fz / n;
        let (sfx_rel, sfy_rel) = (noise.sigma::<M>(0), noise.sigma::<M>(1));
        let (sigma_mz, sigma_kappa) = (noise.sigma::<M>(2), noise.sigma::<M>(3));
        let sqrt_n = M::sqrt(n);
        // The spread within the batch beyond the sensor noise: where the point moves along a bent
        // curve within the batch, the mean of the forces is not the force at the mean slips,
        // and the batch says correspondingly less (`spread` of that spread counts as error).
        let spread = |sum: F, sq: F, noise: F| {
            let v = sum / n;
            (sq / n - v * v - noise * noise).max(F::ZERO) * c.spread
        };
        let force = |sum: F, sq: F, rel: F| {
            let v = sum / n;
            let sf_meas = rel * fz;
            let s2 = (sf_meas / sqrt_n).sq()
                + (c.model_f_rel * v).sq()
                + (c.model_f_abs * fz).sq()
                + (rel * v / sqrt_n).sq()
                + spread(sum, sq, sf_meas);
            (v, M::sqrt(s2).max(F::from_f64(1e-3)))
        };
        let [sq_fx, sq_fy, sq_mz, sq_k] = a.sq;
        let mz = a.mz / n;
        // The trail's calibration σ counts as the torque's model error too: a trail known to
        // ±σ moves Mz by ±σ·|Mz| at every utilisation (the trail's moment is nearly all of it
        // below the limit).
        let smz = M::sqrt(
            (sigma_mz / sqrt_n).sq()
                + (c.model_mz_rel * mz).sq()
                + scale.trail_var * mz * mz
                + (c.model_mz_abs * fz * scale.r0).sq()
                + spread(a.mz, sq_mz, sigma_mz),
        )
        .max(F::from_f64(1e-3));
        let fx = (a.n_fx == a.n).then(|| force(a.fx, sq_fx, sfx_rel));
        let kappa = (a.n_kappa == a.n).then(|| {
            let k = a.kappa / n;
            (
                k,
                M::sqrt(
                    (sigma_kappa / sqrt_n).sq()
                        + (c.model_kappa * scale.kappa).sq()
                        + spread(a.kappa, sq_k, F::ZERO),
                )
                .max(F::from_f64(1e-4)),
            )
        });
        Batch {
            fz,
            gamma: a.gamma / n,
            vx: if a.n_vx == a.n {
                a.vx / n
            } else {
                F::from_f64(20.0)
            },
            fx,
            fy: force(a.fy, sq_fy, sfy_rel),
            mz: (mz, smz),
            kappa,
            dt: F::from_micros(a.us),
            dist: a.dist,
            n: a.n,
        }
    }
}

/// The tyre's scales a batch's σ are stated in: R0, the longitudinal slip at which the linear
/// range ends on the file's surface (μy0·Fz/Kxκ), the calibration's variance of the trail.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Scales<F> {
    pub(crate) r0: F,
    pub(crate) kappa: F,
    pub(crate) trail_var: F,
}

/// A batch's means and their σ.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Batch<F> {
    pub(crate) fz: F,
    pub(crate) gamma: F,
    pub(crate) vx: F,
    /// (value, σ) of Fx (absent: None), Fy, Mz, κ′ (absent: None).
    pub(crate) fx: Option<(F, F)>,
    pub(crate) fy: (F, F),
    pub(crate) mz: (F, F),
    pub(crate) kappa: Option<(F, F)>,
    /// Seconds and metres covered, and the samples it holds.
    pub(crate) dt: F,
    pub(crate) dist: F,
    pub(crate) n: u16,
}

impl<F: Float> Batch<F> {
    /// The batch's horizontal force \[N\]: the larger of |Fy| and |Fx|.
    pub(crate) fn force(&self) -> F {
        self.fy
            .0
            .abs()
            .max(self.fx.map_or(F::ZERO, |(v, _)| v.abs()))
    }

    /// Whether the batch is evidence: its horizontal force reaches `excitation`·Fz. Below it
    /// the batch says nothing of μ that the model can be trusted with (its free-rolling
    /// shifts SVy, Mzr scale with λμ in the model; a real tyre's conicity, ply steer and the
    /// sensors' offsets do not).
    pub(crate) fn excited(&self, c: &Config<F>) -> bool {
        self.force() >= c.excitation * self.fz
    }
}

/// The batch being collected, with what carries over between batches: the clock, the κ′ lag,
/// the last batch's κ′, the count of refused samples.
#[derive(Debug, Clone)]
pub(crate) struct Batcher<F> {
    /// FNOMIN \[N\] of the tyre (the gate on Fz).
    fnomin: F,
    sums: Sums<F>,
    last_t: Option<u32>,
    /// κ′ implied by the measured κ (first-order lag over σκ/|Vx|), and σκ \[m\].
    kappa_lag: Option<F>,
    sigma_kappa_len: F,
    /// The measured κ′ of the last batch closed (cells' κ′ follow its changes).
    kappa_prev: Option<F>,
    bad: u32,
    /// The sensors' noise, tracked ([`Noise`]).
    noise: Noise<F>,
    /// The mean sample interval \[µs\] (integer, so the same on every target) and the samples a
    /// batch then holds.
    dt_mean_us: u32,
    per_batch: u16,
    /// The scales of the σ.
    scales: Scales<F>,
}

impl<F: Float> Batcher<F> {
    /// Nothing collected, for a tyre of nominal load `fnomin` \[N\] and unloaded radius `r0`
    /// \[m\]; the noise starts from the configured one.
    pub(crate) fn new(c: &Config<F>, fnomin: F, r0: F) -> Self {
        Batcher {
            fnomin,
            sums: Sums::new(),
            last_t: None,
            kappa_lag: None,
            sigma_kappa_len: r0,
            kappa_prev: None,
            bad: 0,
            noise: Noise::new([
                c.sigma_f_rel,
                c.sigma_f_rel,
                c.sigma_mz_rel * fnomin * r0,
                c.sigma_kappa,
            ]),
            dt_mean_us: 0,
            per_batch: 1,
            scales: Scales {
                r0,
                kappa: F::from_f64(0.05),
                trail_var: F::ZERO,
            },
        }
    }

    /// The sensors' noise as tracked so far.
    pub(crate) fn noise(&self) -> &Noise<F> {
        &self.noise
    }

    /// The samples a batch holds at the current sample rate (at least 1).
    pub(crate) fn per_batch(&self) -> u16 {
        self.per_batch
    }

    /// The longitudinal slip scale μy0·Fz/Kxκ and the calibration's variance of the trail that
    /// the next batches' σ are stated in.
    pub(crate) fn set_scales(&mut self, kappa: F, trail_var: F) {
        if kappa.is_finite() && kappa > F::ZERO {
            self.scales.kappa = kappa;
        }
        if trail_var.is_finite() && trail_var >= F::ZERO {
            self.scales.trail_var = trail_var;
        }
    }

    /// Samples refused so far (not finite, Fz ≤ 0, a timestamp that does not advance).
    pub(crate) fn bad(&self) -> u32 {
        self.bad
    }

    /// The sums of the batch being collected.
    pub(crate) fn sums(&self) -> &Sums<F> {
        &self.sums
    }

    /// Checks sample `s` and moves the clock on: the interval \[µs\] since the last sample
    /// used, or `None` when `s` is not used (see the module documentation). An interval over
    /// [`MAX_GAP_US`] restarts the batch (the caller ages the evidence by it).
    pub(crate) fn admit(&mut self, c: &Config<F>, s: &Sample<F>) -> Option<u32> {
        let finite = F::all_finite(&[s.fz, s.fy, s.mz])
            && s.fx.is_none_or(|x| x.is_finite())
            && s.kappa.is_none_or(|x| x.is_finite())
            && s.vx.is_none_or(|x| x.is_finite())
            && s.gamma.is_none_or(|x| x.is_finite());
        let dt_us = match self.last_t {
            None => 0,
            Some(t0) => s.t_us.wrapping_sub(t0),
        };
        let advancing = self.last_t.is_none() || (dt_us > 0 && dt_us < 0x8000_0000);
        let fz0 = self.fnomin;
        if !finite || !advancing || s.fz <= c.fz_min_rel * fz0 || s.fz > F::from_f64(10.0) * fz0 {
            if !finite || !advancing || s.fz <= F::ZERO {
                self.bad = self.bad.saturating_add(1);
            }
            if advancing {
                self.last_t = Some(s.t_us);
            }
            return None;
        }
        self.last_t = Some(s.t_us);
        if dt_us > MAX_GAP_US {
            self.restart();
            self.noise.restart();
        } else if dt_us > 0 {
            // The sample interval, averaged over about 16 samples, and the samples a batch
            // then holds (its duration `batch_us` at this rate, at least one).
            self.dt_mean_us = if self.dt_mean_us == 0 {
                dt_us
            } else {
                let d = i64::from(dt_us) - i64::from(self.dt_mean_us);
                u32::try_from(i64::from(self.dt_mean_us) + d / 16).unwrap_or(dt_us)
            };
            let per = (c.batch_us.saturating_add(self.dt_mean_us / 2)) / self.dt_mean_us.max(1);
            self.per_batch = u16::try_from(per).unwrap_or(u16::MAX).max(1);
        }
        Some(dt_us)
    }

    /// Drops the batch being collected and the κ′ lag.
    fn restart(&mut self) {
        self.sums = Sums::new();
        self.kappa_lag = None;
    }

    /// Adds sample `s`, `dt_us` after the last one ([`Batcher::admit`]), to the batch; `false`
    /// (and the batch restarted) when its measured speed is below `vx_min`.
    pub(crate) fn push<M: Backend<F>>(&mut self, c: &Config<F>, s: &Sample<F>, dt_us: u32) -> bool {
        if let Some(vx) = s.vx {
            if vx.abs() < c.vx_min {
                self.restart();
                return false;
            }
        }
        let dt = F::from_micros(dt_us.min(MAX_GAP_US));
        let nan = F::from_f64(f64::NAN);
        self.noise.push([
            s.fx.map_or(nan, |x| x / s.fz),
            s.fy / s.fz,
            s.mz,
            s.kappa.unwrap_or(nan),
        ]);
        // κ′ from the measured κ: first-order lag over σκ/|Vx| (eq. 20 for a constant σκ).
        if let Some(k) = s.kappa {
            let lag = match (self.kappa_lag, s.vx) {
                (Some(prev), Some(vx)) => {
                    let x = dt * vx.abs() / self.sigma_kappa_len.max(F::from_f64(0.01));
                    prev + (F::ONE - M::exp(-x)) * (k - prev)
                }
                _ => k,
            };
            self.kappa_lag = Some(lag);
        } else {
            self.kappa_lag = None;
        }
        let a = &mut self.sums;
        a.n += 1;
        a.fz += s.fz;
        a.fy += s.fy;
        a.mz += s.mz;
        a.sq[1] += s.fy * s.fy;
        a.sq[2] += s.mz * s.mz;
        a.gamma += s.gamma.unwrap_or(c.gamma);
        if let Some(fx) = s.fx {
            a.n_fx += 1;
            a.fx += fx;
            a.sq[0] += fx * fx;
        }
        if let Some(k) = self.kappa_lag {
            a.n_kappa += 1;
            a.kappa += k;
            a.sq[3] += k * k;
        }
        if let Some(vx) = s.vx {
            a.n_vx += 1;
            a.vx += vx;
            a.dist += vx.abs() * dt;
        }
        a.us = a.us.saturating_add(dt_us.min(MAX_GAP_US));
        true
    }

    /// The batch, when it covers `batch_us` (within half a sample interval) or holds the most
    /// samples a batch can: its means and σ; collecting starts anew.
    pub(crate) fn close<M: Backend<F>>(&mut self, c: &Config<F>) -> Option<Batch<F>> {
        let covered = u64::from(self.sums.us) + u64::from(self.dt_mean_us / 2);
        if self.sums.n == 0 || (covered < u64::from(c.batch_us) && self.sums.n < u16::MAX - 1) {
            return None;
        }
        let b = self.sums.batch::<M>(c, &self.noise, &self.scales);
        self.sums = Sums::new();
        Some(b)
    }

    /// The change of the measured κ′ from the last batch to batch `b`, by which every cell's
    /// κ′ follows (its own offset kept): shrunk towards 0 by three times the noise of a
    /// difference of two batch means (d·d²/(d² + 9·2σκ²/n)), so that a change well above the
    /// noise (ABS) passes whole and the noise of a steady κ is not fed into every cell's slip
    /// (it once moved a saturated cell's κ′ by most of its value each batch, and the true
    /// surface lost to a wrong one over a long steady turn on ice; on a small stiff tyre a
    /// κ noise of 0.005 is all of its slip range at μ 0.25, and one σ of it moved every cell's
    /// Fx by most of its grip). `None` without κ in this or the last batch.
    pub(crate) fn kappa_step<M: Backend<F>>(&mut self, b: &Batch<F>) -> Option<F> {
        let step = match (b.kappa, self.kappa_prev) {
            (Some((k, _)), Some(prev)) => {
                let raw = k - prev;
                let v =
                    F::from_f64(18.0) * self.noise.sigma::<M>(3).sq() / F::from_index(b.n.max(1));
                Some(if raw * raw + v > F::ZERO {
                    raw * raw * raw / (raw * raw + v)
                } else {
                    raw
                })
            }
            _ => None,
        };
        self.kappa_prev = b.kappa.map(|(k, _)| k);
        step
    }

    /// σκ \[m\] of the κ′ lag from now on (the relaxation length at the last batch's load),
    /// when it is a positive number.
    pub(crate) fn set_sigma_kappa(&mut self, sx: F) {
        if sx.is_finite() && sx > F::ZERO {
            self.sigma_kappa_len = sx;
        }
    }
}
