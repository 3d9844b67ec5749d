//! The friction estimator alone (`gough::mu::Bank`): its samples, its start on a tyre and side, its
//! update.

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
        let state = state_code(r.state);
        // SAFETY: non-null, the caller's output.
        unsafe {
            out.write(gough_estimate_t {
                mu: r.mu,
                sigma: r.sigma,
                mu_min: r.mu_min,
                state,
                flags: if r.change { GOUGH_EST_CHANGE } else { 0 },
            })
        };
        Ok(())
    })
}
