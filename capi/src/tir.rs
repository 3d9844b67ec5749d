//! `.tir` files: parsing into a `gough_params_t` (f32 and f64 parameters) and a few of their
//! values.

use crate::*;

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
