//! The per-wheel pipeline (`gough::wheel::Corner`): a measurement through the transient filter and
//! the Magic Formula to forces, and to the friction estimator; the measurement, forces and estimate
//! structs shared with the other sections.

use crate::*;

/// `gough_measurement_t::present`: Fx is measured.
pub const GOUGH_HAS_FX: u32 = 1;
/// `present`: Vx is measured.
pub const GOUGH_HAS_VX: u32 = 2;
/// `present`: ω is measured.
pub const GOUGH_HAS_OMEGA: u32 = 4;
/// `present`: δ is measured.
pub const GOUGH_HAS_DELTA: u32 = 8;
/// `present`: α is measured.
pub const GOUGH_HAS_ALPHA: u32 = 16;
/// `present`: κ is measured.
pub const GOUGH_HAS_KAPPA: u32 = 32;
/// `present`: γ is measured.
pub const GOUGH_HAS_GAMMA: u32 = 64;

/// One wheel's measurement (the protocol's `Measurement`). ISO-W axes at the contact point,
/// SI units. The optional fields count only when their `GOUGH_HAS_*` bit is set in `present`.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default)]
pub struct gough_measurement_t {
    /// Wheel: 0 front left, 1 front right, 2 rear left, 3 rear right.
    pub wheel: u32,
    /// Timestamp [µs], wrapping (only differences between a wheel's samples are used).
    pub t_us: u32,
    /// Vertical load Fz [N].
    pub fz: f32,
    /// Measured lateral force Fy [N].
    pub fy: f32,
    /// Measured aligning moment Mz [N m].
    pub mz: f32,
    /// Measured longitudinal force Fx [N] (`GOUGH_HAS_FX`).
    pub fx: f32,
    /// Forward speed of the wheel centre Vx [m/s] (`GOUGH_HAS_VX`).
    pub vx: f32,
    /// Wheel spin speed ω [rad/s] (`GOUGH_HAS_OMEGA`).
    pub omega: f32,
    /// Steering angle δ [rad] (`GOUGH_HAS_DELTA`).
    pub delta: f32,
    /// Slip angle α [rad] (`GOUGH_HAS_ALPHA`).
    pub alpha: f32,
    /// Longitudinal slip κ [-] (`GOUGH_HAS_KAPPA`).
    pub kappa: f32,
    /// Inclination angle γ [rad] (`GOUGH_HAS_GAMMA`).
    pub gamma: f32,
    /// Which optional fields are present: `GOUGH_HAS_*` bits.
    pub present: u32,
}

/// Predicted forces of one wheel (transient filter + Magic Formula). ISO-W, contact point.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default)]
pub struct gough_forces_t {
    /// Longitudinal force Fx [N].
    pub fx: f32,
    /// Lateral force Fy [N].
    pub fy: f32,
    /// Self-aligning moment Mz [N m].
    pub mz: f32,
    /// Which limits clipped an input (`gough::mf::Flags` bits).
    pub flags: u32,
}

/// `gough_estimate_t::state`: within ±0.1 at 95 % by the estimator's own account.
pub const GOUGH_STATE_IDENTIFIABLE: i32 = 0;
/// `state`: some information, not enough to be usable.
pub const GOUGH_STATE_NOT_IDENTIFIABLE: i32 = 1;
/// `state`: nothing known: μ is the prior.
pub const GOUGH_STATE_FALLBACK: i32 = 2;
/// `gough_estimate_t::flags`: a change of surface was declared at this sample (set on that one
/// estimate only).
pub const GOUGH_EST_CHANGE: u32 = 1;
/// `flags`: no estimator runs (a wheel initialised without `GOUGH_WHEEL_ESTIMATOR`): μ is the
/// prior.
pub const GOUGH_EST_NONE: u32 = 2;
/// `flags`: the calibrated model does not explain the data (`gough::mu::Estimate::mismatch`):
/// read μ with care.
pub const GOUGH_EST_MISMATCH: u32 = 4;
/// `gough_wheel_init` option: run the friction estimator (the bank) on the wheel's
/// measurements.
pub const GOUGH_WHEEL_ESTIMATOR: u32 = 1;
/// `gough_wheel_init` option: the wheel is on the vehicle's left. Its signals are taken and its
/// forces given in its own ISO-W axes, the tyre mirrored where the file's TYRESIDE is right.
/// Without `GOUGH_WHEEL_LEFT` or `GOUGH_WHEEL_RIGHT` the tyre is as its file describes it (the
/// other side's signals must then arrive mirrored: Fy, Mz, α, γ negated).
pub const GOUGH_WHEEL_LEFT: u32 = 2;
/// `gough_wheel_init` option: the wheel is on the vehicle's right (see `GOUGH_WHEEL_LEFT`).
pub const GOUGH_WHEEL_RIGHT: u32 = 4;

