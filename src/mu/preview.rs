//! Front-to-rear preview: what a front wheel read of the road, handed to the rear wheel on its
//! side when the rear gets there, and mixed into the rear's likelihoods.
//!
//! A rear wheel runs, a wheelbase later, over the road its front wheel has just read. When the
//! front wheel's estimator makes a **new identification** — its first, its first after the
//! evidence aged out (`Fallback`), or a change of surface (`Estimate::change`) — its likelihood
//! profile ([`Bank::profile`]) is queued with the distance still to roll: the wheelbase, less,
//! for a change, the front's identification gap ([`Bank::identification_gap`]: the distance
//! since its last reading of the old surface, about where it met the new one), so that the
//! reading reaches the rear where the rear meets the change — before the rear's own batches on
//! the new surface, which the mixture would otherwise partly discard. Every
//! rear sample rolls the queued readings on by the distance the rear wheel covered since its
//! last sample (Vx·Δt, with the sign of Vx: reversing moves the place away again); a reading
//! that has arrived is handed to the rear estimator ([`Bank::preview`]) as a [`Reading`] with
//! the weight `Config::weight`, the probability w that the rear wheel runs on what the front
//! read. The rear's likelihoods become the mixture (1 − w)·e^−ℓ + w·e^−ℓ′ ([`Reading`]'s
//! mixture, in a slot of the rear bank's per-sample work): the old surface is no
//! longer taken for granted, and the rear's own batches confirm or overrule the reading within a
//! few batches (a rear wheel that tracks off the front's path, a patch that ends between the
//! axles). A held value the reading excludes is dropped.
//!
//! One [`Preview`] per side (front left → rear left, front right → rear right), never across:
//! on a μ-split the sides differ. Without a measured Vx the distance is unknown and nothing is
//! handed on; a gap between rear samples longer than [`MAX_GAP_US`] (or a timestamp that does
//! not advance) leaves the readings where they are. Readings a reversal has carried more than
//! two wheelbases away are dropped. At most [`QUEUE`] readings are on their way; a further one
//! replaces the oldest (both counted in [`Preview::dropped`]).
//!
//! [`update`] runs one sample of one of a car's four wheels with the previews between them: the
//! one composition the firmware's `wheel::Car`, the host's bench and `gough mu estimate` use.
//!
//! Bounded: a fixed queue, no allocation, a few operations per sample and one mixture (25
//! logarithms and exponentials) per reading handed on.
//!
//! Limits: the rear is taken to follow the front's path at a wheelbase's distance; in a tight
//! turn it runs inside the front's track (off-tracking ≈ L²/2R, 0.1 m at R = 40 m), on a
//! lane change slightly off it. The rear's own evidence decides then.

use super::bank::Bank;
use super::batch::{Sample, MAX_GAP_US};
use super::config::CELLS;
use super::estimate::{Estimate, State};
use super::likelihood::Likelihood;
use crate::math::{Backend, Float};
use crate::mf::Params;

/// A reading of the surface a wheel is running onto: the likelihood profile ℓ′ another wheel's
/// bank had where it ran over the same place ([`Bank::profile`]), with the probability p that
/// it applies here.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Reading<F> {
    profile: [F; CELLS],
    weight: F,
}

impl<F: Float> Reading<F> {
    /// A reading of `profile` with weight `weight` (0 < p < 1); `None` when the profile is not
    /// finite and non-negative or the weight is outside (0, 1).
    pub fn new(profile: &[F; CELLS], weight: F) -> Option<Self> {
        let ok = profile.iter().all(|x| x.is_finite() && *x >= F::ZERO);
        (ok && weight > F::ZERO && weight < F::ONE).then_some(Reading {
            profile: *profile,
            weight,
        })
    }

    /// The profile ℓ′ per cell.
    pub fn profile(&self) -> &[F; CELLS] {
        &self.profile
    }

    /// The probability p that it applies here.
    pub fn weight(&self) -> F {
        self.weight
    }

