//! The bank's tests: streams of a wheel on known surfaces, through the whole estimator.

use super::*;
use crate::math::Libm;
use crate::mf::{self, Input, Options};
use crate::mu::{State, CELLS};
use proptest::prelude::*;
extern crate std;
use std::vec::Vec;

pub(crate) fn tyre() -> Params<f64> {
    let text = include_str!("../../../host-tests/data/tyres/MagicFormula61_Parameters.tir");
    crate::tir::parse(text).unwrap().params
}

/// Samples of a wheel at slips (α(t), κ(t)) and speed `vx` (steady-state Magic Formula on
/// surface μ, the transient option as the estimator evaluates it; κ measured without noise),
/// 1 kHz, clock starting at `t0_us`.
pub(crate) fn slips_stream(
    p: &Params<f64>,
    mu: f64,
    slips: impl Fn(f64) -> (f64, f64),
    vx: f64,
    n: usize,
    t0_us: u32,
) -> Vec<Sample<f64>> {
    let mu0 = mu_y0::<f64, Libm>(p).unwrap();
    let mut q = p.clone();
    q.lmux = p.lmux * mu / mu0;
    q.lmuy = p.lmuy * mu / mu0;
    let opts = Options {
        transient: true,
        moments: false,
        ..Options::default()
    };
    (0..n)
        .map(|i| {
            let (alpha, kappa) = slips(i as f64 * 1e-3);
            let input = Input {
                fz: p.fnomin,
                alpha,
                kappa,
                vx,
                ..Input::default()
            };
            let o = mf::eval::<f64, Libm>(&q, &input, &opts).unwrap();
            Sample {
                t_us: t0_us.wrapping_add((i as u32).wrapping_mul(1000)),
                fz: p.fnomin,
                fy: o.fy,
                mz: o.mz,
                fx: Some(o.fx),
                kappa: Some(kappa),
                vx: Some(vx),
                gamma: Some(0.0),
            }
        })
        .collect()
}

/// A noisy slalom (α = 0.06 rad·sin(π·t), bench noise) on μ 1.0 for `n` samples, then `len`
/// more on `mu`: a change of road at the phase `n` picks.
fn slalom_onto(p: &Params<f64>, mu: f64, n: usize, len: usize) -> Vec<Sample<f64>> {
    let alpha = |t: f64| 0.06 * (core::f64::consts::TAU * 0.5 * t).sin();
    let mut s = stream(p, 1.0, alpha, n, 0);
    s.extend(stream(
        p,
        mu,
        |t| alpha(t + n as f64 * 1e-3),
        len,
        n as u32 * 1000,
    ));
    noisy(s)
}

/// Samples of [`onto_grippier`] on μ 0.3, before the change.
const ONTO_GRIPPIER: usize = 1500;

/// A wheel identified on μ 0.3 in a turn (α ramped to 0.1 rad), then 0.5 s on μ 1.0 at α
/// 0.1 rad: |Fy| near 1.0·Fz, a force the old estimate cannot produce.
fn onto_grippier(p: &Params<f64>) -> Vec<Sample<f64>> {
    let n = ONTO_GRIPPIER;
    let mut s = stream(p, 0.3, |t| 0.1 * (t / 0.5).min(1.0), n, 0);
    s.extend(stream(p, 1.0, |_| 0.1, 500, n as u32 * 1000));
    s
}

/// Samples of a freely rolling wheel (κ 0) at slip angle α(t), 20 m/s.
fn stream(
    p: &Params<f64>,
    mu: f64,
    alpha: impl Fn(f64) -> f64,
    n: usize,
    t0_us: u32,
) -> Vec<Sample<f64>> {
    slips_stream(p, mu, |t| (alpha(t), 0.0), 20.0, n, t0_us)
}

