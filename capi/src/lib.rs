//! gough's C API (issue 41): the core for C firmware, as the static library `libgough.a` and
//! the header `capi/include/gough.h` (generated from this file by cbindgen: `cargo xtask header`;
//! `cargo xtask test-all` fails when the checked-in header differs from a fresh generation).
//!
//! - **No allocation**: every state lives in an opaque, 8-byte aligned storage struct that the
//!   caller declares (`static`, or on its stack) — `gough_params_t`, `gough_wheel_t`,
//!   `gough_estimator_t`, `gough_preview_t`, `gough_rx_t`; their sizes are the `GOUGH_*_SIZE` macros. An
//!   `*_init`/`*_parse` call writes a storage and marks it; any other call on a storage that was
//!   not written so returns `GOUGH_E_UNINIT`.
//! - **No panics across the boundary**: the core does not panic; every function returns
//!   `GOUGH_OK` (0) or a negative `GOUGH_E_*` code. A null pointer is an error
//!   (`GOUGH_E_NULL`), never a crash; the pointers documented as optional may be null.
//! - **Borrowed storage**: a wheel and an estimator keep a pointer to the parameter storage
//!   they were initialised with: that storage must outlive them and must not be rewritten while
//!   they are used.
//! - **Units and axes**: SI units; forces and moments in ISO-W (the wheel's contact point: x
//!   forward, y left, z up), as `gough::mf`.
//!
//! The math backend is `gough::math::Fast` in f32 (what the firmware runs: a C image and the
//! Rust firmware compute the same bits) and `gough::math::Libm` in f64 (`gough_mf_eval_f64`,
//! MFeval's precision).
#![cfg_attr(target_os = "none", no_std)]
#![allow(non_camel_case_types)]
// Raw pointers from C are checked for null before use; each `unsafe` block says why it holds.
#![allow(clippy::missing_safety_doc)]
// The core is a dependency named `core_gough` here: this library's own name is `gough`.

use core::mem::{align_of, size_of};
use core::ptr;
use core_gough::math::{Fast, Libm};
use core_gough::mf::{self, EvalError, Input, Options, Params, Side};
use core_gough::mu::preview::{self, Preview};
use core_gough::mu::{self, Bank};
use core_gough::proto::{self, Feed, Msg, Mtu, Reassembler, Segmenter, Settings, MSG_BUF};
use core_gough::wheel::{self, Corner};

/// On the device the core never panics; the handler must still exist. It stops the core
/// (an ABS/ESC controller's watchdog takes over).
#[cfg(target_os = "none")]
#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    loop {
        core::hint::spin_loop();
    }
}

// ---------------------------------------------------------------------------------------------
// Return codes
// ---------------------------------------------------------------------------------------------

/// Success.
pub const GOUGH_OK: i32 = 0;
/// A required pointer was null.
pub const GOUGH_E_NULL: i32 = -1;
/// An argument is out of its domain (unknown `use_mode`, wheel index above 3, negative
/// pressure, a message kind that cannot be sent, a zero-length frame, ...).
pub const GOUGH_E_ARG: i32 = -2;
/// An input was NaN or infinite.
pub const GOUGH_E_NONFINITE: i32 = -3;
/// The `.tir` text is not valid (its line in `*err_line`).
pub const GOUGH_E_PARSE: i32 = -4;
/// An output buffer is too small.
pub const GOUGH_E_BUFFER: i32 = -5;
/// The model cannot answer: an evaluation overflowed (limits off, inputs far outside the
/// model's range), turn slip asked of a file without it, or the tyre gives no usable friction
/// (an estimator cannot be built).
pub const GOUGH_E_MODEL: i32 = -6;
/// A storage struct was used before its `*_init`/`*_parse`/`*_build` call succeeded.
pub const GOUGH_E_UNINIT: i32 = -7;
/// A measurement carries neither α, κ nor ω (with Vx): no forces to predict.
pub const GOUGH_E_NOSLIP: i32 = -8;
/// A CAN frame or message was dropped by the reassembler (bad header, CRC, order, timeout,
/// version, type or body); counted as the Rust `proto::Counters` count it.
pub const GOUGH_E_PROTO: i32 = -9;

// ---------------------------------------------------------------------------------------------
// Storage
// ---------------------------------------------------------------------------------------------

/// Bytes of a `gough_params_t` (a parsed `.tir` file: f64 and f32 parameters).
pub const GOUGH_PARAMS_SIZE: usize = 2624;
/// Bytes of a `gough_wheel_t` (one wheel's transient filter and bank estimator).
pub const GOUGH_WHEEL_SIZE: usize = 1920;
/// Bytes of a `gough_estimator_t` (one wheel's bank estimator, `gough::mu::bank::Bank`).
pub const GOUGH_ESTIMATOR_SIZE: usize = 1856;
/// Bytes of a `gough_rx_t` (a reassembler of one CAN identifier's messages).
pub const GOUGH_RX_SIZE: usize = 256;
/// Bytes of a `gough_preview_t` (one side's front-to-rear preview, `gough::mu::preview`).
pub const GOUGH_PREVIEW_SIZE: usize = 512;