    /// Mixes the reading into the likelihoods `l`: each cell's ℓ becomes
    /// −ln((1 − p)·e^−(ℓ − min ℓ) + p·e^−ℓ′) — a switch of surface this wheel is told of
    /// rather than one it must find alone. The mixture counts as evidence.
    pub(crate) fn mix_into<M: Backend<F>>(&self, l: &mut Likelihood<F>) {
        let lo = l.min();
        let p = self.weight;
        let (la, lb) = (M::ln(F::ONE - p), M::ln(p));
        for (c, l2) in l.nll.iter_mut().zip(self.profile.iter()) {
            let a = la - (*c - lo);
            let b = lb - *l2;
            let m = a.max(b);
            *c = -(m + M::ln(F::ONE + M::exp(-(a - b).abs())));
        }
        l.evidence = true;
        l.external = l.external.max(p);
    }

    /// Whether the reading excludes cell `k`: its ℓ′ there is above `limit`.
    pub(crate) fn excludes(&self, k: usize, limit: F) -> bool {
        self.profile.get(k).is_some_and(|l| *l > limit)
    }
}

/// Readings on their way from a front wheel to the rear wheel behind it.
pub const QUEUE: usize = 4;

/// Preview settings. SI units.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Config<F> {
    /// Distance the rear wheel rolls to reach where the front wheel was: the wheelbase \[m\].
    pub wheelbase: F,
    /// Probability that the rear wheel runs on what the front wheel read \[-\], 0 < w < 1.
    pub weight: F,
}

impl<F: Float> Config<F> {
    /// A preview over `wheelbase` metres with the default weight (0.9).
    pub fn with_wheelbase(wheelbase: F) -> Self {
        Config {
            wheelbase,
            weight: F::from_f64(0.9),
        }
    }
}

/// Why a preview cannot be built.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum PreviewError {
    /// The wheelbase is not a positive number, or the weight not inside (0, 1).
    BadConfig,
}

impl core::fmt::Display for PreviewError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str("the preview's wheelbase is not positive or its weight not inside (0, 1)")
    }
}

/// A reading on its way: the distance still to roll \[m\] and the front's profile.
#[derive(Debug, Clone, Copy)]
struct Queued<F> {
    left: F,
    profile: [F; CELLS],
}

/// One side's front-to-rear preview (see the module documentation). 456 bytes in `f32` on the
/// M4F (the firmware bench's `bench: mu_preview_*` lines).
#[derive(Debug, Clone)]
pub struct Preview<F> {
    cfg: Config<F>,
    queue: heapless::Deque<Queued<F>, QUEUE>,
    /// Whether the front wheel's estimate has been identifiable since it last fell back.
    identified: bool,
    /// The rear wheel's last timestamp \[µs\].
    last_t: Option<u32>,
    dropped: u32,
    handed: u32,
}

impl<F: Float> Preview<F> {
    /// A preview with settings `cfg`.
    pub fn new(cfg: Config<F>) -> Result<Self, PreviewError> {
        let ok = cfg.wheelbase.is_finite()
            && cfg.wheelbase > F::ZERO
            && cfg.weight > F::ZERO
            && cfg.weight < F::ONE;
        if !ok {
            return Err(PreviewError::BadConfig);
        }
        Ok(Preview {
            cfg,
            queue: heapless::Deque::new(),
            identified: false,
            last_t: None,
            dropped: 0,
            handed: 0,
        })
    }

    /// The settings.
    pub fn config(&self) -> &Config<F> {
        &self.cfg
    }

    /// Readings replaced before they arrived (the queue was full).
    pub fn dropped(&self) -> u32 {
        self.dropped
    }

    /// Readings handed to the rear wheel so far.
    pub fn handed(&self) -> u32 {
        self.handed
    }

    /// Readings on their way.
    pub fn pending(&self) -> usize {
        self.queue.len()
    }

    /// After the front wheel's update: queues its profile when the estimate that update
    /// returned ([`Bank::current`]) is a new identification.
    pub fn front(&mut self, front: &Bank<F>) {
        self.front_with(front, &front.current(), front.identification_gap());
    }

