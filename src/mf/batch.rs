//! Batch evaluation over columns (structure of arrays): [`eval_batch`].
//!
//! Each point is [`super::eval`]'s — the function itself, so a batch's outputs equal
//! `mf::eval`'s at every point, to the bit (`host-tests/tests/batch.rs`
//! checks every MFeval oracle point). What the batch saves is what the caller does not ask for:
//! the overturning and rolling resistance moments Mx, My (five to eight of 45–50 kernel calls,
//! `mf::tests::kernel_calls_per_evaluation`) when neither column is asked for; and the per-call
//! overhead of a caller's loop.
//!
//! No allocation, no panic: the columns' lengths are checked first ([`BatchError::Length`]); a
//! rejected point stops the batch ([`BatchError::Point`], the points before it written).
//!
//! [`eval_batch`] runs [`super::eval`] point by point (any float, any backend: the scalar
//! speed minus what it skips). [`eval_batch_lanes`] (`f64`) runs the same generic formula
//! ([`super::eval`]'s body) on [`Lanes`] of points: the formula's value branches are masks and
//! selects ([`crate::math::Real`]), the kernels [`Lanewise`]'s, the instruction set (AVX-512F,
//! AVX2, the build's baseline) chosen at run time. See docs/magic-formula.md, "Measured
//! speed", for the figures.

use super::{eval, eval_in, EvalError, Flags, Input, Options, Params};
use crate::math::{Backend, Float, Lanes, Lanewise, Libm, Mask, Real};

/// The inputs of a batch, one column per input of [`super::Input`], every column as long as
/// `fz`. SI units, ISO-W, radians.
#[derive(Debug, Clone, Copy)]
pub struct Columns<'a, F> {
    /// Vertical load Fz \[N\].
    pub fz: &'a [F],
    /// Longitudinal slip κ \[-\].
    pub kappa: &'a [F],
    /// Slip angle α \[rad\].
    pub alpha: &'a [F],
    /// Inclination γ \[rad\].
    pub gamma: &'a [F],
    /// Longitudinal speed Vx \[m/s\].
    pub vx: &'a [F],
    /// Turn slip φt \[1/m\]; `None`: 0 at every point.
    pub phit: Option<&'a [F]>,
    /// Inflation pressure p \[Pa\]; `None`: INFLPRES at every point.
    pub p: Option<&'a [F]>,
}

impl<F> Columns<'_, F> {
    /// The number of points (the length of `fz`).
    pub fn len(&self) -> usize {
        self.fz.len()
    }
    /// No point.
    pub fn is_empty(&self) -> bool {
        self.fz.is_empty()
    }
}

/// Per-point factors on four of the file's scaling factors, for [`eval_batch_lanes_scaled`]: at
/// point `i` the evaluation takes λμx = `p.lmux * lmux[i]` (LMUX), and so for λμy (LMUY), λKx
/// (LKX), λKy (LKY); a column `None` keeps the file's factor. A tyre whose friction or stiffnesses
/// move from point to point (a temperature, a speed: the gap diagnosis's extensions) is evaluated
/// in one batch with them. Every column as long as the inputs.
#[derive(Debug, Clone, Copy, Default)]
pub struct Scales<'a> {
    /// Factor on λμx \[-\].
    pub lmux: Option<&'a [f64]>,
    /// Factor on λμy \[-\].
    pub lmuy: Option<&'a [f64]>,
    /// Factor on λKx \[-\].
    pub lkx: Option<&'a [f64]>,
    /// Factor on λKy \[-\].
    pub lky: Option<&'a [f64]>,
}

