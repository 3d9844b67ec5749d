//! `gough mu bound`: how soon *any* estimator could know μ on the benchmark's data — the
//! Cramér–Rao bound of the benchmark, against which `gough mu bench`'s latencies read.
//!
//! Issue 5's target asks for μ within ±0.1 within 150 ms of the utilisation reaching 0.5. Whether
//! that is possible at all depends on how much the benchmark's noisy rows say about μ, not on
//! the estimator. This module measures it with an estimator-free yardstick, computed on the
//! very rows the bench makes (same simulation, same sensor model, same delay):
//!
//! - **Measurements** per row: Fz, Fx, Fy, Mz with the bench's Gaussian noise (Fz, Fx, Fy 1 % of
//!   Fz rms, Mz 2 N·m rms; [`Sensors`]), independent between rows.
//! - **Unknowns**: μ, shared by the rows of a surface, and per row the transient slips α', κ'
//!   and the true load Fz. They are free per row because a method without a slip sensor (the
//!   bank's premise) cannot pin them. Camber γ and Vx are given exactly, as the bench
//!   gives them to the estimator.
//! - **Model**: the simulation's own — the Magic Formula of the bundled file with λμx = λμy =
//!   μ/μy0, evaluated as the simulation evaluates it (`Options::transient`, mounted side). So the
//!   model is exact: no table, no interpolation, nothing an estimator could get wrong.
//! - **Bound**: each row's Fisher information on μ with its own α', κ', Fz eliminated (Schur
//!   complement of JᵀΣ⁻¹J, J by central differences), summed over the surface's rows up to a
//!   time. σ_CRB = 1/√(sum) is the least standard deviation an unbiased estimator of μ can
//!   have from those rows. The bound is local (it does not see ambiguities the non-linear model
//!   may have) and it grants the estimator everything before the deadline, so it is optimistic:
//!   where it says ±0.1 cannot be decided, no estimator decides it; where it says it can, one
//!   might.
//!
//! A wheel can meet the target only if 1.96·σ_CRB ≤ 0.1 at 150 ms after its utilisation first
//! reaches 0.5 (a 95 % interval inside ±0.1). The table puts that beside the bank's own latency
//! (run as `gough mu bench` runs it), wheel by wheel, and (`--ml`) beside [`WindowMl`], a maximum-likelihood
//! reference with the same exact model that shows whether the bound can be reached.

use super::bench::{self, metrics::TARGET_STEP, Sensors, WheelTrace};
use super::{Method, Setup};
use crate::sim::Log;
use gough::math::Libm;
use gough::mf::{self, Input, Options, Params, Side};
use gough::mu::calibration::PROPERTIES;
use std::fmt::Write as _;

/// What `gough mu bound` runs, and where it writes.
#[derive(Debug, Clone, PartialEq)]
pub struct Config {
    /// The bench whose rows are bounded, as [`bench::run`] would run it: its tyre, cases
    /// (shifted as it says), sensors and seed, and the bank's setup and tyre model for the
    /// latency beside the bound; `out` receives bound.md and bound.csv. The bound's model is
    /// the simulated tyre (the file), whatever the bank is given.
    pub bench: bench::Config,
    /// Also run the maximum-likelihood reference ([`WindowMl`]) on every wheel and surface,
    /// with this window \[s\], in (0, 10] (about 1,000 Magic Formula evaluations per row, a
    /// few minutes for the suite); `None`: not.
    pub ml: Option<f64>,
}

impl Default for Config {
    /// The default bench's rows, written to `out/mu_bound`, without the reference.
    fn default() -> Self {
        Config {
            bench: bench::Config {
                out: "out/mu_bound".into(),
                ..bench::Config::default()
            },
            ml: None,
        }
    }
}

/// The simulation's tyre on a surface: the file's parameters with λμx, λμy for μ.
pub struct Surface {
    mu: f64,
    p: Params<f64>,
}

/// The simulation's tyre model of one wheel, as a function of μ and one row's unknowns.
pub struct Model<'a> {
    base: &'a Params<f64>,
    mu_y0: f64,
    opts: Options,
    /// Whether κ is measured (σ: the sensors' `sigma_kappa`), taken as κ′ plus its noise (the
    /// relaxation's lag neglected, as the bank's batches do within their model error).
    kappa_measured: bool,
}

/// One row's unknowns and givens. ISO-W, SI.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RowState {
    /// Transient slip angle α' \[rad\] (unknown).
    pub alpha: f64,
    /// Transient longitudinal slip κ' \[-\] (unknown).
    pub kappa: f64,
    /// Vertical load Fz \[N\] (unknown; measured with noise).
    pub fz: f64,
    /// Inclination γ \[rad\] (given).
    pub gamma: f64,
    /// Forward speed Vx \[m/s\] (given).
    pub vx: f64,
}

impl RowState {
    /// Row `i` of a wheel case's trace: its transient slips, true load, γ and Vx.
    pub fn of_trace(tr: &super::scenario::Trace, i: usize) -> RowState {
        RowState {
            alpha: tr.alpha_t[i],
            kappa: tr.kappa_t[i],
            fz: tr.fz_true[i],
            gamma: tr.gamma[i],
            vx: tr.vx[i],
        }
    }

    /// What one wheel of the vehicle simulation had over a step: its transient slips, load, γ
    /// and Vx.
    pub fn of_wheel(w: &crate::sim::vehicle::WheelRecord) -> RowState {
        RowState {
            alpha: w.alpha_t,
            kappa: w.kappa_t,
            fz: w.fz,
            gamma: w.gamma,
            vx: w.vx,
        }
    }
}