    /// As [`Preview::front`], with the front's estimate `est` and identification gap `gap` \[m\].
    fn front_with(&mut self, front: &Bank<F>, est: &Estimate<F>, gap: F) {
        match est.state {
            State::Fallback => self.identified = false,
            State::NotIdentifiable => {}
            State::Identifiable => {
                if est.change || !self.identified {
                    // A change of surface began where the front's reading of the old one ended,
                    // the identification gap behind it: the rear meets it a wheelbase after
                    // that, and its own batches on the new surface then add to the reading
                    // instead of being mixed away.
                    let behind = if est.change {
                        gap.max(F::ZERO).min(self.cfg.wheelbase)
                    } else {
                        F::ZERO
                    };
                    // (Never ahead of a reading already on its way: the queue stays in order.)
                    let after = self.queue.back().map_or(F::ZERO, |r| r.left);
                    let r = Queued {
                        left: (self.cfg.wheelbase - behind).max(after),
                        profile: front.profile(),
                    };
                    if self.queue.is_full() {
                        self.queue.pop_front();
                        self.dropped = self.dropped.wrapping_add(1);
                    }
                    let _ = self.queue.push_back(r);
                }
                self.identified = true;
            }
        }
    }

    /// Before the rear wheel's update with sample `s`: rolls the readings on by the distance
    /// the rear wheel covered since its last sample and hands `rear` the nearest that has
    /// arrived, if it has mixed in the last one ([`Bank::previewing`]): one per sample.
    pub fn rear<M: Backend<F>>(&mut self, rear: &mut Bank<F>, s: &Sample<F>) {
        let dt_us = self.last_t.map(|t| s.t_us.wrapping_sub(t));
        self.last_t = Some(s.t_us);
        let (Some(dt_us), Some(vx)) = (dt_us, s.vx) else {
            return;
        };
        if dt_us == 0 || dt_us > MAX_GAP_US || !vx.is_finite() {
            return;
        }
        let ds = vx * F::from_micros(dt_us);
        for r in self.queue.iter_mut() {
            r.left -= ds;
        }
        // All readings roll alike, so the oldest is the nearest: arrivals leave at the front,
        // readings a reversal has carried too far away at the back. One per sample, and only
        // when the bank has mixed the last one in (its mixture takes a slot of a sample's
        // work, `Bank::preview`): others that have arrived wait here, in order.
        if self.queue.front().is_some_and(|r| r.left <= F::ZERO) && !rear.previewing() {
            self.hand::<M>(rear);
        }
        let far = F::TWO * self.cfg.wheelbase;
        while self.queue.back().is_some_and(|r| r.left > far) {
            self.queue.pop_back();
            self.dropped = self.dropped.wrapping_add(1);
        }
    }

    /// Hands the nearest reading to `rear` (a few times per change of surface: kept out of
    /// [`Preview::rear`]'s every-sample path). A profile that is not finite and non-negative
    /// is no reading: dropped.
    #[inline(never)]
    fn hand<M: Backend<F>>(&mut self, rear: &mut Bank<F>) {
        if let Some(r) = self.queue.pop_front() {
            if let Some(reading) = Reading::new(&r.profile, self.cfg.weight) {
                rear.preview::<M>(reading);
            }
            self.handed = self.handed.wrapping_add(1);
        }
    }
}

