//! The model's Gough plot, tabulated once: for a few loads, the normalised lateral force
//! f = |Fy|/Fz and the effective pneumatic trail τ = −Mz/Fy along the slip angle, on the file's
//! own test surface (λμ = 1).
//!
//! Why this suffices: λμ scales the Magic Formula's peak Dy and, through By = Kyα/(Cy·Dy) and
//! Bt ∝ λKy/λμy (4.E26), (A58), its slip axis inversely, so the whole (Fy, Mz) curve is the λμ = 1
//! curve scaled radially by λμ with α scaled by 1/λμ (exactly so for the brush model, up to the
//! small horizontal/vertical shifts for the Magic Formula). The ratio τ = −Mz/Fy is therefore
//! independent of λμ and tells how far along the curve the tyre is — without the slip angle —
//! and λμ = |F|/(Fz·f) at that point. The host tests measure the error this leaves.

use crate::brush::Brush;
use crate::math::{Backend, Float};
use crate::mf::{self, Input, Options, Params};

/// Loads the table holds, as multiples of the reference load.
pub const LOAD_NODES: [f64; 7] = [0.2, 0.4, 0.6, 0.8, 1.0, 1.35, 1.8];
/// Surfaces the table holds, as λμ: the curves are nearly but not exactly radial images of each
/// other (the shifts SHy, SHt do not scale, SVy scales with the digressive λμ' of (4.E8)), so the
/// estimate is taken from the two surfaces that bracket it.
pub const LAMBDA_NODES: [f64; 4] = [0.15, 0.35, 0.65, 1.0];
/// Slip-angle nodes per load, side and surface.
pub const POINTS: usize = 20;
const NL: usize = LOAD_NODES.len();
const NS: usize = LAMBDA_NODES.len();
/// Largest tabulated slip angle at λμ = 1 \[rad\]: well past full sliding of any car tyre.
pub const ALPHA_MAX: f64 = 0.6;

/// Where the tyre model comes from.
#[derive(Debug, Clone, Copy)]
pub enum Model<'a, F> {
    /// A Magic Formula parameter set (its λμ are set to 1 for the table).
    Mf(&'a Params<F>),
    /// A brush model (its μ is the reference).
    Brush(Brush<F>),
}

/// The tabulated Gough curves: 4 surfaces × 7 loads × 2 sides × 20 points × (τ, f), about
/// 9 KB in f32. Built once per tyre and shared by the estimators of all wheels.
#[derive(Debug, Clone)]
pub struct GoughTable<F> {
    /// Loads of the nodes \[N\].
    pub fz: [F; NL],
    /// τ \[m\] per surface, load, side (0: α > 0, 1: α < 0), node; strictly decreasing over
    /// `len`.
    pub tau: [[[[F; POINTS]; 2]; NL]; NS],
    /// f = |Fy|/Fz \[-\] (absolute, on that surface) per surface, load, side, node.
    pub f: [[[[F; POINTS]; 2]; NL]; NS],
    /// Number of usable (monotone) nodes per surface, load and side.
    pub len: [[[u8; 2]; NL]; NS],
    /// Sign of Fy for α > 0 in this model (−1 for ISO-W files).
    pub fy_sign: F,
    /// μ of the table's surface: μy0 (Magic Formula: μy at Fz0, γ = 0, nominal pressure).
    pub mu0: F,
    /// μy0/μx0: the friction ellipse's aspect (1 for the isotropic brush model).
    pub mu_ratio: F,
}

/// One point inverted from the table.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Inversion<F> {
    /// f at the point \[-\].
    pub f: F,
    /// ∂f/∂τ along the table \[1/m\] (for the error propagation).
    pub df_dtau: F,
    /// Trail drop 1 − τ/τ0, 0 at the smallest tabulated slip, → 1 at full sliding.
    pub drop: F,
    /// The point was beyond the table's end (full sliding).
    pub saturated: bool,
}

fn alpha_node(k: usize) -> f64 {
    let x = (k + 1) as f64 / POINTS as f64;
    ALPHA_MAX * x * x // dense near zero, where the trail changes least
}