/// 64-bit words of a `gough_params_t`.
pub const GOUGH_PARAMS_WORDS: usize = GOUGH_PARAMS_SIZE / 8;
/// 64-bit words of a `gough_wheel_t`.
pub const GOUGH_WHEEL_WORDS: usize = GOUGH_WHEEL_SIZE / 8;
/// 64-bit words of a `gough_estimator_t`.
pub const GOUGH_ESTIMATOR_WORDS: usize = GOUGH_ESTIMATOR_SIZE / 8;
/// 64-bit words of a `gough_rx_t`.
pub const GOUGH_RX_WORDS: usize = GOUGH_RX_SIZE / 8;
/// 64-bit words of a `gough_preview_t`.
pub const GOUGH_PREVIEW_WORDS: usize = GOUGH_PREVIEW_SIZE / 8;

/// A parsed tyre (`gough_tir_parse`). Opaque; declare it, never read it.
#[repr(C)]
pub struct gough_params_t {
    _opaque: [u64; GOUGH_PARAMS_WORDS],
}

/// One wheel's pipeline (`gough_wheel_init`). Opaque; points to its `gough_params_t`.
#[repr(C)]
pub struct gough_wheel_t {
    _opaque: [u64; GOUGH_WHEEL_WORDS],
}

/// One wheel's friction estimator (`gough_estimator_init`). Opaque; points to its
/// `gough_params_t`.
#[repr(C)]
pub struct gough_estimator_t {
    _opaque: [u64; GOUGH_ESTIMATOR_WORDS],
}

/// A reassembler of the messages of one CAN identifier (`gough_rx_init`). Opaque.
#[repr(C)]
pub struct gough_rx_t {
    _opaque: [u64; GOUGH_RX_WORDS],
}

/// One side's front-to-rear preview (`gough_preview_init`). Opaque.
#[repr(C)]
pub struct gough_preview_t {
    _opaque: [u64; GOUGH_PREVIEW_WORDS],
}

/// A storage's contents behind its magic word.
#[repr(C)]
struct Slot<T> {
    magic: u32,
    val: T,
}

const MAGIC_PARAMS: u32 = 0x676f_7001;
const MAGIC_WHEEL: u32 = 0x676f_7003;
const MAGIC_EST: u32 = 0x676f_7004;
const MAGIC_RX: u32 = 0x676f_7005;
const MAGIC_PREVIEW: u32 = 0x676f_7006;

struct ParamsIn {
    p32: Params<f32>,
    p64: Params<f64>,
}

struct WheelIn {
    params: *const Params<f32>,
    wheel: Corner<f32>,
}

struct EstIn {
    bank: Bank<f32>,
    /// The tyre the bank was built for (the caller keeps it alive, documented).
    params: &'static ParamsIn,
}

macro_rules! fits {
    ($t:ty, $s:ty, $size:expr) => {
        const _: () = assert!(size_of::<Slot<$t>>() <= $size && align_of::<Slot<$t>>() <= 8);
        const _: () = assert!(size_of::<$s>() == $size && align_of::<$s>() == 8);
    };
}
fits!(ParamsIn, gough_params_t, GOUGH_PARAMS_SIZE);
fits!(WheelIn, gough_wheel_t, GOUGH_WHEEL_SIZE);
fits!(EstIn, gough_estimator_t, GOUGH_ESTIMATOR_SIZE);
fits!(Reassembler<MSG_BUF>, gough_rx_t, GOUGH_RX_SIZE);
fits!(Preview<f32>, gough_preview_t, GOUGH_PREVIEW_SIZE);

/// Bytes each storage needs on this target (what the `GOUGH_*_SIZE` macros round up):
/// params, wheel, estimator, rx, preview. For `docs/c-api.md` and the tests.
pub fn used_sizes() -> [usize; 5] {
    [
        size_of::<Slot<ParamsIn>>(),
        size_of::<Slot<WheelIn>>(),
        size_of::<Slot<EstIn>>(),
        size_of::<Slot<Reassembler<MSG_BUF>>>(),
        size_of::<Slot<Preview<f32>>>(),
    ]
}

/// The value in storage `p` if it carries `magic`.
///
/// # Safety
/// `p` is null or points to a storage of at least `size_of::<Slot<T>>()` bytes, aligned to 8,
/// that is either initialised by this library (magic set) or holds any bytes at all.
unsafe fn get<'a, S, T>(p: *const S, magic: u32) -> Result<&'a T, i32> {
    if p.is_null() {
        return Err(GOUGH_E_NULL);
    }
    let s = p.cast::<Slot<T>>();
    // SAFETY: the caller's storage is at least this large and aligned; a u32 has no invalid bits.
    if unsafe { ptr::addr_of!((*s).magic).read() } != magic {
        return Err(GOUGH_E_UNINIT);
    }
    // SAFETY: the magic says this library wrote a valid T here.
    Ok(unsafe { &(*s).val })
}

/// [`get`], mutable.
///
/// # Safety
/// As [`get`], and no other reference to the storage is alive.
unsafe fn get_mut<'a, S, T>(p: *mut S, magic: u32) -> Result<&'a mut T, i32> {
    if p.is_null() {
        return Err(GOUGH_E_NULL);
    }
    let s = p.cast::<Slot<T>>();
    // SAFETY: as in `get`.
    if unsafe { ptr::addr_of!((*s).magic).read() } != magic {
        return Err(GOUGH_E_UNINIT);
    }
    // SAFETY: as in `get`; exclusive by the caller's contract.
    Ok(unsafe { &mut (*s).val })
}

/// Writes `val` into storage `p` and marks it.
///
/// # Safety
/// `p` is non-null, aligned to 8 and at least `size_of::<Slot<T>>()` bytes.
unsafe fn put<S, T>(p: *mut S, magic: u32, val: T) {
    let s = p.cast::<Slot<T>>();
    // SAFETY: by the caller's contract; the old contents are overwritten, never dropped.
    unsafe {
        ptr::addr_of_mut!((*s).magic).write(0);
        ptr::addr_of_mut!((*s).val).write(val);
        ptr::addr_of_mut!((*s).magic).write(magic);
    }
}