impl<'a> Model<'a> {
    /// The tyre `base` mounted on `side`, surfaces scaled from the file's μy0 (docs/architecture.md).
    pub fn new(base: &'a Params<f64>, side: Side) -> Result<Model<'a>, String> {
        Ok(Model {
            base,
            mu_y0: crate::sim::vehicle::mu_y0(base)?,
            opts: Options {
                transient: true,
                mounted: Some(side),
                moments: false,
                ..Options::default()
            },
            kappa_measured: false,
        })
    }

    /// The wheel cases' tyre `base` (`gough mu bench`'s wheel level, `super::scenario`): as
    /// the file describes it (not mounted), surfaces scaled from `mu_y0` as the scenarios
    /// scale them, κ measured (the scenarios log it; the vehicle suite's bound does not count
    /// it).
    pub fn unmounted(base: &'a Params<f64>, mu_y0: f64) -> Model<'a> {
        Model {
            base,
            mu_y0,
            opts: Options {
                transient: true,
                moments: false,
                ..Options::default()
            },
            kappa_measured: true,
        }
    }

    /// The parameters of surface μ, as the simulation sets them.
    pub fn surface(&self, mu: f64) -> Surface {
        let mut p = self.base.clone();
        p.lmux = self.base.lmux * mu / self.mu_y0;
        p.lmuy = self.base.lmuy * mu / self.mu_y0;
        Surface { mu, p }
    }

    /// (Fx, Fy, Mz) of row `r` on surface `s`; `None` where the model fails.
    pub fn forces(&self, s: &Surface, r: &RowState) -> Option<[f64; 3]> {
        let o = mf::eval::<f64, Libm>(
            &s.p,
            &Input {
                fz: r.fz,
                kappa: r.kappa,
                alpha: r.alpha,
                gamma: r.gamma,
                vx: r.vx,
                ..Input::default()
            },
            &self.opts,
        )
        .ok()?;
        [o.fx, o.fy, o.mz]
            .iter()
            .all(|v| v.is_finite())
            .then_some([o.fx, o.fy, o.mz])
    }
}

/// Central-difference steps of μ and of the row's α', κ', Fz.
const H_MU: f64 = 1e-4;
const H_ALPHA: f64 = 1e-5;
const H_KAPPA: f64 = 1e-5;

/// Central-difference steps of the calibrated properties θ (ln trail, ln trail shape, trail
/// shift \[rad\], ln Kxκ; `gough::mu::calibration`).
const H_CAL: [f64; PROPERTIES] = [1e-4, 1e-4, 1e-6, 1e-4];

/// Surfaces μ − h and μ + h for the μ derivative, and at μ the tyre with each calibrated
/// property θⱼ moved by ∓h (for the bound with the calibration unknown).
pub struct Surfaces {
    lo: Surface,
    hi: Surface,
    cal: [[Surface; 2]; PROPERTIES],
}

impl Surfaces {
    /// About μ.
    pub fn new(m: &Model, mu: f64) -> Surfaces {
        let moved = |j: usize, d: f64| {
            let mut t = [0.0; PROPERTIES];
            t[j] = d;
            let base = m.surface(mu);
            Surface {
                mu,
                p: super::calibrate::apply(&base.p, &t),
            }
        };
        Surfaces {
            lo: m.surface(mu - H_MU),
            hi: m.surface(mu + H_MU),
            cal: std::array::from_fn(|j| [moved(j, -H_CAL[j]), moved(j, H_CAL[j])]),
        }
    }
}

/// Fisher information on μ of one row at state `r` on surfaces `s`, with the row's α', κ', Fz
/// eliminated; sensor noise as in `sens` (σ of Fz, Fx, Fy: `sigma_rel`·Fz; of Mz: `sigma_mz`).
/// 0 where the model fails or the row carries no load.
pub fn row_information(m: &Model, s: &Surfaces, r: &RowState, sens: &Sensors) -> f64 {
    // The (μ, μ) entry of the information on (μ, θ): the row's nuisances are eliminated the
    // same way, and θ not at all (known).
    row_information_cal(m, s, r, sens)[0][0]
}

/// Fisher information of one row on (μ, θ) — the surface and the four calibrated properties
/// of the tyre (`gough::mu::calibration`: ln trail, ln trail shape, trail shift, ln Kxκ) — with
/// the row's α', κ', Fz eliminated, as [`row_information`] does for μ alone. Zero where the
/// model fails or the row carries no load.
pub fn row_information_cal(
    m: &Model,
    s: &Surfaces,
    r: &RowState,
    sens: &Sensors,
) -> [[f64; 1 + PROPERTIES]; 1 + PROPERTIES] {
    const K: usize = 1 + PROPERTIES;
    let zero = [[0.0; K]; K];
    if r.fz.is_nan() || r.fz <= 0.0 {
        return zero;
    }
    let sf = (sens.sigma_rel * r.fz).max(1e-9);
    let sd = [sf, sf, sens.sigma_mz.max(1e-9)];
    let diff = |a: Option<[f64; 3]>, b: Option<[f64; 3]>, h: f64| -> Option<[f64; 3]> {
        let (a, b) = (a?, b?);
        Some(std::array::from_fn(|k| (a[k] - b[k]) / (2.0 * h)))
    };
    let with = |f: &dyn Fn(&mut RowState)| {
        let mut q = *r;
        f(&mut q);
        q
    };
    let hz = (1e-4 * r.fz).max(1e-3);
    let col = |q1: RowState, q0: RowState, h: f64| -> Option<[f64; 3]> {
        let a = diff(m.forces(&s.lo, &q1), m.forces(&s.lo, &q0), h)?;
        let b = diff(m.forces(&s.hi, &q1), m.forces(&s.hi, &q0), h)?;
        Some(std::array::from_fn(|k| 0.5 * (a[k] + b[k])))
    };
    let mut cols = [[0.0; 3]; K + 3];
    let ok = (|| {
        cols[0] = diff(m.forces(&s.hi, r), m.forces(&s.lo, r), H_MU)?;
        for (j, [lo, hi]) in s.cal.iter().enumerate() {
            cols[1 + j] = diff(m.forces(hi, r), m.forces(lo, r), H_CAL[j])?;
        }
        cols[K] = col(
            with(&|q| q.alpha += H_ALPHA),
            with(&|q| q.alpha -= H_ALPHA),
            H_ALPHA,
        )?;
        cols[K + 1] = col(
            with(&|q| q.kappa += H_KAPPA),
            with(&|q| q.kappa -= H_KAPPA),
            H_KAPPA,
        )?;
        cols[K + 2] = col(with(&|q| q.fz += hz), with(&|q| q.fz -= hz), hz)?;
        Some(())
    })();
    if ok.is_none() {
        return zero;
    }
    let dot = |a: &[f64; 3], b: &[f64; 3]| (0..3).map(|k| a[k] * b[k] / (sd[k] * sd[k])).sum();
    // The nuisance block (α', κ', Fz; the measured Fz on its diagonal) with a vanishing ridge:
    // a nuisance the measurements do not see (a zero column, e.g. κ' of a wheel at a limit) is
    // eliminated without inventing information.
    let mut nn = [[0.0f64; 3]; 3];
    for (a, row) in nn.iter_mut().enumerate() {
        for (b, x) in row.iter_mut().enumerate() {
            *x = dot(&cols[K + a], &cols[K + b]);
        }
    }
    nn[2][2] += 1.0 / (sf * sf);
    if m.kappa_measured {
        nn[1][1] += 1.0 / sens.sigma_kappa.max(1e-9).powi(2);
    }
    let scale = (0..3).map(|k| nn[k][k]).fold(0.0, f64::max).max(1e-300);
    for (k, row) in nn.iter_mut().enumerate() {
        row[k] += 1e-12 * scale;
    }
    // Iₖₖ − Iₖₙ·Iₙₙ⁻¹·Iₙₖ.
    let mut x = [[0.0f64; 3]; K];
    for (i, xi) in x.iter_mut().enumerate() {
        let ni = [0, 1, 2].map(|a| dot(&cols[i], &cols[K + a]));
        match solve(nn, ni) {
            Some(v) => *xi = v,
            None => return zero,
        }
    }
    let mut out = zero;
    for i in 0..K {
        for j in 0..K {
            let nj = [0, 1, 2].map(|a| dot(&cols[j], &cols[K + a]));
            out[i][j] = dot(&cols[i], &cols[j]) - (0..3).map(|a| x[i][a] * nj[a]).sum::<f64>();
        }
    }
    out
}

/// σ of μ from the information `info` on (μ, θ) gathered by [`row_information_cal`] and the
/// calibration's prior σ `prior` (the bank's `cal_sigma`: a cold start, the tyre known to its
/// envelope): √(I⁻¹)₀₀ with the prior's 1/σ² on θ's diagonal. ∞ without information on μ.
pub fn sigma_with_calibration(
    info: &[[f64; 1 + PROPERTIES]; 1 + PROPERTIES],
    prior: &[f64; PROPERTIES],
) -> f64 {
    let mut a = *info;
    for (j, s) in prior.iter().enumerate() {
        a[1 + j][1 + j] += 1.0 / (s * s).max(1e-300);
    }
    if a[0][0] <= 0.0 {
        return f64::INFINITY;
    }
    let mut e0 = [0.0; 1 + PROPERTIES];
    e0[0] = 1.0;
    match solve(a, e0) {
        Some(x) if x[0] > 0.0 && x[0].is_finite() => x[0].sqrt(),
        _ => f64::INFINITY,
    }
}

/// Length of the maximum-likelihood reference's window \[s\] unless `--ml-window` says otherwise.
pub const ML_WINDOW: f64 = 1.0;

/// One μ cell of [`WindowMl`]: the surface, the row nuisances (α', κ', Fz) found for the last
/// row, and the cost of each row still in the window.
struct Cell {
    s: Surface,
    theta: [f64; 3],
    seeded: bool,
    cost: std::collections::VecDeque<f64>,
    sum: f64,
}

/// The maximum-likelihood reference: μ over a sliding window of rows with the exact model
/// (host only, f64; about 1,000 Magic Formula evaluations per row, nothing a device can afford).
///
/// For each μ of a grid it minimises each row's weighted squared residual of (Fz, Fx, Fy, Mz)
/// over the row's own α', κ', Fz (two Gauss–Newton steps from the cell's previous row, a scan
/// of α' when a cell starts or loses the row), and sums half those minima over the window: the
/// profile negative log-likelihood of μ. The estimate is the grid's minimum. It reads neither α
/// nor κ. It shows whether the [Cramér–Rao bound](self) can be reached, not how to reach it on
/// a device.
pub struct WindowMl<'a> {
    model: &'a Model<'a>,
    cells: Vec<Cell>,
    rows: usize,
    sens: Sensors,
}

impl<'a> WindowMl<'a> {
    /// μ grid `mu_lo + k·step`, `k < n`; a window of `rows` rows.
    pub fn new(
        model: &'a Model<'a>,
        mu_lo: f64,
        step: f64,
        n: usize,
        rows: usize,
        sens: Sensors,
    ) -> WindowMl<'a> {
        WindowMl {
            model,
            cells: (0..n)
                .map(|k| Cell {
                    s: model.surface(mu_lo + step * k as f64),
                    theta: [0.0; 3],
                    seeded: false,
                    cost: std::collections::VecDeque::with_capacity(rows + 1),
                    sum: 0.0,
                })
                .collect(),
            rows: rows.max(1),
            sens,
        }
    }

