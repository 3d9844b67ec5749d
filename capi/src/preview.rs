//! The front-to-rear preview (`gough::mu::preview`): one side's hand-over of what the front wheel
//! read to the rear wheel.

use crate::*;
use core_gough::mu::preview;

/// Starts one side's front-to-rear preview (`gough::mu::preview`: what the front wheel's
/// estimator read is handed to the rear wheel's on the same side once it has rolled
/// `wheelbase` metres, measured by the rear's Vx; weight 0.9). Use one per side, never across.
/// Per sample: after the front wheel's update `gough_preview_front` (or `_front_wheel`),
/// before the rear wheel's update `gough_preview_rear` (or `_rear_wheel`) with the sample the
/// rear is about to take. `GOUGH_E_ARG`: the wheelbase is not a positive number.
#[no_mangle]
pub unsafe extern "C" fn gough_preview_init(pv: *mut gough_preview_t, wheelbase: f32) -> i32 {
    ret(|| {
        if pv.is_null() {
            return Err(GOUGH_E_NULL);
        }
        // SAFETY: non-null; unmark, so that a failure leaves it unusable.
        unsafe { pv.cast::<u32>().write(0) };
        let val =
            Preview::new(preview::Config::with_wheelbase(wheelbase)).map_err(|_| GOUGH_E_ARG)?;
        // SAFETY: non-null, GOUGH_PREVIEW_SIZE bytes aligned to 8.
        unsafe { put(pv, MAGIC_PREVIEW, val) };
        Ok(())
    })
}

/// After the front estimator's `gough_estimator_update`: queues what it read when that update
/// made a new identification (its first, its first after a fallback, a change of surface).
#[no_mangle]
pub unsafe extern "C" fn gough_preview_front(
    pv: *mut gough_preview_t,
    front: *const gough_estimator_t,
) -> i32 {
    ret(|| {
        // SAFETY: storages or null; the preview exclusive for the call.
        let pv: &mut Preview<f32> = unsafe { get_mut(pv, MAGIC_PREVIEW)? };
        // SAFETY: as above.
        let front: &EstIn = unsafe { get(front, MAGIC_EST)? };
        pv.front(&front.bank);
        Ok(())
    })
}

/// Before the rear estimator's `gough_estimator_update` with sample `s`: rolls the readings on
/// by the distance the rear wheel covered since its last sample (`s`'s Vx; without
/// `GOUGH_HAS_VX` nothing moves) and hands those that have arrived to `rear`.
/// `GOUGH_E_NONFINITE`: the sample is refused (nothing changes).
#[no_mangle]
pub unsafe extern "C" fn gough_preview_rear(
    pv: *mut gough_preview_t,
    rear: *mut gough_estimator_t,
    s: *const gough_sample_t,
) -> i32 {
    ret(|| {
        // SAFETY: storages or null, distinct (their magic words differ); exclusive for the call.
        let pv: &mut Preview<f32> = unsafe { get_mut(pv, MAGIC_PREVIEW)? };
        // SAFETY: as above.
        let rear: &mut EstIn = unsafe { get_mut(rear, MAGIC_EST)? };
        if s.is_null() {
            return Err(GOUGH_E_NULL);
        }
        // SAFETY: non-null, the caller's sample.
        let sample = sample(&unsafe { s.read() })?;
        pv.rear::<Fast>(&mut rear.bank, &sample);
        Ok(())
    })
}

/// `gough_preview_front` for a wheel's pipeline (`gough_wheel_step` of the front wheel first).
/// `GOUGH_E_ARG`: the wheel runs no estimator.
#[no_mangle]
pub unsafe extern "C" fn gough_preview_front_wheel(
    pv: *mut gough_preview_t,
    front: *const gough_wheel_t,
) -> i32 {
    ret(|| {
        // SAFETY: storages or null; the preview exclusive for the call.
        let pv: &mut Preview<f32> = unsafe { get_mut(pv, MAGIC_PREVIEW)? };
        // SAFETY: as above.
        let front: &WheelIn = unsafe { get(front, MAGIC_WHEEL)? };
        pv.front(front.wheel.estimator().ok_or(GOUGH_E_ARG)?);
        Ok(())
    })
}

/// `gough_preview_rear` for a wheel's pipeline, before its `gough_wheel_step` with `m` (the
/// estimator's sample of `m`, κ from ω as the step takes it). `GOUGH_E_ARG`: the wheel runs no
/// estimator, or `m`'s wheel index is not 0–3; `GOUGH_E_NONFINITE`: `m` is refused.
#[no_mangle]
pub unsafe extern "C" fn gough_preview_rear_wheel(
    pv: *mut gough_preview_t,
    rear: *mut gough_wheel_t,
    m: *const gough_measurement_t,
) -> i32 {
    ret(|| {
        // SAFETY: storages or null, distinct (their magic words differ); exclusive for the call.
        let pv: &mut Preview<f32> = unsafe { get_mut(pv, MAGIC_PREVIEW)? };
        // SAFETY: as above.
        let wi: &mut WheelIn = unsafe { get_mut(rear, MAGIC_WHEEL)? };
        if m.is_null() {
            return Err(GOUGH_E_NULL);
        }
        // SAFETY: non-null, the caller's measurement.
        let meas = wheel::Measurement::from(&measurement(&unsafe { m.read() })?);
        // SAFETY: set by `gough_wheel_init` to caller-owned params that outlive the wheel.
        let p = unsafe { &*wi.params };
        let s = wheel::sample::<f32, Fast>(p, &meas);
        let bank = wi.wheel.estimator_mut().ok_or(GOUGH_E_ARG)?;
        pv.rear::<Fast>(bank, &s);
        Ok(())
    })
}
