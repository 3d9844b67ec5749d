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
//!
//! Each curve is evaluated at 20 slip angles (and where its usable part starts, and at two
//! more points between each pair of its slip angles there) and then held as f against the trail
//! ratio ρ = τ/τ0 on a grid (linear between those points) in two halves, each uniform in ρ: from
//! 1 down to the curve's *anchor* ρa, where f reaches [`ANCHOR_SHARE`] of the curve's peak, and
//! from ρa down to 0. Along the grid the trail collapses at one pace on every curve, although
//! it does so at different ρ on curves of different loads (f against ρ is steep there, and the
//! steep part moves along ρ with load). A reading between load or camber nodes is placed on the
//! grid of an anchor interpolated like the curves, and then every curve bracketing it is read
//! at the same grid position, by one multiplication instead of a search. The ambiguity test's look-up
//! the other way, τ at a force, is first bounded from 8 force cells per curve (the chord across
//! a cell, and how far the curve strays from it), also without a search ([`Curve::tau_band`]).

use super::brush::Brush;
use gough::math::{Backend, Float};
use gough::mf::{self, combined::Arm, Input, Options, Params, Side};

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
///
/// The usable (monotone) part is held as f against the trail ratio ρ = τ/τ0 on a grid whose
/// node i lies at ρᵢ = [`grid_rho`]`(i, anchor)`: uniform in ρ from 1 to the anchor (nodes 0 to
/// [`HALF_CELLS`]) and from the anchor to 0 (nodes [`HALF_CELLS`] to [`RHO_CELLS`]). A reading
/// finds its cell by one multiplication, with no search, and the same cell serves every curve
/// it is read on (the corners of its load and camber, on one surface; [`RhoAt`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Curve<F> {
    /// f = |Fy|/Fz \[-\] (absolute, on that surface) at ρᵢ, for i < `len`: linear between the
    /// slip-angle nodes the model was evaluated at; the last node is the first at or beyond
    /// the usable part's end, on its last segment's line (so that the grid reads that segment
    /// exactly); the nodes past it continue that line.
    pub f: [F; RHO_POINTS],
    /// The rising branch (f, τ): the trail before its peak, the last `rise_len` entries. At
    /// small slip the residual torque and the shifts make the trail grow first, so a reading
    /// there can look like a slippery surface at large slip; kept to recognise that ambiguity.
    pub rise: [(F, F); RISE],
    /// τ0: the trail where the usable part starts, the largest of it \[m\] (> 0; 0 for an
    /// empty curve): where f reaches the cut-off (10 % of the surface's μ) while the trail
    /// still falls there, else at the trail's peak; both found between the slip-angle nodes.
    pub tau0: F,
    /// What a reading past the aligning torque's sign change can mean (near and beyond the
    /// force peak, out into deep sliding where τ rises again and no longer tells the slip): the
    /// middle of the range of f seen there and its half-width (the range of f once the trail
    /// has turned negative, with the last usable point's f; that point's f alone when the curve
    /// has no negative trail).
    pub sat: [F; 2],
    /// The trail ratio ρa where f reaches [`ANCHOR_SHARE`] of the usable part's largest f: the
    /// grid's middle node \[-\] (in \[1/16, 15/16\]; 0 for an empty curve).
    pub anchor: F,
    /// A grid position ([`grid_pos`]) at or beyond this is past the sign change (the last
    /// usable point's ratio; ρ = 0 if lower and the curve has a negative trail).
    pub x_sat: F,
    /// A grid position beyond this is no point of this curve at all: far below the most
    /// negative trail the curve ever shows, e.g. a lateral force near zero from the shifts with
    /// the residual torque still acting (the last usable point's ratio less a quarter).
    pub x_floor: F,
    /// Number of grid nodes of `f` (≥ 2; 0 for an empty curve).
    pub len: u8,
    /// Number of points of the rising branch.
    pub rise_len: u8,
    /// Number of leading points of the rising branch followed by the grid
    /// ([`Curve::point`]) over which f strictly increases: the points before the curve's force
    /// peak, where [`Curve::tau_at`] searches.
    pub peak: u8,
    /// f at the curve's force peak (the last point of [`Curve::tau_at`]'s range; 0 for an
    /// empty curve) \[-\].
    pub f_top: F,
    /// [`BAND_CELLS`]/`f_top`: a force's cell of the bounds (0 for an empty curve).
    pub band_scale: F,
    /// The free-rolling tyre's Fx/Fz against f = |Fy|/Fz: \[c0, c2\] of Fx/Fz ≈ c0 + c2·f²
    /// (the shifts SHx, SVx make Fx nonzero at κ = 0, and the weight Gxα shrinks it as the
    /// slip angle grows), through the smallest slip angle's point and the force peak's \[-\].
    /// The table holds the torque with this Fx's moment s·Fx removed (eq. 17); a sample that
    /// carries no Fx is taken to roll free, and this is its Fx. Zero for the brush model.
    pub fx_free: [F; 2],
    /// Per edge i of [`BAND_CELLS`] equal cells of f from 0 to `f_top` (edge i at
    /// f·`band_scale` = i): \[[`Curve::tau_at`] there, how far `tau_at` strays from the chord
    /// to the next edge over cell i\] \[m\] (the last edge's second entry is 0). The stray is
    /// the largest over the cell padded by 1/1024 of its width, widened by a margin far above
    /// the rounding of the look-up: chord ± stray bounds the trail at a force, and the
    /// ambiguity test decides most readings from these alone, without a search (see
    /// [`Curve::tau_band`]).
    pub band: [[F; 2]; BAND_CELLS + 1],
}