impl<F: Float> GoughTable<F> {
    /// Tabulates `model` at camber `gamma` \[rad\]. `None` if the model gives no usable curve
    /// (e.g. zero cornering stiffness) at some load.
    pub fn build<M: Backend<F>>(model: Model<'_, F>, gamma: F) -> Option<Self> {
        let mut src = match model {
            Model::Mf(p) => Src::Mf(p.clone()),
            Model::Brush(b) => Src::Brush(b),
        };
        src.set_lambda(F::ONE);
        let (fz_ref, mu0, mu_ratio) = match &src {
            Src::Mf(q) => {
                let (_, _, mu0, mux0) = mf_fy_mz::<F, M>(q, F::ZERO, q.fnomin, F::ZERO)?;
                if mux0 <= F::ZERO || mu0 <= F::ZERO {
                    return None;
                }
                (q.fnomin, mu0, mu0 / mux0)
            }
            Src::Brush(b) => (b.fz0, b.mu, F::ONE),
        };
        let mut t = GoughTable {
            fz: [F::ZERO; NL],
            tau: [[[[F::ZERO; POINTS]; 2]; NL]; NS],
            f: [[[[F::ZERO; POINTS]; 2]; NL]; NS],
            len: [[[0; 2]; NL]; NS],
            fy_sign: F::ZERO,
            mu0,
            mu_ratio,
        };
        let (fy_probe, _) = src.eval::<M>(F::from_f64(0.05), fz_ref, gamma)?;
        t.fy_sign = fy_probe.sign_nz();
        for (j, &ln) in LOAD_NODES.iter().enumerate() {
            *t.fz.get_mut(j)? = fz_ref * F::from_f64(ln);
        }
        for (si, &lam) in LAMBDA_NODES.iter().enumerate() {
            src.set_lambda(F::from_f64(lam));
            for j in 0..NL {
                let fz = *t.fz.get(j)?;
                for side in 0..2 {
                    // A curve with no usable monotone part (an asymmetric tyre's ply-steer side
                    // at low friction) stays empty: its points are simply not identifiable.
                    let (taus, fs, n) = curve::<F, M>(&src, fz, gamma, side, t.fy_sign, lam, mu0)
                        .unwrap_or(([F::ZERO; POINTS], [F::ZERO; POINTS], 0));
                    *t.tau.get_mut(si)?.get_mut(j)?.get_mut(side)? = taus;
                    *t.f.get_mut(si)?.get_mut(j)?.get_mut(side)? = fs;
                    *t.len.get_mut(si)?.get_mut(j)?.get_mut(side)? = n;
                }
            }
        }
        // The tyre's own surface at the nominal load must be usable on both sides.
        let nominal = LOAD_NODES.iter().position(|&x| x == 1.0)?;
        let own = t.len.get(NS - 1)?.get(nominal)?;
        if own.iter().any(|&n| n < 4) {
            return None;
        }
        Some(t)
    }

    /// τ0: the trail at the smallest usable slip of surface `si`, load `j`, side `side` \[m\].
    pub fn tau0(&self, si: usize, j: usize, side: usize) -> Option<F> {
        self.tau.get(si)?.get(j)?.get(side)?.first().copied()
    }

