//! The Magic Formula: one evaluation in f32 (`math::Fast`, as the firmware) or f64 (`math::Libm`,
//! MFeval's precision), MFeval's `useMode`s.

use crate::*;

/// Operating point of one Magic Formula evaluation (f32). ISO-W axes, SI units.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default)]
pub struct gough_mf_input_t {
    /// Vertical load Fz [N] (positive: the tyre is loaded).
    pub fz: f32,
    /// Longitudinal slip κ [-] (positive: driving).
    pub kappa: f32,
    /// Slip angle α [rad] (ISO-W: positive gives a negative Fy on a tyre without offsets).
    pub alpha: f32,
    /// Inclination (camber) angle γ [rad].
    pub gamma: f32,
    /// Turn slip φt [1/m] (used with use_mode xx2 only).
    pub phit: f32,
    /// Forward speed of the wheel centre Vx [m/s].
    pub vx: f32,
    /// Inflation pressure p [Pa]; 0: the file's INFLPRES.
    pub p: f32,
}

/// Operating point of one Magic Formula evaluation (f64), as `gough_mf_input_t`.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default)]
pub struct gough_mf_input_f64_t {
    /// Vertical load Fz [N].
    pub fz: f64,
    /// Longitudinal slip κ [-].
    pub kappa: f64,
    /// Slip angle α [rad].
    pub alpha: f64,
    /// Inclination angle γ [rad].
    pub gamma: f64,
    /// Turn slip φt [1/m].
    pub phit: f64,
    /// Forward speed Vx [m/s].
    pub vx: f64,
    /// Inflation pressure p [Pa]; 0: the file's INFLPRES.
    pub p: f64,
}

/// Result of one Magic Formula evaluation (f32). Forces and moments at the contact point,
/// ISO-W axes (x forward, y left, z up).
#[repr(C)]
#[derive(Debug, Clone, Copy, Default)]
pub struct gough_mf_output_t {
    /// Longitudinal force Fx [N].
    pub fx: f32,
    /// Lateral force Fy [N].
    pub fy: f32,
    /// Vertical load Fz [N] as used (clipped to FZMIN..FZMAX with limits on).
    pub fz: f32,
    /// Overturning moment Mx [N m].
    pub mx: f32,
    /// Rolling resistance moment My [N m].
    pub my: f32,
    /// Self-aligning moment Mz [N m].
    pub mz: f32,
    /// Longitudinal friction coefficient μx [-].
    pub mu_x: f32,
    /// Lateral friction coefficient |μy| [-].
    pub mu_y: f32,
    /// Longitudinal relaxation length σκ [m].
    pub sigma_x: f32,
    /// Lateral relaxation length σα [m].
    pub sigma_y: f32,
    /// Longitudinal slip stiffness Kxκ [N].
    pub k_xk: f32,
    /// Cornering stiffness Kyα [N/rad].
    pub k_ya: f32,
    /// Pneumatic trail t [m].
    pub t: f32,
    /// Residual torque Mzr [N m].
    pub m_zr: f32,
    /// The κ used [-] (after the limits).
    pub kappa: f32,
    /// Which limits clipped an input (`gough::mf::Flags` bits; 0: none).
    pub flags: u32,
}

/// Result of one Magic Formula evaluation (f64), as `gough_mf_output_t`.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default)]
pub struct gough_mf_output_f64_t {
    /// Longitudinal force Fx [N].
    pub fx: f64,
    /// Lateral force Fy [N].
    pub fy: f64,
    /// Vertical load Fz [N] as used.
    pub fz: f64,
    /// Overturning moment Mx [N m].
    pub mx: f64,
    /// Rolling resistance moment My [N m].
    pub my: f64,
    /// Self-aligning moment Mz [N m].
    pub mz: f64,
    /// Longitudinal friction coefficient μx [-].
    pub mu_x: f64,
    /// Lateral friction coefficient |μy| [-].
    pub mu_y: f64,
    /// Longitudinal relaxation length σκ [m].
    pub sigma_x: f64,
    /// Lateral relaxation length σα [m].
    pub sigma_y: f64,
    /// Longitudinal slip stiffness Kxκ [N].
    pub k_xk: f64,
    /// Cornering stiffness Kyα [N/rad].
    pub k_ya: f64,
    /// Pneumatic trail t [m].
    pub t: f64,
    /// Residual torque Mzr [N m].
    pub m_zr: f64,
    /// The κ used [-].
    pub kappa: f64,
    /// Which limits clipped an input (`gough::mf::Flags` bits; 0: none).
    pub flags: u32,
}