/// Cells of a [`Curve`]'s trail bounds against force.
pub const BAND_CELLS: usize = 8;

/// Cells of the trail-ratio grid of a [`Curve`]: ρ from 1 down to 0 in steps of 1/32.
pub const RHO_CELLS: usize = 32;
/// Nodes of the trail-ratio grid.
pub const RHO_POINTS: usize = RHO_CELLS + 1;

/// Cells of a [`Curve`]'s grid above its anchor, and below it.
pub const HALF_CELLS: usize = RHO_CELLS / 2;

/// The grid's middle node: where f reaches this share of the usable part's largest f. There
/// the curves of every load are at the same stage of their trail's collapse, and f rises
/// steeply against ρ about it. Comparing curves at equal ρ instead misplaced readings between
/// the load nodes by up to 0.055 in λμ (`mu::tests::load_interpolation_error`; shares of 0.3,
/// 0.4, 0.5, 0.7 and 0.8 gave 0.027, 0.025, 0.023, 0.028 and 0.035 there, 0.6 gives 0.023 and
/// the least on the nodes). Between camber nodes see `mu::tests::camber_interpolation_error`.
pub const ANCHOR_SHARE: f64 = 0.6;

/// Bounds of a curve's anchor: the two halves of the grid keep some width.
const ANCHOR_RANGE: (f64, f64) = (1.0 / 16.0, 15.0 / 16.0);

/// ρ at position `x` along the grid of anchor `anchor` (node i at x = i): 1 − (x/h)·(1 − ρa)
/// for x ≤ h = [`HALF_CELLS`], ρa·(2 − x/h) beyond; the inverse of [`grid_pos`] for an anchor
/// within \[1/16, 15/16\], as every curve's is (`grid_pos` clamps the anchor to that range).
#[inline]
pub fn grid_rho<F: Float>(x: F, anchor: F) -> F {
    let u = x * F::from_f64(1.0 / HALF_CELLS as f64);
    if u <= F::ONE {
        F::ONE - u * (F::ONE - anchor)
    } else {
        anchor * (F::TWO - u)
    }
}

/// The position of ρ along the grid of anchor `anchor` (clamped to its range), and ∂x/∂ρ:
/// x = h·(1 − ρ)/(1 − ρa) for ρ ≥ ρa, h·(2 − ρ/ρa) below (h = [`HALF_CELLS`]); beyond the
/// grid's ends the same lines continue.
#[inline]
pub fn grid_pos<F: Float>(rho: F, anchor: F) -> (F, F) {
    let (lo, hi) = ANCHOR_RANGE;
    let a = anchor.max(F::from_f64(lo)).min(F::from_f64(hi));
    let h = F::from_index(HALF_CELLS as u16);
    if rho >= a {
        let k = h / (F::ONE - a);
        ((F::ONE - rho) * k, -k)
    } else {
        let k = h / a;
        (h + (a - rho) * k, -k)
    }
}