/// On a surface midway between two cells' centres, held near its limit, no far surface is
/// reported identifiable (docs/estimator.md, "Off the grid"; `gough mu bench --mu-shift
/// 0.025`). With fixed hypotheses (before the fitted offsets) μ 0.125 was: 36 of 5,000
/// samples identifiable and off by more than 0.2.
#[test]
fn a_surface_between_two_hypotheses_is_never_read_as_a_far_one() {
    let p = tyre();
    let mut worst = std::vec::Vec::new();
    for mu in [0.125, 0.325, 0.525] {
        let peak = -0.08 * mu / 0.525;
        let s = noisy(stream(&p, mu, |t| peak * (t / 1.0).min(1.0), 5000, 0));
        let est = run(&p, &s);
        let ident = |e: &&Estimate<f64>| e.state == State::Identifiable;
        let off = est
            .iter()
            .filter(ident)
            .filter(|e| (e.mu - mu).abs() > 0.2)
            .count();
        let near = est
            .iter()
            .filter(ident)
            .filter(|e| (e.mu - mu).abs() <= 0.05)
            .count();
        worst.push((mu, off, near));
    }
    // (μ, identifiable and off by > 0.2, identifiable within ±0.05; samples of 5,000)
    std::println!("{worst:?}");
    // Never confidently wrong, and read on each.
    assert!(
        worst.iter().all(|&(_, off, near)| off == 0 && near > 500),
        "{worst:?}"
    );
}

/// The defaults with the tyre's calibration known (a warm start; the simulated tyre is its
/// file): the σ of the properties a tenth of the prior's.
pub(crate) fn warm() -> Config<f64> {
    let d = Config::<f64>::default();
    Config {
        cal_sigma: d.cal_sigma.map(|s| s * 0.1),
        ..d
    }
}

fn run(p: &Params<f64>, s: &[Sample<f64>]) -> Vec<Estimate<f64>> {
    let mut e = Bank::new::<Libm>(p, None, Config::default()).unwrap();
    s.iter().map(|x| e.update::<Libm>(p, x)).collect()
}

/// Adds the bench's sensor noise (forces 1 % of Fz, Mz 2 N·m, κ 0.005 rms; a fixed LCG).
pub(crate) fn noisy(mut s: Vec<Sample<f64>>) -> Vec<Sample<f64>> {
    let mut x = 0x2545_f491_4f6c_dd1du64;
    let mut gauss = move || {
        // Sum of 12 uniforms − 6: unit variance, deterministic.
        (0..12)
            .map(|_| {
                x = x
                    .wrapping_mul(6_364_136_223_846_793_005)
                    .wrapping_add(1_442_695_040_888_963_407);
                (x >> 11) as f64 / (1u64 << 53) as f64
            })
            .sum::<f64>()
            - 6.0
    };
    for r in s.iter_mut() {
        let sf = 0.01 * r.fz;
        r.fy += sf * gauss();
        r.mz += 2.0 * gauss();
        r.fx = r.fx.map(|v| v + sf * gauss());
        r.fz += sf * gauss();
        r.kappa = r.kappa.map(|v| v + 0.005 * gauss());
    }
    s
}

#[test]
fn straight_running_is_never_identifiable() {
    let p = tyre();
    // With the sensors' noise: nothing to read.
    for mu in [0.3, 1.0] {
        let est = run(&p, &noisy(stream(&p, mu, |_| 0.0, 3000, 0)));
        assert!(
            est.iter().all(|e| e.state != State::Identifiable),
            "μ {mu}: {:?}",
            est.last()
        );
    }
    // Without noise, the free-rolling shifts (SVy, Mzr) carry a little of μ: whatever is
    // reported identifiable is right.
    let est = run(&p, &stream(&p, 0.3, |_| 0.0, 3000, 0));
    for e in &est {
        if e.state == State::Identifiable {
            assert!((e.mu - 0.3).abs() <= 0.1, "{e:?}");
        }
    }
}

#[test]
fn a_hard_turn_on_a_wet_road_reads_its_friction() {
    let p = tyre();
    // α ramps to 0.1 rad over 0.5 s: beyond the peak on μ 0.5.
    let est = run(&p, &stream(&p, 0.5, |t| 0.1 * (t / 0.5).min(1.0), 1500, 0));
    let last = est.last().unwrap();
    assert_eq!(last.state, State::Identifiable, "{last:?}");
    assert!((last.mu - 0.5).abs() < 0.05, "{last:?}");
    // Never identifiable with a wrong value on the way.
    for e in &est {
        if e.state == State::Identifiable {
            assert!((e.mu - 0.5).abs() <= 0.1, "{e:?}");
        }
    }
}

