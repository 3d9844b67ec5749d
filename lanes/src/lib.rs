//! `gough-lanes`: the core's lane batch, compiled here once.
//!
//! [`gough::mf::eval_batch_lanes_scaled`] is `#[inline]`: its three widths of the whole Magic
//! Formula (AVX-512F, AVX2, the baseline) are compiled in the crate that calls them. The host's
//! crates that call it (`gough-host`'s gap diagnosis, the Python package) call it through this
//! one non-generic function instead, so that a build compiles the lanes once, and a test build
//! of `gough-host` (its library and its unit tests) does not compile them twice. It adds nothing:
//! the same arguments, the same results. In the `dev` and `test` profiles it is built at
//! `opt-level = 1` (the workspace's `Cargo.toml`): the lanes compile in about two minutes there, and
//! unoptimised they would need more stack than a test thread has.
use gough::mf::{self, BatchError, Columns, Isa, Options, Outputs, Params, Scales};

/// [`gough::mf::eval_batch_lanes_scaled`]: the Magic Formula at every point of `inputs` in
/// lanes on `isa` (`Isa::Auto`: the widest this processor has), with per-point factors on
/// λμx, λμy, λKx, λKy; each point within 1e-9·FNOMIN of `mf::eval`. Returns how many points
/// went through lanes.
pub fn eval_batch_lanes_scaled(
    isa: Isa,
    p: &Params<f64>,
    inputs: &Columns<'_, f64>,
    scales: &Scales<'_>,
    opts: &Options,
    out: &mut Outputs<'_, f64>,
) -> Result<usize, BatchError> {
    mf::eval_batch_lanes_scaled(isa, p, inputs, scales, opts, out)
}