    /// Takes one measured row (Fz, Fx, Fy, Mz; γ and Vx given) and returns the window's estimate.
    pub fn update(&mut self, fz: f64, fx: f64, fy: f64, mz: f64, gamma: f64, vx: f64) -> f64 {
        let sf = self.sens.sigma_rel * fz.abs().max(100.0);
        let y = Meas {
            m: [fz, fx, fy, mz],
            sd: [sf, sf, sf, self.sens.sigma_mz.max(1e-9)],
            gamma,
            vx,
        };
        for c in &mut self.cells {
            if !c.seeded {
                c.theta = seed(self.model, &c.s, &y);
                c.seeded = true;
            }
            let mut f = refine(self.model, &c.s, &mut c.theta, &y);
            // Far beyond the noise (χ² of 4 channels): the cell lost the row; scan again.
            if f > 100.0 {
                let mut th = seed(self.model, &c.s, &y);
                let g = refine(self.model, &c.s, &mut th, &y);
                if g < f {
                    (c.theta, f) = (th, g);
                }
            }
            c.cost.push_back(0.5 * f);
            c.sum += 0.5 * f;
            if c.cost.len() > self.rows {
                c.sum -= c.cost.pop_front().unwrap_or(0.0);
            }
        }
        self.cells
            .iter()
            .min_by(|a, b| a.sum.total_cmp(&b.sum))
            .map_or(f64::NAN, |c| c.s.mu)
    }
}

/// A row's measurements, their σ, and its givens.
struct Meas {
    m: [f64; 4],
    sd: [f64; 4],
    gamma: f64,
    vx: f64,
}

/// Weighted residuals of (Fz, Fx, Fy, Mz) at nuisances `th` = (α', κ', Fz).
fn residuals(m: &Model, s: &Surface, th: &[f64; 3], y: &Meas) -> Option<[f64; 4]> {
    let f = m.forces(
        s,
        &RowState {
            alpha: th[0],
            kappa: th[1],
            fz: th[2],
            gamma: y.gamma,
            vx: y.vx,
        },
    )?;
    Some([
        (y.m[0] - th[2]) / y.sd[0],
        (y.m[1] - f[0]) / y.sd[1],
        (y.m[2] - f[1]) / y.sd[2],
        (y.m[3] - f[2]) / y.sd[3],
    ])
}

fn cost(r: &[f64; 4]) -> f64 {
    r.iter().map(|v| v * v).sum()
}

/// The best α' of a scan over ±0.3 rad (κ' = 0, Fz as measured).
fn seed(m: &Model, s: &Surface, y: &Meas) -> [f64; 3] {
    let mut best = (f64::INFINITY, [0.0, 0.0, y.m[0]]);
    for k in -60..=60 {
        let th = [f64::from(k) * 0.005, 0.0, y.m[0]];
        if let Some(r) = residuals(m, s, &th, y) {
            if cost(&r) < best.0 {
                best = (cost(&r), th);
            }
        }
    }
    best.1
}