/// A reading from ahead waits at most one sample for a slot of the rear's work (`work`),
/// wherever in a batch's fit it arrives; a second one arriving while one waits mixes that
/// one in first.
#[test]
fn a_reading_from_ahead_is_mixed_in_within_a_sample() {
    let p = tyre();
    let s = stream(&p, 0.5, |t| 0.1 * (t / 0.5).min(1.0), 1500, 0);
    let mut b = Bank::new::<Libm>(&p, None, Config::default()).unwrap();
    let profile: [f64; CELLS] = core::array::from_fn(|k| 0.5 * (k as f64 - 4.0).powi(2));
    let reading = |w: f64| Reading::new(&profile, w).unwrap();
    let mut waits = [0usize; 2];
    for (i, x) in s.iter().enumerate() {
        if i >= 300 {
            let mut r = b.clone();
            r.preview::<Libm>(reading(0.9));
            assert!(r.previewing());
            let n = s[i..].iter().take_while(|y| {
                r.update::<Libm>(&p, y);
                r.previewing()
            });
            let n = n.count();
            assert!(n <= 1, "sample {i}: waited {n} samples");
            waits[n] += 1;
            // The first is mixed in by the second's arrival (the likelihoods move at once),
            // the second waits.
            let mut r = b.clone();
            r.preview::<Libm>(reading(0.9));
            assert_eq!(r.profile(), b.profile());
            r.preview::<Libm>(reading(0.5));
            assert_ne!(r.profile(), b.profile(), "sample {i}");
            assert!(r.previewing());
        }
        b.update::<Libm>(&p, x);
    }
    // Mostly at once; a wait only on the samples that close a batch with fits to do.
    assert!(waits[0] > 10 * waits[1], "{waits:?}");
    // One sample per batch (the 100 Hz configuration): every sample closes a batch and
    // fits every cell in contention, and a reading still waits one sample at most.
    let cfg = Config::default();
    let mut b = Bank::new::<Libm>(&p, None, cfg).unwrap();
    for (i, x) in s.iter().enumerate().step_by(10) {
        if i >= 300 && i % 50 == 0 {
            let mut r = b.clone();
            r.preview::<Libm>(reading(0.9));
            r.update::<Libm>(&p, x);
            r.update::<Libm>(&p, x);
            assert!(!r.previewing(), "sample {i}");
        }
        b.update::<Libm>(&p, x);
    }
}

/// A slalom on μ 1.0 (cells far from it excluded, fitted on every [`VISIT`]th batch only),
/// then the road drops to 0.3, at eight phases of the slalom: the batch the likeliest cell
/// no longer explains is fitted on every cell (the first batch on the new road), and the
/// new surface is read within 100 ms at every phase (56–96 ms, the tyre's calibration known:
/// [`warm`]; before the calibration, 55–78 ms). Without the refit (each far
/// cell's last χ² and slips standing until its visit) it took 89–95 ms at three of them.
#[test]
fn a_drop_in_friction_refits_every_cell_at_once() {
    let p = tyre();
    for n in [2650usize, 2700, 2750, 2800, 2850, 2900, 3100, 3300] {
        let s = slalom_onto(&p, 0.3, n, 900);
        let mut b = Bank::new::<Libm>(&p, None, warm()).unwrap();
        let (mut refit, mut read) = (None, None);
        for (i, x) in s.iter().enumerate() {
            let before = b.n_active;
            let e = b.update::<Libm>(&p, x);
            if i < n {
                continue;
            }
            if refit.is_none() && before < CELLS && b.n_active == CELLS {
                refit = Some(i - n);
            }
            if read.is_none() && e.state == State::Identifiable && (e.mu - 0.3).abs() <= 0.1 {
                read = Some(i - n);
            }
        }
        assert!(refit.is_some_and(|k| k < 20), "change at {n} ms: {refit:?}");
        assert!(read.is_some_and(|k| k <= 100), "change at {n} ms: {read:?}");
    }
}

/// Issue 39's dry → ice step, at nine phases of a slalom (the step at full lateral force,
/// on the way down, at a zero crossing, on the way up): the ice (μ 0.1) is read —
/// identifiable within ±0.1, and within ±0.1 from then on — within 150 ms of meeting it at
/// every phase (69–138 ms; at the zero crossing the slowest), and that first identification
/// carries the change flag; no flag on the dry road before.
#[test]
fn a_dry_to_ice_step_is_read_and_flagged_within_150_ms() {
    let p = tyre();
    for n in [2650usize, 2700, 2750, 2800, 2850, 2900, 3000, 3100, 3300] {
        let est = run(&p, &slalom_onto(&p, 0.1, n, 900));
        assert!(est[..n].iter().all(|e| !e.change), "step at {n} ms");
        let read = est[n..]
            .iter()
            .position(|e| e.state == State::Identifiable && (e.mu - 0.1).abs() <= 0.1);
        assert!(read.is_some_and(|k| k <= 150), "step at {n} ms: {read:?}");
        let k = read.unwrap_or(0);
        assert!(est[n + k].change, "step at {n} ms: {:?}", est[n + k]);
        assert!(
            est[n + k..].iter().all(|e| (e.mu - 0.1).abs() <= 0.1),
            "step at {n} ms"
        );
    }
}