impl<F: Float> Curve<F> {
    /// A curve with no usable point.
    pub const fn empty() -> Self {
        Curve {
            f: [F::ZERO; RHO_POINTS],
            rise: [(F::ZERO, F::ZERO); RISE],
            tau0: F::ZERO,
            sat: [F::ZERO; 2],
            anchor: F::ZERO,
            x_sat: F::ZERO,
            x_floor: F::ZERO,
            len: 0,
            rise_len: 0,
            peak: 0,
            f_top: F::ZERO,
            band_scale: F::ZERO,
            fx_free: [F::ZERO; 2],
            band: [[F::ZERO; 2]; BAND_CELLS + 1],
        }
    }

    /// The rising branch (before the trail's peak), as (f, τ).
    pub fn rise(&self) -> &[(F, F)] {
        self.rise
            .get(RISE.saturating_sub(self.rise_len as usize)..)
            .unwrap_or(&[])
    }

    /// The `k`-th point (f, τ) of the rising branch followed by the grid (grid node i at
    /// τ = τ0·ρᵢ); `None` past the grid's end.
    #[inline]
    pub fn point(&self, k: usize) -> Option<(F, F)> {
        let nr = self.rise_len as usize;
        match k.checked_sub(nr) {
            None => self.rise.get(RISE - nr + k).copied(),
            Some(i) if i < self.len as usize => Some((
                *self.f.get(i)?,
                self.tau0 * grid_rho(F::from_index(i as u16), self.anchor),
            )),
            Some(_) => None,
        }
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

/// The tabulated Gough curves: 7 cambers × 4 surfaces × 7 loads × 2 sides, each f at 33 trail
/// ratios plus its rising branch and its trail bounds over 8 force cells: about 126 KB in f32.
/// Built once per tyre (and mounting side) and shared by the estimators of the wheels on that
/// side.
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
    /// ∂f/∂ρ along the table \[-\] (for the error propagation; ρ = τ/τ0).
    pub df_drho: F,
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

    /// [`GoughTable::build`] into an existing table, in place: no 126 KB temporary on the stack
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
                let (_, _, _, mu0, mux0) = mf_fy_mz::<F, M>(q, *m, F::ZERO, q.fnomin, F::ZERO)?;
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

/// A trail ratio ρ = τ/τ0 placed on the grid of the [`Curve`]s: its position, cell and where
/// in it. Computed once per reading and surface, on the grid of the anchor interpolated between
/// the curves bracketing the reading, and read on each of them at that position.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RhoAt<F> {
    /// ρ \[-\].
    pub rho: F,
    /// The position x along the grid ([`grid_pos`]).
    pub x: F,
    /// ∂x/∂ρ there (< 0).
    dx_drho: F,
    /// ⌊x⌋, clamped to the grid's cells.
    cell: usize,
    /// x − cell.
    frac: F,
}

impl<F: Float> RhoAt<F> {
    /// Places ρ on the grid of anchor `anchor` (any value: NaN and values outside the grid are
    /// placed at its ends, and [`Curve::read`] turns them away).
    pub fn new(rho: F, anchor: F) -> Self {
        let (x, dx_drho) = grid_pos(rho, anchor);
        let cell = x.floor_index(RHO_CELLS - 1);
        RhoAt {
            rho,
            x,
            dx_drho,
            cell,
            frac: x - F::from_index(cell as u16),
        }
    }
}

impl<F: Float> Curve<F> {
    /// Bounds (lo, hi) of [`Curve::tau_at`]`(f)` from the cell of `band` holding `f`, with no
    /// search: `None` exactly where `tau_at` gives `None` (f beyond the force peak or NaN, an
    /// empty curve).
    #[inline]
    pub fn tau_band(&self, f: F) -> Option<(F, F)> {
        // f ≤ f_top, NaN excluded; f < 0 reads cell 0, where the trail is the first point's,
        // as in `tau_at`. (An empty curve has no peak.)
        #[allow(clippy::neg_cmp_op_on_partial_ord)]
        if !(f <= self.f_top) || self.peak == 0 {
            return None;
        }
        let x = f * self.band_scale;
        let i = x.floor_index(BAND_CELLS - 1);
        let [[a, dev], [b, _]] = *self.band.get(i..i + 2)? else {
            return None;
        };
        // The chord at f (below 0, its start: `tau_at` is constant there).
        let mid = a + (x - F::from_index(i as u16)).max(F::ZERO) * (b - a);
        Some((mid - dev, mid + dev))
    }