/// Runs `f`, mapping `Err(code)` to `code` and `Ok(())` to `GOUGH_OK`.
fn ret(f: impl FnOnce() -> Result<(), i32>) -> i32 {
    match f() {
        Ok(()) => GOUGH_OK,
        Err(e) => e,
    }
}

// ---------------------------------------------------------------------------------------------
// .tir
// ---------------------------------------------------------------------------------------------

/// Parses the `.tir` text `text[0..len]` (UTF-8; the bytes need not end in NUL) into `out`.
/// On `GOUGH_E_PARSE`, `*err_line` (optional: may be NULL) gets the 1-based line of the first
/// error (0: the file as a whole), and `out` is left unmarked (unusable) — it is never half
/// written. The text need not outlive the call.
#[no_mangle]
pub unsafe extern "C" fn gough_tir_parse(
    text: *const core::ffi::c_char,
    len: usize,
    out: *mut gough_params_t,
    err_line: *mut u32,
) -> i32 {
    ret(|| {
        if text.is_null() || out.is_null() {
            return Err(GOUGH_E_NULL);
        }
        // SAFETY: the caller gives `len` readable bytes at `text`.
        let bytes = unsafe { core::slice::from_raw_parts(text.cast::<u8>(), len) };
        let fail = |line: u32| {
            if !err_line.is_null() {
                // SAFETY: non-null, the caller's u32.
                unsafe { err_line.write(line) };
            }
            GOUGH_E_PARSE
        };
        // SAFETY: `out` is non-null: unmark it first, so that a failed parse leaves it unusable.
        unsafe { out.cast::<u32>().write(0) };
        let s = match core::str::from_utf8(bytes) {
            Ok(s) => s,
            Err(e) => {
                let upto = bytes.get(..e.valid_up_to()).unwrap_or(&[]);
                return Err(fail(
                    1 + upto.iter().filter(|&&b| b == b'\n').count() as u32,
                ));
            }
        };
        let tir = core_gough::tir::parse(s).map_err(|e| fail(e.line))?;
        let p64 = tir.params;
        let p32 = p64.cast::<f32>();
        // SAFETY: non-null; the storage is GOUGH_PARAMS_SIZE bytes, aligned to 8 (its type).
        unsafe { put(out, MAGIC_PARAMS, ParamsIn { p32, p64 }) };
        if !err_line.is_null() {
            // SAFETY: non-null, the caller's u32.
            unsafe { err_line.write(0) };
        }
        Ok(())
    })
}

/// A few of a parsed tyre's parameters (for scaling and display).
#[repr(C)]
#[derive(Debug, Clone, Copy, Default)]
pub struct gough_params_info_t {
    /// Nominal load FNOMIN [N].
    pub fnomin: f64,
    /// Unloaded radius UNLOADED_RADIUS R0 [m].
    pub unloaded_radius: f64,
    /// Reference speed LONGVL [m/s].
    pub longvl: f64,
    /// Inflation pressure INFLPRES [Pa], as parsed.
    pub inflpres: f64,
}

/// Copies a few of the parsed tyre's parameters into `*out`.
#[no_mangle]
pub unsafe extern "C" fn gough_params_info(
    p: *const gough_params_t,
    out: *mut gough_params_info_t,
) -> i32 {
    ret(|| {
        // SAFETY: a params storage or null.
        let params: &ParamsIn = unsafe { get(p, MAGIC_PARAMS)? };
        if out.is_null() {
            return Err(GOUGH_E_NULL);
        }
        let q = &params.p64;
        // SAFETY: non-null, the caller's output.
        unsafe {
            out.write(gough_params_info_t {
                fnomin: q.fnomin,
                unloaded_radius: q.unloaded_radius,
                longvl: q.longvl,
                inflpres: q.inflpres,
            })
        };
        Ok(())
    })
}

// ---------------------------------------------------------------------------------------------
// Magic Formula
// ---------------------------------------------------------------------------------------------

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

// ---------------------------------------------------------------------------------------------
// Per-wheel pipeline
// ---------------------------------------------------------------------------------------------

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

fn finite(xs: &[f32]) -> bool {
    xs.iter().all(|x| x.is_finite())
}

fn opt(present: u32, bit: u32, x: f32) -> Option<f32> {
    (present & bit != 0).then_some(x)
}

