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
use crate::mf::{self, combined::Arm, Input, Options, Params, Side};

/// Loads the table holds, as multiples of the reference load.
pub const LOAD_NODES: [f64; 7] = [0.2, 0.4, 0.6, 0.8, 1.0, 1.35, 1.8];
/// Surfaces the table holds, as λμ: the curves are nearly but not exactly radial images of each
/// other (the shifts SHy, SHt do not scale, SVy scales with the digressive λμ' of (4.E8)), so the
/// estimate is taken from the two surfaces that bracket it.
pub const LAMBDA_NODES: [f64; 4] = [0.15, 0.35, 0.65, 1.0];
/// Slip-angle nodes per load, side and surface.
pub const POINTS: usize = 20;
/// Inclination angles the table holds \[rad\] (±2°): camber moves the Gough curve (camber
/// thrust, the camber terms of the trail and residual torque), and a wheel's camber changes
/// with roll; the estimate interpolates between the bracketing nodes.
pub const CAMBER_NODES: [f64; 7] = [-0.045, -0.03, -0.015, 0.0, 0.015, 0.03, 0.045];
const NL: usize = LOAD_NODES.len();
const NS: usize = LAMBDA_NODES.len();
const NG: usize = CAMBER_NODES.len();
/// Points kept of the rising branch (small slip, before the trail peaks).
pub const RISE: usize = POINTS / 2;

/// One value per curve: camber × load × side × surface (the surfaces innermost: a reading
/// looks up its camber, load and side once and then reads every surface there).
pub type PerCurve<T> = [[[[T; NS]; 2]; NL]; NG];

/// One tabulated curve of the Gough plot (one camber, surface, load and side): everything the
/// per-sample path reads of it, in one record so that one index reaches it all.
/// τ in m, f = |Fy|/Fz dimensionless (ISO-W forces, as in the `.tir` file).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Curve<F> {
    /// The points (f, τ): f = |Fy|/Fz \[-\] (absolute, on that surface), τ \[m\]. From index
    /// [`RISE`] the usable (monotone) part, τ strictly decreasing over `len` points
    /// ([`Curve::usable`]); right before it, ending at [`RISE`], the `rise_len` points of the
    /// rising branch ([`Curve::rise`]), so that the two read on as one array.
    pub points: [(F, F); RISE + POINTS],
    /// What a reading past the aligning torque's sign change can mean (near and beyond the
    /// force peak, out into deep sliding where τ rises again and no longer tells the slip): the
    /// middle of the range of f seen there and its half-width (the range of f once the trail
    /// has turned negative, with the last usable point's f; that point's f alone when the curve
    /// has no negative trail).
    pub sat: [F; 2],
    /// A trail at or below this \[m\] is past the sign change (the last usable point's trail;
    /// 0 if higher and the curve has a negative trail).
    pub tau_sat: F,
    /// A trail below this \[m\] is no point of this curve at all: far below the most negative
    /// trail the curve ever shows, e.g. a lateral force near zero from the shifts with the
    /// residual torque still acting (the last usable point's trail less a quarter of |τ0|).
    pub tau_floor: F,
    /// Number of usable (monotone) points.
    pub len: u8,
    /// Number of points of the rising branch: the trail before its peak. At small slip the
    /// residual torque and the shifts make the trail grow first, so a reading there can look
    /// like a slippery surface at large slip; kept to recognise that ambiguity.
    pub rise_len: u8,
    /// Number of leading points of the rising branch followed by the monotone part over which
    /// f strictly increases: the points before the curve's force peak, where [`Curve::tau_at`]
    /// searches.
    pub peak: u8,
}

impl<F: Float> Curve<F> {
    /// A curve with no usable point.
    pub const fn empty() -> Self {
        Curve {
            points: [(F::ZERO, F::ZERO); RISE + POINTS],
            sat: [F::ZERO; 2],
            tau_sat: F::ZERO,
            tau_floor: F::ZERO,
            len: 0,
            rise_len: 0,
            peak: 0,
        }
    }

    /// The usable (monotone) part: τ strictly decreases.
    pub fn usable(&self) -> &[(F, F)] {
        self.points
            .get(RISE..RISE + self.len as usize)
            .unwrap_or(&[])
    }