    /// The trail where the curve's force is `f`: along the rising branch and then the
    /// grid, up to the curve's force peak (linear in f between points; below the first point,
    /// that point's trail). `None` when f lies beyond the curve's peak force — no point of
    /// this curve has that force — or the curve is empty.
    pub fn tau_at(&self, f: F) -> Option<F> {
        self.tau_at_from(f, &mut 0)
    }

    /// [`Curve::tau_at`], searching the grid from node `hint` (0: no hint) and setting it to
    /// the node found. Any hint gives the same result; a near one is cheaper (the curves of
    /// neighbouring loads and cambers cross a force at nearly the same node).
    pub fn tau_at_from(&self, f: F, hint: &mut usize) -> Option<F> {
        // The points before the peak: the rising branch's, then the grid's.
        let n = self.peak as usize;
        let nr = (self.rise_len as usize).min(RISE);
        let rise = self.rise.get(RISE - nr..)?;
        let (rise, grid) = match n.checked_sub(nr) {
            None => (rise.get(..n)?, &[][..]),
            Some(ng) => (rise, self.f.get(..ng)?),
        };
        let (f0, t0) = match rise.first() {
            Some(&p) => p,
            None => (*grid.first()?, self.tau0),
        };
        if f <= f0 {
            return Some(t0);
        }
        let lerp = |(f0, t0): (F, F), (f1, t1): (F, F)| t0 + (f - f0) / (f1 - f0) * (t1 - t0);
        if let Some(&last) = rise.last() {
            if f <= last.0 {
                // On the rising branch: the segment ending at the first point with f_k ≥ f.
                let k = rise.partition_point(|p| p.0 < f);
                return Some(lerp(*rise.get(k.checked_sub(1)?)?, *rise.get(k)?));
            }
            // Between the rising branch and the grid (or beyond the peak: no grid).
            let g0 = (*grid.first()?, self.tau0);
            if f <= g0.0 {
                return Some(lerp(last, g0));
            }
        }
        if f > *grid.last()? {
            return None; // beyond the force peak
        }
        // On the grid: the cell ending at the first node i with f_i ≥ f (i ≥ 1: f > f_0;
        // unique, as f strictly increases there).
        let i = if (1..grid.len()).contains(hint) {
            // Walk from the hint: down while the node below also has f_i−1 ≥ f (i − 1 ≥ 1
            // there), up while f_i < f (i + 1 < len there, as f ≤ the last f).
            let mut i = *hint;
            while i > 1 && grid.get(i - 1).is_some_and(|&x| x >= f) {
                i -= 1;
            }
            while grid.get(i).is_some_and(|&x| x < f) {
                i += 1;
            }
            i
        } else {
            grid.partition_point(|&x| x < f)
        };
        *hint = i;
        let (fa, fb) = (*grid.get(i.checked_sub(1)?)?, *grid.get(i)?);
        let cells = F::from_index(i as u16 - 1) + (f - fa) / (fb - fa);
        Some(self.tau0 * grid_rho(cells, self.anchor))
    }

