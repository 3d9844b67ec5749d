//! `gough mu map`: from which utilisation the product's estimator (the bank) reads μ on a given
//! tyre.
//!
//! For each surface μ and load, the tyre's own Magic Formula (λμx = λμy = μ/μy0, pure side
//! slip, at the file's reference speed LONGVL and the inclination γ asked, 0 by default) gives
//! steady, noise-free Fy, Mz, Fz along a slip-angle sweep (α > 0, where Fy < 0) up to the peak;
//! the samples carry γ, the free-rolling κ (0, as a wheel-speed sensor reads it) and, unless
//! `--no-fx`, the model's free-rolling Fx. At each point a fresh bank ([`Method::Bank`], default
//! settings, the wheel as the file describes the tyre) runs over [`STEPS`] ms of that constant
//! sample at 1 kHz, rolling at 20 m/s (its batches, fits and likelihoods: all of it, as on a
//! wheel); the point counts as identifiable when the bank ends `identifiable`. The map reports
//! the lowest utilisation |F|/(μ·Fz) at which that happens, and the estimate there. The bank's
//! likelihoods still budget for the configured sensor noise and model error, so this is the
//! best case a wheel can do at a steady point: a real manoeuvre adds noise and transients, and
//! its history (how the point got there) tells the bank more than one point does.
//!
//! Beside it, the physics that decides the map, independent of the estimator: at utilisation
//! 0.5, the pneumatic trail τ = −Mz/Fy on the surface's curve and how far the curve of a
//! surface 0.1 grippier lies from it at the same force. The smaller that gap, the more nearly
//! two surfaces explain the same steady point.
use super::{Method, Sample, Setup};
use gough::mf::{self, Params};
use gough::mu::State;
use gough::proto::Wheel;

/// Surfaces of the map (μ).
pub const MUS: [f64; 10] = [1.0, 0.9, 0.8, 0.7, 0.6, 0.5, 0.4, 0.3, 0.2, 0.1];
/// Loads of the map (× Fz0).
pub const LOADS: [f64; 3] = [0.5, 1.0, 1.5];

/// One surface at one load.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cell {
    /// Surface μ (λμ·μy0).
    pub mu: f64,
    /// Load / Fz0.
    pub load: f64,
    /// Lowest utilisation at which the steady point is identifiable (`None`: not up to the peak).
    pub first_util: Option<f64>,
    /// The estimate there, μ̂ − μ.
    pub err: Option<f64>,
    /// The estimate's σ there.
    pub sigma: Option<f64>,
    /// Trail at utilisation 0.5 \[m\] (`None`: the curve never reaches it).
    pub trail: Option<f64>,
    /// Trail at the same force on the surface 0.1 grippier, minus `trail` \[m\].
    pub gap: Option<f64>,
}

/// Samples of 1 ms the bank runs on each point: the bench's latency target
/// ([`super::bench::TARGET_LATENCY`], 150 ms; 15 of the bank's batches). Held longer, a steady
/// point's evidence keeps adding up and the map reads lower utilisations (500 ms: μ 0.4–0.7 from
/// about 0.3 at Fz0).
pub const STEPS: usize = 150;

fn eval(p: &Params<f64>, lam: f64, fz: f64, alpha: f64, gamma: f64) -> Option<mf::Output<f64>> {
    super::peers::eval_cambered(p, lam, fz, alpha, 0.0, gamma)
}

