//! The friction estimator alone (`gough::mu::Bank`): its samples, its start on a tyre and side, its
//! update, and its calibration of the tyre (`gough::mu::calibration`) out and in.

use crate::*;

/// One sample for the estimator alone (`gough::mu::Sample`). ISO-W at the contact point,
/// SI units; the optional fields count only with their `GOUGH_HAS_*` bit in `present`
/// (`GOUGH_HAS_FX`, `GOUGH_HAS_KAPPA`, `GOUGH_HAS_VX`, `GOUGH_HAS_GAMMA`). Never α.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default)]
pub struct gough_sample_t {
    /// Timestamp [µs], wrapping: only differences are used.
    pub t_us: u32,
    /// Vertical load Fz [N].
    pub fz: f32,
    /// Measured lateral force Fy [N].
    pub fy: f32,
    /// Measured aligning moment Mz [N m].
    pub mz: f32,
    /// Measured longitudinal force Fx [N] (`GOUGH_HAS_FX`).
    pub fx: f32,
    /// Longitudinal slip κ [-] (`GOUGH_HAS_KAPPA`).
    pub kappa: f32,
    /// Forward speed Vx [m/s] (`GOUGH_HAS_VX`).
    pub vx: f32,
    /// Inclination angle γ [rad] (`GOUGH_HAS_GAMMA`).
    pub gamma: f32,
    /// `GOUGH_HAS_*` bits.
    pub present: u32,
}

/// The estimator's sample of C's, or `GOUGH_E_NONFINITE`.
pub(crate) fn sample(s: &gough_sample_t) -> Result<mu::Sample<f32>, i32> {
    let p = s.present;
    let sample = mu::Sample {
        t_us: s.t_us,
        fz: s.fz,
        fy: s.fy,
        mz: s.mz,
        fx: opt(p, GOUGH_HAS_FX, s.fx),
        kappa: opt(p, GOUGH_HAS_KAPPA, s.kappa),
        vx: opt(p, GOUGH_HAS_VX, s.vx),
        gamma: opt(p, GOUGH_HAS_GAMMA, s.gamma),
    };
    let given = [sample.fx, sample.kappa, sample.vx, sample.gamma];
    if !finite(&[s.fz, s.fy, s.mz]) || given.iter().flatten().any(|x| !x.is_finite()) {
        return Err(GOUGH_E_NONFINITE);
    }
    Ok(sample)
}

/// Starts the friction estimator (`gough::mu::bank::Bank`, default settings, the tyre as the
/// file describes it) of one wheel on tyre `p`. **`p` must outlive the estimator** and stay
/// unchanged while it runs (the estimator keeps a pointer to it). `GOUGH_E_MODEL`: the tyre
/// gives no usable friction. `gough_estimator_init_on` mounts it on a side.
#[no_mangle]
pub unsafe extern "C" fn gough_estimator_init(
    e: *mut gough_estimator_t,
    p: *const gough_params_t,
) -> i32 {
    // SAFETY: the caller's pointers, as documented above.
    unsafe { gough_estimator_init_on(e, p, 0) }
}

/// `gough_estimator_init` for a wheel on a side: `options` `GOUGH_WHEEL_LEFT` or
/// `GOUGH_WHEEL_RIGHT` (its samples in the wheel's own ISO-W axes, the tyre mirrored where the
/// file describes the other side's), or 0 (as the file describes the tyre). `GOUGH_E_ARG`: any
/// other bit, or both sides.
#[no_mangle]
pub unsafe extern "C" fn gough_estimator_init_on(
    e: *mut gough_estimator_t,
    p: *const gough_params_t,
    options: u32,
) -> i32 {
    ret(|| {
        let mounted = side_of(options, 0)?;
        // SAFETY: a params storage or null; the caller keeps it alive (documented).
        let params: &'static ParamsIn = unsafe { get(p, MAGIC_PARAMS)? };
        if e.is_null() {
            return Err(GOUGH_E_NULL);
        }
        // SAFETY: non-null; unmark, so that a failure leaves it unusable.
        unsafe { e.cast::<u32>().write(0) };
        let bank = Bank::new::<Fast>(&params.p32, mounted, mu::Config::default())
            .map_err(|_| GOUGH_E_MODEL)?;
        // SAFETY: non-null, GOUGH_ESTIMATOR_SIZE bytes aligned to 8.
        unsafe { put(e, MAGIC_EST, EstIn { bank, params }) };
        Ok(())
    })
}