    /// The rising branch (before the trail's peak).
    pub fn rise(&self) -> &[(F, F)] {
        self.points
            .get(RISE.saturating_sub(self.rise_len as usize)..RISE)
            .unwrap_or(&[])
    }

    /// The rising branch followed by the monotone part up to the force peak (`peak` points),
    /// where f strictly increases.
    fn before_peak(&self) -> &[(F, F)] {
        let from = RISE.saturating_sub(self.rise_len as usize);
        self.points
            .get(from..from + self.peak as usize)
            .unwrap_or(&[])
    }

    /// τ0: the trail at the smallest usable slip \[m\] (0 for an empty curve).
    pub fn tau0(&self) -> F {
        self.points[RISE].1
    }
}

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

/// The tabulated Gough curves: 7 cambers × 4 surfaces × 7 loads × 2 sides × 20 points × (τ, f),
/// plus each curve's rising branch: about 102 KB in f32. Built once per tyre (and mounting side) and shared by the estimators of
/// the wheels on that side.
#[derive(Debug, Clone)]
pub struct GoughTable<F> {
    /// Loads of the nodes \[N\].
    pub fz: [F; NL],
    /// [`LAMBDA_NODES`] in `F` (no conversion on the per-sample path).
    pub lam: [F; NS],
    /// [`CAMBER_NODES`] in `F` \[rad\].
    pub cam: [F; NG],
    /// The curves per camber, load, side (0: α > 0, 1: α < 0) and surface.
    pub curves: PerCurve<Curve<F>>,
    /// Sign of Fy for α > 0 in this model (−1 for ISO-W files).
    pub fy_sign: F,
    /// μ of the table's surface: μy0 (Magic Formula: μy at Fz0, γ = 0, nominal pressure).
    pub mu0: F,
    /// μy0/μx0: the friction ellipse's aspect (1 for the isotropic brush model).
    pub mu_ratio: F,
    /// The tyre is mirrored (mounted on the side opposite its TYRESIDE): quantities computed
    /// from the file's coefficients outside the table (the Fx moment arm s) must be mirrored
    /// too.
    pub mirrored: bool,
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
    /// Half-width of the f range a saturated point can mean (0 when not saturated).
    pub f_spread: F,
}

fn alpha_node(k: usize) -> f64 {
    let x = (k + 1) as f64 / POINTS as f64;
    // Cubic spacing: dense near zero, where the residual torque and the shifts bend the trail
    // (the rising branch must be resolved to recognise readings there), coarse in deep sliding.
    ALPHA_MAX * x * x * x
}

impl<F: Float> GoughTable<F> {
    /// Tabulates `model` for a wheel mounted on `mounted` (the Magic Formula mirrors the tyre
    /// when that differs from the file's TYRESIDE; `None`: as the file is). `None` if the model
    /// gives no usable curve at the nominal load.
    pub fn build<M: Backend<F>>(model: Model<'_, F>, mounted: Option<Side>) -> Option<Self> {
        let mut t = Self::zeroed();
        Self::build_into::<M>(&mut t, model, mounted)?;
        Some(t)
    }

    /// An all-zero table (no usable curve): the starting point of [`GoughTable::build_into`].
    /// The all-zero bit pattern is exactly this value, so a device may also zero the memory of
    /// a static slot instead of constructing one on the stack.
    pub fn zeroed() -> Self {
        GoughTable {
            fz: [F::ZERO; NL],
            lam: [F::ZERO; NS],
            cam: [F::ZERO; NG],
            curves: [[[[Curve::empty(); NS]; 2]; NL]; NG],
            fy_sign: F::ZERO,
            mu0: F::ZERO,
            mu_ratio: F::ZERO,
            mirrored: false,
        }
    }