/// The slip angle on the rising branch where |Fy| reaches `force` on surface λμ `lam`
/// (bisection), with the output there; `None` if the curve's peak is below it.
fn at_force(p: &Params<f64>, lam: f64, fz: f64, gamma: f64, force: f64) -> Option<mf::Output<f64>> {
    let (mut lo, mut hi) = (0.0, None);
    let mut a = 1e-3;
    while a < 0.5 {
        if eval(p, lam, fz, a, gamma)?.fy.abs() >= force {
            hi = Some(a);
            break;
        }
        lo = a;
        a += 1e-3;
    }
    let mut hi = hi?;
    for _ in 0..50 {
        let mid = 0.5 * (lo + hi);
        if eval(p, lam, fz, mid, gamma)?.fy.abs() >= force {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    eval(p, lam, fz, hi, gamma)
}

/// The map of tyre `p` (see the module's doc). `with_fx`: the samples carry the measured Fx
/// (at pure side slip, the free-rolling Fx of the model), as the benchmark's do.
pub fn map(p: &Params<f64>, with_fx: bool, gamma: f64) -> Result<Vec<Cell>, String> {
    // The bank builds on this tyre (an error here says why it cannot).
    Method::Bank.estimator(p, &Setup::one_wheel(None))?;
    // Surfaces scaled from the file's μy0, as the simulation scales them (docs/architecture.md).
    let mu0 = crate::sim::vehicle::mu_y0(p)?;
    let probe = Probe {
        p,
        mu0,
        with_fx,
        gamma,
    };
    let mut cells = Vec::new();
    for &mu in &MUS {
        for &load in &LOADS {
            cells.push(probe.cell(mu, load)?);
        }
    }
    Ok(cells)
}

/// What every cell is measured with.
struct Probe<'a> {
    p: &'a Params<f64>,
    mu0: f64,
    with_fx: bool,
    gamma: f64,
}

impl Probe<'_> {
    /// The bank's last estimate after [`STEPS`] samples of the steady point `o`.
    fn run(&self, o: &mf::Output<f64>) -> Result<Option<super::Estimate>, String> {
        let mut est = Method::Bank.estimator(self.p, &Setup::one_wheel(None))?;
        let mut last = None;
        for k in 0..STEPS {
            last = Some(est.update(
                Wheel::FrontLeft,
                &Sample {
                    t: k as f64 * 1e-3,
                    fz: o.fz,
                    fy: o.fy,
                    mz: o.mz,
                    fx: self.with_fx.then_some(o.fx),
                    vx: Some(20.0),
                    kappa: Some(0.0),
                    alpha: None,
                    gamma: Some(self.gamma),
                },
            ));
        }
        Ok(last)
    }

    fn cell(&self, mu: f64, load: f64) -> Result<Cell, String> {
        let Probe { p, mu0, gamma, .. } = *self;
        let fz = load * p.fnomin;
        let lam = mu / mu0;
        let mut out = Cell {
            mu,
            load,
            first_util: None,
            err: None,
            sigma: None,
            trail: None,
            gap: None,
        };
        // The sweep: up to the peak of |Fy|, in steps of 1 % of the slip angle at the peak's scale.
        let da = 2e-4 * mu.max(0.1);
        // The force of α > 0 is Fy < 0 and grows in that direction up to the peak; at small
        // slip the shifts and the camber thrust can make Fy positive, so |Fy| first falls.
        let mut peak = f64::NEG_INFINITY;
        for i in 1..2000 {
            let alpha = i as f64 * da;
            let Some(o) = eval(p, lam, fz, alpha, gamma) else {
                break;
            };
            let f = -o.fy;
            if f < peak {
                break; // past the peak
            }
            peak = f;
            let util = o.fx.hypot(o.fy) / (mu * fz);
            if util < 0.2 || i % 5 != 0 {
                continue;
            }
            if let Some(e) = self.run(&o)?.filter(|e| e.state == State::Identifiable) {
                out.first_util = Some(util);
                out.err = Some(e.mu - mu);
                out.sigma = Some(e.sigma);
                break;
            }
        }
        // The trail at utilisation 0.5, and on the surface 0.1 grippier at the same force.
        let force = 0.5 * mu * fz;
        if let Some(o) = at_force(p, lam, fz, gamma, force) {
            let tau = -o.mz / o.fy;
            out.trail = Some(tau);
            out.gap = at_force(p, (mu + 0.1) / mu0, fz, gamma, force).map(|g| -g.mz / g.fy - tau);
        }
        Ok(out)
    }
}

/// The map as a terminal table (markdown).
pub fn render(cells: &[Cell], name: &str, fz0: f64, with_fx: bool, gamma: f64) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    let fx = if with_fx { "measured" } else { "not measured" };
    let _ = writeln!(
        s,
        "identifiability map of {name}: steady pure side slip (α > 0, γ {gamma} rad, at LONGVL), \
         noise-free, Fx {fx}, the bank's defaults at 1 kHz for {STEPS} ms per point"
    );
    let _ = writeln!(
        s,
        "lowest utilisation at which μ is identifiable (estimate − μ there); trail at utilisation \
         0.5 and the gap to the curve of μ + 0.1 at that force, at Fz0 = {fz0:.0} N"
    );
    let _ = write!(s, "| μ |");
    for l in LOADS {
        let _ = write!(s, " {l}·Fz0 |");
    }
    let _ = writeln!(s, " trail at util 0.5 [mm] | gap to μ + 0.1 [mm] |");
    let _ = writeln!(s, "|---|{}---|---|", "---|".repeat(LOADS.len()));
    for mu in MUS {
        let _ = write!(s, "| {mu:.1} |");
        let row: Vec<&Cell> = cells.iter().filter(|c| c.mu == mu).collect();
        for c in &row {
            match (c.first_util, c.err) {
                (Some(u), Some(e)) => {
                    let _ = write!(s, " {u:.2} ({e:+.3}) |");
                }
                _ => {
                    let _ = write!(s, " not identifiable |");
                }
            }
        }
        let at_fz0 = row.iter().find(|c| c.load == 1.0);
        let mm = |x: Option<f64>| x.map_or("–".to_string(), |x| format!("{:.1}", x * 1e3));
        let _ = writeln!(
            s,
            " {} | {} |",
            mm(at_fz0.and_then(|c| c.trail)),
            mm(at_fz0.and_then(|c| c.gap))
        );
    }
    s
}

/// The map as CSV.
pub fn csv(cells: &[Cell]) -> String {
    let f = |x: Option<f64>| x.map_or(String::new(), |x| format!("{x:.6}"));
    let mut s = String::from("mu,load_rel,first_util,err,sigma,trail_u05_m,gap_m\n");
    for c in cells {
        s += &format!(
            "{},{},{},{},{},{},{}\n",
            c.mu,
            c.load,
            f(c.first_util),
            f(c.err),
            f(c.sigma),
            f(c.trail),
            f(c.gap)
        );
    }
    s
}