/// The change flag compares with the last identifiable value, also when the value held
/// after it was dropped on the way — by the evidence turning against it, or here by a
/// force it cannot produce (μ 0.3 → 1.0 at α 0.1 rad, as in the test below): the first
/// identification of the new road is flagged, nothing before it. Compared with the held
/// value, the flag was lost (and the preview handed the rear wheel nothing; `gough mu
/// bench` counts 25 change flags per seed with this, each a change of road; a scratch
/// listing found 8–10 before).
#[test]
fn a_change_is_flagged_also_when_the_held_value_was_dropped() {
    let p = tyre();
    let n = ONTO_GRIPPIER;
    let est = run(&p, &onto_grippier(&p));
    assert!(est[..n].iter().all(|e| !e.change));
    // The first identification that is not the old road's.
    let first = est[n..]
        .iter()
        .position(|e| e.state == State::Identifiable && (e.mu - 0.3).abs() > 0.1)
        .map(|k| est[n + k]);
    assert!(
        first.is_some_and(|e| e.change && (e.mu - 1.0).abs() <= 0.1),
        "{first:?}"
    );
    assert_eq!(est.iter().filter(|e| e.change).count(), 1);
}

/// The per-sample budget's structure, on streams that make every kind of sample: a slalom
/// on μ 1.0 onto 0.3 (the refit of every cell) with sensor noise, the rear's own profile
/// handed to it every 7th sample (the bench's stress of the preview). With batches of 2 to
/// 10 samples no sample fits more than ⌈CELLS/batch⌉ cells (at least [`SLOTS`]) counting a
/// mixture as one — but for a reading that already waited a sample, which takes a slot of
/// its own (never at 1 kHz's batches of 10) —, a sample that finishes a batch fits fewer
/// than that, and no batch's fit is left for the next batch's close; with one sample per
/// batch (100 Hz) the last holds too.
#[test]
fn no_sample_takes_more_than_its_slots() {
    let p = tyre();
    let n = 2850;
    let s = slalom_onto(&p, 0.3, n, 1500);
    for batch in [10u16, 7, 5, 3, 2, 1] {
        // The stream is at 1 kHz: `batch` samples of it are `batch` ms.
        let cfg = Config {
            batch_us: u32::from(batch) * 1000,
            ..Config::default()
        };
        let slots = CELLS.div_ceil(usize::from(batch)).max(SLOTS);
        let mut b = Bank::new::<Libm>(&p, None, cfg).unwrap();
        let (mut refits, mut finishing, mut full) = (0, 0, 0);
        for (i, x) in s.iter().enumerate() {
            // (A profile taken right after a mixture may hold a value a rounding below 0: no
            // reading then.)
            if let Some(r) = Reading::new(&b.profile(), 0.9).filter(|_| i % 7 == 0) {
                b.preview::<Libm>(r);
            }
            b.update::<Libm>(&p, x);
            let t = b.trace;
            refits += usize::from(t.refit);
            assert_eq!(t.forced_fits, 0, "batch {batch}, sample {i}: {t:?}");
            if batch > 1 {
                let own = usize::from(t.own_slot);
                assert!(batch < 10 || own == 0, "sample {i}: {t:?}");
                assert!(t.load <= slots + own, "batch {batch}, sample {i}: {t:?}");
                assert!(t.load_finishing < slots, "batch {batch}, sample {i}: {t:?}");
                full += usize::from(t.load == slots);
                finishing += usize::from(t.load_finishing > 0);
            }
        }
        assert!(refits > 0, "batch {batch}: the stream refits every cell");
        if batch > 1 {
            // The stream reaches both limits (at batch 2 on about ten samples, 9 to 12
            // as the gates change; hundreds at the larger batches).
            assert!(
                full >= 5 && finishing >= 5,
                "batch {batch}: {full} {finishing}"
            );
        }
    }
}