/// A friction estimate.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default)]
pub struct gough_estimate_t {
    /// Road friction μ [-] on the tyre file's scale (1: the tyre's test surface as fitted,
    /// λμ = 1); the prior in `GOUGH_STATE_FALLBACK`.
    pub mu: f32,
    /// Standard deviation of μ [-].
    pub sigma: f32,
    /// The lowest μ [-] the evidence has not excluded: a lower bound a controller may rely on
    /// in any state (the lowest hypothesis, 0.1, when nothing is excluded).
    pub mu_min: f32,
    /// `GOUGH_STATE_*`.
    pub state: i32,
    /// `GOUGH_EST_*` bits.
    pub flags: u32,
}

pub(crate) fn finite(xs: &[f32]) -> bool {
    xs.iter().all(|x| x.is_finite())
}

pub(crate) fn opt(present: u32, bit: u32, x: f32) -> Option<f32> {
    (present & bit != 0).then_some(x)
}

pub(crate) fn measurement(m: &gough_measurement_t) -> Result<proto::Measurement, i32> {
    let wheel = proto::Wheel::from_index(m.wheel as usize).ok_or(GOUGH_E_ARG)?;
    let p = m.present;
    let r = proto::Measurement {
        wheel,
        t_us: m.t_us,
        fz: m.fz,
        fy: m.fy,
        mz: m.mz,
        fx: opt(p, GOUGH_HAS_FX, m.fx),
        vx: opt(p, GOUGH_HAS_VX, m.vx),
        omega: opt(p, GOUGH_HAS_OMEGA, m.omega),
        delta: opt(p, GOUGH_HAS_DELTA, m.delta),
        alpha: opt(p, GOUGH_HAS_ALPHA, m.alpha),
        kappa: opt(p, GOUGH_HAS_KAPPA, m.kappa),
        gamma: opt(p, GOUGH_HAS_GAMMA, m.gamma),
    };
    let given = [r.fx, r.vx, r.omega, r.delta, r.alpha, r.kappa, r.gamma];
    if !finite(&[r.fz, r.fy, r.mz]) || given.iter().flatten().any(|x| !x.is_finite()) {
        return Err(GOUGH_E_NONFINITE);
    }
    Ok(r)
}

pub(crate) fn state_code(s: mu::State) -> i32 {
    match s {
        mu::State::Identifiable => GOUGH_STATE_IDENTIFIABLE,
        mu::State::NotIdentifiable => GOUGH_STATE_NOT_IDENTIFIABLE,
        mu::State::Fallback => GOUGH_STATE_FALLBACK,
    }
}

/// An estimate as C's (the change flag as `GOUGH_EST_CHANGE`, the mismatch indication as
/// `GOUGH_EST_MISMATCH`).
pub(crate) fn estimate_c(e: &mu::Estimate<f32>) -> gough_estimate_t {
    let change = if e.change { GOUGH_EST_CHANGE } else { 0 };
    let mismatch = if e.mismatch { GOUGH_EST_MISMATCH } else { 0 };
    gough_estimate_t {
        mu: e.mu,
        sigma: e.sigma,
        mu_min: e.mu_min,
        state: state_code(e.state),
        flags: change | mismatch,
    }
}

/// The side `GOUGH_WHEEL_LEFT`/`RIGHT` in `options` asks for (`None`: neither); `GOUGH_E_ARG`
/// for both, or for a bit outside them and `other`.
pub(crate) fn side_of(options: u32, other: u32) -> Result<Option<Side>, i32> {
    let sides = GOUGH_WHEEL_LEFT | GOUGH_WHEEL_RIGHT;
    if options & !(other | sides) != 0 || options & sides == sides {
        return Err(GOUGH_E_ARG);
    }
    Ok(if options & GOUGH_WHEEL_LEFT != 0 {
        Some(Side::Left)
    } else if options & GOUGH_WHEEL_RIGHT != 0 {
        Some(Side::Right)
    } else {
        None
    })
}

/// Starts one wheel's pipeline on tyre `p`: the transient filter (relaxation lengths) → the
/// Magic Formula (limits on) → forces, and, with `GOUGH_WHEEL_ESTIMATOR` in `options`, the
/// friction estimator (the bank, as `gough_estimator_init`, with the prior μ 0.3 of the
/// protocol's default `Settings`) on the measured Fz, Fy, Mz, Fx, κ (or κ from ω), Vx, γ —
/// never α. `GOUGH_WHEEL_LEFT` or `GOUGH_WHEEL_RIGHT` mounts the tyre on that side (the Magic
/// Formula and the estimator mirror it where the file describes the other side's tyre), as the
/// firmware mounts its four wheels. **`p` must outlive the wheel** and stay unchanged while it
/// runs. `GOUGH_E_MODEL`: the estimator was asked for and the tyre gives no usable friction (the
/// wheel is then not initialised); `GOUGH_E_ARG`: an unknown option bit, or both sides.
#[no_mangle]
pub unsafe extern "C" fn gough_wheel_init(
    w: *mut gough_wheel_t,
    p: *const gough_params_t,
    options: u32,
) -> i32 {
    ret(|| {
        // SAFETY: a params storage or null; the caller keeps it alive (documented).
        let params: &'static ParamsIn = unsafe { get(p, MAGIC_PARAMS)? };
        if w.is_null() {
            return Err(GOUGH_E_NULL);
        }
        let mounted = side_of(options, GOUGH_WHEEL_ESTIMATOR)?;
        // SAFETY: non-null; unmark, so that a failure leaves it unusable.
        unsafe { w.cast::<u32>().write(0) };
        let mut wheel = Corner::on(mounted);
        if options & GOUGH_WHEEL_ESTIMATOR != 0 {
            wheel
                .start_estimator::<Fast>(&params.p32, Settings::default().estimator_config())
                .map_err(|_| GOUGH_E_MODEL)?;
        }
        let val = WheelIn {
            params: &params.p32,
            wheel,
        };
        // SAFETY: non-null, GOUGH_WHEEL_SIZE bytes aligned to 8.
        unsafe { put(w, MAGIC_WHEEL, val) };
        Ok(())
    })
}