impl Scales<'_> {
    /// No column: every point on the file's factors.
    fn is_none(&self) -> bool {
        self.lmux.is_none() && self.lmuy.is_none() && self.lkx.is_none() && self.lky.is_none()
    }

    /// Each column's length against `n`.
    fn check(&self, n: usize) -> Result<(), BatchError> {
        let cols = [
            ("lmux", self.lmux),
            ("lmuy", self.lmuy),
            ("lkx", self.lkx),
            ("lky", self.lky),
        ];
        for (column, c) in cols {
            check(column, c.map(<[f64]>::len), n)?;
        }
        Ok(())
    }

    /// `q`'s four factors those of `p` times point `i`'s (the file's where a column is `None`).
    fn apply(&self, p: &Params<f64>, q: &mut Params<f64>, i: usize) {
        let at = |c: Option<&[f64]>, base: f64| match c.and_then(|c| c.get(i)) {
            Some(&s) => base * s,
            None => base,
        };
        q.lmux = at(self.lmux, p.lmux);
        q.lmuy = at(self.lmuy, p.lmuy);
        q.lkx = at(self.lkx, p.lkx);
        q.lky = at(self.lky, p.lky);
    }
}

/// The output columns a batch writes: one per field of [`super::Output`], each `None` (not
/// computed where that saves work, not written) or as long as the inputs.
#[derive(Debug, Default)]
pub struct Outputs<'a, F> {
    /// Fx \[N\].
    pub fx: Option<&'a mut [F]>,
    /// Fy \[N\].
    pub fy: Option<&'a mut [F]>,
    /// Fz used \[N\].
    pub fz: Option<&'a mut [F]>,
    /// Mx \[N·m\] (with `my`: computed only when one of them is asked for).
    pub mx: Option<&'a mut [F]>,
    /// My \[N·m\].
    pub my: Option<&'a mut [F]>,
    /// Mz \[N·m\].
    pub mz: Option<&'a mut [F]>,
    /// μx \[-\].
    pub mu_x: Option<&'a mut [F]>,
    /// |μy| \[-\].
    pub mu_y: Option<&'a mut [F]>,
    /// Kxκ \[N\].
    pub k_xk: Option<&'a mut [F]>,
    /// Kyα \[N/rad\].
    pub k_ya: Option<&'a mut [F]>,
    /// Pneumatic trail t \[m\].
    pub t: Option<&'a mut [F]>,
    /// Residual torque Mzr \[N·m\].
    pub m_zr: Option<&'a mut [F]>,
    /// σx \[m\].
    pub sigma_x: Option<&'a mut [F]>,
    /// σy \[m\].
    pub sigma_y: Option<&'a mut [F]>,
    /// κ after the low-speed reduction \[-\].
    pub kappa: Option<&'a mut [F]>,
    /// What was clipped or regularised.
    pub flags: Option<&'a mut [Flags]>,
}

/// Why a batch stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum BatchError {
    /// A column's length differs from `fz`'s; nothing was computed.
    Length {
        /// The column (the field's name in [`Columns`] or [`Outputs`]).
        column: &'static str,
        /// Its length.
        len: usize,
        /// The length of `fz`.
        expected: usize,
    },
    /// The point at `index` was rejected; the points before it are written, none after.
    Point {
        /// Its index in the columns.
        index: usize,
        /// Why.
        error: EvalError,
    },
}

impl core::fmt::Display for BatchError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            BatchError::Length {
                column,
                len,
                expected,
            } => write!(f, "column {column}: {len} values, expected {expected}"),
            BatchError::Point { index, error } => write!(f, "point {index}: {error}"),
        }
    }
}

impl core::error::Error for BatchError {}

/// Writes `v` at `i` of an asked-for column.
#[inline(always)]
fn put<T>(col: &mut Option<&mut [T]>, i: usize, v: T) {
    if let Some(x) = col.as_deref_mut().and_then(|c| c.get_mut(i)) {
        *x = v;
    }
}

/// The length check of one column.
fn check(column: &'static str, len: Option<usize>, expected: usize) -> Result<(), BatchError> {
    match len {
        Some(len) if len != expected => Err(BatchError::Length {
            column,
            len,
            expected,
        }),
        _ => Ok(()),
    }
}