#[test]
fn a_force_the_estimate_cannot_produce_ends_the_identification_at_once() {
    let p = tyre();
    // Identified on μ 0.3, then the wheel runs onto μ 1.0 at α 0.1 rad: |Fy| near 1.0·Fz.
    let n = ONTO_GRIPPIER;
    let est = run(&p, &onto_grippier(&p));
    let before = est[n - 1];
    assert_eq!(before.state, State::Identifiable, "{before:?}");
    assert!((before.mu - 0.3).abs() < 0.05, "{before:?}");
    // From the batch's 3rd sample on the new surface: not the old value, not identifiable,
    // and μ bounded from below — a batch and its fit (20 samples) would have been too late.
    for (i, e) in est.iter().enumerate().skip(n + 3).take(30) {
        assert_ne!(e.state, State::Identifiable, "{i}: {e:?}");
        assert!(e.mu >= 0.5 && e.mu_min >= 0.5, "{i}: {e:?}");
    }
    // and then the new surface is read.
    let last = est.last().unwrap();
    assert_eq!(last.state, State::Identifiable, "{last:?}");
    assert!((last.mu - 1.0).abs() < 0.05, "{last:?}");
}

#[test]
fn an_identification_ages_while_the_force_says_nothing_of_the_surface() {
    let p = tyre();
    // Identified on μ 1.0 in a hard turn (α 0.1 rad), then 0.6 s at α 0.005 rad (|Fy| about
    // 0.1·Fz: the linear range, every surface above it explains it alike), then α 0.1 again.
    let alpha = |t: f64| {
        if t < 1.5 {
            0.1 * (t / 0.5).min(1.0)
        } else if t < 2.1 {
            0.005
        } else {
            0.1
        }
    };
    let est = run(&p, &noisy(stream(&p, 1.0, alpha, 2600, 0)));
    let at = |t: f64| est[(t * 1000.0) as usize];
    assert_eq!(at(1.499).state, State::Identifiable, "{:?}", at(1.499));
    // Within 0.25 s of the low force (at 20 m/s, σ² grows by 0.02 per second from the last
    // batch that used 0.3 of the surface; from about 0.015 it passes 0.1/1.96 in ~0.12 s):
    // no longer identifiable, the value held.
    for (i, e) in est.iter().enumerate().take(2100).skip(1750) {
        assert_ne!(e.state, State::Identifiable, "{i}: {e:?}");
        assert!((e.mu - 1.0).abs() < 0.1, "{i}: {e:?}");
    }
    // Back in the turn: identifiable again, on the same value.
    let last = est.last().unwrap();
    assert_eq!(last.state, State::Identifiable, "{last:?}");
    assert!((last.mu - 1.0).abs() < 0.05, "{last:?}");
    // Without the rule (`inform_util` 0), on a tyre known exactly (no calibration σ to make
    // the linear range uninformative by itself), the identification stood through the quiet
    // stretch.
    let mut e = Bank::new::<Libm>(
        &p,
        None,
        Config {
            inform_util: 0.0,
            cal_sigma: [0.0; 4],
            ..Config::default()
        },
    )
    .unwrap();
    let old: Vec<_> = noisy(stream(&p, 1.0, alpha, 2600, 0))
        .iter()
        .map(|x| e.update::<Libm>(&p, x))
        .collect();
    assert_eq!(old[2099].state, State::Identifiable, "{:?}", old[2099]);
}

/// A turn under drive at 15 m/s: slips α, κ ramped in over 1 s and held, measured with the
/// bench's noise.
fn steady(p: &Params<f64>, mu: f64, alpha: f64, kappa: f64, n: usize) -> Vec<Sample<f64>> {
    let ramp = |t: f64| t.min(1.0);
    noisy(slips_stream(
        p,
        mu,
        |t| (alpha * ramp(t), kappa * ramp(t)),
        15.0,
        n,
        0,
    ))
}

#[test]
fn a_long_steady_turn_on_ice_is_read_and_never_as_another_surface() {
    let p = tyre();
    // α −0.02 rad, κ 0.01 under drive on μ 0.1 for 40 s, the measured κ with 0.005 rms of
    // noise (half the slip): never identifiable as another surface.
    let st = steady(&p, 0.1, -0.02, 0.01, 40_000);
    let est = run(&p, &st);
    let wrong = est
        .iter()
        .filter(|e| e.state == State::Identifiable && (e.mu - 0.1).abs() > 0.1)
        .count();
    let ident = est
        .iter()
        .filter(|e| e.state == State::Identifiable)
        .count();
    // Read, and held, on its own surface: the resultant exceeds μx·Fz and μy·Fz here (the
    // vertical shift SVx scales with λμ′, not λμ*), which a force check against the friction
    // ellipse's axes took for a grippier surface and kept the estimate from ever settling.
    assert!(
        ident > 30_000,
        "identifiable on {ident} samples; {:?}",
        est.last()
    );
    assert_eq!(wrong, 0, "{:?}", est.last());
}