fn options(use_mode: u32) -> Result<Options, i32> {
    u16::try_from(use_mode)
        .ok()
        .and_then(Options::from_use_mode)
        .ok_or(GOUGH_E_ARG)
}

fn eval_err(e: EvalError) -> i32 {
    match e {
        EvalError::NonFinite(_) => GOUGH_E_NONFINITE,
        EvalError::NonPositivePressure => GOUGH_E_ARG,
        _ => GOUGH_E_MODEL,
    }
}

macro_rules! output {
    ($o:expr, $t:ident) => {{
        let o = $o;
        $t {
            fx: o.fx,
            fy: o.fy,
            fz: o.fz,
            mx: o.mx,
            my: o.my,
            mz: o.mz,
            mu_x: o.mu_x,
            mu_y: o.mu_y,
            sigma_x: o.sigma_x,
            sigma_y: o.sigma_y,
            k_xk: o.k_xk,
            k_ya: o.k_ya,
            t: o.t,
            m_zr: o.m_zr,
            kappa: o.kappa,
            flags: u32::from(o.flags.0),
        }
    }};
}

/// Evaluates the Magic Formula in f32 (`gough::math::Fast`, the firmware's backend) with
/// MFeval's `use_mode` (hundreds 1 = limits on, 2 = off; tens 1 = α, 2 = α* = tan α; units 1 =
/// no turn slip, 2 = turn slip): 111, 121, 211, 221, 112, ...
#[no_mangle]
pub unsafe extern "C" fn gough_mf_eval(
    p: *const gough_params_t,
    input: *const gough_mf_input_t,
    use_mode: u32,
    out: *mut gough_mf_output_t,
) -> i32 {
    ret(|| {
        // SAFETY: a params storage or null.
        let params: &ParamsIn = unsafe { get(p, MAGIC_PARAMS)? };
        if input.is_null() || out.is_null() {
            return Err(GOUGH_E_NULL);
        }
        // SAFETY: non-null, the caller's input.
        let i = unsafe { input.read() };
        let opts = options(use_mode)?;
        let x = Input {
            fz: i.fz,
            kappa: i.kappa,
            alpha: i.alpha,
            gamma: i.gamma,
            phit: i.phit,
            vx: i.vx,
            p: (i.p != 0.0).then_some(i.p),
        };
        let o = mf::eval::<f32, Fast>(&params.p32, &x, &opts).map_err(eval_err)?;
        // SAFETY: non-null, the caller's output.
        unsafe { out.write(output!(o, gough_mf_output_t)) };
        Ok(())
    })
}

/// Evaluates the Magic Formula in f64 (`gough::math::Libm`: MFeval's precision) with MFeval's
/// `use_mode`, as `gough_mf_eval`. Meant for the host (on an M4F, f64 is software).
#[no_mangle]
pub unsafe extern "C" fn gough_mf_eval_f64(
    p: *const gough_params_t,
    input: *const gough_mf_input_f64_t,
    use_mode: u32,
    out: *mut gough_mf_output_f64_t,
) -> i32 {
    ret(|| {
        // SAFETY: a params storage or null.
        let params: &ParamsIn = unsafe { get(p, MAGIC_PARAMS)? };
        if input.is_null() || out.is_null() {
            return Err(GOUGH_E_NULL);
        }
        // SAFETY: non-null, the caller's input.
        let i = unsafe { input.read() };
        let opts = options(use_mode)?;
        let x = Input {
            fz: i.fz,
            kappa: i.kappa,
            alpha: i.alpha,
            gamma: i.gamma,
            phit: i.phit,
            vx: i.vx,
            p: (i.p != 0.0).then_some(i.p),
        };
        let o = mf::eval::<f64, Libm>(&params.p64, &x, &opts).map_err(eval_err)?;
        // SAFETY: non-null, the caller's output.
        unsafe { out.write(output!(o, gough_mf_output_f64_t)) };
        Ok(())
    })
}