    /// Inverts τ → f on surface `si`, load `j`, side `side`. `None` when τ is above the usable
    /// range (the trail has not dropped: the point is not identifiable).
    pub fn invert(&self, si: usize, j: usize, side: usize, tau: F) -> Option<Inversion<F>> {
        let taus = self.tau.get(si)?.get(j)?.get(side)?;
        let fs = self.f.get(si)?.get(j)?.get(side)?;
        let len = *self.len.get(si)?.get(j)?.get(side)? as usize;
        let start = 0;
        let tau0 = *taus.get(start)?;
        if tau >= tau0 || !tau.is_finite() {
            return None;
        }
        let last = len.checked_sub(1)?;
        let (tau_end, f_end) = (*taus.get(last)?, *fs.get(last)?);
        if tau <= tau_end {
            let drop = if tau0 > F::ZERO {
                F::ONE - tau_end / tau0
            } else {
                F::ONE
            };
            return Some(Inversion {
                f: f_end,
                df_dtau: F::ZERO,
                drop,
                saturated: true,
            });
        }
        // Binary search for k with taus[k] > tau >= taus[k+1] on [start, last].
        let (mut lo, mut hi) = (start, last);
        while hi - lo > 1 {
            let mid = (lo + hi) / 2;
            if *taus.get(mid)? > tau {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let (t0, t1, f0, f1) = (*taus.get(lo)?, *taus.get(hi)?, *fs.get(lo)?, *fs.get(hi)?);
        let slope = (f1 - f0) / (t1 - t0); // t1 < t0 strictly
        let f = f0 + (tau - t0) * slope;
        let drop = if tau0 > F::ZERO {
            F::ONE - tau / tau0
        } else {
            F::ONE
        };
        Some(Inversion {
            f,
            df_dtau: slope,
            drop,
            saturated: false,
        })
    }
}

/// (Fy, Mz, μy, μx) of the Magic Formula at pure side slip, limits off, nominal pressure.
fn mf_fy_mz<F: Float, M: Backend<F>>(
    q: &Params<F>,
    alpha: F,
    fz: F,
    gamma: F,
) -> Option<(F, F, F, F)> {
    let opts = Options {
        limits: false,
        ..Options::default()
    };
    let inp = Input {
        fz,
        alpha,
        gamma,
        vx: q.longvl,
        ..Input::default()
    };
    let o = mf::eval::<F, M>(q, &inp, &opts).ok()?;
    Some((o.fy, o.mz, o.mu_y, o.mu_x))
}

/// The model behind the table, on a settable surface λμ.
enum Src<F> {
    Mf(Params<F>),
    Brush(Brush<F>),
}

impl<F: Float> Src<F> {
    fn set_lambda(&mut self, lambda: F) {
        match self {
            Src::Mf(q) => {
                q.lmux = lambda;
                q.lmuy = lambda;
            }
            Src::Brush(_) => {}
        }
    }

    /// (Fy, Mz) at the current surface; the brush model's surface is scaled here (its curves
    /// are exactly radial).
    fn eval<M: Backend<F>>(&self, alpha: F, fz: F, gamma: F) -> Option<(F, F)> {
        match self {
            Src::Mf(q) => mf_fy_mz::<F, M>(q, alpha, fz, gamma).map(|(fy, mz, _, _)| (fy, mz)),
            Src::Brush(b) => Some(b.fy_mz::<M>(alpha, fz)),
        }
    }
}

/// One tabulated curve: (τ, f, usable length) at load `fz`, on `side`, surface λ (the slip
/// axis is stretched by λ so that every surface gets the same resolution along its curve).
fn curve<F: Float, M: Backend<F>>(
    src: &Src<F>,
    fz: F,
    gamma: F,
    side: usize,
    fy_sign: F,
    lambda: f64,
    mu0: F,
) -> Option<([F; POINTS], [F; POINTS], u8)> {
    let sgn = if side == 0 { F::ONE } else { -F::ONE };
    let (scale, lam_f) = match src {
        Src::Brush(_) => (F::from_f64(lambda), F::from_f64(lambda)),
        Src::Mf(_) => (F::from_f64(lambda), F::ONE),
    };
    let mut taus = [F::ZERO; POINTS];
    let mut fs = [F::ZERO; POINTS];
    for k in 0..POINTS {
        let alpha = sgn * scale * F::from_f64(alpha_node(k));
        // Brush: evaluate at λ = 1 on the stretched axis and scale radially (exact).
        let alpha_eval = match src {
            Src::Brush(_) => M::atan(M::tan(alpha) / scale),
            Src::Mf(_) => alpha,
        };
        let (fy, mz) = src.eval::<M>(alpha_eval, fz, gamma)?;
        let (fy, mz) = (fy * lam_f, mz * lam_f);
        let fy_dir = fy * fy_sign * sgn; // > 0 on the expected side
        *taus.get_mut(k)? = if fy_dir > F::ZERO {
            -mz / fy
        } else {
            F::from_f64(1e9)
        };
        *fs.get_mut(k)? = fy_dir / fz;
    }
    // Usable part: from the largest trail among points with a well-defined ratio (|Fy| ≥ 10 %
    // of the surface's peak, so that shifts do not dominate), the points on which τ strictly
    // decreases; a flat or rising tail (full sliding, Mz ≈ 0) ends it.
    let f_min = F::from_f64(0.1 * lambda) * mu0;
    let mut first = None;
    let mut best = F::ZERO;
    for k in 0..POINTS / 2 {
        let (tk, fk) = (*taus.get(k)?, *fs.get(k)?);
        if fk >= f_min && tk < F::from_f64(1e8) && (first.is_none() || tk > best) {
            first = Some(k);
            best = tk;
        }
    }
    let first = first?;
    if best <= F::ZERO {
        return None; // no positive trail to collapse from: nothing to read
    }
    let mut kept_t = [F::ZERO; POINTS];
    let mut kept_f = [F::ZERO; POINTS];
    let mut n = 0;
    for k in first..POINTS {
        let (tk, fk) = (*taus.get(k)?, *fs.get(k)?);
        let ok = n == 0 || kept_t.get(n - 1).is_some_and(|&prev| tk < prev);
        if !ok || fk <= F::ZERO {
            break;
        }
        *kept_t.get_mut(n)? = tk;
        *kept_f.get_mut(n)? = fk;
        n += 1;
    }
    if n < 4 {
        return None;
    }
    Some((kept_t, kept_f, n as u8))
}