/// One sample into the estimator; `*out` gets the estimate after it. A sample with a
/// non-finite value is refused (`GOUGH_E_NONFINITE`, nothing changes).
#[no_mangle]
pub unsafe extern "C" fn gough_estimator_update(
    e: *mut gough_estimator_t,
    s: *const gough_sample_t,
    out: *mut gough_estimate_t,
) -> i32 {
    ret(|| {
        // SAFETY: an estimator storage or null; exclusive for the call.
        let est: &mut EstIn = unsafe { get_mut(e, MAGIC_EST)? };
        if s.is_null() || out.is_null() {
            return Err(GOUGH_E_NULL);
        }
        // SAFETY: non-null, the caller's sample.
        let sample = sample(&unsafe { s.read() })?;
        let r = est.bank.update::<Fast>(&est.params.p32, &sample);
        // SAFETY: non-null, the caller's output.
        unsafe { out.write(estimate_c(&r)) };
        Ok(())
    })
}

/// `gough_calibration_t::value` index: the peak-trail scale (1 = the file).
pub const GOUGH_CAL_TRAIL: usize = 0;
/// `value` index: the scale of the trail's shape factor Bt.
pub const GOUGH_CAL_TRAIL_SHAPE: usize = 1;
/// `value` index: the trail's shift against the force, SHt − SHy [rad].
pub const GOUGH_CAL_TRAIL_SHIFT: usize = 2;
/// `value` index: the longitudinal slip stiffness scale (Kxκ).
pub const GOUGH_CAL_KX: usize = 3;
/// Number of calibrated properties.
pub const GOUGH_CAL_PROPERTIES: usize = 4;

/// An estimator's calibration of the tyre on the car relative to its file
/// (`gough::mu::calibration::Exported`): what a device stores at power-down and hands back at
/// power-up so that its estimators start warm.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default)]
pub struct gough_calibration_t {
    /// By `GOUGH_CAL_*` index: trail scale, trail-shape scale, trail shift [rad], Kxκ scale
    /// (scales: 1 = the file, > 0).
    pub value: [f32; GOUGH_CAL_PROPERTIES],
    /// Their σ (≥ 0): of a scale's logarithm (a relative σ), of the shift in rad.
    pub sigma: [f32; GOUGH_CAL_PROPERTIES],
    /// Batches that moved the calibration (0: the file as it is).
    pub batches: u32,
}

/// Writes `bank`'s calibration into `out` (`GOUGH_E_NULL` if null).
pub(crate) unsafe fn write_calibration(
    bank: &Bank<f32>,
    out: *mut gough_calibration_t,
) -> Result<(), i32> {
    if out.is_null() {
        return Err(GOUGH_E_NULL);
    }
    let e = bank.calibration().export::<Fast>();
    // SAFETY: non-null, the caller's output.
    unsafe {
        out.write(gough_calibration_t {
            value: e.value,
            sigma: e.sigma,
            batches: e.batches,
        })
    };
    Ok(())
}

/// Hands `bank` the calibration at `cal` (`GOUGH_E_NULL` if null; refusals as codes).
pub(crate) unsafe fn read_calibration(
    bank: &mut Bank<f32>,
    cal: *const gough_calibration_t,
) -> Result<(), i32> {
    if cal.is_null() {
        return Err(GOUGH_E_NULL);
    }
    // SAFETY: non-null, the caller's calibration.
    let c = unsafe { cal.read() };
    let e = mu::calibration::Exported {
        value: c.value,
        sigma: c.sigma,
        batches: c.batches,
    };
    bank.import_calibration::<Fast>(&e)
        .map_err(|err| match err {
            mu::calibration::CalibrationError::NotFinite => GOUGH_E_CAL_INVALID,
            mu::calibration::CalibrationError::OutOfBounds => GOUGH_E_CAL_BOUNDS,
        })
}

/// The estimator's calibration of the tyre into `*out`: each property's value and σ, and how
/// many batches moved it.
#[no_mangle]
pub unsafe extern "C" fn gough_estimator_get_calibration(
    e: *const gough_estimator_t,
    out: *mut gough_calibration_t,
) -> i32 {
    ret(|| {
        // SAFETY: an estimator storage or null.
        let est: &EstIn = unsafe { get(e, MAGIC_EST)? };
        // SAFETY: the caller's output or null (checked there).
        unsafe { write_calibration(&est.bank, out) }
    })
}

/// The estimator starts from calibration `*cal` (one `gough_estimator_get_calibration` gave
/// earlier, stored across a power cycle): from its next batch on the surfaces are read relative
/// to it. Refused, nothing changed: `GOUGH_E_CAL_INVALID` (a value or σ not a finite number, a
/// scale ≤ 0, a σ < 0), `GOUGH_E_CAL_BOUNDS` (a value beyond 4 prior σ).
#[no_mangle]
pub unsafe extern "C" fn gough_estimator_set_calibration(
    e: *mut gough_estimator_t,
    cal: *const gough_calibration_t,
) -> i32 {
    ret(|| {
        // SAFETY: an estimator storage or null; exclusive for the call.
        let est: &mut EstIn = unsafe { get_mut(e, MAGIC_EST)? };
        // SAFETY: the caller's calibration or null (checked there).
        unsafe { read_calibration(&mut est.bank, cal) }
    })
}