/// One measurement through the wheel's pipeline: `*forces` gets the predicted forces, `*est`
/// the friction estimate after this sample (both required). Returns `GOUGH_E_NOSLIP` (no
/// α, κ or ω) or `GOUGH_E_MODEL` when there are no forces — `*forces` is then zero and `*est`
/// still updated —, `GOUGH_E_NONFINITE` or `GOUGH_E_ARG` (wheel index) when the measurement is
/// refused (nothing changes).
#[no_mangle]
pub unsafe extern "C" fn gough_wheel_step(
    w: *mut gough_wheel_t,
    m: *const gough_measurement_t,
    forces: *mut gough_forces_t,
    est: *mut gough_estimate_t,
) -> i32 {
    ret(|| {
        // SAFETY: a wheel storage or null; exclusive for the call.
        let wi: &mut WheelIn = unsafe { get_mut(w, MAGIC_WHEEL)? };
        if m.is_null() || forces.is_null() || est.is_null() {
            return Err(GOUGH_E_NULL);
        }
        // SAFETY: non-null, the caller's measurement.
        let meas = wheel::Measurement::from(&measurement(&unsafe { m.read() })?);
        // SAFETY: set by `gough_wheel_init` to caller-owned params that outlive the wheel.
        let p = unsafe { &*wi.params };
        let f = wi
            .wheel
            .forces::<Fast>(p, Settings::default().limits, &meas);
        let e = match wi.wheel.estimate::<Fast>(p, &meas) {
            Some(e) => estimate_c(&e),
            None => gough_estimate_t {
                mu: Settings::default().fallback_mu,
                sigma: 1.0,
                mu_min: 0.0,
                state: GOUGH_STATE_FALLBACK,
                flags: GOUGH_EST_NONE,
            },
        };
        // SAFETY: non-null, the caller's outputs.
        unsafe { est.write(e) };
        match f {
            Ok(f) => {
                // SAFETY: as above.
                unsafe {
                    forces.write(gough_forces_t {
                        fx: f.fx,
                        fy: f.fy,
                        mz: f.mz,
                        flags: u32::from(f.flags.0),
                    })
                };
                Ok(())
            }
            Err(c) => {
                // SAFETY: as above.
                unsafe { forces.write(gough_forces_t::default()) };
                Err(if c == wheel::Error::NoSlip {
                    GOUGH_E_NOSLIP
                } else {
                    GOUGH_E_MODEL
                })
            }
        }
    })
}

/// The wheel's estimator's calibration of the tyre into `*out` (`gough_estimator_get_calibration`).
/// `GOUGH_E_ARG`: the wheel runs no estimator (initialised without `GOUGH_WHEEL_ESTIMATOR`).
#[no_mangle]
pub unsafe extern "C" fn gough_wheel_get_calibration(
    w: *const gough_wheel_t,
    out: *mut gough_calibration_t,
) -> i32 {
    ret(|| {
        // SAFETY: a wheel storage or null.
        let wi: &WheelIn = unsafe { get(w, MAGIC_WHEEL)? };
        let bank = wi.wheel.estimator().ok_or(GOUGH_E_ARG)?;
        // SAFETY: the caller's output or null (checked there).
        unsafe { write_calibration(bank, out) }
    })
}

/// The wheel's estimator starts from calibration `*cal` (`gough_estimator_set_calibration`).
/// `GOUGH_E_ARG`: the wheel runs no estimator; `GOUGH_E_CAL_INVALID`, `GOUGH_E_CAL_BOUNDS`: refused,
/// nothing changed.
#[no_mangle]
pub unsafe extern "C" fn gough_wheel_set_calibration(
    w: *mut gough_wheel_t,
    cal: *const gough_calibration_t,
) -> i32 {
    ret(|| {
        // SAFETY: a wheel storage or null; exclusive for the call.
        let wi: &mut WheelIn = unsafe { get_mut(w, MAGIC_WHEEL)? };
        let bank = wi.wheel.estimator_mut().ok_or(GOUGH_E_ARG)?;
        // SAFETY: the caller's calibration or null (checked there).
        unsafe { read_calibration(bank, cal) }
    })
}