fn measurement(m: &gough_measurement_t) -> Result<proto::Measurement, i32> {
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

fn state_code(s: mu::State) -> i32 {
    match s {
        mu::State::Identifiable => GOUGH_STATE_IDENTIFIABLE,
        mu::State::NotIdentifiable => GOUGH_STATE_NOT_IDENTIFIABLE,
        mu::State::Fallback => GOUGH_STATE_FALLBACK,
    }
}

/// An estimate as C's (the change flag as `GOUGH_EST_CHANGE`).
fn estimate_c(e: &mu::Estimate<f32>) -> gough_estimate_t {
    gough_estimate_t {
        mu: e.mu,
        sigma: e.sigma,
        mu_min: e.mu_min,
        state: state_code(e.state),
        flags: if e.change { GOUGH_EST_CHANGE } else { 0 },
    }
}

/// The side `GOUGH_WHEEL_LEFT`/`RIGHT` in `options` asks for (`None`: neither); `GOUGH_E_ARG`
/// for both, or for a bit outside them and `other`.
fn side_of(options: u32, other: u32) -> Result<Option<Side>, i32> {
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

// ---------------------------------------------------------------------------------------------
// Estimator alone
// ---------------------------------------------------------------------------------------------

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
fn sample(s: &gough_sample_t) -> Result<mu::Sample<f32>, i32> {
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

// ---------------------------------------------------------------------------------------------
// Front-to-rear preview
// ---------------------------------------------------------------------------------------------

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

// ---------------------------------------------------------------------------------------------
// Protocol
// ---------------------------------------------------------------------------------------------

/// `gough_msg_t::kind`: no message (`gough_rx_feed`: not complete yet).
pub const GOUGH_MSG_NONE: u32 = 0;
/// Host → device: a measurement (`gough_msg_t::measurement`).
pub const GOUGH_MSG_MEASUREMENT: u32 = 1;
/// Host → device: start a parameter upload (`param_len`, `param_hash`).
pub const GOUGH_MSG_PARAM_BEGIN: u32 = 2;
/// Host → device: a chunk of `.tir` text (`param_offset`, `chunk_len`, `chunk`).
pub const GOUGH_MSG_PARAM_CHUNK: u32 = 3;
/// Host → device: end of the upload (`param_hash`).
pub const GOUGH_MSG_PARAM_COMMIT: u32 = 4;
/// Host → device: settings (`settings`).
pub const GOUGH_MSG_SETTINGS: u32 = 5;
/// Host → device: a command (`command`: 0 reset, 1 status request, 2 stop).
pub const GOUGH_MSG_COMMAND: u32 = 6;
/// Device → host: predicted forces (`wheel`, `t_us`, `forces`).
pub const GOUGH_MSG_FORCES: u32 = 7;
/// Device → host: a friction estimate (`wheel`, `t_us`, `estimate`).
pub const GOUGH_MSG_ESTIMATE: u32 = 8;
/// Device → host: a status report (received only: its fields are not carried here).
pub const GOUGH_MSG_STATUS: u32 = 9;
/// Device → host: an acknowledgement (`ack_of`, `ack_seq`, `ack_code`, `ack_line`).
pub const GOUGH_MSG_ACK: u32 = 10;
/// A complete message the C API does not map (the four-wheel `CompactBatch` and
/// `CompactResults`, protocol types 0x08 and 0x85): only `kind` is set.
pub const GOUGH_MSG_OTHER: u32 = 11;
/// Bytes of `.tir` text in one parameter chunk, at most.
pub const GOUGH_CHUNK_LEN: usize = 48;
/// Frames of one message, at most (classic CAN, 8 bytes each).
pub const GOUGH_MAX_FRAMES: usize = 16;

/// The protocol's settings (`docs/protocol.md`).
#[repr(C)]
#[derive(Debug, Clone, Copy, Default)]
pub struct gough_settings_t {
    /// Clip inputs to the `.tir` ranges: 1 on, 0 off.
    pub limits: u32,
    /// μ [-] reported in the fallback state (the estimators' prior).
    pub fallback_mu: f32,
    /// The car's wheelbase [m] for the front-to-rear preview; 0: none. The device refuses
    /// anything but 0 or a positive number (ack code 10).
    pub wheelbase: f32,
}

/// One protocol message, flattened: `kind` (`GOUGH_MSG_*`) says which fields count.
#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub struct gough_msg_t {
    /// `GOUGH_MSG_*`.
    pub kind: u32,
    /// `GOUGH_MSG_MEASUREMENT`.
    pub measurement: gough_measurement_t,
    /// `GOUGH_MSG_FORCES`, `GOUGH_MSG_ESTIMATE`: wheel 0..3 (FL, FR, RL, RR).
    pub wheel: u32,
    /// `GOUGH_MSG_FORCES`, `GOUGH_MSG_ESTIMATE`: timestamp of the measurement [µs].
    pub t_us: u32,
    /// `GOUGH_MSG_FORCES`: the forces (ISO-W, contact point; flags are 16 bits on the wire).
    pub forces: gough_forces_t,
    /// `GOUGH_MSG_ESTIMATE`: μ, σ, μ_min, state, and in `flags` the change of surface
    /// (`GOUGH_EST_CHANGE`; `GOUGH_EST_NONE` is not on the wire: ignored when sending).
    pub estimate: gough_estimate_t,
    /// `GOUGH_MSG_PARAM_BEGIN`: length of the `.tir` text [bytes].
    pub param_len: u32,
    /// `GOUGH_MSG_PARAM_BEGIN`, `GOUGH_MSG_PARAM_COMMIT`: CRC-32 of the text.
    pub param_hash: u32,
    /// `GOUGH_MSG_PARAM_CHUNK`: where the chunk goes in the text [bytes].
    pub param_offset: u32,
    /// `GOUGH_MSG_PARAM_CHUNK`: bytes in `chunk` (≤ `GOUGH_CHUNK_LEN`).
    pub chunk_len: u32,
    /// `GOUGH_MSG_PARAM_CHUNK`: the text.
    pub chunk: [u8; GOUGH_CHUNK_LEN],
    /// `GOUGH_MSG_SETTINGS`.
    pub settings: gough_settings_t,
    /// `GOUGH_MSG_COMMAND`: 0 reset, 1 status request, 2 stop.
    pub command: u32,
    /// `GOUGH_MSG_ACK`: message-type byte of the request.
    pub ack_of: u32,
    /// `GOUGH_MSG_ACK`: sequence number of the request.
    pub ack_seq: u32,
    /// `GOUGH_MSG_ACK`: 0 ok, 1 bad hash, 2 bad length, 3 bad offset, 4 not in upload, 5 .tir
    /// error (`ack_line`), 6 no params, 7 no slip, 8 evaluation error, 9 not supported,
    /// 10 bad settings.
    pub ack_code: u32,
    /// `GOUGH_MSG_ACK` with code 5: 1-based line of the first error (0: the whole file).
    pub ack_line: u32,
}

/// One classic CAN frame.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default)]
pub struct gough_frame_t {
    /// 11-bit CAN identifier (0x300 measurements, 0x301 configuration, 0x310 results, 0x311
    /// status and acknowledgements).
    pub id: u32,
    /// Data bytes used (1..8).
    pub len: u32,
    /// Data.
    pub data: [u8; 8],
}

const ZERO_MSG: gough_msg_t = gough_msg_t {
    kind: GOUGH_MSG_NONE,
    measurement: gough_measurement_t {
        wheel: 0,
        t_us: 0,
        fz: 0.0,
        fy: 0.0,
        mz: 0.0,
        fx: 0.0,
        vx: 0.0,
        omega: 0.0,
        delta: 0.0,
        alpha: 0.0,
        kappa: 0.0,
        gamma: 0.0,
        present: 0,
    },
    wheel: 0,
    t_us: 0,
    forces: gough_forces_t {
        fx: 0.0,
        fy: 0.0,
        mz: 0.0,
        flags: 0,
    },
    estimate: gough_estimate_t {
        mu: 0.0,
        sigma: 0.0,
        mu_min: 0.0,
        state: 0,
        flags: 0,
    },
    param_len: 0,
    param_hash: 0,
    param_offset: 0,
    chunk_len: 0,
    chunk: [0; GOUGH_CHUNK_LEN],
    settings: gough_settings_t {
        limits: 0,
        fallback_mu: 0.0,
        wheelbase: 0.0,
    },
    command: 0,
    ack_of: 0,
    ack_seq: 0,
    ack_code: 0,
    ack_line: 0,
};

fn to_c_meas(m: &proto::Measurement) -> gough_measurement_t {
    let mut present = 0;
    let mut f = |x: Option<f32>, bit: u32| match x {
        Some(v) => {
            present |= bit;
            v
        }
        None => 0.0,
    };
    let (fx, vx, omega, delta, alpha, kappa, gamma) = (
        f(m.fx, GOUGH_HAS_FX),
        f(m.vx, GOUGH_HAS_VX),
        f(m.omega, GOUGH_HAS_OMEGA),
        f(m.delta, GOUGH_HAS_DELTA),
        f(m.alpha, GOUGH_HAS_ALPHA),
        f(m.kappa, GOUGH_HAS_KAPPA),
        f(m.gamma, GOUGH_HAS_GAMMA),
    );
    gough_measurement_t {
        wheel: m.wheel.index() as u32,
        t_us: m.t_us,
        fz: m.fz,
        fy: m.fy,
        mz: m.mz,
        fx,
        vx,
        omega,
        delta,
        alpha,
        kappa,
        gamma,
        present,
    }
}

fn ack_code(c: proto::AckCode) -> (u32, u32) {
    use proto::AckCode as A;
    match c {
        A::Ok => (0, 0),
        A::BadHash => (1, 0),
        A::BadLength => (2, 0),
        A::BadOffset => (3, 0),
        A::NotInUpload => (4, 0),
        A::TirError { line } => (5, line),
        A::NoParams => (6, 0),
        A::NoSlip => (7, 0),
        A::EvalError => (8, 0),
        A::NotSupported => (9, 0),
        A::BadSettings => (10, 0),
    }
}

fn ack_from(code: u32, line: u32) -> Option<proto::AckCode> {
    use proto::AckCode as A;
    Some(match code {
        0 => A::Ok,
        1 => A::BadHash,
        2 => A::BadLength,
        3 => A::BadOffset,
        4 => A::NotInUpload,
        5 => A::TirError { line },
        6 => A::NoParams,
        7 => A::NoSlip,
        8 => A::EvalError,
        9 => A::NotSupported,
        10 => A::BadSettings,
        _ => return None,
    })
}

fn to_c(m: &Msg) -> gough_msg_t {
    let mut o = ZERO_MSG;
    match m {
        Msg::Measurement(x) => {
            o.kind = GOUGH_MSG_MEASUREMENT;
            o.measurement = to_c_meas(x);
        }
        // A compact measurement reaches C as the measurement it stands for.
        Msg::CompactMeasurement(x) => {
            o.kind = GOUGH_MSG_MEASUREMENT;
            o.measurement = to_c_meas(&x.measurement());
        }
        Msg::ParamBegin(x) => {
            o.kind = GOUGH_MSG_PARAM_BEGIN;
            o.param_len = x.len;
            o.param_hash = x.hash;
        }
        Msg::ParamChunk(x) => {
            o.kind = GOUGH_MSG_PARAM_CHUNK;
            o.param_offset = x.offset;
            let d = x.data.as_slice();
            o.chunk_len = d.len() as u32;
            for (c, b) in o.chunk.iter_mut().zip(d) {
                *c = *b;
            }
        }
        Msg::ParamCommit(x) => {
            o.kind = GOUGH_MSG_PARAM_COMMIT;
            o.param_hash = x.hash;
        }
        Msg::Settings(s) => {
            o.kind = GOUGH_MSG_SETTINGS;
            o.settings = gough_settings_t {
                limits: u32::from(s.limits),
                fallback_mu: s.fallback_mu,
                wheelbase: s.wheelbase,
            };
        }
        Msg::Command(c) => {
            o.kind = GOUGH_MSG_COMMAND;
            o.command = match c {
                proto::Command::Reset => 0,
                proto::Command::StatusRequest => 1,
                proto::Command::Stop => 2,
            };
        }
        Msg::Forces(f) => {
            o.kind = GOUGH_MSG_FORCES;
            o.wheel = f.wheel.index() as u32;
            o.t_us = f.t_us;
            o.forces = gough_forces_t {
                fx: f.fx,
                fy: f.fy,
                mz: f.mz,
                flags: u32::from(f.flags),
            };
        }
        Msg::Estimate(e) => {
            o.kind = GOUGH_MSG_ESTIMATE;
            o.wheel = e.wheel.index() as u32;
            o.t_us = e.t_us;
            o.estimate = estimate_c(&e.estimate());
        }
        Msg::Status(_) => o.kind = GOUGH_MSG_STATUS,
        Msg::CompactBatch(_) | Msg::CompactResults(_) => o.kind = GOUGH_MSG_OTHER,
        Msg::Ack(a) => {
            o.kind = GOUGH_MSG_ACK;
            o.ack_of = u32::from(a.of);
            o.ack_seq = u32::from(a.seq);
            let (c, l) = ack_code(a.code);
            o.ack_code = c;
            o.ack_line = l;
        }
    }
    o
}

fn from_c(m: &gough_msg_t) -> Result<Msg, i32> {
    let wheel = || proto::Wheel::from_index(m.wheel as usize).ok_or(GOUGH_E_ARG);
    Ok(match m.kind {
        GOUGH_MSG_MEASUREMENT => Msg::Measurement(measurement(&m.measurement)?),
        GOUGH_MSG_PARAM_BEGIN => Msg::ParamBegin(proto::ParamBegin {
            len: m.param_len,
            hash: m.param_hash,
        }),
        GOUGH_MSG_PARAM_CHUNK => {
            let d = m
                .chunk
                .get(..m.chunk_len as usize)
                .and_then(proto::Bytes::new)
                .ok_or(GOUGH_E_ARG)?;
            Msg::ParamChunk(proto::ParamChunk {
                offset: m.param_offset,
                data: d,
            })
        }
        GOUGH_MSG_PARAM_COMMIT => Msg::ParamCommit(proto::ParamCommit { hash: m.param_hash }),
        GOUGH_MSG_SETTINGS => {
            let s = &m.settings;
            if !finite(&[s.fallback_mu, s.wheelbase]) {
                return Err(GOUGH_E_NONFINITE);
            }
            Msg::Settings(Settings {
                limits: s.limits != 0,
                fallback_mu: s.fallback_mu,
                wheelbase: s.wheelbase,
            })
        }
        GOUGH_MSG_COMMAND => Msg::Command(match m.command {
            0 => proto::Command::Reset,
            1 => proto::Command::StatusRequest,
            2 => proto::Command::Stop,
            _ => return Err(GOUGH_E_ARG),
        }),
        GOUGH_MSG_FORCES => {
            let f = &m.forces;
            if !finite(&[f.fx, f.fy, f.mz]) {
                return Err(GOUGH_E_NONFINITE);
            }
            Msg::Forces(proto::Forces {
                wheel: wheel()?,
                t_us: m.t_us,
                fx: f.fx,
                fy: f.fy,
                mz: f.mz,
                flags: u16::try_from(f.flags).map_err(|_| GOUGH_E_ARG)?,
            })
        }
        GOUGH_MSG_ESTIMATE => {
            let e = &m.estimate;
            if !finite(&[e.mu, e.sigma, e.mu_min]) {
                return Err(GOUGH_E_NONFINITE);
            }
            Msg::Estimate(proto::Estimate {
                wheel: wheel()?,
                t_us: m.t_us,
                mu: e.mu,
                sigma: e.sigma,
                state: match e.state {
                    GOUGH_STATE_IDENTIFIABLE => mu::State::Identifiable,
                    GOUGH_STATE_NOT_IDENTIFIABLE => mu::State::NotIdentifiable,
                    GOUGH_STATE_FALLBACK => mu::State::Fallback,
                    _ => return Err(GOUGH_E_ARG),
                },
                mu_min: e.mu_min,
                change: e.flags & GOUGH_EST_CHANGE != 0,
            })
        }
        GOUGH_MSG_ACK => Msg::Ack(proto::Ack {
            of: u8::try_from(m.ack_of).map_err(|_| GOUGH_E_ARG)?,
            seq: u8::try_from(m.ack_seq).map_err(|_| GOUGH_E_ARG)?,
            code: ack_from(m.ack_code, m.ack_line).ok_or(GOUGH_E_ARG)?,
        }),
        _ => return Err(GOUGH_E_ARG),
    })
}

/// Encodes `msg` with sequence number `seq` into classic CAN frames `frames[0..*n]` (`cap`
/// frames available; `GOUGH_MAX_FRAMES` always suffice). `GOUGH_E_BUFFER`: more than `cap`
/// frames needed (`*n` gets how many). A status message cannot be sent from C
/// (`GOUGH_E_ARG`).
#[no_mangle]
pub unsafe extern "C" fn gough_msg_encode(
    msg: *const gough_msg_t,
    seq: u8,
    frames: *mut gough_frame_t,
    cap: usize,
    n: *mut usize,
) -> i32 {
    ret(|| {
        if msg.is_null() || frames.is_null() || n.is_null() {
            return Err(GOUGH_E_NULL);
        }
        // SAFETY: non-null, the caller's message.
        let m = from_c(unsafe { &*msg })?;
        let mut seg = Segmenter::new(&m, seq, Mtu::Classic).map_err(|_| GOUGH_E_ARG)?;
        let need = seg.frame_count();
        // SAFETY: non-null, the caller's count.
        unsafe { n.write(need) };
        if need > cap {
            return Err(GOUGH_E_BUFFER);
        }
        let id = u32::from(proto::id::of(m.msg_type()));
        let mut buf = [0u8; 64];
        let mut k = 0;
        while let Some(f) = seg.next_frame(&mut buf) {
            let mut data = [0u8; 8];
            for (d, b) in data.iter_mut().zip(f) {
                *d = *b;
            }
            if k >= cap {
                return Err(GOUGH_E_BUFFER);
            }
            // SAFETY: k < cap frames of the caller's array.
            unsafe {
                frames.add(k).write(gough_frame_t {
                    id,
                    len: f.len() as u32,
                    data,
                })
            };
            k += 1;
        }
        Ok(())
    })
}

/// Starts a reassembler (one per CAN identifier received).
#[no_mangle]
pub unsafe extern "C" fn gough_rx_init(rx: *mut gough_rx_t) -> i32 {
    if rx.is_null() {
        return GOUGH_E_NULL;
    }
    // SAFETY: non-null, GOUGH_RX_SIZE bytes aligned to 8.
    unsafe { put(rx, MAGIC_RX, Reassembler::<MSG_BUF>::new()) };
    GOUGH_OK
}

/// Feeds one received frame at time `now_ms` [ms] (a message whose frames are more than 50 ms
/// apart is dropped). `*out` gets the message when this frame completes one, else
/// `kind = GOUGH_MSG_NONE`. `GOUGH_E_PROTO`: the frame or the message was dropped (counted).
#[no_mangle]
pub unsafe extern "C" fn gough_rx_feed(
    rx: *mut gough_rx_t,
    frame: *const gough_frame_t,
    now_ms: u32,
    out: *mut gough_msg_t,
) -> i32 {
    ret(|| {
        // SAFETY: a reassembler storage or null; exclusive for the call.
        let r: &mut Reassembler<MSG_BUF> = unsafe { get_mut(rx, MAGIC_RX)? };
        if frame.is_null() || out.is_null() {
            return Err(GOUGH_E_NULL);
        }
        // SAFETY: non-null, the caller's frame.
        let f = unsafe { &*frame };
        let data = f
            .data
            .get(..f.len as usize)
            .filter(|d| !d.is_empty())
            .ok_or(GOUGH_E_ARG)?;
        let (msg, code) = match r.feed(data, now_ms) {
            Feed::Pending => (ZERO_MSG, Ok(())),
            Feed::Done(m) => (to_c(&m), Ok(())),
            Feed::Dropped(_) => (ZERO_MSG, Err(GOUGH_E_PROTO)),
        };
        // SAFETY: non-null, the caller's output.
        unsafe { out.write(msg) };
        code
    })
}

/// The storage macros against what each type needs on this target, and the basic contract from
/// Rust (the C-side tests are `capi/tests/host_test.c` and the example firmware, run by
/// `cargo xtask test-all`).
#[cfg(test)]
mod tests {
    use super::*;
    use std::boxed::Box;
    use std::ptr;

    #[test]
    fn every_storage_macro_fits_its_type_with_little_slack() {
        let used = used_sizes();
        let macros = [
            GOUGH_PARAMS_SIZE,
            GOUGH_WHEEL_SIZE,
            GOUGH_ESTIMATOR_SIZE,
            GOUGH_RX_SIZE,
            GOUGH_PREVIEW_SIZE,
        ];
        let names = ["params", "wheel", "estimator", "rx", "preview"];
        for ((u, m), n) in used.iter().zip(macros).zip(names) {
            println!(
                "{n}: needs {u} bytes on this target, GOUGH_{}_SIZE = {m}",
                n.to_uppercase()
            );
            assert!(*u <= m, "{n}: {u} > {m}");
            // The macros are the largest target's need (x86-64) rounded up: keep them tight.
            if cfg!(target_pointer_width = "64") {
                assert!(
                    m - u < 64,
                    "{n}: {m} bytes declared for {u} needed: shrink the macro"
                );
            }
        }
    }

    #[test]
    fn null_pointers_and_uninitialised_storage_are_errors() {
        let text = include_str!("../../host-tests/data/tyres/MagicFormula61_Parameters.tir");
        let mut p = Box::new(gough_params_t_zeroed());
        let mut line = 7u32;
        // SAFETY: valid pointers or null, as the C API allows.
        unsafe {
            assert_eq!(
                gough_tir_parse(ptr::null(), 3, &mut *p, &mut line),
                GOUGH_E_NULL
            );
            let input = gough_mf_input_t {
                fz: 4000.0,
                vx: 10.0,
                alpha: 0.02,
                ..Default::default()
            };
            let mut out = gough_mf_output_t::default();
            assert_eq!(gough_mf_eval(&*p, &input, 111, &mut out), GOUGH_E_UNINIT);
            assert_eq!(
                gough_tir_parse(text.as_ptr().cast(), text.len(), &mut *p, &mut line),
                GOUGH_OK
            );
            assert_eq!(line, 0);
            assert_eq!(gough_mf_eval(&*p, &input, 111, &mut out), GOUGH_OK);
            assert!(
                out.fy < 0.0,
                "ISO-W: positive α gives negative Fy ({})",
                out.fy
            );
            assert_eq!(
                gough_mf_eval(&*p, &input, 111, ptr::null_mut()),
                GOUGH_E_NULL
            );
            assert_eq!(gough_mf_eval(&*p, &input, 131, &mut out), GOUGH_E_ARG);
            let bad = "[MODEL]\nFITTYP = 61\nLONGVL = x\n";
            assert_eq!(
                gough_tir_parse(bad.as_ptr().cast(), bad.len(), &mut *p, &mut line),
                GOUGH_E_PARSE
            );
            assert_eq!(line, 3);
            // A failed parse leaves the storage unusable.
            assert_eq!(gough_mf_eval(&*p, &input, 111, &mut out), GOUGH_E_UNINIT);
        }
    }

    #[test]
    fn a_preview_through_the_c_api_is_the_core_preview() {
        let text = include_str!("../../host-tests/data/tyres/MagicFormula61_Parameters.tir");
        let mut p = Box::new(gough_params_t_zeroed());
        let mut line = 0u32;
        // Storages as C declares them (zeroed: unmarked).
        // SAFETY: opaque arrays of u64: all-zero bits are valid unmarked storages.
        let mut ests: Vec<gough_estimator_t> =
            (0..2).map(|_| unsafe { std::mem::zeroed() }).collect();
        // SAFETY: as above.
        let mut pv: Box<gough_preview_t> = Box::new(unsafe { std::mem::zeroed() });
        // SAFETY: valid pointers or null, as the C API allows.
        unsafe {
            assert_eq!(
                gough_tir_parse(text.as_ptr().cast(), text.len(), &mut *p, &mut line),
                GOUGH_OK
            );
            assert_eq!(gough_preview_init(&mut *pv, 0.0), GOUGH_E_ARG);
            assert_eq!(gough_preview_init(ptr::null_mut(), 2.9), GOUGH_E_NULL);
            assert_eq!(gough_preview_front(&mut *pv, &ests[0]), GOUGH_E_UNINIT);
            assert_eq!(gough_preview_init(&mut *pv, 2.9), GOUGH_OK);
            for e in ests.iter_mut() {
                assert_eq!(gough_estimator_init(e, &*p), GOUGH_OK);
            }
        }
        let p32 = core_gough::tir::parse(text).unwrap().params.cast::<f32>();
        let mut ice = p32.clone();
        ice.lmux *= 0.3;
        ice.lmuy *= 0.3;
        let cfg = mu::Config::default();
        let mut banks = [
            Bank::new::<Fast>(&p32, None, cfg).unwrap(),
            Bank::new::<Fast>(&p32, None, cfg).unwrap(),
        ];
        let mut rpv = Preview::new(preview::Config::with_wheelbase(2.9f32)).unwrap();
        let mut alone = Bank::new::<Fast>(&p32, None, cfg).unwrap();
        let mut differs = 0;
        for i in 0..3000u32 {
            for w in 0..2 {
                // Front (0) at α −0.05 onto ice at 1.5 s, rear (1) at −0.01, 145 ms later.
                let on_ice = i >= 1500 + if w == 1 { 145 } else { 0 };
                let a = if w == 1 { -0.01 } else { -0.05 } * (i as f32 / 500.0).min(1.0);
                let input = Input {
                    fz: 5000.0,
                    alpha: a,
                    vx: 20.0,
                    ..Input::default()
                };
                let q = if on_ice { &ice } else { &p32 };
                let o = mf::eval::<f32, Fast>(q, &input, &Options::default()).unwrap();
                let cs = gough_sample_t {
                    t_us: 1000 * i,
                    fz: 5000.0,
                    fy: o.fy,
                    mz: o.mz,
                    fx: o.fx,
                    vx: 20.0,
                    present: GOUGH_HAS_FX | GOUGH_HAS_VX,
                    ..Default::default()
                };
                let s = sample(&cs).unwrap();
                let mut ce = gough_estimate_t::default();
                // SAFETY: initialised storages, valid pointers.
                unsafe {
                    if w == 1 {
                        assert_eq!(gough_preview_rear(&mut *pv, &mut ests[1], &cs), GOUGH_OK);
                    }
                    assert_eq!(gough_estimator_update(&mut ests[w], &cs, &mut ce), GOUGH_OK);
                    if w == 0 {
                        assert_eq!(gough_preview_front(&mut *pv, &ests[0]), GOUGH_OK);
                    }
                }
                if w == 1 {
                    rpv.rear::<Fast>(&mut banks[1], &s);
                }
                let r = banks[w].update::<Fast>(&p32, &s);
                if w == 0 {
                    rpv.front(&banks[0]);
                } else {
                    let a = alone.update::<Fast>(&p32, &s);
                    differs += usize::from(a.mu.to_bits() != r.mu.to_bits());
                }
                assert_eq!(
                    (ce.mu.to_bits(), ce.sigma.to_bits(), ce.mu_min.to_bits()),
                    (r.mu.to_bits(), r.sigma.to_bits(), r.mu_min.to_bits()),
                    "wheel {w}, sample {i}"
                );
            }
        }
        assert!(
            rpv.handed() >= 1 && differs > 0,
            "{} {differs}",
            rpv.handed()
        );
    }

    fn gough_params_t_zeroed() -> gough_params_t {
        // SAFETY: an opaque array of u64: all-zero bits are a valid (unmarked) storage.
        unsafe { std::mem::zeroed() }
    }
}