/// The Magic Formula of `p.version` at every point of `inputs`, into the columns of `out` that
/// are `Some`: at each point what [`super::eval`] gives there, to the bit (the same function).
/// Mx, My are computed only when `out.mx` or `out.my` is asked for (and `opts.moments` is on).
///
/// ```
/// use gough::{math::Libm, mf::{self, Columns, Input, Options, Outputs, Params, Version}};
/// let mut p = Params::<f64>::zeroed(Version::Mf52); // a made-up tyre, for the example
/// p.fnomin = 4000.0; p.unloaded_radius = 0.3; p.longvl = 16.7; p.vxlow = 1.0;
/// p.pcy1 = 1.3; p.pdy1 = 1.0; p.pky1 = -20.0; p.pky2 = 2.0; p.pcx1 = 1.6; p.pdx1 = 1.0;
/// p.pkx1 = 20.0; p.qcz1 = 1.2; p.qbz1 = 10.0; p.qdz1 = 0.1;
/// let opts = Options { limits: false, ..Options::default() };
/// let (fz, kappa, alpha) = ([4000.0, 3000.0], [0.0, -0.05], [0.05, 0.02]);
/// let cols = Columns { fz: &fz, kappa: &kappa, alpha: &alpha, gamma: &[0.0; 2], vx: &[20.0; 2],
///                      phit: None, p: None };
/// let (mut fx, mut fy) = ([0.0; 2], [0.0; 2]);
/// let mut out = Outputs { fx: Some(&mut fx), fy: Some(&mut fy), ..Outputs::default() };
/// mf::eval_batch::<f64, Libm>(&p, &cols, &opts, &mut out).unwrap();
/// let i = Input { fz: 3000.0, kappa: -0.05, alpha: 0.02, vx: 20.0, ..Default::default() };
/// assert_eq!(fy[1], mf::eval::<f64, Libm>(&p, &i, &opts).unwrap().fy);
/// ```
pub fn eval_batch<F: Float, M: Backend<F>>(
    p: &Params<F>,
    inputs: &Columns<'_, F>,
    opts: &Options,
    out: &mut Outputs<'_, F>,
) -> Result<(), BatchError> {
    let opts = check_lengths(inputs, opts, out)?;
    for i in 0..inputs.len() {
        point::<F, M>(p, inputs, &opts, out, i)?;
    }
    Ok(())
}