#[test]
fn the_clock_origin_does_not_matter() {
    let p = tyre();
    let a = |t: f64| 0.08 * (t / 0.4).min(1.0);
    let e0 = run(&p, &stream(&p, 0.7, a, 1200, 0));
    // 10⁶ s later, and across the u32 wrap.
    let e1 = run(
        &p,
        &stream(
            &p,
            0.7,
            a,
            1200,
            (1_000_000_000_000u64 % (1u64 << 32)) as u32,
        ),
    );
    let e2 = run(&p, &stream(&p, 0.7, a, 1200, u32::MAX - 500_000));
    assert_eq!(e0, e1);
    assert_eq!(e0, e2);
}

#[test]
fn bad_samples_are_held_and_counted() {
    let p = tyre();
    let mut s = stream(&p, 0.5, |t| 0.1 * (t / 0.5).min(1.0), 1500, 0);
    let mut e = Bank::new::<Libm>(&p, None, Config::default()).unwrap();
    let mut last = None;
    for (i, x) in s.iter_mut().enumerate() {
        if i % 97 == 0 {
            x.fy = f64::NAN;
        }
        if i % 89 == 0 {
            x.fz = -5.0;
        }
        if i % 83 == 0 {
            x.mz = f64::INFINITY;
        }
        let est = e.update::<Libm>(&p, x);
        assert!(est.mu.is_finite() && est.sigma.is_finite());
        last = Some(est);
    }
    assert!(e.bad_samples() >= 40, "{}", e.bad_samples());
    let last = last.unwrap();
    assert!((last.mu - 0.5).abs() < 0.05, "{last:?}");
}

#[test]
fn a_config_without_a_grid_or_a_batch_is_refused() {
    let p = tyre();
    for cfg in [
        Config {
            batch_us: 0,
            ..Config::default()
        },
        Config {
            mu_hi_rel: 0.0,
            ..Config::default()
        },
        Config {
            cal_sigma: [0.1, -0.01, 0.002, 0.1],
            ..Config::default()
        },
        Config {
            mu_step: 0.0,
            ..Config::default()
        },
        Config {
            mu_lo: f64::NAN,
            ..Config::default()
        },
    ] {
        assert_eq!(
            Bank::new::<Libm>(&p, None, cfg).err(),
            Some(BuildError::BadConfig)
        );
    }
    let mut flat = p.clone();
    flat.lmuy = 0.0;
    assert_eq!(
        Bank::new::<Libm>(&flat, None, Config::default()).err(),
        Some(BuildError::NoFriction)
    );
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]
    #[test]
    fn any_finite_stream_gives_finite_estimates(
        rows in proptest::collection::vec(
            (0u32..3000, -2e4f64..2e4, -1e4f64..1e4, -500f64..500.0, -1e4f64..1e4, -1.5f64..1.5, -60f64..60.0, -0.3f64..0.3),
            1..400,
        )
    ) {
        let p = tyre();
        let mut e = Bank::new::<Libm>(&p, Some(Side::Right), Config::default()).unwrap();
        let mut t = 0u32;
        for (dt, fz, fy, mz, fx, k, vx, g) in rows {
            t = t.wrapping_add(dt);
            let est = e.update::<Libm>(&p, &Sample { t_us: t, fz, fy, mz, fx: Some(fx), kappa: Some(k), vx: Some(vx), gamma: Some(g) });
            prop_assert!(est.mu.is_finite() && est.sigma.is_finite() && est.sigma >= 0.0);
            prop_assert!(est.mu_min.is_finite());
        }
    }
}

/// A known road is taken only on the bank's grid and finite; `None` returns to the online
/// calibration; nothing counted before a batch.
#[test]
fn a_known_surface_is_refused_outside_the_grid() {
    let p = tyre();
    let mut b = Bank::new::<Libm>(&p, None, Config::default()).unwrap();
    let top = b.grid().mu_of(CELLS - 1);
    for bad in [0.0, -0.3, f64::NAN, f64::INFINITY, top * 1.01] {
        assert!(!b.set_known_surface(Some(bad)), "{bad}");
    }
    assert!(b.set_known_surface(Some(0.8)));
    assert!(b.set_known_surface(Some(top)));
    assert_eq!(b.known_surface_batches(), (0, 0));
    assert!(b.set_known_surface(None));
}