/// One sample `s` of wheel `wheel` (0–3 = FL, FR, RL, RR) through its bank, with `previews`
/// (left, right) between the axles: a rear wheel first takes the readings that have reached it
/// ([`Preview::rear`]), a front wheel's new identification is queued after its update
/// ([`Preview::front`]). Without previews (or for another index) the bank's own update.
pub fn update<F: Float, M: Backend<F>>(
    previews: Option<&mut [Preview<F>; 2]>,
    wheel: usize,
    bank: &mut Bank<F>,
    params: &Params<F>,
    s: &Sample<F>,
) -> Estimate<F> {
    let Some(pv) = previews
        .and_then(|p| p.get_mut(wheel % 2))
        .filter(|_| wheel < 4)
    else {
        return bank.update::<M>(params, s);
    };
    if wheel >= 2 {
        pv.rear::<M>(bank, s);
    }
    let e = bank.update::<M>(params, s);
    if wheel < 2 {
        pv.front(bank);
    }
    e
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Libm;
    use crate::mu::bank::tests::{noisy, slips_stream, tyre, warm};
    use crate::mu::Config as BankConfig;
    extern crate std;
    use std::vec::Vec;

    const L: f64 = 2.7;

    /// A steady turn at slip angle `slip`, 20 m/s, `n` ms: μ 1.0 for the first 3 s (plus
    /// `lag_ms`: the rear meets a change L/Vx later), then `mu2`.
    fn turn(mu2: f64, lag_ms: usize, n: usize, slip: f64) -> Vec<Sample<f64>> {
        turn_ramp(mu2, lag_ms, n, slip, 0.0)
    }

    /// As [`turn`], the slip angle growing by `ramp` \[rad/s\] from the change of surface on.
    fn turn_ramp(mu2: f64, lag_ms: usize, n: usize, slip: f64, ramp: f64) -> Vec<Sample<f64>> {
        let p = tyre();
        let alpha = |t: f64| slip * (t / 0.5).min(1.0);
        let change = 3000 + lag_ms;
        let mut a = slips_stream(&p, 1.0, |t| (alpha(t), 0.0), 20.0, change, 0);
        let b = slips_stream(
            &p,
            mu2,
            |t| (slip + ramp * t, 0.0),
            20.0,
            n - change,
            (change as u32) * 1000,
        );
        a.extend(b);
        noisy(a)
    }

    /// Front and rear over their streams, the rear with or without the preview; the rear's
    /// estimates.
    /// The bank's defaults with the tyre's calibration known (a warm start, the simulated tyre
    /// being its file): these tests are of the hand-over, not of a cold start, where a steady
    /// turn at one slip angle cannot tell the trail from the surface (`crate::mu::calibration`).
    fn pair(front: &[Sample<f64>], rear: &[Sample<f64>], with: bool) -> Vec<Estimate<f64>> {
        let p = tyre();
        let mut f = Bank::new::<Libm>(&p, None, warm()).unwrap();
        let mut r = Bank::new::<Libm>(&p, None, warm()).unwrap();
        let mut pv = Preview::new(Config::with_wheelbase(L)).unwrap();
        front
            .iter()
            .zip(rear)
            .map(|(sf, sr)| {
                f.update::<Libm>(&p, sf);
                pv.front(&f);
                if with {
                    pv.rear::<Libm>(&mut r, sr);
                }
                r.update::<Libm>(&p, sr)
            })
            .collect()
    }

    /// First sample from which the estimate stays identifiable within ±0.1 of `mu`.
    fn settled(est: &[Estimate<f64>], from: usize, mu: f64) -> Option<usize> {
        let mut first = None;
        for (i, e) in est.iter().enumerate().skip(from).rev() {
            if e.state != State::Identifiable || (e.mu - mu).abs() > 0.1 {
                break;
            }
            first = Some(i);
        }
        first
    }

    #[test]
    fn a_rear_wheel_told_of_ice_reads_it_sooner_than_alone() {
        let lag = (L / 20.0 * 1000.0) as usize;
        // The front runs onto ice in a hard turn and reads it at once; the rear starts at a
        // small slip angle (0.4 of the ice's grip: the curve nearly linear, where μ moves by
        // several hundredths per per cent of the trail, so that the rear's own evidence stays
        // short of an identification while its calibration is known to 1 %) that grows by
        // 6 mrad/s. The reading cannot make the rear identifiable by itself (at weight 0.9 it
        // lifts a cell by at most ln 10 ≈ 2.3, below `exclude_nll`): it shortens the evidence
        // the rear needs. Measured: told 183 ms, alone 305 ms after the rear meets the ice
        // (at 0.3 of the grip: 735 and 765 ms, the calibration's σ deciding; from 0.45 on
        // both read it within 75–95 ms).
        let front = turn(0.3, 0, 6000, -0.03);
        let rear = turn_ramp(0.3, lag, 6000, -0.012, -0.006);
        let alone = pair(&front, &rear, false);
        let told = pair(&front, &rear, true);
        let on_ice = 3000 + lag;
        let a = settled(&alone, on_ice, 0.3).map(|i| i - on_ice);
        let t = settled(&told, on_ice, 0.3).map(|i| i - on_ice);
        std::println!("told {t:?} ms, alone {a:?} ms");
        assert!(
            t.is_some_and(|t| t <= 200 && a.is_none_or(|a| t + 100 < a)),
            "told {t:?} ms, alone {a:?} ms"
        );
        // Never confidently wrong on the way.
        assert!(told
            .iter()
            .enumerate()
            .all(|(i, e)| e.state != State::Identifiable
                || (e.mu - if i < on_ice { 1.0 } else { 0.3 }).abs() <= 0.1));
    }

    #[test]
    fn a_reading_that_does_not_apply_is_overruled() {
        // The front runs onto ice, the rear never does (a patch that ended between the axles).
        // The rear turns at 0.05 rad (at 0.03 its own μ 1.0 is not identifiable with the
        // trail known to 1 %: μ moves by ~0.04 per per cent of trail there).
        let front = turn(0.3, 0, 6000, -0.03);
        let rear = turn(1.0, 0, 6000, -0.05);
        let told = pair(&front, &rear, true);
        let wrong = told
            .iter()
            .filter(|e| e.state == State::Identifiable && (e.mu - 1.0).abs() > 0.1)
            .count();
        assert_eq!(wrong, 0);
        let back = settled(&told, 3000, 1.0).unwrap();
        std::println!("identifiable at 1.0 again from {back} ms");
        assert!(back < 3300, "{back}");
    }

    fn at(t_ms: u32, vx: Option<f64>) -> Sample<f64> {
        Sample {
            t_us: t_ms.wrapping_mul(1000),
            fz: 4000.0,
            fy: 0.0,
            mz: 0.0,
            fx: None,
            kappa: None,
            vx,
            gamma: None,
        }
    }

    fn identified(change: bool) -> Estimate<f64> {
        Estimate {
            mu: 0.5,
            sigma: 0.02,
            mu_min: 0.4,
            state: State::Identifiable,
            change,
            mismatch: false,
        }
    }

    #[test]
    fn a_reading_arrives_after_a_wheelbase_and_only_with_a_speed() {
        let p = tyre();
        let b = Bank::new::<Libm>(&p, None, BankConfig::default()).unwrap();
        let mut rear = b.clone();
        let mut pv = Preview::new(Config::with_wheelbase(2.0)).unwrap();
        pv.front_with(&b, &identified(false), 0.0);
        // Identifiable again without a change: nothing new.
        pv.front_with(&b, &identified(false), 0.0);
        assert_eq!(pv.pending(), 1);
        // Without Vx nothing moves; at 10 m/s 2 m take 200 ms.
        for t in 0..500 {
            pv.rear::<Libm>(&mut rear, &at(t, None));
        }
        assert_eq!((pv.pending(), pv.handed()), (1, 0));
        let mut arrived = None;
        for t in 500..800 {
            pv.rear::<Libm>(&mut rear, &at(t, Some(10.0)));
            if arrived.is_none() && pv.handed() == 1 {
                arrived = Some(t);
            }
        }
        // 200 steps of 10 mm from t = 500 ms (the clock ran on without a speed).
        assert!(matches!(arrived, Some(699..=700)), "{arrived:?}");
        // A change of surface is new; so is an identification after a fallback.
        pv.front_with(&b, &identified(true), 0.0);
        let fb = Estimate {
            state: State::Fallback,
            ..identified(false)
        };
        pv.front_with(&b, &fb, 0.0);
        pv.front_with(&b, &identified(false), 0.0);
        assert_eq!(pv.pending(), 2);
        // Reversing carries them away: dropped beyond two wheelbases.
        for t in 800..1300 {
            pv.rear::<Libm>(&mut rear, &at(t, Some(-10.0)));
        }
        assert_eq!((pv.pending(), pv.dropped(), pv.handed()), (0, 2, 1));
        // A gap longer than MAX_GAP_US moves nothing.
        pv.front_with(&b, &identified(true), 0.0);
        pv.rear::<Libm>(&mut rear, &at(100_000, Some(10.0)));
        assert_eq!(pv.pending(), 1);
        // At most QUEUE readings on their way: a further one replaces the oldest.
        for _ in 0..QUEUE {
            pv.front_with(&b, &identified(true), 0.0);
        }
        assert_eq!((pv.pending(), pv.dropped()), (QUEUE, 3));
    }

    #[test]
    fn a_change_is_placed_where_the_front_met_it_never_ahead_of_an_earlier_reading() {
        let p = tyre();
        let b = Bank::new::<Libm>(&p, None, BankConfig::default()).unwrap();
        let mut rear = b.clone();
        let mut pv = Preview::new(Config::with_wheelbase(2.0)).unwrap();
        // A first identification rolls the whole wheelbase whatever the gap (no old surface).
        pv.front_with(&b, &identified(false), 0.5);
        // A change read 0.5 m after the front met it: 1.5 m to roll, but not ahead of the first.
        pv.front_with(&b, &identified(true), 0.5);
        // One 0.5 m beyond a wheelbase (a long gap) would be due at once: after the others.
        pv.front_with(&b, &identified(true), 2.5);
        assert_eq!(pv.pending(), 3);
        let mut handed_at = Vec::new();
        for t in 0..300 {
            let before = pv.handed();
            let s = at(t, Some(10.0));
            pv.rear::<Libm>(&mut rear, &s);
            if pv.handed() > before {
                handed_at.push((t, pv.handed() - before));
            }
            // (The rear's update mixes the reading in; until then the next one waits.)
            if t != 201 {
                rear.update::<Libm>(&p, &s);
            }
        }
        // 10 mm per step from the second sample on: all three arrive with the first, 2 m on,
        // and are handed one per sample as the rear mixes each in (none on a sample after
        // which the rear did not).
        assert_eq!(handed_at, [(200, 1), (201, 1), (203, 1)]);
        assert!(!rear.previewing());
        // Reversing 2.1 m carries all three beyond two wheelbases at once (the queue in
        // order: its back is the farthest).
        let mut pv = Preview::new(Config::with_wheelbase(2.0)).unwrap();
        pv.front_with(&b, &identified(false), 0.0);
        pv.front_with(&b, &identified(true), 0.5);
        pv.front_with(&b, &identified(true), 2.5);
        for t in 1000..1211 {
            pv.rear::<Libm>(&mut rear, &at(t, Some(-10.0)));
        }
        assert_eq!((pv.pending(), pv.dropped(), pv.handed()), (0, 3, 0));
        // Alone, a change with a 0.5 m gap arrives 0.5 m (50 steps) sooner than a wheelbase.
        let mut pv = Preview::new(Config::with_wheelbase(2.0)).unwrap();
        pv.front_with(&b, &identified(true), 0.5);
        let arrived = (300..600).find(|&t| {
            pv.rear::<Libm>(&mut rear, &at(t, Some(10.0)));
            pv.handed() == 1
        });
        assert_eq!(arrived, Some(450));
    }

    #[test]
    fn a_bad_config_is_refused() {
        for (wheelbase, weight) in [(0.0, 0.9), (f64::NAN, 0.9), (2.7, 0.0), (2.7, 1.0)] {
            assert_eq!(
                Preview::new(Config { wheelbase, weight }).err(),
                Some(PreviewError::BadConfig)
            );
        }
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(32))]
        /// A front and a rear wheel on random finite streams, the preview between them over a
        /// short wheelbase, and raw readings of any floats: every estimate finite.
        #[test]
        fn any_streams_and_readings_give_finite_estimates(
            rows in proptest::collection::vec(
                (0u32..3000, -2e4f64..2e4, -1e4f64..1e4, -500f64..500.0, -1.5f64..1.5, -60f64..60.0),
                1..300,
            ),
            raw in proptest::collection::vec(proptest::num::f64::ANY, CELLS),
            weight in proptest::num::f64::ANY,
        ) {
            let p = tyre();
            let mut f = Bank::new::<Libm>(&p, None, BankConfig::default()).unwrap();
            let mut r = f.clone();
            let mut pv = Preview::new(Config::with_wheelbase(0.3)).unwrap();
            let profile: [f64; CELLS] = core::array::from_fn(|k| raw[k]);
            let mut t = 0u32;
            for (i, (dt, fz, fy, mz, k, vx)) in rows.into_iter().enumerate() {
                t = t.wrapping_add(dt);
                let s = Sample { t_us: t, fz, fy, mz, fx: Some(fy * 0.3), kappa: Some(k), vx: Some(vx), gamma: None };
                f.update::<Libm>(&p, &s);
                pv.front(&f);
                pv.rear::<Libm>(&mut r, &s);
                // (Raw floats: most are no reading, and are ignored.)
                if let Some(reading) = Reading::new(&profile, weight).filter(|_| i % 50 == 0) {
                    r.preview::<Libm>(reading);
                }
                let e = r.update::<Libm>(&p, &s);
                proptest::prop_assert!(e.mu.is_finite() && e.sigma.is_finite() && e.sigma >= 0.0 && e.mu_min.is_finite(), "{e:?}");
            }
        }
    }
}