/// Every column's length against `fz`'s; the options with the moments off when no column asks
/// for Mx or My (hoisted out of the loop: what no column asks for is not computed).
fn check_lengths<F>(
    inputs: &Columns<'_, F>,
    opts: &Options,
    out: &Outputs<'_, F>,
) -> Result<Options, BatchError> {
    let n = inputs.len();
    let ins: [(&'static str, Option<usize>); 6] = [
        ("kappa", Some(inputs.kappa.len())),
        ("alpha", Some(inputs.alpha.len())),
        ("gamma", Some(inputs.gamma.len())),
        ("vx", Some(inputs.vx.len())),
        ("phit", inputs.phit.map(<[F]>::len)),
        ("p", inputs.p.map(<[F]>::len)),
    ];
    for (column, len) in ins {
        check(column, len, n)?;
    }
    let len = |c: &Option<&mut [F]>| c.as_deref().map(<[F]>::len);
    let outs: [(&'static str, Option<usize>); 16] = [
        ("fx", len(&out.fx)),
        ("fy", len(&out.fy)),
        ("fz", len(&out.fz)),
        ("mx", len(&out.mx)),
        ("my", len(&out.my)),
        ("mz", len(&out.mz)),
        ("mu_x", len(&out.mu_x)),
        ("mu_y", len(&out.mu_y)),
        ("k_xk", len(&out.k_xk)),
        ("k_ya", len(&out.k_ya)),
        ("t", len(&out.t)),
        ("m_zr", len(&out.m_zr)),
        ("sigma_x", len(&out.sigma_x)),
        ("sigma_y", len(&out.sigma_y)),
        ("kappa", len(&out.kappa)),
        ("flags", out.flags.as_deref().map(<[Flags]>::len)),
    ];
    for (column, len) in outs {
        check(column, len, n)?;
    }
    Ok(Options {
        moments: opts.moments && (out.mx.is_some() || out.my.is_some()),
        ..*opts
    })
}

/// Point `i` by [`super::eval`], into the asked-for columns.
#[inline(always)]
fn point<F: Float, M: Backend<F>>(
    p: &Params<F>,
    inputs: &Columns<'_, F>,
    opts: &Options,
    out: &mut Outputs<'_, F>,
    i: usize,
) -> Result<(), BatchError> {
    let at = |c: &[F], i: usize| c.get(i).copied().unwrap_or(F::ZERO);
    let input = Input {
        fz: at(inputs.fz, i),
        kappa: at(inputs.kappa, i),
        alpha: at(inputs.alpha, i),
        gamma: at(inputs.gamma, i),
        phit: inputs.phit.map_or(F::ZERO, |c| at(c, i)),
        vx: at(inputs.vx, i),
        p: inputs.p.and_then(|c| c.get(i).copied()),
    };
    let o = eval::<F, M>(p, &input, opts).map_err(|error| BatchError::Point { index: i, error })?;
    put(&mut out.fx, i, o.fx);
    put(&mut out.fy, i, o.fy);
    put(&mut out.fz, i, o.fz);
    put(&mut out.mx, i, o.mx);
    put(&mut out.my, i, o.my);
    put(&mut out.mz, i, o.mz);
    put(&mut out.mu_x, i, o.mu_x);
    put(&mut out.mu_y, i, o.mu_y);
    put(&mut out.k_xk, i, o.k_xk);
    put(&mut out.k_ya, i, o.k_ya);
    put(&mut out.t, i, o.t);
    put(&mut out.m_zr, i, o.m_zr);
    put(&mut out.sigma_x, i, o.sigma_x);
    put(&mut out.sigma_y, i, o.sigma_y);
    put(&mut out.kappa, i, o.kappa);
    put(&mut out.flags, i, o.flags);
    Ok(())
}

/// The instruction set a lane batch runs on ([`eval_batch_lanes_on`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Isa {
    /// The widest this processor has (checked at run time with `std`; without `std`, two lanes
    /// in what the build targets).
    Auto,
    /// AVX-512F (x86_64; `std` to detect it): 16 `f64` lanes, two 8-lane registers in step.
    Avx512,
    /// AVX2 and FMA (x86_64; `std` to detect it): 8 `f64` lanes, two 4-lane registers in step.
    Avx2,
    /// What the build targets (SSE2 on x86_64, NEON on aarch64): 4 `f64` lanes, two 2-lane
    /// registers in step.
    Baseline,
}

/// [`eval_batch`] in `f64` with several points per instruction: the same generic formula
/// ([`super::eval`]'s body) on [`Lanes`] of 16 (AVX-512F), 8 (AVX2 + FMA) or 4 points, chosen
/// at run time (with `std`), with [`Lanewise`]'s kernels. Each width is two registers' worth:
/// the formula is a chain of dependent kernels (atan of atan, then sin), and two independent
/// registers in step keep the vector units busier than one (AVX2: 4 lanes ~330–400 ns a
/// point, 8 lanes ~250–260, the scalar path ~760 in the same runs, MF 6.1, on a shared machine). Each point is within 1e-9·FNOMIN of
/// `mf::eval::<f64, Libm>` with the same flags (`host-tests/tests/batch.rs`, every MFeval oracle
/// point); not to the bit, as `libm`'s kernels are not the lanes'. The same columns, length
/// checks and errors as [`eval_batch`].
///
/// A chunk of lanes that some of the lanes' value branches cannot take together — Fz > 0 in
/// some lanes and ≤ 0 in others, a rejected point, a result that overflows — is evaluated point
/// by point with [`super::eval`] (`Libm`). Turn slip runs in lanes too (the effective rolling
/// radius iterates in each lane until that lane's settles). Returns how many points were
/// evaluated in lanes.
///
/// `#[inline]`, as are the functions it dispatches to: the three widths of the whole formula
/// are compiled in the crate that calls them, at that crate's optimisation level, and not in
/// every build of the core (the device's included), where they had made the core library's
/// compile 445 s instead of 11 s at `opt-level = 2`. Unoptimised (`opt-level = 0` in the calling crate), the
/// 16 lanes' temporaries each keep their own stack slot: more than the 2 MiB of a spawned
/// thread (4 MiB was enough, `host-tests/tests/batch.rs`).
#[inline]
pub fn eval_batch_lanes(
    p: &Params<f64>,
    inputs: &Columns<'_, f64>,
    opts: &Options,
    out: &mut Outputs<'_, f64>,
) -> Result<usize, BatchError> {
    eval_batch_lanes_on(Isa::Auto, p, inputs, opts, out)
}

/// [`eval_batch_lanes`] on a chosen instruction set (one the processor lacks, or that the build
/// cannot detect, runs as [`Isa::Auto`]).
#[inline]
pub fn eval_batch_lanes_on(
    isa: Isa,
    p: &Params<f64>,
    inputs: &Columns<'_, f64>,
    opts: &Options,
    out: &mut Outputs<'_, f64>,
) -> Result<usize, BatchError> {
    eval_batch_lanes_scaled(isa, p, inputs, &Scales::default(), opts, out)
}

/// [`eval_batch_lanes_on`] with per-point factors on λμx, λμy, λKx, λKy ([`Scales`]): at each
/// point within 1e-9·FNOMIN of [`super::eval`] on `p` with that point's factors (the product
/// `p.lmuy * lmuy[i]` is the same number either way). A scale column of another length than the
/// inputs is a [`BatchError::Length`] before anything is computed.
#[inline]
pub fn eval_batch_lanes_scaled(
    isa: Isa,
    p: &Params<f64>,
    inputs: &Columns<'_, f64>,
    scales: &Scales<'_>,
    opts: &Options,
    out: &mut Outputs<'_, f64>,
) -> Result<usize, BatchError> {
    let opts = check_lengths(inputs, opts, out)?;
    scales.check(inputs.len())?;
    #[cfg(all(feature = "std", target_arch = "x86_64"))]
    {
        let avx512 = std::is_x86_feature_detected!("avx512f");
        let avx2 = std::is_x86_feature_detected!("avx2") && std::is_x86_feature_detected!("fma");
        let (use512, use2) = match isa {
            Isa::Auto => (avx512, avx2),
            Isa::Avx512 => (avx512, !avx512 && avx2),
            Isa::Avx2 => (false, avx2),
            Isa::Baseline => (false, false),
        };
        if use512 {
            // SAFETY: the processor has AVX-512F (detected just above).
            return unsafe { lanes_avx512(p, inputs, scales, &opts, out) };
        }
        if use2 {
            // SAFETY: the processor has AVX2 and FMA (detected just above).
            return unsafe { lanes_avx2(p, inputs, scales, &opts, out) };
        }
    }
    let _ = isa;
    lanes::<4>(p, inputs, scales, &opts, out)
}

/// [`lanes`] of 16 compiled for AVX-512F.
#[cfg(all(feature = "std", target_arch = "x86_64"))]
#[target_feature(enable = "avx512f,avx2,fma")]
#[inline]
fn lanes_avx512(
    p: &Params<f64>,
    inputs: &Columns<'_, f64>,
    scales: &Scales<'_>,
    opts: &Options,
    out: &mut Outputs<'_, f64>,
) -> Result<usize, BatchError> {
    lanes::<16>(p, inputs, scales, opts, out)
}

/// [`lanes`] of 8 compiled for AVX2 and FMA.
#[cfg(all(feature = "std", target_arch = "x86_64"))]
#[target_feature(enable = "avx2,fma")]
#[inline]
fn lanes_avx2(
    p: &Params<f64>,
    inputs: &Columns<'_, f64>,
    scales: &Scales<'_>,
    opts: &Options,
    out: &mut Outputs<'_, f64>,
) -> Result<usize, BatchError> {
    lanes::<8>(p, inputs, scales, opts, out)
}

/// The points `N` at a time (the last chunk padded with its last point); a chunk the lanes
/// cannot take together point by point. `opts` from [`check_lengths`]; `scales` checked.
#[inline(always)]
fn lanes<const N: usize>(
    p: &Params<f64>,
    inputs: &Columns<'_, f64>,
    scales: &Scales<'_>,
    opts: &Options,
    out: &mut Outputs<'_, f64>,
) -> Result<usize, BatchError> {
    let mut pl: Params<Lanes<f64, N>> = p.cast();
    let base = (pl.lmux, pl.lmuy, pl.lkx, pl.lky);
    // The parameters of a point evaluated alone, with its factors (only when there are any).
    let mut q = (!scales.is_none()).then(|| p.clone());
    let n = inputs.len();
    let (mut i, mut in_lanes) = (0, 0);
    while i < n {
        let len = N.min(n - i);
        let scaled = |c: Option<&[f64]>, b: Lanes<f64, N>| c.map_or(b, |c| b * gather(c, i, len));
        pl.lmux = scaled(scales.lmux, base.0);
        pl.lmuy = scaled(scales.lmuy, base.1);
        pl.lkx = scaled(scales.lkx, base.2);
        pl.lky = scaled(scales.lky, base.3);
        if chunk::<N>(&pl, inputs, opts, out, i, len) {
            in_lanes += len;
        } else {
            for k in i..i + len {
                match q.as_mut() {
                    Some(q) => {
                        scales.apply(p, q, k);
                        point::<f64, Libm>(q, inputs, opts, out, k)?;
                    }
                    None => point::<f64, Libm>(p, inputs, opts, out, k)?,
                }
            }
        }
        i += N;
    }
    Ok(in_lanes)
}

/// Column `c`'s points `i..i + len` in lanes, the rest of the lanes repeating the last.
#[inline(always)]
fn gather<const N: usize>(c: &[f64], i: usize, len: usize) -> Lanes<f64, N> {
    let src = c.get(i..i + len).unwrap_or(&[]);
    let last = src.last().copied().unwrap_or(0.0);
    let mut a = [last; N];
    for (x, &v) in a.iter_mut().zip(src) {
        *x = v;
    }
    Lanes(a)
}

/// Writes lanes `..len` at `i` of an asked-for column.
#[inline(always)]
fn scatter<T: Copy, const N: usize>(col: &mut Option<&mut [T]>, i: usize, len: usize, v: [T; N]) {
    if let Some(dst) = col.as_deref_mut().and_then(|c| c.get_mut(i..i + len)) {
        for (d, s) in dst.iter_mut().zip(v) {
            *d = s;
        }
    }
}

/// Points `i..i + len` in one evaluation of lanes; `false` (nothing written) when the lanes
/// cannot take them together (mixed contact, an error in some lane).
#[inline(always)]
fn chunk<const N: usize>(
    pl: &Params<Lanes<f64, N>>,
    inputs: &Columns<'_, f64>,
    opts: &Options,
    out: &mut Outputs<'_, f64>,
    i: usize,
    len: usize,
) -> bool {
    let fz = gather::<N>(inputs.fz, i, len);
    let zero = Lanes::<f64, N>::ZERO;
    // Every lane in contact, or none (`prepared::stages` takes one path for all).
    if !(fz.mask_gt(zero).all() || fz.mask_le(zero).all()) {
        return false;
    }
    let input = Input {
        fz,
        kappa: gather(inputs.kappa, i, len),
        alpha: gather(inputs.alpha, i, len),
        gamma: gather(inputs.gamma, i, len),
        phit: inputs.phit.map_or(zero, |c| gather(c, i, len)),
        vx: gather(inputs.vx, i, len),
        p: inputs.p.map(|c| gather(c, i, len)),
    };
    let Ok(o) = eval_in::<Lanes<f64, N>, Lanewise>(pl, &input, opts) else {
        return false;
    };
    scatter(&mut out.fx, i, len, o.fx.0);
    scatter(&mut out.fy, i, len, o.fy.0);
    scatter(&mut out.fz, i, len, o.fz.0);
    scatter(&mut out.mx, i, len, o.mx.0);
    scatter(&mut out.my, i, len, o.my.0);
    scatter(&mut out.mz, i, len, o.mz.0);
    scatter(&mut out.mu_x, i, len, o.mu_x.0);
    scatter(&mut out.mu_y, i, len, o.mu_y.0);
    scatter(&mut out.k_xk, i, len, o.k_xk.0);
    scatter(&mut out.k_ya, i, len, o.k_ya.0);
    scatter(&mut out.t, i, len, o.t.0);
    scatter(&mut out.m_zr, i, len, o.m_zr.0);
    scatter(&mut out.sigma_x, i, len, o.sigma_x.0);
    scatter(&mut out.sigma_y, i, len, o.sigma_y.0);
    scatter(&mut out.kappa, i, len, o.kappa.0);
    scatter(&mut out.flags, i, len, o.flags.0);
    true
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Libm;
    use crate::mf::{eval, Output, Version};

    fn tyre() -> Params<f64> {
        crate::tir::parse(include_str!(
            "../../host-tests/data/tyres/MagicFormula61_Parameters.tir"
        ))
        .map(|t| t.params)
        .unwrap()
    }

    #[test]
    fn lengths_are_checked_before_anything_is_written() {
        let p = tyre();
        let z = [0.0; 3];
        let cols = Columns {
            fz: &[4000.0; 3],
            kappa: &z,
            alpha: &z[..2],
            gamma: &z,
            vx: &[20.0; 3],
            phit: None,
            p: None,
        };
        let mut fx = [7.0; 3];
        let mut out = Outputs {
            fx: Some(&mut fx),
            ..Outputs::default()
        };
        let e = eval_batch::<f64, Libm>(&p, &cols, &Options::default(), &mut out);
        assert_eq!(
            e,
            Err(BatchError::Length {
                column: "alpha",
                len: 2,
                expected: 3
            })
        );
        assert_eq!(fx, [7.0; 3]);
        let cols = Columns { alpha: &z, ..cols };
        let mut short = [0.0; 2];
        let mut out = Outputs {
            mz: Some(&mut short),
            ..Outputs::default()
        };
        assert!(matches!(
            eval_batch::<f64, Libm>(&p, &cols, &Options::default(), &mut out),
            Err(BatchError::Length { column: "mz", .. })
        ));
    }

    #[test]
    fn a_rejected_point_stops_the_batch() {
        let p = tyre();
        let cols = Columns {
            fz: &[4000.0, f64::NAN, 4000.0],
            kappa: &[0.01; 3],
            alpha: &[0.02; 3],
            gamma: &[0.0; 3],
            vx: &[20.0; 3],
            phit: None,
            p: None,
        };
        let mut fy = [0.0; 3];
        let mut out = Outputs {
            fy: Some(&mut fy),
            ..Outputs::default()
        };
        let e = eval_batch::<f64, Libm>(&p, &cols, &Options::default(), &mut out);
        assert_eq!(
            e,
            Err(BatchError::Point {
                index: 1,
                error: EvalError::NonFinite(crate::mf::InputField::Fz)
            })
        );
        assert!(fy[0] < 0.0 && fy[2] == 0.0);
    }

    /// Every column equals `mf::eval`'s field, to the bit, f64 and f32, with and without the
    /// moments and σ asked for (the oracle-wide check is `host-tests/tests/batch.rs`).
    #[test]
    fn columns_equal_eval() {
        let p = tyre();
        assert_eq!(p.version, Version::Mf61);
        let n = 50;
        let f = |i: usize| i as f64 / (n - 1) as f64;
        let fz: std::vec::Vec<f64> = (0..n).map(|i| p.fnomin * (0.2 + 1.6 * f(i))).collect();
        let kappa: std::vec::Vec<f64> = (0..n).map(|i| -0.4 + 0.7 * f(i)).collect();
        let alpha: std::vec::Vec<f64> =
            (0..n).map(|i| 0.3 * (2.0 * f((i * 7) % n) - 1.0)).collect();
        let gamma: std::vec::Vec<f64> = (0..n).map(|i| 0.05 * f((i * 3) % n)).collect();
        let vx: std::vec::Vec<f64> = (0..n).map(|i| 30.0 * f((i * 11) % n) - 1.0).collect();
        let cols = Columns {
            fz: &fz,
            kappa: &kappa,
            alpha: &alpha,
            gamma: &gamma,
            vx: &vx,
            phit: None,
            p: None,
        };
        let opts = Options::default();
        let mut c = [[0.0f64; 50]; 15];
        let mut flags = [Flags::default(); 50];
        {
            let [fx, fy, fzo, mx, my, mz, mux, muy, kxk, kya, t, mzr, sx, sy, k] = &mut c;
            let mut out = Outputs {
                fx: Some(fx),
                fy: Some(fy),
                fz: Some(fzo),
                mx: Some(mx),
                my: Some(my),
                mz: Some(mz),
                mu_x: Some(mux),
                mu_y: Some(muy),
                k_xk: Some(kxk),
                k_ya: Some(kya),
                t: Some(t),
                m_zr: Some(mzr),
                sigma_x: Some(sx),
                sigma_y: Some(sy),
                kappa: Some(k),
                flags: Some(&mut flags),
            };
            eval_batch::<f64, Libm>(&p, &cols, &opts, &mut out).unwrap();
        }
        for i in 0..n {
            let o: Output<f64> = eval::<f64, Libm>(
                &p,
                &Input {
                    fz: fz[i],
                    kappa: kappa[i],
                    alpha: alpha[i],
                    gamma: gamma[i],
                    phit: 0.0,
                    vx: vx[i],
                    p: None,
                },
                &opts,
            )
            .unwrap();
            let want = [
                o.fx, o.fy, o.fz, o.mx, o.my, o.mz, o.mu_x, o.mu_y, o.k_xk, o.k_ya, o.t, o.m_zr,
                o.sigma_x, o.sigma_y, o.kappa,
            ];
            for (k, w) in want.iter().enumerate() {
                assert_eq!(c[k][i].to_bits(), w.to_bits(), "point {i} column {k}");
            }
            assert_eq!(flags[i], o.flags);
        }
        // Only Fx, Fy, Mz asked for: the same values (Mx, My and σ skipped).
        let (mut fx, mut fy, mut mz) = ([0.0f64; 50], [0.0f64; 50], [0.0f64; 50]);
        let mut out = Outputs {
            fx: Some(&mut fx),
            fy: Some(&mut fy),
            mz: Some(&mut mz),
            ..Outputs::default()
        };
        eval_batch::<f64, Libm>(&p, &cols, &opts, &mut out).unwrap();
        assert_eq!((fx, fy, mz), (c[0], c[1], c[5]));
        // f32.
        let p32 = p.cast::<f32>();
        let to32 = |v: &[f64]| v.iter().map(|&x| x as f32).collect::<std::vec::Vec<f32>>();
        let (fz32, k32, a32, g32, v32) = (
            to32(&fz),
            to32(&kappa),
            to32(&alpha),
            to32(&gamma),
            to32(&vx),
        );
        let cols32 = Columns {
            fz: &fz32,
            kappa: &k32,
            alpha: &a32,
            gamma: &g32,
            vx: &v32,
            phit: None,
            p: None,
        };
        let mut mz32 = [0.0f32; 50];
        let mut out = Outputs {
            mz: Some(&mut mz32),
            ..Outputs::default()
        };
        eval_batch::<f32, Libm>(&p32, &cols32, &opts, &mut out).unwrap();
        for i in 0..n {
            let o = eval::<f32, Libm>(
                &p32,
                &Input {
                    fz: fz32[i],
                    kappa: k32[i],
                    alpha: a32[i],
                    gamma: g32[i],
                    phit: 0.0,
                    vx: v32[i],
                    p: None,
                },
                &opts,
            )
            .unwrap();
            assert_eq!(mz32[i].to_bits(), o.mz.to_bits(), "f32 point {i}");
        }
    }
}