/// x with a·x = b, by Gaussian elimination with partial pivoting; `None` if a is singular.
pub fn solve<const N: usize>(mut a: [[f64; N]; N], mut b: [f64; N]) -> Option<[f64; N]> {
    for c in 0..N {
        let p = (c..N).max_by(|&x, &y| a[x][c].abs().total_cmp(&a[y][c].abs()))?;
        if a[p][c] == 0.0 || !a[p][c].is_finite() {
            return None;
        }
        a.swap(c, p);
        b.swap(c, p);
        let (pivot, bc) = (a[c], b[c]);
        for (row, bi) in a.iter_mut().zip(b.iter_mut()).skip(c + 1) {
            let f = row[c] / pivot[c];
            for (x, &y) in row.iter_mut().zip(&pivot).skip(c) {
                *x -= f * y;
            }
            *bi -= f * bc;
        }
    }
    let mut x = [0.0f64; N];
    for c in (0..N).rev() {
        x[c] = (b[c] - (c + 1..N).map(|k| a[c][k] * x[k]).sum::<f64>()) / a[c][c];
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}

/// Two Gauss–Newton steps on `th` (forward differences; a step is kept only if it lowers the
/// cost; slip steps capped at 0.05). Returns the cost reached.
fn refine(m: &Model, s: &Surface, th: &mut [f64; 3], y: &Meas) -> f64 {
    const H: [f64; 3] = [1e-6, 1e-6, 1e-2];
    let Some(mut r) = residuals(m, s, th, y) else {
        return f64::INFINITY;
    };
    let mut f0 = cost(&r);
    for _ in 0..2 {
        let mut j = [[0.0f64; 3]; 4];
        for k in 0..3 {
            let mut t = *th;
            t[k] += H[k];
            let Some(rp) = residuals(m, s, &t, y) else {
                return f0;
            };
            for i in 0..4 {
                j[i][k] = (rp[i] - r[i]) / H[k];
            }
        }
        // (JᵀJ)·d = −Jᵀr, with a vanishing ridge for a nuisance the row does not see.
        let mut a = [[0.0f64; 3]; 3];
        let mut g = [0.0f64; 3];
        for p in 0..3 {
            for q in 0..3 {
                a[p][q] = (0..4).map(|i| j[i][p] * j[i][q]).sum();
            }
            a[p][p] = a[p][p] * (1.0 + 1e-9) + 1e-12;
            g[p] = -(0..4).map(|i| j[i][p] * r[i]).sum::<f64>();
        }
        let Some(d) = solve(a, g) else { break };
        let t = [
            th[0] + d[0].clamp(-0.05, 0.05),
            th[1] + d[1].clamp(-0.05, 0.05),
            th[2] + d[2],
        ];
        match residuals(m, s, &t, y) {
            Some(rn) if cost(&rn) < f0 => {
                (*th, r, f0) = (t, rn, cost(&rn));
            }
            _ => break,
        }
    }
    f0
}

/// One wheel on one surface of a case: what the bound and the bank say.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WheelBound {
    /// True μ of the surface.
    pub mu: f64,
    /// σ_CRB from the surface's rows up to the one where the utilisation first reaches 0.5.
    pub sigma_at_util: f64,
    /// σ_CRB from the surface's rows up to 150 ms later (the target's deadline).
    pub sigma_at_deadline: f64,
    /// The same with the tyre's calibrated properties unknown too (each with the bank's prior
    /// σ, a cold start: [`sigma_with_calibration`]), learnt from the same rows.
    pub sigma_cal_at_deadline: f64,
    /// The bank's latency from utilisation 0.5 to staying within ±0.1 \[s\], if it
    /// gets there.
    pub bank_latency: Option<f64>,
    /// Whether the maximum-likelihood reference ([`WindowMl`]) is within ±0.1 at the deadline
    /// and through the 0.3 s after it (or to the surface's end), when run.
    pub ml_within: Option<bool>,
}

impl WheelBound {
    /// Whether a 95 % interval of an unbiased estimator can lie within ±0.1 at the deadline.
    pub fn decidable(&self) -> bool {
        1.96 * self.sigma_at_deadline <= 0.1
    }

    /// The same with the calibrated properties unknown.
    pub fn decidable_cal(&self) -> bool {
        1.96 * self.sigma_cal_at_deadline <= 0.1
    }
}

/// The target's deadline after the utilisation first reaches 0.5 \[s\].
pub const DEADLINE: f64 = 0.150;

/// Information on μ from `rows` on surfaces `surf`: with the tyre exact (a number) and on
/// (μ, θ) with the calibrated properties unknown ([`row_information_cal`]).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Gathered {
    /// Σ of [`row_information`].
    pub exact: f64,
    /// Σ of [`row_information_cal`].
    pub cal: [[f64; 1 + PROPERTIES]; 1 + PROPERTIES],
}

impl Gathered {
    /// Adds row `r`'s information.
    pub fn add(&mut self, m: &Model, surf: &Surfaces, r: &RowState, sens: &Sensors) {
        let ic = row_information_cal(m, surf, r, sens);
        self.exact += ic[0][0];
        for (s, x) in self.cal.iter_mut().zip(ic.iter()) {
            for (s, x) in s.iter_mut().zip(x.iter()) {
                *s += x;
            }
        }
    }

    /// σ_CRB with the tyre exact.
    pub fn sigma(&self) -> f64 {
        if self.exact > 0.0 {
            1.0 / self.exact.sqrt()
        } else {
            f64::INFINITY
        }
    }

    /// σ_CRB with the calibrated properties unknown, each with the bank's prior σ.
    pub fn sigma_cal(&self) -> f64 {
        sigma_with_calibration(&self.cal, &gough::mu::Config::<f64>::default().cal_sigma)
    }
}

/// Bounds of wheel `w` of a simulated case (`tr`: its rows as [`bench::measure`] made them),
/// one per surface on which its utilisation reaches 0.5. `bank_latency(a, b)` gives the bank's
/// estimator's latency on the surface's rows `a..b`; `ml` (a window length \[s\]) also runs
/// [`WindowMl`] there.
pub fn wheel_bounds(
    m: &Model,
    log: &Log,
    w: usize,
    sens: &Sensors,
    tr: &WheelTrace,
    bank_latency: &dyn Fn(usize, usize) -> Option<f64>,
    ml: Option<f64>,
) -> Vec<WheelBound> {
    let util = &tr.util;
    let recs = &log.records;
    let lag = (sens.delay / log.dt).round() as usize;
    // The rows' true μ (undelayed, as the bench's metrics take it).
    let mu = &tr.mu_true;
    let mut out = Vec::new();
    for (a, b) in bench::segments(mu) {
        if let Some(i5) = (a..b).find(|&i| util[i] >= 0.5) {
            let t_dead = recs[i5].t + DEADLINE;
            let end = (i5..b).take_while(|&i| recs[i].t <= t_dead + 1e-9).last();
            let surf = Surfaces::new(m, mu[a]);
            let mut sum = Gathered::default();
            let mut at_util = Gathered::default();
            for i in a..=end.unwrap_or(i5) {
                // Row i carries the state of record i − lag (the sensors' delay).
                let src = &recs[i.saturating_sub(lag)].wheels[w];
                // A row from before the surface began measured the previous surface.
                if i.saturating_sub(lag) >= a {
                    let row = RowState::of_wheel(src);
                    sum.add(m, &surf, &row, sens);
                }
                if i == i5 {
                    at_util = sum;
                }
            }
            let reached = end.is_some_and(|e| recs[e].t + 1e-9 >= t_dead);
            out.push(WheelBound {
                mu: mu[a],
                sigma_at_util: at_util.sigma(),
                sigma_at_deadline: if reached {
                    sum.sigma()
                } else {
                    f64::INFINITY // the surface ends before the deadline
                },
                sigma_cal_at_deadline: if reached {
                    sum.sigma_cal()
                } else {
                    f64::INFINITY
                },
                bank_latency: bank_latency(a, b),
                ml_within: ml
                    .zip(end.filter(|&e| recs[e].t + 1e-9 >= t_dead))
                    .map(|(window, e)| ml_within(m, tr, sens, log.dt, window, e, a + lag..b)),
            });
        }
    }
    out
}

/// The bounds of one wheel of a wheel case ([`trace_bounds`]): μ and σ_CRB with the tyre exact
/// and with its calibration unknown, per surface and per step of the surface.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct TraceBounds {
    /// One per surface on which the utilisation reaches 0.5: `[μ, σ, σ_cal]` at the
    /// [`DEADLINE`] after it first does (∞ where the surface ends before it).
    pub surfaces: Vec<[f64; 3]>,
    /// One per step of the surface (every surface but the first): `[μ, σ, σ_cal]` from the rows
    /// of the new surface up to [`TARGET_STEP`] after its first row (∞ where it ends before),
    /// whatever the utilisation — what the step target asks of the bank.
    pub steps: Vec<[f64; 3]>,
}