    /// Inverts ρ = τ/τ0 → f at the grid position of `at` ([`RhoAt::new`]). `None` when ρ is
    /// not below 1 (the trail has not dropped: the point is not identifiable), beyond the
    /// curve's floor, NaN, or the curve is empty.
    pub fn read(&self, at: &RhoAt<F>) -> Option<Inversion<F>> {
        let x = at.x;
        if self.len < 2 {
            return None; // an empty curve
        }
        // Past 0 (ρ below 1), NaN excluded (one comparison); +∞ is caught by the floor below.
        #[allow(clippy::neg_cmp_op_on_partial_ord)]
        if !(x > F::ZERO) {
            return None;
        }
        if x > self.x_floor {
            return None;
        }
        if x >= self.x_sat {
            // Past the aligning torque's sign change: near the force peak or in deep sliding,
            // where the trail no longer tells where on the (falling) force curve the tyre is.
            // The middle of the f range seen there, and how wide it is.
            let [f, f_spread] = self.sat;
            return Some(Inversion {
                f,
                df_drho: F::ZERO,
                saturated: true,
                f_spread,
            });
        }
        // x < x_sat ≤ the grid's last node: the cell lies on the grid (a cell past it, from
        // rounding, reads the same line: the nodes past the grid continue it).
        let (f0, f1) = (*self.f.get(at.cell)?, *self.f.get(at.cell + 1)?);
        let df = f1 - f0;
        Some(Inversion {
            f: f0 + at.frac * df,
            df_drho: df * at.dx_drho,
            saturated: false,
            f_spread: F::ZERO,
        })
    }

    /// [`Curve::read`] at ρ placed on this curve's own grid.
    pub fn invert(&self, rho: F) -> Option<Inversion<F>> {
        self.read(&RhoAt::new(rho, self.anchor))
    }
}

/// (Fy, Mz, Fx, μy, μx) of the Magic Formula at pure side slip, limits off, nominal pressure;
/// Mz without the moment s·Fx of that (free-rolling) Fx.
fn mf_fy_mz<F: Float, M: Backend<F>>(
    q: &Params<F>,
    mounted: Option<Side>,
    alpha: F,
    fz: F,
    gamma: F,
) -> Option<(F, F, F, F, F)> {
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
    Some((o.fy, o.mz - s * o.fx, o.fx, o.mu_y, o.mu_x))
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
        self.eval_fx::<M>(alpha, fz, gamma)
            .map(|(fy, mz, _)| (fy, mz))
    }