    /// [`GoughTable::build`] into an existing table, in place: no 102 KB temporary on the stack
    /// (what a device needs). On `None` the slot holds a partial table: rebuild or zero it.
    pub fn build_into<M: Backend<F>>(
        slot: &mut Self,
        model: Model<'_, F>,
        mounted: Option<Side>,
    ) -> Option<()> {
        let mirrored = match model {
            Model::Mf(p) => p.mirrored_on(mounted),
            Model::Brush(_) => false,
        };
        let mut src = match model {
            Model::Mf(p) => Src::Mf(p.clone(), mounted),
            Model::Brush(b) => Src::Brush(b),
        };
        src.set_lambda(F::ONE);
        let (fz_ref, mu0, mu_ratio) = match &src {
            Src::Mf(q, m) => {
                let (_, _, mu0, mux0) = mf_fy_mz::<F, M>(q, *m, F::ZERO, q.fnomin, F::ZERO)?;
                if mux0 <= F::ZERO || mu0 <= F::ZERO {
                    return None;
                }
                (q.fnomin, mu0, mu0 / mux0)
            }
            Src::Brush(b) => (b.fz0, b.mu, F::ONE),
        };
        let t = slot;
        t.fz = [F::ZERO; NL];
        t.lam = LAMBDA_NODES.map(F::from_f64);
        t.cam = CAMBER_NODES.map(F::from_f64);
        t.fy_sign = F::ZERO;
        t.mu0 = mu0;
        t.mu_ratio = mu_ratio;
        t.mirrored = mirrored;
        let (fy_probe, _) = src.eval::<M>(F::from_f64(0.05), fz_ref, F::ZERO)?;
        t.fy_sign = fy_probe.sign_nz();
        for (j, &ln) in LOAD_NODES.iter().enumerate() {
            *t.fz.get_mut(j)? = fz_ref * F::from_f64(ln);
        }
        for (gi, &g) in CAMBER_NODES.iter().enumerate() {
            let gamma = F::from_f64(g);
            for (si, &lam) in LAMBDA_NODES.iter().enumerate() {
                src.set_lambda(F::from_f64(lam));
                for j in 0..NL {
                    let fz = *t.fz.get(j)?;
                    for side in 0..2 {
                        // A curve with no usable monotone part (an asymmetric tyre's ply-steer side
                        // at low friction) stays empty: its points are simply not identifiable.
                        let c = curve::<F, M>(&src, fz, gamma, side, t.fy_sign, lam, mu0)
                            .unwrap_or(Curve::empty());
                        *t.curves
                            .get_mut(gi)?
                            .get_mut(j)?
                            .get_mut(side)?
                            .get_mut(si)? = c;
                    }
                }
            }
        }
        // The tyre's own surface at the nominal load must be usable on both sides.
        let nominal = LOAD_NODES.iter().position(|&x| x == 1.0)?;
        let flat = CAMBER_NODES.iter().position(|&x| x == 0.0)?;
        let own = t.curves.get(flat)?.get(nominal)?;
        if own
            .iter()
            .any(|sides| sides.get(NS - 1).is_none_or(|c| c.len < 4))
        {
            return None;
        }
        Some(())
    }

    /// The curves of every surface at camber node `g`, load node `j`, side `side` (0: α > 0,
    /// 1: α < 0); `None` when an index is out of range.
    pub fn surfaces(&self, g: usize, j: usize, side: usize) -> Option<&[Curve<F>; NS]> {
        self.curves.get(g)?.get(j)?.get(side)
    }
}

