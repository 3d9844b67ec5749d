//! Storage: the opaque, caller-declared structs every state lives in (`GOUGH_*_SIZE` bytes, aligned
//! to 8), their magic words, and the checked access to them; the compile-time checks that each
//! state fits its storage.

use crate::*;

/// Bytes of a `gough_params_t` (a parsed `.tir` file: f64 and f32 parameters).
pub const GOUGH_PARAMS_SIZE: usize = 2624;
/// Bytes of a `gough_wheel_t` (one wheel's transient filter and bank estimator).
pub const GOUGH_WHEEL_SIZE: usize = 2560;
/// Bytes of a `gough_estimator_t` (one wheel's bank estimator, `gough::mu::bank::Bank`).
pub const GOUGH_ESTIMATOR_SIZE: usize = 2496;
/// Bytes of a `gough_rx_t` (a reassembler of one CAN identifier's messages).
pub const GOUGH_RX_SIZE: usize = 320;
/// Bytes of a `gough_preview_t` (one side's front-to-rear preview, `gough::mu::preview`).
pub const GOUGH_PREVIEW_SIZE: usize = 512;
/// Bytes of a `gough_verifier_t` (the checking of a device's secured answers,
/// `gough::proto::auth::Verifier`: the keyed AES-CMAC and the counters).
pub const GOUGH_VERIFIER_SIZE: usize = 896;

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
/// 64-bit words of a `gough_verifier_t`.
pub const GOUGH_VERIFIER_WORDS: usize = GOUGH_VERIFIER_SIZE / 8;

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

/// The checking of a device's secured answers (`gough_verifier_init`). Opaque; holds the
/// keyed AES-CMAC (the key's round keys), never read it.
#[repr(C)]
pub struct gough_verifier_t {
    _opaque: [u64; GOUGH_VERIFIER_WORDS],
}

/// A storage's contents behind its magic word.
#[repr(C)]
pub(crate) struct Slot<T> {
    magic: u32,
    val: T,
}

pub(crate) const MAGIC_PARAMS: u32 = 0x676f_7001;
pub(crate) const MAGIC_WHEEL: u32 = 0x676f_7003;
pub(crate) const MAGIC_EST: u32 = 0x676f_7004;
pub(crate) const MAGIC_RX: u32 = 0x676f_7005;
pub(crate) const MAGIC_PREVIEW: u32 = 0x676f_7006;
pub(crate) const MAGIC_VERIFIER: u32 = 0x676f_7007;

pub(crate) struct ParamsIn {
    pub(crate) p32: Params<f32>,
    pub(crate) p64: Params<f64>,
}

pub(crate) struct WheelIn {
    pub(crate) params: *const Params<f32>,
    pub(crate) wheel: Corner<f32>,
}

pub(crate) struct EstIn {
    pub(crate) bank: Bank<f32>,
    /// The tyre the bank was built for (the caller keeps it alive, documented).
    pub(crate) params: &'static ParamsIn,
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
// The verifier's AES state is aligned to 16 on x86-64 (SSE): it lives at the first 16-aligned
// byte of its 8-aligned storage ([`aligned`]), so the storage holds its slot and 8 bytes more.
const _: () = assert!(
    size_of::<Slot<proto::Verifier>>() + VERIFIER_SHIFT <= GOUGH_VERIFIER_SIZE
        && align_of::<Slot<proto::Verifier>>() <= 16
);
const _: () = assert!(
    size_of::<gough_verifier_t>() == GOUGH_VERIFIER_SIZE && align_of::<gough_verifier_t>() == 8
);
/// The most a 16-aligned slot lies past the start of an 8-aligned storage.
const VERIFIER_SHIFT: usize = align_of::<Slot<proto::Verifier>>().saturating_sub(8);

/// Where a verifier's slot lies in its storage `p`: the first byte aligned for it.
pub(crate) fn aligned(p: *mut gough_verifier_t) -> *mut gough_verifier_t {
    let a = align_of::<Slot<proto::Verifier>>();
    let off = (p as usize).wrapping_neg() & (a - 1);
    p.cast::<u8>().wrapping_add(off).cast()
}

/// Bytes each storage needs on this target (what the `GOUGH_*_SIZE` macros round up):
/// params, wheel, estimator, rx, preview, verifier. For `docs/c-api.md` and the tests.
pub fn used_sizes() -> [usize; 6] {
    [
        size_of::<Slot<ParamsIn>>(),
        size_of::<Slot<WheelIn>>(),
        size_of::<Slot<EstIn>>(),
        size_of::<Slot<Reassembler<MSG_BUF>>>(),
        size_of::<Slot<Preview<f32>>>(),
        size_of::<Slot<proto::Verifier>>() + VERIFIER_SHIFT,
    ]
}

/// The value in storage `p` if it carries `magic`.
///
/// # Safety
/// `p` is null or points to a storage of at least `size_of::<Slot<T>>()` bytes, aligned to 8,
/// that is either initialised by this library (magic set) or holds any bytes at all.
pub(crate) unsafe fn get<'a, S, T>(p: *const S, magic: u32) -> Result<&'a T, i32> {
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
pub(crate) unsafe fn get_mut<'a, S, T>(p: *mut S, magic: u32) -> Result<&'a mut T, i32> {
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
pub(crate) unsafe fn put<S, T>(p: *mut S, magic: u32, val: T) {
    let s = p.cast::<Slot<T>>();
    // SAFETY: by the caller's contract; the old contents are overwritten, never dropped.
    unsafe {
        ptr::addr_of_mut!((*s).magic).write(0);
        ptr::addr_of_mut!((*s).val).write(val);
        ptr::addr_of_mut!((*s).magic).write(magic);
    }
}

/// Runs `f`, mapping `Err(code)` to `code` and `Ok(())` to `GOUGH_OK`.
pub(crate) fn ret(f: impl FnOnce() -> Result<(), i32>) -> i32 {
    match f() {
        Ok(()) => GOUGH_OK,
        Err(e) => e,
    }
}