/// The bounds of one wheel of a wheel case (`super::scenario`: its trace with the transient
/// slips), per surface on which the utilisation reaches 0.5 and per step of the surface: μ,
/// and σ_CRB at the deadline with the tyre exact and with the calibration unknown — the
/// calibration learnt from every row before the deadline, the earlier surfaces' included (their
/// μ eliminated). The sensors are the scenario's (`Noise`, no delay; κ as the model says).
pub fn trace_bounds(m: &Model, tr: &super::scenario::Trace, sens: &Sensors) -> TraceBounds {
    let mut out = TraceBounds::default();
    // What the earlier surfaces' rows told of the tyre (their μ eliminated): the calibration is
    // the tyre's, carried across a change of road.
    let mut before = [[0.0; PROPERTIES]; PROPERTIES];
    for (a, b) in bench::segments(&tr.mu) {
        let surf = Surfaces::new(m, tr.mu[a]);
        let row = |i: usize| RowState::of_trace(tr, i);
        let t_dead = (a..b)
            .find(|&i| tr.util[i] >= 0.5)
            .map(|i5| tr.t[i5] + DEADLINE);
        let mut g = Gathered::default();
        for (i, e) in before.iter().enumerate() {
            for (j, x) in e.iter().enumerate() {
                g.cal[1 + i][1 + j] += x;
            }
        }
        // A step's deadline: TARGET_STEP after the new surface's first row.
        let t_step = (a > 0).then(|| tr.t[a] + TARGET_STEP);
        let (mut at_dead, mut at_step): (Option<Gathered>, Option<Gathered>) = (None, None);
        for i in a..b {
            for (t, at) in [(t_dead, &mut at_dead), (t_step, &mut at_step)] {
                if t.is_some_and(|td| at.is_none() && tr.t[i] > td + 1e-9) {
                    *at = Some(g);
                }
            }
            g.add(m, &surf, &row(i), sens);
        }
        // A surface that ends before the deadline decides nothing by it.
        let bound = |td: f64, at: Option<Gathered>| {
            let reached = at.is_some() || tr.t[b - 1] + 1e-9 >= td;
            let d = at.unwrap_or(g);
            if reached {
                [tr.mu[a], d.sigma(), d.sigma_cal()]
            } else {
                [tr.mu[a], f64::INFINITY, f64::INFINITY]
            }
        };
        if let Some(td) = t_dead {
            out.surfaces.push(bound(td, at_dead));
        }
        if let Some(td) = t_step {
            out.steps.push(bound(td, at_step));
        }
        // The whole surface's information on θ, its μ eliminated, for the surfaces after it.
        let c = &g.cal;
        if c[0][0] > 0.0 {
            for i in 0..PROPERTIES {
                for j in 0..PROPERTIES {
                    before[i][j] = c[1 + i][1 + j] - c[1 + i][0] * c[0][1 + j] / c[0][0];
                }
            }
        } else {
            for i in 0..PROPERTIES {
                for j in 0..PROPERTIES {
                    before[i][j] = c[1 + i][1 + j];
                }
            }
        }
    }
    out
}

/// Runs [`WindowMl`] with a `window` \[s\] over wheel trace `tr` up to row `dead` (its window
/// starting no earlier than `surface.start`, the surface's first row measured on it) and on
/// through 0.3 s or to `surface.end`; whether it stays within ±0.1 of the truth from `dead` on.
fn ml_within(
    m: &Model,
    tr: &WheelTrace,
    sens: &Sensors,
    dt: f64,
    window: f64,
    dead: usize,
    surface: std::ops::Range<usize>,
) -> bool {
    let (first, end) = (surface.start, surface.end);
    let rows = (window / dt).round() as usize;
    let start = first.max((dead + 1).saturating_sub(rows)).min(dead);
    let stop = end.min(dead + 1 + (0.3 / dt).round() as usize);
    let mut est = WindowMl::new(m, 0.05, 0.01, 126, rows, *sens);
    for i in start..stop {
        let r = &tr.rows[i];
        let v = |x: Option<f64>| x.unwrap_or(f64::NAN);
        let mu = est.update(r.fz, v(r.fx), r.fy, r.mz, r.gamma.unwrap_or(0.0), v(r.vx));
        if i >= dead && (mu - tr.mu_true[i]).abs() > 0.1 {
            return false;
        }
    }
    true
}

/// Runs `gough mu bound --wheel-cases`: the wheel cases at 200 Hz (every tyre of `tyres`, every
/// scenario, the tyre exact and drawn from the envelope under `seed`), each wheel-surface's
/// bound at the deadline with the tyre exact and with its calibration unknown, beside the
/// bank's wheel-surfaces within ±0.1 within 150 ms (cold start, as `gough mu bench` runs
/// them); per tyre and level. Writes `bound_wheel.md` into `out` and prints it.
pub fn run_wheel_cases(
    tyres: &std::path::Path,
    seed: u64,
    out: &std::path::Path,
) -> Result<(), String> {
    use super::bench::wheel::{self, Level};
    use super::scenario::{self, Noise};
    let (tyres, _) = wheel::tyres(tyres)?;
    let scenarios = wheel::scenarios();
    std::fs::create_dir_all(out).map_err(|e| format!("{}: {e}", out.display()))?;
    const COLUMNS: &str = "| wheel-surfaces | ±0.1 decidable in 150 ms, tyre exact | the same, calibration unknown | the bank within ±0.1 in 150 ms | steps | decidable in 200 ms, tyre exact | calibration unknown | the bank in 200 ms |\n";
    let line = |name: &str, level: &str, n: &[usize; 8]| {
        let cells: Vec<String> = n.iter().map(|x| x.to_string()).collect();
        format!("| {name} | {level} | {} |\n", cells.join(" | "))
    };
    let mut md = format!("| tyre | level {COLUMNS}|---|---|---|---|---|---|---|---|---|---|\n");
    let levels = [Level::Exact, Level::Envelope];
    // Per level: wheel-surfaces, decidable exact, decidable with the calibration unknown, the
    // bank's; steps, decidable in 200 ms exact, the same with the calibration unknown, the bank's.
    let mut total = [[0usize; 8]; 2];
    // By scenario and level, over the tyres.
    let mut by_sc = vec![[[0usize; 8]; 2]; scenarios.len()];
    for (ti, tyre) in tyres.iter().enumerate() {
        for (li, &level) in levels.iter().enumerate() {
            let mut n = [0usize; 8];
            for (si, sc) in scenarios.iter().enumerate() {
                let d = wheel::perturbation(seed, tyre, sc.name, level);
                let truth = wheel::truth(tyre, &d, level);
                let mu0 = scenario::mu_y0(&truth)?;
                let model = Model::unmounted(&truth, mu0);
                let noise = Noise::default();
                let sens = noise.sensors(&truth);
                let mut k = [0usize; 8];
                for s in &sc.wheels {
                    let tr = scenario::simulate(&truth, s, wheel::RATE, &noise, seed)?;
                    let tb = trace_bounds(&model, &tr, &sens);
                    for (o, list) in [(0, &tb.surfaces), (4, &tb.steps)] {
                        for [_, sg, sc] in list {
                            k[o] += 1;
                            k[o + 1] += usize::from(1.96 * sg <= 0.1);
                            k[o + 2] += usize::from(1.96 * sc <= 0.1);
                        }
                    }
                }
                let case = wheel::WheelCase {
                    tyre: ti,
                    scenario: si,
                    level,
                    rate: wheel::RATE,
                };
                let r = wheel::run_case(&case, &tyres, &scenarios, seed, false, &wheel::estimator)?;
                k[3] = r.cold.metrics.ws_within;
                k[7] = r.cold.steps.iter().filter(|s| s.in_time()).count();
                for ((n, b), k) in n.iter_mut().zip(by_sc[si][li].iter_mut()).zip(k) {
                    *n += k;
                    *b += k;
                }
            }
            for (t, x) in total[li].iter_mut().zip(n) {
                *t += x;
            }
            md += &line(&tyre.file, level.name(), &n);
            eprintln!("{} {}: done", tyre.file, level.name());
        }
    }
    for (li, level) in levels.iter().enumerate() {
        md += &line(
            &format!("all {} tyres", tyres.len()),
            level.name(),
            &total[li],
        );
    }
    md += &format!("\n| scenario | level {COLUMNS}|---|---|---|---|---|---|---|---|---|---|\n");
    for (sc, b) in scenarios.iter().zip(&by_sc) {
        for (li, level) in levels.iter().enumerate() {
            md += &line(sc.name, level.name(), &b[li]);
        }
    }
    md += &format!(
        "\nσ_CRB of μ from each wheel-surface's rows up to 150 ms after its utilisation first reaches 0.5 (decidable: 1.96·σ ≤ 0.1), the tyre's model the simulated tyre's own; \"calibration unknown\": its trail, trail shape, trail shift and Kxκ unknown too, each with the bank's prior σ, learnt from every row before the deadline, the earlier surfaces' included (a cold start). A step: σ_CRB from the new surface's rows up to 200 ms after its first, whatever the utilisation; the bank's step read in time as `gough mu bench` counts it (identifiable within ±0.1 by then and staying). Seed {seed}, 200 Hz, the scenarios' noise (κ measured, taken as κ′ plus its noise).\n"
    );
    std::fs::write(out.join("bound_wheel.md"), &md).map_err(|e| e.to_string())?;
    print!("{md}");
    eprintln!("-> {}/bound_wheel.md", out.display());
    Ok(())
}