impl<F: Float> Curve<F> {
    /// The trail where the curve's force is `f`: along the rising branch and then the
    /// monotone part, up to the curve's force peak (linear in f between table points; below the
    /// first point, that point's trail). `None` when f lies beyond the curve's peak force — no
    /// point of this curve has that force — or the curve is empty.
    pub fn tau_at(&self, f: F) -> Option<F> {
        let pts = self.before_peak();
        let (f0, t0) = *pts.first()?;
        if f <= f0 {
            return Some(t0);
        }
        // Smallest k with f ≤ f_k (f strictly increases here): bisection.
        let (mut lo, mut hi) = (0, pts.len() - 1);
        if f > pts.get(hi)?.0 {
            return None; // beyond the force peak
        }
        while hi - lo > 1 {
            let mid = (lo + hi) / 2;
            if f <= pts.get(mid)?.0 {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        let ((f0, t0), (f1, t1)) = (*pts.get(lo)?, *pts.get(hi)?);
        Some(t0 + (f - f0) / (f1 - f0) * (t1 - t0))
    }

    /// Inverts τ → f. `None` when τ is above the usable range (the trail has not dropped: the
    /// point is not identifiable).
    ///
    /// `hint` is the table segment to start the search from; it is set to the segment found.
    /// Any start gives the same result; a near one is cheaper. The curves of neighbouring loads,
    /// cambers and surfaces are sampled at the same fractions of their slip range, so the
    /// segment found on one is a good start on the next.
    pub fn invert(&self, tau: F, hint: &mut usize) -> Option<Inversion<F>> {
        let pts = self.points.get(RISE..)?;
        // Usable points 0..=last, last ≥ 1 (an empty curve has none).
        let last = (self.len as usize)
            .min(POINTS)
            .checked_sub(1)
            .filter(|&l| l > 0)?;
        let tau0 = pts.first()?.1;
        // Not below τ0, NaN included (one comparison where `>=` plus a finiteness test took
        // two); −∞ is caught by the floor below.
        #[allow(clippy::neg_cmp_op_on_partial_ord)]
        if !(tau < tau0) {
            return None;
        }
        if tau < self.tau_floor {
            return None;
        }
        let drop = |tau: F| {
            if tau0 > F::ZERO {
                F::ONE - tau / tau0
            } else {
                F::ONE
            }
        };
        if tau <= self.tau_sat {
            // Past the aligning torque's sign change: near the force peak or in deep sliding,
            // where the trail no longer tells where on the (falling) force curve the tyre is.
            // The middle of the f range seen there, and how wide it is.
            let [f, f_spread] = self.sat;
            return Some(Inversion {
                f,
                df_dtau: F::ZERO,
                drop: drop(tau.max(pts.get(last)?.1)),
                saturated: true,
                f_spread,
            });
        }
        // The k with τ_k > τ ≥ τ_k+1 (unique: τ strictly decreases over the usable points,
        // τ_0 > τ > τ_last), walking from the hint: down while τ_k ≤ τ (k > 0 there, as
        // τ_0 > τ), up while τ_k+1 > τ (k + 1 < last there, as τ_last < τ). At most `POINTS`
        // steps.
        let mut k = (*hint).min(last - 1);
        for _ in 0..POINTS {
            let (a, b) = (pts.get(k)?.1, pts.get(k + 1)?.1);
            if a <= tau {
                k = k.saturating_sub(1);
            } else if b > tau {
                k += 1;
            } else {
                break;
            }
        }
        *hint = k;
        let ((f0, t0), (f1, t1)) = (*pts.get(k)?, *pts.get(k + 1)?);
        let slope = (f1 - f0) / (t1 - t0); // t1 < t0 strictly
        Some(Inversion {
            f: f0 + (tau - t0) * slope,
            df_dtau: slope,
            drop: drop(tau),
            saturated: false,
            f_spread: F::ZERO,
        })
    }
}

/// (Fy, Mz, μy, μx) of the Magic Formula at pure side slip, limits off, nominal pressure.
fn mf_fy_mz<F: Float, M: Backend<F>>(
    q: &Params<F>,
    mounted: Option<Side>,
    alpha: F,
    fz: F,
    gamma: F,
) -> Option<(F, F, F, F)> {
    let opts = Options {
        limits: false,
        mounted,
        moments: false,
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
    // The table holds the torque of the lateral force alone: the moment s·Fx of the free-rolling
    // Fx (the shifts SHx, SVx make it nonzero at κ = 0) is removed with the same arm the estimator
    // removes from each sample, mirrored like the tyre (eq. (17), (A56)).
    let dfz = (fz - q.fnomin) / q.fnomin;
    let s = Arm::from_params(q).s_mounted(q.mirrored_on(mounted), o.fy, dfz, gamma);
    Some((o.fy, o.mz - s * o.fx, o.mu_y, o.mu_x))
}

/// The model behind the table, on a settable surface λμ.
enum Src<F> {
    Mf(Params<F>, Option<Side>),
    Brush(Brush<F>),
}

impl<F: Float> Src<F> {
    fn set_lambda(&mut self, lambda: F) {
        match self {
            Src::Mf(q, _) => {
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
            Src::Mf(q, m) => {
                mf_fy_mz::<F, M>(q, *m, alpha, fz, gamma).map(|(fy, mz, _, _)| (fy, mz))
            }
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
) -> Option<Curve<F>> {
    let sgn = if side == 0 { F::ONE } else { -F::ONE };
    let (scale, lam_f) = match src {
        Src::Brush(_) => (F::from_f64(lambda), F::from_f64(lambda)),
        Src::Mf(..) => (F::from_f64(lambda), F::ONE),
    };
    let mut taus = [F::ZERO; POINTS];
    let mut fs = [F::ZERO; POINTS];
    for k in 0..POINTS {
        let alpha = sgn * scale * F::from_f64(alpha_node(k));
        // Brush: evaluate at λ = 1 on the stretched axis and scale radially (exact).
        let alpha_eval = match src {
            Src::Brush(_) => M::atan(M::tan(alpha) / scale),
            Src::Mf(..) => alpha,
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
    let mut kept = [(F::ZERO, F::ZERO); POINTS];
    let mut n = 0;
    for k in first..POINTS {
        let (tk, fk) = (*taus.get(k)?, *fs.get(k)?);
        let ok = n == 0 || kept.get(n - 1).is_some_and(|&(_, prev)| tk < prev);
        if !ok || fk <= F::ZERO {
            break;
        }
        *kept.get_mut(n)? = (fk, tk);
        n += 1;
    }
    if n < 4 {
        return None;
    }
    // f once τ ≤ 0: from the last positive-trail point on, through the sampled tail.
    let mut neg = [F::ZERO; 2];
    if let Some(k0) = (first..POINTS).find(|&k| taus.get(k).is_some_and(|&x| x <= F::ZERO)) {
        let from = k0.saturating_sub(1).max(first);
        let (mut lo, mut hi) = (F::from_f64(1e9), F::ZERO);
        for k in from..POINTS {
            let fk = *fs.get(k)?;
            lo = lo.min(fk);
            hi = hi.max(fk);
        }
        // Out to a spinning wheel (α = 0.8 rad), beyond the stretched axis: the deepest
        // sliding a reading with τ < 0 can come from.
        for &a in &[0.3, 0.45, 0.6, 0.8] {
            if a > lambda * ALPHA_MAX {
                let alpha = sgn * F::from_f64(a);
                let alpha_eval = match src {
                    Src::Brush(_) => M::atan(M::tan(alpha) / scale),
                    Src::Mf(..) => alpha,
                };
                let (fy, _) = src.eval::<M>(alpha_eval, fz, gamma)?;
                let fk = fy * lam_f * fy_sign * sgn / fz;
                if fk > F::ZERO {
                    lo = lo.min(fk);
                }
            }
        }
        neg = [lo, hi];
    }
    // The rising branch: points before `first` with a positive force on this side.
    let mut rise = [(F::ZERO, F::ZERO); RISE];
    let mut nr = 0;
    for k in 0..first.min(RISE) {
        let (tk, fk) = (*taus.get(k)?, *fs.get(k)?);
        if fk > F::ZERO && tk < F::from_f64(1e8) {
            *rise.get_mut(nr)? = (fk, tk);
            nr += 1;
        }
    }
    // One array: the rising branch right-aligned before `RISE`, the usable part from it.
    let mut points = [(F::ZERO, F::ZERO); RISE + POINTS];
    points
        .get_mut(RISE - nr..RISE)?
        .copy_from_slice(rise.get(..nr)?);
    points
        .get_mut(RISE..RISE + n)?
        .copy_from_slice(kept.get(..n)?);
    let [neg_lo, neg_hi] = neg;
    let (f_end, tau_end) = *kept.get(n - 1)?;
    let (lo, hi) = if neg_hi > F::ZERO {
        (neg_lo.min(f_end), neg_hi.max(f_end))
    } else {
        (f_end, f_end)
    };
    let tau0 = kept[0].1;
    let mut c = Curve {
        points,
        len: n as u8,
        sat: [F::HALF * (hi + lo), F::HALF * (hi - lo)],
        tau_sat: if neg_hi > F::ZERO {
            tau_end.max(F::ZERO)
        } else {
            tau_end
        },
        tau_floor: tau_end - F::from_f64(0.25) * tau0.abs(),
        rise_len: nr as u8,
        peak: 0,
    };
    let both = c.points.get(RISE - nr..RISE + n)?;
    let mut peak = 1;
    while peak < nr + n && both.get(peak)?.0 > both.get(peak - 1)?.0 {
        peak += 1;
    }
    c.peak = peak as u8;
    Some(c)
}