    /// (Fy, Mz, Fx): [`Src::eval`] with the free-rolling Fx (0 for the brush model).
    fn eval_fx<M: Backend<F>>(&self, alpha: F, fz: F, gamma: F) -> Option<(F, F, F)> {
        match self {
            Src::Mf(q, m) => {
                mf_fy_mz::<F, M>(q, *m, alpha, fz, gamma).map(|(fy, mz, fx, _, _)| (fy, mz, fx))
            }
            Src::Brush(b) => {
                let (fy, mz) = b.fy_mz::<M>(alpha, fz);
                Some((fy, mz, F::ZERO))
            }
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
    // Slip angle of node k at λμ = 1.
    let node = |k: usize| F::from_f64(alpha_node(k));
    // (f, τ, Fx/Fz) at slip angle `a` at λμ = 1 (on the stretched axis).
    let at = |a: F| {
        let alpha = sgn * scale * a;
        // Brush: evaluate at λ = 1 on the stretched axis and scale radially (exact).
        let alpha_eval = match src {
            Src::Brush(_) => M::atan(M::tan(alpha) / scale),
            Src::Mf(..) => alpha,
        };
        let (fy, mz, fx) = src.eval_fx::<M>(alpha_eval, fz, gamma)?;
        let (fy, mz) = (fy * lam_f, mz * lam_f);
        let fy_dir = fy * fy_sign * sgn; // > 0 on the expected side
        let tau = if fy_dir > F::ZERO {
            -mz / fy
        } else {
            F::from_f64(1e9)
        };
        Some((fy_dir / fz, tau, fx / fz))
    };
    // The slip angle between `lo` and `hi`, (α, f) with f(lo) < `target` ≤ f(hi), where f
    // reaches `target`: secant steps in α (f is nearly linear in α there), kept bracketed, until
    // f is within 0.1 % of it (at most 4 steps). (α, f, τ) of the last point found at or above
    // it (or within the 0.1 %); `None` if none.
    let cross = |mut lo: (F, F), mut hi: (F, F), target: F| {
        let mut found = None;
        for _ in 0..4 {
            let a = lo.0 + (hi.0 - lo.0) * ((target - lo.1) / (hi.1 - lo.1));
            let (fd, td, _) = at(a)?;
            if fd < target {
                lo = (a, fd);
            } else {
                hi = (a, fd);
                found = Some((a, fd, td));
            }
            if (fd - target).abs() <= target * F::from_f64(1e-3) {
                found = Some((a, fd, td));
                break;
            }
        }
        found
    };
    let mut taus = [F::ZERO; POINTS];
    let mut fs = [F::ZERO; POINTS];
    let mut fxs = [F::ZERO; POINTS];
    for k in 0..POINTS {
        let (f, tau, fx) = at(node(k))?;
        (*fs.get_mut(k)?, *taus.get_mut(k)?, *fxs.get_mut(k)?) = (f, tau, fx);
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
    // τ0 between the nodes. Every curve is read relative to its own τ0, and the load
    // interpolation compares curves at equal τ/τ0: a τ0 taken at whichever node happens to be
    // first (its f anywhere from the cut-off to the next node) misplaces the reading between
    // loads (the first node changes between 1.35 and 1.8·Fz0: the first estimates at 1.5·Fz0
    // leaned +0.055, now +0.023, `gough mu map`). So the usable part starts where it truly does:
    // where f reaches the cut-off `f_min` when the trail still falls there (the residual torque
    // makes it largest at the smallest force), or at the trail's peak (the vertex of the
    // parabola through the nodes about `first`). `start`: that point (slip angle, f, τ) when it
    // lies before the node `first` (which then follows it) or after it (the node then joins the
    // rising branch).
    let mut start = None;
    if let (Some(&ta), Some(&tb), Some(&tc), Some(&fa), Some(&fb)) = (
        first.checked_sub(1).and_then(|k| taus.get(k)),
        taus.get(first),
        taus.get(first + 1),
        first.checked_sub(1).and_then(|k| fs.get(k)),
        fs.get(first),
    ) {
        let den = ta - F::TWO * tb + tc;
        let a = if fa < f_min && fb > fa && ta > tb {
            // f crosses the cut-off between the nodes.
            cross((node(first - 1), fa), (node(first), fb), f_min).map(|(a, _, _)| a)
        } else if ta < F::from_f64(1e8) && den < F::ZERO {
            // The vertex, in node positions (the nodes' α is cubic in the position).
            let d = (F::HALF * (ta - tc) / den).max(-F::HALF).min(F::HALF);
            let x = (F::from_index(first as u16 + 1) + d) * F::from_f64(1.0 / POINTS as f64);
            Some(F::from_f64(ALPHA_MAX) * x * x * x)
        } else {
            None
        };
        if let Some(a) = a.filter(|&a| a != node(first)) {
            let (fp, tp, _) = at(a)?;
            if tp > tb && fp >= f_min * F::from_f64(1.0 - 1e-3) && fp > F::ZERO {
                start = Some((a, fp, tp));
            }
        }
    }
    // The usable part, (f, τ) and the slip angle of each point: from `start` (if any), then
    // the nodes from `first` (after `start`: from the next) on which τ strictly decreases.
    let mut kept = [(F::ZERO, F::ZERO); POINTS];
    let mut kept_a = [F::ZERO; POINTS];
    let mut n = 0;
    let mut from = first;
    if let Some((a, f, t)) = start {
        (*kept.first_mut()?, *kept_a.first_mut()?) = ((f, t), a);
        n = 1;
        if a > node(first) {
            from = first + 1;
        }
    }
    for k in from..POINTS {
        let (tk, fk) = (*taus.get(k)?, *fs.get(k)?);
        let ok = n == 0 || kept.get(n - 1).is_some_and(|&(_, prev)| tk < prev);
        if !ok || fk <= F::ZERO {
            break;
        }
        (*kept.get_mut(n)?, *kept_a.get_mut(n)?) = ((fk, tk), node(k));
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
    let rise_end = if from > first { first + 1 } else { first };
    for k in 0..rise_end.min(RISE) {
        let (tk, fk) = (*taus.get(k)?, *fs.get(k)?);
        if fk > F::ZERO && tk < F::from_f64(1e8) {
            *rise.get_mut(nr)? = (fk, tk);
            nr += 1;
        }
    }
    // The rising branch right-aligned, as the curve holds it.
    let mut rise_r = [(F::ZERO, F::ZERO); RISE];
    rise_r
        .get_mut(RISE - nr..)?
        .copy_from_slice(rise.get(..nr)?);
    let [neg_lo, neg_hi] = neg;
    let (f_end, tau_end) = *kept.get(n - 1)?;
    let (lo, hi) = if neg_hi > F::ZERO {
        (neg_lo.min(f_end), neg_hi.max(f_end))
    } else {
        (f_end, f_end)
    };
    // The usable part on the ρ grid: in the segment k between slip-angle nodes with
    // τ_k ≥ τ0·ρᵢ ≥ τ_k+1, linear between SUB + 1 points of the model along it (f bends between
    // the nodes: on the nodes alone, readings on the load nodes erred by up to 0.031 in λμ from
    // a utilisation of 0.5, now 0.007, `load_interpolation_error`), up to the first grid node
    // at or beyond the usable part's end, which lies on the last piece's line.
    let tau0 = kept.first()?.1; // > 0
                                // The anchor: ρ where f first reaches ANCHOR_SHARE of the usable part's largest f (between
                                // the points kept, found in α; on the chord if the secant finds nothing).
    let kept_n = kept.get(..n)?;
    let f_big = kept_n.iter().fold(F::ZERO, |m, p| m.max(p.0));
    let target = F::from_f64(ANCHOR_SHARE) * f_big;
    let anchor = match kept_n.iter().position(|p| p.0 >= target) {
        Some(k) if k > 0 => {
            let ((f0, t0), (f1, t1)) = (*kept.get(k - 1)?, *kept.get(k)?);
            let lo = (*kept_a.get(k - 1)?, f0);
            let hi = (*kept_a.get(k)?, f1);
            let tau_a = match cross(lo, hi, target) {
                Some((_, _, t)) => t,
                None => t0 + (target - f0) / (f1 - f0) * (t1 - t0),
            };
            tau_a / tau0
        }
        // Already there where the usable part starts.
        _ => F::ONE,
    };
    let anchor = anchor
        .max(F::from_f64(ANCHOR_RANGE.0))
        .min(F::from_f64(ANCHOR_RANGE.1));
    const SUB: usize = 3;
    let mut f = [F::ZERO; RHO_POINTS];
    let mut len = 0;
    let mut k = 0;
    // The points along segment `k` (computed when the grid first reaches it).
    let mut seg = [(F::ZERO, F::ZERO); SUB + 1];
    let mut seg_k = None;
    for (i, slot) in f.iter_mut().enumerate() {
        let tau_i = tau0 * grid_rho(F::from_index(i as u16), anchor);
        while k + 2 < n && kept.get(k + 1)?.1 > tau_i {
            k += 1;
        }
        if seg_k != Some(k) {
            let (ends, a, da) = (
                (*kept.get(k)?, *kept.get(k + 1)?),
                *kept_a.get(k)?,
                *kept_a.get(k + 1)? - *kept_a.get(k)?,
            );
            for (m, p) in seg.iter_mut().enumerate() {
                *p = match m {
                    0 => ends.0,
                    SUB => ends.1,
                    _ => at(a + da * F::from_index(m as u16) * F::from_f64(1.0 / SUB as f64))
                        .map(|(f, t, _)| (f, t))?,
                };
            }
            seg_k = Some(k);
        }
        // The piece of the segment holding τᵢ: the first whose far end has τ ≤ τᵢ (the last
        // beyond the segment's end); the chord of the whole segment if the model's trail is
        // not monotone along it.
        let monotone = seg.windows(2).all(|w| matches!(w, [a, b] if b.1 < a.1));
        let ((f0, t0), (f1, t1)) = if monotone {
            let m = seg
                .iter()
                .skip(1)
                .position(|p| p.1 <= tau_i)
                .unwrap_or(SUB - 1);
            (*seg.get(m)?, *seg.get(m + 1)?)
        } else {
            (*kept.get(k)?, *kept.get(k + 1)?)
        };
        *slot = f0 + (tau_i - t0) * ((f1 - f0) / (t1 - t0));
        if len == 0 && tau_i <= tau_end {
            len = i + 1; // the grid's last node; the ones past it continue the last segment
        }
    }
    if len == 0 {
        len = RHO_POINTS; // the usable part reaches below ρ = 0
    }
    let tau_sat = if neg_hi > F::ZERO {
        tau_end.max(F::ZERO)
    } else {
        tau_end
    };
    // The free-rolling Fx/Fz as c0 + c2·f², through the smallest slip angle's point and the
    // force peak's (the weight Gxα falls off with α², and f grows about linearly with α there).
    let (mut k_top, mut f_hi) = (0, F::ZERO);
    for (k, &fk) in fs.iter().enumerate() {
        if fk > f_hi {
            (k_top, f_hi) = (k, fk);
        }
    }
    let (f_lo, fx_lo, fx_hi) = (fs.first()?.max(F::ZERO), *fxs.first()?, *fxs.get(k_top)?);
    let den = f_hi.sq() - f_lo.sq();
    let c2 = if den > F::from_f64(1e-6) {
        (fx_hi - fx_lo) / den
    } else {
        F::ZERO
    };
    let fx_free = [fx_lo - c2 * f_lo.sq(), c2];
    let mut c = Curve {
        f,
        rise: rise_r,
        tau0,
        sat: [F::HALF * (hi + lo), F::HALF * (hi - lo)],
        anchor,
        x_sat: grid_pos(tau_sat / tau0, anchor).0,
        x_floor: grid_pos(tau_end / tau0 - F::from_f64(0.25), anchor).0,
        len: len as u8,
        rise_len: nr as u8,
        peak: 0,
        f_top: F::ZERO,
        band_scale: F::ZERO,
        fx_free,
        band: [[F::ZERO; 2]; BAND_CELLS + 1],
    };
    let mut peak = 1;
    while peak < nr + len && c.point(peak)?.0 > c.point(peak - 1)?.0 {
        peak += 1;
    }
    c.peak = peak as u8;
    // The trail's bounds per force cell: `tau_at` is linear between the points before the
    // peak (constant below the first), and so is its difference from the cell's chord; the
    // difference's extremes over a cell lie at the cell's ends or at a point inside it.
    let f_top = c.point(peak - 1)?.0;
    if f_top > F::ZERO {
        let n = F::from_index(BAND_CELLS as u16);
        let width = f_top / n;
        let scale = n / f_top;
        let mut edge = [F::ZERO; BAND_CELLS + 1];
        for (i, slot) in edge.iter_mut().enumerate() {
            *slot = c.tau_at((width * F::from_index(i as u16)).min(f_top))?;
        }
        let mut dev = [F::ZERO; BAND_CELLS];
        for (i, slot) in dev.iter_mut().enumerate() {
            let (a, b) = (*edge.get(i)?, *edge.get(i + 1)?);
            let x0 = F::from_index(i as u16);
            // The chord as `tau_band` evaluates it.
            let chord = |f: F| a + (f * scale - x0).max(F::ZERO) * (b - a);
            // The cell, widened by 1/1024 of its width on either side: a force the look-up
            // places in it by a rounded product lies within.
            let pad = width * F::from_f64(1.0 / 1024.0);
            let fa = (width * x0 - pad).max(F::ZERO);
            let fb = (width * (x0 + F::ONE) + pad).min(f_top);
            let mut worst = F::ZERO;
            let mut far = a.abs().max(b.abs());
            for f in [fa, fb] {
                let t = c.tau_at(f)?;
                worst = worst.max((t - chord(f)).abs());
                far = far.max(t.abs());
            }
            for k in 0..peak {
                let (fk, tk) = c.point(k)?;
                if fk > fa && fk < fb {
                    worst = worst.max((tk - chord(fk)).abs());
                    far = far.max(tk.abs());
                }
            }
            // The margin: far above the look-up's rounding (and the weighted sums' in the
            // test), far below the test's tolerance (≥ 2 % of τ0).
            *slot = worst + F::from_f64(1e-4) * (far + tau0);
        }
        c.f_top = f_top;
        c.band_scale = scale;
        for (slot, (&t, &d)) in c
            .band
            .iter_mut()
            .zip(edge.iter().zip(dev.iter().chain([&F::ZERO])))
        {
            *slot = [t, d];
        }
    }
    Some(c)
}