/// Runs `gough mu bound`: writes `bound.md` and `bound.csv` into `a.bench.out` and prints the
/// table.
pub fn run(a: &Config) -> Result<(), String> {
    let ml = a.ml;
    if let Some(w) = ml.filter(|w| !(w.is_finite() && *w > 0.0 && *w <= 10.0)) {
        return Err(format!("--ml-window {w}: not a window length in (0, 10] s"));
    }
    let b = &a.bench;
    // `p`: the simulated tyre, the bound's model; `est`: the bank's (`model_error`).
    let p = crate::tyre::load(&b.tir)?.params;
    let est = bench::model_with_error(&p, &b.model_error)?;
    // The bank as `gough mu bench` runs it.
    let setup = Setup::car(b.preview);
    let sens = b.sensors;
    let models = [Model::new(&p, Side::Left)?, Model::new(&p, Side::Right)?];
    let mut cases = bench::suite_shifted(b.mu_shift);
    if let Some(n) = b.cases {
        cases.truncate(n);
    }
    std::fs::create_dir_all(&b.out).map_err(|e| format!("{}: {e}", b.out.display()))?;
    let mut md = String::new();
    let _ = writeln!(
        md,
        "| manoeuvre | road | wheel | μ | σ_CRB at util 0.5 | σ_CRB 150 ms later | ±0.1 decidable by then | the same, tyre calibration unknown | decidable | bank latency [s] | ML within ±0.1 from then |"
    );
    let _ = writeln!(md, "|---|---|---|---|---|---|---|---|---|---|---|");
    let mut csv = String::from(
        "manoeuvre,road,wheel,mu,sigma_at_util,sigma_at_deadline,decidable,sigma_cal_at_deadline,decidable_cal,bank_latency_s,ml_within\n",
    );
    let names = ["fl", "fr", "rl", "rr"];
    let (mut n_wheels, mut n_dec, mut n_bank, mut n_ml) = (0, 0, 0, 0);
    let mut n_dec_cal = 0;
    let (mut n_cases, mut case_dec, mut case_bank) = (0, 0, 0);
    for c in &cases {
        let log = bench::simulate_case(&p, c)?;
        let mut dec_lat: Vec<f64> = Vec::new();
        let mut bank_lat: Vec<f64> = Vec::new();
        let mut any = false;
        let traces: Vec<WheelTrace> = (0..4)
            .map(|w| bench::measure(&log, w, &sens, b.seed))
            .collect();
        let ests = bench::run_method(Method::Bank, &est, &setup, &traces)?;
        for (w, ((name, tr), est)) in names.iter().zip(&traces).zip(&ests).enumerate() {
            let lat = |s: usize, e: usize| bench::segment_latency(tr, est, s, e);
            let model = &models[usize::from(!w.is_multiple_of(2))];
            for b in wheel_bounds(model, &log, w, &sens, tr, &lat, ml) {
                any = true;
                n_wheels += 1;
                n_dec += usize::from(b.decidable());
                n_dec_cal += usize::from(b.decidable_cal());
                let g_ok = b.bank_latency.is_some_and(|l| l <= DEADLINE);
                n_bank += usize::from(g_ok);
                n_ml += usize::from(b.ml_within == Some(true));
                let ml_cell = |yes: &str, no: &str| match b.ml_within {
                    Some(true) => yes.to_string(),
                    Some(false) => no.to_string(),
                    None => String::new(),
                };
                if b.decidable() {
                    dec_lat.push(0.0);
                }
                if let Some(l) = b.bank_latency {
                    bank_lat.push(l);
                }
                let f = |s: f64| {
                    if s.is_finite() {
                        format!("{s:.4}")
                    } else {
                        "∞".into()
                    }
                };
                let gl = b.bank_latency.map_or("–".into(), |l| format!("{l:.3}"));
                let _ = writeln!(
                    md,
                    "| {} | {} | {name} | {:.2} | {} | {} | {} | {} | {} | {gl} | {} |",
                    c.manoeuvre,
                    c.road,
                    b.mu,
                    f(b.sigma_at_util),
                    f(b.sigma_at_deadline),
                    if b.decidable() { "yes" } else { "no" },
                    f(b.sigma_cal_at_deadline),
                    if b.decidable_cal() { "yes" } else { "no" },
                    if ml.is_some() {
                        ml_cell("yes", "no")
                    } else {
                        "–".into()
                    },
                );
                let _ = writeln!(
                    csv,
                    "{},{},{name},{:.3},{},{},{},{},{},{},{}",
                    c.manoeuvre,
                    bench::csv_field(&c.road),
                    b.mu,
                    b.sigma_at_util,
                    b.sigma_at_deadline,
                    b.decidable(),
                    b.sigma_cal_at_deadline,
                    b.decidable_cal(),
                    b.bank_latency.map_or(String::new(), |l| format!("{l:.4}")),
                    ml_cell("true", "false"),
                );
            }
        }
        if any {
            n_cases += 1;
            case_dec += usize::from(!dec_lat.is_empty());
            case_bank += usize::from(bench::median(bank_lat).is_some_and(|l| l <= DEADLINE));
        }
        eprintln!("{} on {}: done", c.manoeuvre, c.road);
    }
    let _ = writeln!(
        md,
        "\nWheel-surfaces reaching utilisation 0.5: {n_wheels}. ±0.1 decidable within 150 ms by an unbiased estimator with the exact model (1.96·σ_CRB ≤ 0.1): {n_dec}; with the tyre's calibrated properties unknown too (trail, its shape and shift, Kxκ, each with the bank's prior σ, learnt from the same rows): {n_dec_cal}. The bank within ±0.1 within 150 ms: {n_bank}.{}\nCases with a wheel reaching utilisation 0.5: {n_cases}; with at least one wheel decidable: {case_dec}; the bank's median latency ≤ 150 ms (the bench's criterion): {case_bank}.",
        if let Some(w) = ml {
            format!(" The maximum-likelihood reference ({w} s window) within ±0.1 from 150 ms on (through 0.3 s): {n_ml}.")
        } else {
            String::new()
        }
    );
    std::fs::write(b.out.join("bound.md"), &md).map_err(|e| e.to_string())?;
    std::fs::write(b.out.join("bound.csv"), &csv).map_err(|e| e.to_string())?;
    print!("{md}");
    eprintln!("-> {}/bound.md, bound.csv", b.out.display());
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tyre() -> Params<f64> {
        crate::tyre::load(std::path::Path::new(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../host-tests/data/tyres/MagicFormula61_Parameters.tir"
        )))
        .unwrap()
        .params
    }

    #[test]
    fn the_calibration_unknown_widens_the_bound_and_a_sweep_narrows_it() {
        let p = tyre();
        let m = Model::new(&p, Side::Left).unwrap();
        let sens = Sensors::default();
        let surf = Surfaces::new(&m, 0.8);
        let prior = gough::mu::Config::<f64>::default().cal_sigma;
        let row = |alpha: f64| RowState {
            alpha,
            kappa: 0.0,
            fz: p.fnomin,
            gamma: 0.0,
            vx: 20.0,
        };
        let gather = |alphas: &[f64]| {
            let mut exact = 0.0;
            let mut cal = [[0.0; 1 + PROPERTIES]; 1 + PROPERTIES];
            for &a in alphas {
                for _ in 0..30 {
                    exact += row_information(&m, &surf, &row(a), &sens);
                    let i = row_information_cal(&m, &surf, &row(a), &sens);
                    for (c, x) in cal.iter_mut().zip(i.iter()) {
                        for (c, x) in c.iter_mut().zip(x.iter()) {
                            *c += x;
                        }
                    }
                }
            }
            (1.0 / exact.sqrt(), cal)
        };
        let (s_exact, cal) = gather(&[0.04]);
        let known = sigma_with_calibration(&cal, &[1e-9; PROPERTIES]);
        assert!(
            (known - s_exact).abs() < 1e-3 * s_exact,
            "{known} {s_exact}"
        );
        let steady = sigma_with_calibration(&cal, &prior);
        assert!(steady > 2.0 * s_exact, "{steady} {s_exact}");
        let (_, swept) = gather(&[0.01, 0.02, 0.03, 0.04, 0.05, 0.06]);
        let sweep = sigma_with_calibration(&swept, &prior);
        assert!(sweep < 0.5 * steady, "{sweep} {steady}");
    }

    /// The wheel cases' bound: one entry per surface the utilisation reaches 0.5 on; the
    /// calibration unknown never narrows it; a slalom on 0.6 decides μ either way; steady
    /// cornering at utilisation 0.65 on 1.0 only with the tyre known (a steady point on a
    /// grippy road tells the trail from the road no better than the calibration's prior), and
    /// after the step to 0.3 either way (near that road's limit the force says it).
    #[test]
    fn the_wheel_cases_bound_tells_a_sweep_from_a_steady_point() {
        use crate::mu::scenario::{self, Manoeuvre, Noise, Scenario};
        let p = tyre();
        let mu0 = scenario::mu_y0(&p).unwrap();
        let m = Model::unmounted(&p, mu0);
        let noise = Noise::default();
        let sens = noise.sensors(&p);
        let run = |manoeuvre, mu: [f64; 2], step, duration| {
            let sc = Scenario {
                manoeuvre,
                mu,
                step,
                duration,
            };
            let tr = scenario::simulate(&p, &sc, 200.0, &noise, 1).unwrap();
            trace_bounds(&m, &tr, &sens)
        };
        let slalom = run(
            Manoeuvre::Slalom {
                amplitude: 1.3,
                freq: 0.5,
            },
            [0.6, 0.6],
            None,
            3.0,
        );
        assert!(slalom.steps.is_empty());
        let slalom = slalom.surfaces;
        assert_eq!(slalom.len(), 1);
        let [mu, s, sc] = slalom[0];
        assert_eq!(mu, 0.6);
        assert!(sc >= s && 1.96 * sc <= 0.1, "{s} {sc}");
        let steady = run(
            Manoeuvre::SteadyCornering { util: 0.65 },
            [1.0, 0.3],
            Some(2.0),
            4.0,
        );
        // The step's own bound, 200 ms after it: near the new road's limit, decided either way.
        assert_eq!(steady.steps.len(), 1, "{steady:?}");
        let [mu, s, sc] = steady.steps[0];
        assert_eq!(mu, 0.3);
        assert!(sc >= s && 1.96 * sc <= 0.1, "{s} {sc}");
        let steady = steady.surfaces;
        assert_eq!(steady.len(), 2, "{steady:?}");
        let [mu, s, sc] = steady[0];
        assert_eq!(mu, 1.0);
        assert!(1.96 * s <= 0.1 && 1.96 * sc > 0.1, "{s} {sc}");
        let [mu, s, sc] = steady[1];
        assert_eq!(mu, 0.3);
        assert!(sc >= s && 1.96 * sc <= 0.1, "{s} {sc}");
    }

    /// Where a step down in steady cornering is decided (docs/mu_bound.md, "Steps"): MF 6.2, the
    /// wheel cases' cornering 1.0 → 0.3 on the file (seed 1, 200 Hz). With the calibration
    /// unknown the rows of the 200 ms after the step decide the new μ, the new steady point
    /// alone (40 rows like the one 100 ms after the step) does not: the information is in the
    /// transient, the tyre sliding at the new road's limit. Figures print with `--nocapture`.
    #[test]
    fn a_step_down_is_decided_by_the_transient_after_it() {
        use crate::mu::bench::wheel;
        use crate::mu::scenario::{self, Noise};
        let p = crate::tyre::load(std::path::Path::new(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../host-tests/data/tyres/MagicFormula62_Parameters.tir"
        )))
        .unwrap()
        .params;
        let sc = wheel::scenarios()
            .into_iter()
            .find(|s| s.name == "cornering 1.0→0.3")
            .unwrap();
        let noise = Noise::default();
        let sens = noise.sensors(&p);
        let m = Model::unmounted(&p, scenario::mu_y0(&p).unwrap());
        let tr = scenario::simulate(&p, &sc.wheels[0], wheel::RATE, &noise, 1).unwrap();
        let a = (1..tr.mu.len())
            .find(|&i| tr.mu[i] != tr.mu[i - 1])
            .unwrap();
        let t0 = tr.t[a];
        let surf = Surfaces::new(&m, tr.mu[a]);
        let row = |i: usize| RowState::of_trace(&tr, i);
        let window = |from: f64| {
            let mut g = Gathered::default();
            for i in (a..tr.t.len()).filter(|&i| tr.t[i] >= t0 + from - 1e-9) {
                if tr.t[i] > t0 + TARGET_STEP + 1e-9 {
                    break;
                }
                g.add(&m, &surf, &row(i), &sens);
            }
            g
        };
        let mut last = 0.0;
        for from in [0.0, 0.03, 0.05, 0.07, 0.1] {
            let g = window(from);
            println!(
                "rows from {:.0} ms to 200 ms after the step: σ {:.4}, calibration unknown {:.4}",
                from * 1e3,
                g.sigma(),
                g.sigma_cal()
            );
            assert!(g.sigma_cal() >= last, "fewer rows, no smaller σ");
            last = g.sigma_cal();
        }
        let full = window(0.0);
        let i1 = (a..tr.t.len())
            .find(|&i| tr.t[i] >= t0 + 0.1 - 1e-9)
            .unwrap();
        let mut steady = Gathered::default();
        for _ in 0..40 {
            steady.add(&m, &surf, &row(i1), &sens);
        }
        println!(
            "40 rows of the steady point: σ {:.4}, calibration unknown {:.4}",
            steady.sigma(),
            steady.sigma_cal()
        );
        assert!(1.96 * full.sigma_cal() <= 0.1, "{}", full.sigma_cal());
        assert!(1.96 * steady.sigma_cal() > 0.1, "{}", steady.sigma_cal());
    }

    /// The bound is what it claims: at one operating point, the spread of the exact
    /// maximum-likelihood estimate of μ from one noisy row (solved for μ, α', κ', Fz) matches
    /// σ_CRB = 1/√I within Monte-Carlo error. Noise is scaled down so that the linearisation
    /// the bound rests on holds.
    #[test]
    fn one_row_bound_matches_monte_carlo_spread() {
        let p = tyre();
        let m = Model::new(&p, Side::Left).unwrap();
        let sens = Sensors {
            sigma_mz: 0.2,
            sigma_rel: 0.001,
            delay: 0.0,
            ..Sensors::default()
        };
        let mu = 0.6;
        let truth = RowState {
            alpha: 0.05,
            kappa: -0.02,
            fz: 4000.0,
            gamma: 0.0,
            vx: 20.0,
        };
        let surf = Surfaces::new(&m, mu);
        let info = row_information(&m, &surf, &truth, &sens);
        assert!(info > 0.0);
        let sigma = 1.0 / info.sqrt();
        let y0 = m.forces(&m.surface(mu), &truth).unwrap();
        // 4 equations (Fz, Fx, Fy, Mz), 4 unknowns: ML = the exact solution, by Newton.
        let solve = |meas: [f64; 4]| -> Option<f64> {
            let mut th = [mu, truth.alpha, truth.kappa, truth.fz];
            for _ in 0..30 {
                let st = |t: &[f64; 4]| RowState {
                    alpha: t[1],
                    kappa: t[2],
                    fz: t[3],
                    ..truth
                };
                let f = |t: &[f64; 4]| -> Option<[f64; 4]> {
                    let y = m.forces(&m.surface(t[0]), &st(t))?;
                    Some([t[3], y[0], y[1], y[2]])
                };
                let y = f(&th)?;
                let r: Vec<f64> = (0..4).map(|k| meas[k] - y[k]).collect();
                let hs = [1e-6, 1e-7, 1e-7, 1e-2];
                let mut j = [[0.0f64; 4]; 4];
                for c in 0..4 {
                    let mut t = th;
                    t[c] += hs[c];
                    let yp = f(&t)?;
                    for k in 0..4 {
                        j[k][c] = (yp[k] - y[k]) / hs[c];
                    }
                }
                let d = solve(j, [r[0], r[1], r[2], r[3]])?;
                for k in 0..4 {
                    th[k] += d[k];
                }
                if d[0].abs() < 1e-12 {
                    break;
                }
            }
            Some(th[0])
        };
        let mut noise = crate::rng::Rng::new(0x9E37_79B9_7F4A_7C15);
        let mut gauss = || noise.normal();
        let sf = sens.sigma_rel * truth.fz;
        let n = 400;
        let mut est = Vec::with_capacity(n);
        for _ in 0..n {
            let meas = [
                truth.fz + sf * gauss(),
                y0[0] + sf * gauss(),
                y0[1] + sf * gauss(),
                y0[2] + sens.sigma_mz * gauss(),
            ];
            est.push(solve(meas).unwrap());
        }
        let mean = est.iter().sum::<f64>() / n as f64;
        let sd = (est.iter().map(|e| (e - mean).powi(2)).sum::<f64>() / (n - 1) as f64).sqrt();
        // The sample sd of 400 normal draws is within ±10 % of σ with probability > 0.99.
        assert!(
            (sd / sigma - 1.0).abs() < 0.1,
            "Monte-Carlo sd {sd:.5} against σ_CRB {sigma:.5}"
        );
        assert!((mean - mu).abs() < 4.0 * sigma / (n as f64).sqrt() + 1e-6);
    }

    /// The maximum-likelihood reference reads μ from rows it is not told the slips of: 300
    /// rows (0.3 s at 1 kHz) of the model's own forces on μ 0.6 at 0.7·Fz0, the slip angle
    /// ramping from 1° to 2.5° (utilisation about 0.55 to 0.8), with the bench's noise. It ends
    /// within one grid step of the truth.
    #[test]
    fn window_ml_reads_mu_without_the_slips() {
        let p = tyre();
        let m = Model::new(&p, Side::Left).unwrap();
        let sens = Sensors::default();
        let s = m.surface(0.6);
        let mut ml = WindowMl::new(&m, 0.3, 0.02, 31, 300, sens);
        let mut noise = crate::rng::Rng::new(0x2545_F491_4F6C_DD1D);
        let mut gauss = || noise.normal();
        let fz = 0.7 * p.fnomin;
        let mut last = f64::NAN;
        for i in 0..300 {
            let alpha = (1.0 + 1.5 * f64::from(i) / 300.0).to_radians();
            let r = RowState {
                alpha,
                kappa: 0.0,
                fz,
                gamma: 0.0,
                vx: 20.0,
            };
            let y = m.forces(&s, &r).unwrap();
            let sf = sens.sigma_rel * fz;
            last = ml.update(
                fz + sf * gauss(),
                y[0] + sf * gauss(),
                y[1] + sf * gauss(),
                y[2] + sens.sigma_mz * gauss(),
                0.0,
                20.0,
            );
        }
        assert!((last - 0.6).abs() <= 0.02 + 1e-9, "ML reads {last}");
    }

    /// The model is the simulation's: a simulated row's forces come back exactly from its
    /// transient slips, load, camber and speed.
    #[test]
    fn model_reproduces_the_simulation() {
        let p = tyre();
        let c = bench::Case::new("sine-dwell", "mu=0.7").unwrap();
        let log = bench::simulate_case(&p, &c).unwrap();
        for w in 0..4 {
            let side = if w % 2 == 0 { Side::Left } else { Side::Right };
            let m = Model::new(&p, side).unwrap();
            let s = m.surface(0.7);
            let mut worst = 0.0f64;
            for r in log.records.iter().step_by(97) {
                let x = &r.wheels[w];
                let y = m.forces(&s, &RowState::of_wheel(x)).unwrap();
                worst = worst
                    .max((y[0] - x.fx).abs())
                    .max((y[1] - x.fy).abs())
                    .max((y[2] - x.mz).abs());
            }
            assert!(worst < 1e-6, "wheel {w}: worst difference {worst}");
        }
    }
}
