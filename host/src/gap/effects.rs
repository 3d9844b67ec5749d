//! The candidate effects: each a parametric extension of the sim with a physical form.
//!
//! An effect's parameters start at the values that reproduce the sim exactly (SIM.tir's own
//! coefficients, unit factors, zero lag, zero bias), so "no change" is always inside its model.
//!
//! | effect | form | parameters |
//! |---|---|---|
//! | `camber` | the file's camber terms re-fitted: MF 6.x Fy camber stiffness Kyγ (4.E30) and camber vertical shift Svyγ (4.E28), Mzr camber (4.E47); MF 5.x/Delft 96 the camber shift Shy (PHY3) instead of Kyγ | `pky6 pvy3 qdz8` (6.x), `phy3 pvy3 qdz8` |
//! | `inflation_pressure` | MF 6.x: the pressure terms of Kxκ, μx, Kyα, μy and the trail re-fitted (4.E15, 4.E13, 4.E25, 4.E23, A60); MF 5.x (no pressure model): λKx, λKy, λμx, λμy each times (1 + a·dpi), dpi = (p − p̃)/p̃ about the log's median p̃ | `ppx1 ppx3 ppy1 ppy3 ppz1` / `a_kx a_ky a_mux a_muy` |
//! | `turn_slip` | MF 6.x with turn-slip coefficients: the reductions of Kyα, μy, trail and the spin moment re-fitted (4.79, 4.78, 4.91, 4.96); otherwise a linear spin force and moment ΔFy = c_fy·Fz·R0·φt, ΔMz = c_mz·Fz·R0²·φt | `pkyp1 pdyp1 qdtp1 qdrp1` / `c_fy c_mz` |
//! | `combined_slip` | the weighting-function slopes Bxα (4.E54), Byκ (4.E62) and the Fx moment arm s (4.E76) re-fitted | `rbx1 rby1 ssz1` |
//! | `relaxation_length` | σκ, σα times s·(1 + c·dfz) (a σ(Fz) relaxation); without filters in SIM.tir, σα = s_alpha·R0·Fz/Fz0, σκ = s_kappa·R0·Fz/(2·Fz0) | `s_kappa s_alpha c_fz` |
//! | `speed_dependent_friction` | λμx = λμy = (1 + b·(|Vx| − V0)/V0)/(1 + a·Vs/V0), Vs the slip speed (TNO's λμV form plus a forward-speed trend), V0 = LONGVL | `a_vs b_vx` |
//! | `thermal` | one tread temperature node T (in units of the slip power over Fz0·V0) heated by the slip power Ps = |Fx·Vsx| + |Fy·Vsy| of the *measured* forces and cooled towards ambient (T = 0) at a speed-dependent rate: τ·dT/dt = Ps/(Fz0·V0) − h(V)·T, h = 1 + c_v·(|Vx|/V0 − 1) (floored at 0.05), from a fitted start temperature t0 (a log need not start with a cold tyre); τ from 0.05 s to 200 s; grip around an optimum, λμx = λμy = 1 + mu0 + mu1·T + mu2·T² (the optimum at −mu1/(2·mu2) when mu2 < 0; mu0: the file's temperature is not ambient), the slip stiffnesses λKx = λKy = 1 + k1·T | `mu0 mu1 mu2 k1 tau c_v t0` |
//! | `sensor_lag` | a first-order lag per channel (exact for a first-order hold) | `tau_fx tau_fy tau_mz` \[s\] |
//! | `sensor_bias` | a constant offset per channel | `b_fx b_fy b_mz` \[N, N, N·m\] |
//! | `conicity_plysteer` | the zero-slip offsets re-fitted: Fy horizontal and vertical shifts (4.E27, 4.E29), the trail's shift (4.E35) | `phy1 pvy1 qhz1` |
//!
//! Each extension can be evaluated two ways: exactly (a full run of the sim with the extension,
//! used for scoring) and on a subset of rows (for fitting), where the slips fed to the Magic
//! Formula are those of the baseline run (for effects that change σ only through the cornering
//! and slip stiffness, that is a second-order approximation inside the fit; the scores are
//! always exact).

use super::fit::Bounds;
use super::log::Log;
use super::sim::{lag, node_from, Lambda, Mods, Out, RowError, Run, SigmaMode, Sim};
use gough::mf::{Key, Params};

/// A candidate effect.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Effect {
    /// Camber terms.
    Camber,
    /// Inflation-pressure terms.
    InflationPressure,
    /// Turn slip.
    TurnSlip,
    /// Combined-slip weighting.
    CombinedSlip,
    /// Relaxation lengths.
    RelaxationLength,
    /// Friction falling with slip speed.
    SpeedDependentFriction,
    /// Tread temperature from slip power.
    Thermal,
    /// Sensor lag per channel.
    SensorLag,
    /// Sensor bias per channel.
    SensorBias,
    /// Conicity / ply-steer offsets.
    ConicityPlysteer,
}

/// Every candidate, in report order before sorting.
pub const ALL: [Effect; 10] = [
    Effect::Camber,
    Effect::InflationPressure,
    Effect::TurnSlip,
    Effect::CombinedSlip,
    Effect::RelaxationLength,
    Effect::SpeedDependentFriction,
    Effect::Thermal,
    Effect::SensorLag,
    Effect::SensorBias,
    Effect::ConicityPlysteer,
];

impl Effect {
    /// Name as in the report.
    pub const fn name(self) -> &'static str {
        match self {
            Effect::Camber => "camber",
            Effect::InflationPressure => "inflation_pressure",
            Effect::TurnSlip => "turn_slip",
            Effect::CombinedSlip => "combined_slip",
            Effect::RelaxationLength => "relaxation_length",
            Effect::SpeedDependentFriction => "speed_dependent_friction",
            Effect::Thermal => "thermal",
            Effect::SensorLag => "sensor_lag",
            Effect::SensorBias => "sensor_bias",
            Effect::ConicityPlysteer => "conicity_plysteer",
        }
    }

    /// Looks an effect up by its report name.
    pub fn from_name(s: &str) -> Option<Effect> {
        ALL.iter().copied().find(|e| e.name() == s)
    }

    /// The physical form, one line (for the report).
    pub const fn form(self) -> &'static str {
        match self {
            Effect::Camber => "camber terms re-fitted (Kyγ or Shyγ, Svyγ, Mzr camber)",
            Effect::InflationPressure => {
                "pressure terms re-fitted (MF 6.x), or λK, λμ linear in dpi (MF 5.x)"
            }
            Effect::TurnSlip => {
                "turn-slip reductions re-fitted (MF 6.x), or a linear spin force and moment"
            }
            Effect::CombinedSlip => {
                "combined-slip slopes rbx1, rby1, shape factors rcx1, rcy1 and the Fx arm ssz1"
            }
            Effect::RelaxationLength => "σ times s·(1 + c·dfz)",
            Effect::SpeedDependentFriction => "λμ = (1 + b·(|Vx|−V0)/V0)/(1 + a·Vs/V0)",
            Effect::Thermal => {
                "λμ = 1 + mu0 + mu1·T + mu2·T², λK = 1 + k1·T, τ·dT/dt = slip power/(Fz0·V0) \
                 − (1 + c_v·(|Vx|/V0 − 1))·T, T(0) = t0"
            }
            Effect::SensorLag => "first-order lag per channel",
            Effect::SensorBias => "constant offset per channel",
            Effect::ConicityPlysteer => "zero-slip offsets phy1, pvy1, qhz1 re-fitted",
        }
    }

    /// Cheap to evaluate on every row (no Magic Formula evaluation per call): fitted on all
    /// training rows rather than a subsample.
    pub const fn cheap(self) -> bool {
        matches!(self, Effect::SensorLag | Effect::SensorBias)
    }
}

/// What the effects share: the log, the sim, its baseline run and per-row quantities.
#[derive(Debug, Clone)]
pub struct Ctx<'a> {
    /// The log.
    pub log: &'a Log,
    /// The sim.
    pub sim: &'a Sim,
    /// The baseline run (SIM.tir as it is).
    pub base: Run,
    /// Noise floor per channel (`stats::noise_floor` of the baseline residual), floored.
    pub noise: [f64; 3],
    /// Slip speed |Vs| per row \[m/s\] (log kinematics).
    pub vs: Vec<f64>,
    /// Slip power of the measured forces over Fz0·V0 per row \[-\].
    pub power: Vec<f64>,
    /// dfz = (Fz − Fz0)/Fz0 per row.
    pub dfz: Vec<f64>,
    /// Reference pressure of the MF 5.x pressure extension: the log's median p \[Pa\].
    pub p_ref: f64,
    /// Rows that are scored and fitted: all but those within [`SETTLE_SIGMAS`] relaxation
    /// lengths of travel after a gap in time, where the filter restarted in a steady state that
    /// the tyre was not in (see `sim`'s "Gaps").
    pub settled: Vec<bool>,
}

/// Travel after a restart, in relaxation lengths (the larger of σκ, σα at the restart), over
/// which rows are left out of fits and scores: e^(−3) ≈ 5 % of the restart's error is left.
pub const SETTLE_SIGMAS: f64 = 3.0;

impl<'a> Ctx<'a> {
    /// Runs the baseline and prepares the per-row quantities.
    pub fn new(log: &'a Log, sim: &'a Sim) -> Result<Ctx<'a>, RowError> {
        let base = sim.run(log, &sim.params, &Mods::default())?;
        let mut noise = [0.0; 3];
        for (c, nz) in noise.iter_mut().enumerate() {
            let r: Vec<f64> = (0..log.len())
                .map(|i| log.meas[i][c] - base.out[i][c])
                .collect();
            let scale = super::stats::rms(log.meas.iter().map(|m| m[c]));
            // Floor: a clean (noise-free) log still needs a finite normalisation.
            *nz = super::stats::noise_floor(&r).max(1e-6 * scale.max(1.0));
        }
        let p = &sim.params;
        let (fz0, v0) = (p.fnomin, p.longvl.abs().max(1.0));
        let n = log.len();
        let mut vs = Vec::with_capacity(n);
        let mut power = Vec::with_capacity(n);
        for i in 0..n {
            let (vsx, vsy) = log.slip_velocity(i);
            vs.push(vsx.hypot(vsy));
            power.push((log.meas[i][0] * vsx).abs() + (log.meas[i][1] * vsy).abs());
        }
        for w in power.iter_mut() {
            *w /= fz0 * v0;
        }
        let dfz = log.fz.iter().map(|&f| (f - fz0) / fz0).collect();
        let p_ref = log
            .p
            .as_ref()
            .map(|p| super::stats::median(p))
            .unwrap_or(0.0);
        let mut settled = vec![true; n];
        let restarts = log.restarts();
        let mut travel = f64::INFINITY;
        let mut need = 0.0;
        for i in 0..n {
            if i > 0 && restarts[i] {
                travel = 0.0;
                need = SETTLE_SIGMAS * base.sigma[i][0].max(base.sigma[i][1]);
            } else if i > 0 {
                travel += 0.5 * (log.vx[i].abs() + log.vx[i - 1].abs()) * (log.t[i] - log.t[i - 1]);
            }
            settled[i] = travel >= need;
        }
        Ok(Ctx {
            log,
            sim,
            base,
            noise,
            settled,
            vs,
            power,
            dfz,
            p_ref,
        })
    }

    /// Residual of the baseline, row by row (0 on rows not [`Ctx::settled`]).
    pub fn base_resid(&self) -> Vec<Out> {
        self.resid(&self.base.out)
    }

    /// measured − predicted per row, 0 on rows not [`Ctx::settled`].
    pub fn resid(&self, pred: &[Out]) -> Vec<Out> {
        let mut r = resid(self.log, pred);
        for (x, &ok) in r.iter_mut().zip(&self.settled) {
            if !ok {
                *x = [0.0; 3];
            }
        }
        r
    }
}

/// measured − predicted per row.
pub fn resid(log: &Log, pred: &[Out]) -> Vec<Out> {
    log.meas
        .iter()
        .zip(pred)
        .map(|(m, p)| [m[0] - p[0], m[1] - p[1], m[2] - p[2]])
        .collect()
}

#[derive(Debug, Clone, PartialEq)]
enum Variant {
    Keys(Vec<Key>),
    PressureLambda,
    TurnSlipAdd,
    Relaxation,
    SpeedFriction,
    Thermal,
    Lag,
    Bias,
}

/// An effect's parameters for a given log and sim.
#[derive(Debug, Clone, PartialEq)]
pub struct Spec {
    /// The effect.
    pub effect: Effect,
    /// Parameter names as in the report (`.tir` keys in lower case where they are keys).
    pub names: Vec<String>,
    /// Starting points (the first reproduces the sim; more for multi-start fits).
    pub starts: Vec<Vec<f64>>,
    /// Bounds and scales.
    pub bounds: Bounds,
    /// A coarse scan: points whose cost is evaluated before the fit, the best of them added to
    /// the starting points. Set where the file's values sit on a flat point of the effect (a
    /// block absent from the file: a combined-slip weight with B = 0 or C = 0 is 1 whatever the
    /// other coefficient, so its gradient vanishes and a fit from there never leaves).
    pub scan: Vec<Vec<f64>>,
    variant: Variant,
}

/// (key, floor of its scale, lower bound if the sign is physical).
const KEY_SCALES: &[(&str, f64, Option<f64>)] = &[
    ("PKY6", 0.5, None),
    ("PHY3", 0.01, None),
    ("PVY3", 0.1, None),
    ("QDZ8", 0.1, None),
    ("PPX1", 0.3, None),
    ("PPX3", 0.1, None),
    ("PPY1", 0.3, None),
    ("PPY3", 0.1, None),
    ("PPZ1", 0.3, None),
    ("PKYP1", 0.5, Some(0.0)),
    ("PDYP1", 0.2, Some(0.0)),
    ("QDTP1", 5.0, Some(0.0)),
    ("QDRP1", 0.5, Some(0.0)),
    ("RBX1", 5.0, Some(0.5)),
    ("RBY1", 5.0, Some(0.5)),
    ("RCX1", 0.5, Some(0.0)),
    ("RCY1", 0.5, Some(0.0)),
    ("SSZ1", 0.02, None),
    ("PHY1", 0.003, None),
    ("PVY1", 0.01, None),
    ("QHZ1", 0.003, None),
    ("LMUX", 0.3, Some(0.05)),
    ("LMUY", 0.3, Some(0.05)),
    ("LKX", 0.3, Some(0.05)),
    ("LKY", 0.3, Some(0.05)),
];

fn keys_spec(effect: Effect, p: &Params<f64>, names: &[&str]) -> Spec {
    let mut keys = Vec::new();
    let (mut start, mut lo, mut hi, mut scale) = (vec![], vec![], vec![], vec![]);
    for &n in names {
        let Some(k) = Key::from_name(n) else { continue };
        let (floor, lower) = KEY_SCALES
            .iter()
            .find(|e| e.0 == n)
            .map(|e| (e.1, e.2))
            .unwrap_or((0.1, None));
        let v = p.get(k);
        let s = v.abs().max(floor);
        keys.push(k);
        start.push(v);
        scale.push(s);
        let l = v - 5.0 * s;
        lo.push(match lower {
            Some(b) => l.max(b.min(v)),
            None => l,
        });
        hi.push(v + 5.0 * s);
    }
    Spec {
        effect,
        names: keys.iter().map(|k| k.name().to_ascii_lowercase()).collect(),
        starts: vec![start],
        bounds: Bounds { lo, hi, scale },
        scan: Vec::new(),
        variant: Variant::Keys(keys),
    }
}

fn simple(
    effect: Effect,
    names: &[&str],
    starts: Vec<Vec<f64>>,
    b: [&[f64]; 3],
    v: Variant,
) -> Spec {
    Spec {
        effect,
        names: names.iter().map(|s| s.to_string()).collect(),
        starts,
        bounds: Bounds {
            lo: b[0].to_vec(),
            hi: b[1].to_vec(),
            scale: b[2].to_vec(),
        },
        scan: Vec::new(),
        variant: v,
    }
}

/// The parameters of `effect` for this log and sim, or why it does not apply.
pub fn spec(effect: Effect, ctx: &Ctx) -> Result<Spec, String> {
    let (log, sim) = (ctx.log, ctx.sim);
    let p = &sim.params;
    let n = log.len();
    match effect {
        Effect::Camber => {
            let gmax = log.gamma.iter().fold(0.0f64, |a, g| a.max(g.abs()));
            if gmax < 1e-5 {
                return Err("γ = 0 throughout the log: the camber terms do nothing".into());
            }
            let names: &[&str] = if p.version.is_mf6() {
                &["PKY6", "PVY3", "QDZ8"]
            } else {
                &["PHY3", "PVY3", "QDZ8"]
            };
            Ok(keys_spec(effect, p, names))
        }
        Effect::InflationPressure => {
            let Some(pr) = &log.p else {
                return Err("no p column: the pressure is INFLPRES throughout".into());
            };
            if p.version.is_mf6() {
                let p0 = p.nompres;
                if pr.iter().all(|&x| (x - p0).abs() <= 1e-6 * p0) {
                    return Err("p = NOMPRES throughout: the pressure terms do nothing".into());
                }
                Ok(keys_spec(
                    effect,
                    p,
                    &["PPX1", "PPX3", "PPY1", "PPY3", "PPZ1"],
                ))
            } else {
                let (lo, hi) = pr
                    .iter()
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
                        (a.min(x), b.max(x))
                    });
                if hi - lo <= 1e-6 * ctx.p_ref {
                    return Err(
                        "p is constant and MF 5.x has no pressure terms: nothing to fit".into(),
                    );
                }
                Ok(simple(
                    effect,
                    &["a_kx", "a_ky", "a_mux", "a_muy"],
                    vec![vec![0.0; 4]],
                    [&[-5.0; 4], &[5.0; 4], &[0.5; 4]],
                    Variant::PressureLambda,
                ))
            }
        }
        Effect::TurnSlip => {
            let any = log
                .phit
                .as_ref()
                .is_some_and(|ph| ph.iter().any(|&x| x != 0.0));
            if !any {
                return Err("no turn slip in the log (no phit column, or φt = 0)".into());
            }
            if sim.turn_slip {
                Ok(keys_spec(effect, p, &["PKYP1", "PDYP1", "QDTP1", "QDRP1"]))
            } else {
                Ok(simple(
                    effect,
                    &["c_fy", "c_mz"],
                    vec![vec![0.0; 2]],
                    [&[-50.0, -50.0], &[50.0, 50.0], &[1.0, 1.0]],
                    Variant::TurnSlipAdd,
                ))
            }
        }
        Effect::CombinedSlip => {
            let both = (0..n)
                .filter(|&i| log.kappa[i].abs() > 0.005 && log.alpha[i].abs() > 0.005)
                .count();
            if both < 20 {
                return Err("fewer than 20 rows with both |κ| and |α| > 0.005".into());
            }
            // The slopes and the shape factors of the weights Gxα, Gyκ (4.E54, 4.E62) and the
            // Fx arm of Mz: a file without the block (all zero) must be able to express it.
            let mut sp = keys_spec(effect, p, &["RBX1", "RBY1", "RCX1", "RCY1", "SSZ1"]);
            let v = sp.starts[0].clone();
            if let [rbx1, rby1, rcx1, rcy1, ssz1] = v[..] {
                if rbx1 * rcx1 == 0.0 || rby1 * rcy1 == 0.0 {
                    // Flat at the file's values: scan the slopes over the range of tyre files
                    // (book and bundled files: RBX1 ≈ 5–25, RBY1 ≈ 5–15) with C = 1 where absent.
                    let cx = if rcx1 != 0.0 { rcx1 } else { 1.0 };
                    let cy = if rcy1 != 0.0 { rcy1 } else { 1.0 };
                    let grid = |b: f64| {
                        if b != 0.0 {
                            vec![b]
                        } else {
                            vec![4.0, 10.0, 20.0]
                        }
                    };
                    for bx in grid(rbx1) {
                        for by in grid(rby1) {
                            sp.scan.push(vec![bx, by, cx, cy, ssz1]);
                        }
                    }
                }
            }
            Ok(sp)
        }
        Effect::RelaxationLength => {
            let starts = if sim.filters {
                vec![vec![1.0, 1.0, 0.0]]
            } else {
                vec![vec![0.3, 0.3, 0.0], vec![1.0, 1.0, 0.0]]
            };
            Ok(simple(
                effect,
                &["s_kappa", "s_alpha", "c_fz"],
                starts,
                [&[0.0, 0.0, -0.95], &[5.0, 5.0, 3.0], &[0.2, 0.2, 0.2]],
                Variant::Relaxation,
            ))
        }
        Effect::SpeedDependentFriction => Ok(simple(
            effect,
            &["a_vs", "b_vx"],
            vec![vec![0.0, 0.0]],
            [&[-0.9, -0.9], &[20.0, 2.0], &[0.5, 0.2]],
            Variant::SpeedFriction,
        )),
        Effect::Thermal => {
            let m = super::stats::mean(&ctx.power);
            if m <= 0.0 {
                return Err("no slip power in the log".into());
            }
            // Scales: a λ change of 0.1 at the log's mean temperature (T ≈ mean power).
            let ks = 0.1 / m;
            let pmax = ctx.power.iter().fold(0.0f64, |a, &b| a.max(b));
            Ok(simple(
                effect,
                &["mu0", "mu1", "mu2", "k1", "tau", "c_v", "t0", "tau_k"],
                // τ multi-started (the fit is flat in it at the sim); the carcass started ten
                // times slower than the tread (bounded by the log's longest τ).
                [0.3f64, 2.0, 10.0, 40.0]
                    .iter()
                    .map(|&tau| {
                        vec![
                            0.0,
                            0.0,
                            0.0,
                            0.0,
                            tau.ln(),
                            0.0,
                            0.0,
                            (10.0 * tau).min(500.0).ln(),
                        ]
                    })
                    .collect(),
                [
                    &[
                        -0.5,
                        -10.0 * ks,
                        -10.0 * ks / m,
                        -10.0 * ks,
                        0.05f64.ln(),
                        -0.9,
                        0.0,
                        0.05f64.ln(),
                    ],
                    &[
                        0.5,
                        10.0 * ks,
                        10.0 * ks / m,
                        10.0 * ks,
                        200f64.ln(),
                        3.0,
                        2.0 * pmax,
                        1000f64.ln(),
                    ],
                    &[0.05, ks, ks / m, ks, 0.5, 0.3, m, 0.5],
                ],
                Variant::Thermal,
            ))
        }
        Effect::SensorLag => Ok(simple(
            effect,
            &["tau_fx", "tau_fy", "tau_mz"],
            vec![vec![0.0; 3]],
            [&[0.0; 3], &[0.5; 3], &[0.01; 3]],
            Variant::Lag,
        )),
        Effect::SensorBias => {
            let big: Vec<f64> = (0..3)
                .map(|c| 10.0 * super::stats::rms(log.meas.iter().map(|m| m[c])) + 1.0)
                .collect();
            Ok(simple(
                effect,
                &["b_fx", "b_fy", "b_mz"],
                vec![vec![0.0; 3]],
                [
                    &[-big[0], -big[1], -big[2]],
                    &big,
                    &[
                        ctx.noise[0].max(1e-3 * big[0]),
                        ctx.noise[1].max(1e-3 * big[1]),
                        ctx.noise[2].max(1e-3 * big[2]),
                    ],
                ],
                Variant::Bias,
            ))
        }
        Effect::ConicityPlysteer => Ok(keys_spec(effect, p, &["PHY1", "PVY1", "QHZ1"])),
    }
}

impl Spec {
    /// The `.tir` keys this effect re-fits, in the order of its parameters (`None`: an effect
    /// whose parameters are not Magic Formula coefficients).
    pub fn keys(&self) -> Option<&[Key]> {
        match &self.variant {
            Variant::Keys(k) => Some(k),
            _ => None,
        }
    }

    /// A spec re-fitting the `.tir` keys `names` of `p` (starting at `p`'s values, bounds at
    /// ±5 scales as the effects' own), labelled `effect`: what the corrected file's
    /// projection of an effect onto constant coefficients fits (`super::tirfile`).
    pub fn of_keys(effect: Effect, p: &Params<f64>, names: &[&str]) -> Spec {
        keys_spec(effect, p, names)
    }

    /// The reported value of parameter `j` (τ of `thermal` in seconds, not its logarithm).
    pub fn reported(&self, theta: &[f64]) -> Vec<(String, f64)> {
        self.names
            .iter()
            .zip(theta)
            .map(|(n, &v)| {
                if self.variant == Variant::Thermal && (n == "tau" || n == "tau_k") {
                    (n.clone(), v.exp())
                } else {
                    (n.clone(), v)
                }
            })
            .collect()
    }

    /// The parameter set with this effect's `.tir` keys at `theta` (SIM.tir's otherwise).
    pub fn params(&self, base: &Params<f64>, theta: &[f64]) -> Params<f64> {
        let mut q = base.clone();
        if let Variant::Keys(keys) = &self.variant {
            for (k, &v) in keys.iter().zip(theta) {
                q.set(*k, v);
            }
        }
        q
    }

    /// The per-row λ multipliers of the friction and pressure extensions (`None` for others).
    pub fn lambdas(&self, ctx: &Ctx, theta: &[f64]) -> Option<Vec<Lambda>> {
        let log = ctx.log;
        let n = log.len();
        match self.variant {
            Variant::PressureLambda => {
                let pr = log.p.as_ref()?;
                let f = |a: f64, d: f64| (1.0 + a * d).max(0.05);
                Some(
                    pr.iter()
                        .map(|&x| {
                            let d = (x - ctx.p_ref) / ctx.p_ref;
                            Lambda {
                                kx: f(theta[0], d),
                                ky: f(theta[1], d),
                                mux: f(theta[2], d),
                                muy: f(theta[3], d),
                            }
                        })
                        .collect(),
                )
            }
            Variant::SpeedFriction => {
                let v0 = ctx.sim.params.longvl.abs().max(1.0);
                Some(
                    (0..n)
                        .map(|i| {
                            let num = 1.0 + theta[1] * (log.vx[i].abs() - v0) / v0;
                            let den = 1.0 + theta[0] * ctx.vs[i] / v0;
                            Lambda::mu((num / den.max(0.05)).clamp(0.05, 5.0))
                        })
                        .collect(),
                )
            }
            Variant::Thermal => {
                let v0 = ctx.sim.params.longvl.abs().max(1.0);
                let h: Vec<f64> = log
                    .vx
                    .iter()
                    .map(|v| (1.0 + theta[5] * (v.abs() / v0 - 1.0)).max(0.05))
                    .collect();
                let temp = node_from(&ctx.power, &log.t, theta[4].exp(), Some(&h), theta[6]);
                // The carcass: heated by the tread, to the tread's temperature in steady state.
                let tks = node_from(&temp, &log.t, theta[7].exp(), None, theta[6]);
                Some(
                    temp.iter()
                        .zip(&tks)
                        .map(|(&tk, &tks)| {
                            let k = (1.0 + theta[3] * tks).clamp(0.05, 5.0);
                            Lambda {
                                kx: k,
                                ky: k,
                                ..Lambda::mu(
                                    (1.0 + theta[0] + theta[1] * tk + theta[2] * tk * tk)
                                        .clamp(0.05, 5.0),
                                )
                            }
                        })
                        .collect(),
                )
            }
            _ => None,
        }
    }

    /// Relaxation lengths per row for the relaxation extension.
    pub fn sigmas(&self, ctx: &Ctx, theta: &[f64]) -> Vec<[f64; 2]> {
        let p = &ctx.sim.params;
        (0..ctx.log.len())
            .map(|i| {
                let g = (1.0 + theta[2] * ctx.dfz[i]).max(0.0);
                let base = if ctx.sim.filters {
                    ctx.base.sigma[i]
                } else {
                    let fzn = (ctx.log.fz[i] / p.fnomin).max(0.0);
                    [0.5 * p.unloaded_radius * fzn, p.unloaded_radius * fzn]
                };
                [base[0] * theta[0] * g, base[1] * theta[1] * g]
            })
            .collect()
    }

    /// Predictions of the sim with this effect at `theta`: on `rows` (the fast path of a fit), or
    /// on every row, exactly (`rows = None`). `None` when the model fails at this `theta`.
    pub fn predict(&self, ctx: &Ctx, theta: &[f64], rows: Option<&[usize]>) -> Option<Vec<Out>> {
        self.predict_with(ctx, theta, rows, &ctx.base.slips)
    }

    /// [`Spec::predict`], the fast path taking its slips from `slips` (a run's).
    fn predict_with(
        &self,
        ctx: &Ctx,
        theta: &[f64],
        rows: Option<&[usize]>,
        slips: &[[f64; 2]],
    ) -> Option<Vec<Out>> {
        let (log, sim) = (ctx.log, ctx.sim);
        let all: Vec<usize>;
        let sel = match rows {
            Some(r) => r,
            None => {
                all = (0..log.len()).collect();
                &all
            }
        };
        let pick = |full: &[Out]| -> Vec<Out> { sel.iter().map(|&i| full[i]).collect() };
        match &self.variant {
            Variant::Keys(_) => {
                let q = self.params(&sim.params, theta);
                match rows {
                    Some(r) => sim.eval_rows(log, &q, slips, r, &Mods::default()).ok(),
                    None => sim.run(log, &q, &Mods::default()).ok().map(|r| r.out),
                }
            }
            Variant::PressureLambda | Variant::SpeedFriction | Variant::Thermal => {
                let l = self.lambdas(ctx, theta)?;
                let mods = Mods {
                    lambda: Some(&l),
                    ..Mods::default()
                };
                match rows {
                    Some(r) => sim.eval_rows(log, &sim.params, slips, r, &mods).ok(),
                    None => sim.run(log, &sim.params, &mods).ok().map(|r| r.out),
                }
            }
            Variant::Relaxation => {
                let sg = self.sigmas(ctx, theta);
                let slips = sim.slips(log, &sg).ok()?;
                let mods = if sim.filters {
                    Mods::default()
                } else {
                    Mods {
                        sigma: SigmaMode::Given(&sg),
                        ..Mods::default()
                    }
                };
                sim.eval_rows(log, &sim.params, &slips, sel, &mods).ok()
            }
            Variant::TurnSlipAdd => {
                let r0 = sim.params.unloaded_radius;
                Some(
                    sel.iter()
                        .map(|&i| {
                            let k = log.fz[i].max(0.0) * r0 * log.phit_at(i);
                            let b = ctx.base.out[i];
                            [b[0], b[1] + theta[0] * k, b[2] + theta[1] * k * r0]
                        })
                        .collect(),
                )
            }
            Variant::Lag => {
                let mut full = ctx.base.out.clone();
                for c in 0..3 {
                    let u: Vec<f64> = ctx.base.out.iter().map(|o| o[c]).collect();
                    for (f, y) in full.iter_mut().zip(lag(&u, &log.t, theta[c])) {
                        f[c] = y;
                    }
                }
                Some(pick(&full))
            }
            Variant::Bias => Some(
                sel.iter()
                    .map(|&i| {
                        let b = ctx.base.out[i];
                        [b[0] + theta[0], b[1] + theta[1], b[2] + theta[2]]
                    })
                    .collect(),
            ),
        }
    }

    /// Does the effect change the relaxation lengths through the slip stiffnesses (σ = |K|/C)?
    fn moves_sigma(&self, ctx: &Ctx) -> bool {
        ctx.sim.filters && matches!(self.variant, Variant::Keys(_) | Variant::PressureLambda)
    }

    /// Fits the effect on `rows` (normalised least squares over the three channels, each
    /// divided by its noise floor), from each starting point; the best fit's parameters.
    ///
    /// The fast path evaluates the Magic Formula on `rows` only, at the slips of a full run.
    /// Where the effect changes σ (a re-fitted stiffness), those slips are refreshed: after a
    /// fit, one exact run at the fitted parameters gives new slips and the fit is repeated from
    /// there, up to [`SLIP_REFRESH`] times (a fixed point: at the truth the frozen and the
    /// exact predictions agree, so clean data give the truth back).
    pub fn fit(&self, ctx: &Ctx, rows: &[usize]) -> Option<super::fit::Fit> {
        let log = ctx.log;
        let noise = ctx.noise;
        let mut slips = ctx.base.slips.clone();
        let mut starts = self.starts.clone();
        let mut best: Option<super::fit::Fit> = None;
        let refresh = if self.moves_sigma(ctx) {
            SLIP_REFRESH
        } else {
            0
        };
        for round in 0..=refresh {
            let resid = |th: &[f64]| -> Option<Vec<f64>> {
                let pred = self.predict_with(ctx, th, Some(rows), &slips)?;
                let mut r = Vec::with_capacity(3 * rows.len());
                for (k, &i) in rows.iter().enumerate() {
                    for c in 0..3 {
                        r.push((log.meas[i][c] - pred[k][c]) / noise[c]);
                    }
                }
                r.iter().all(|v| v.is_finite()).then_some(r)
            };
            if round == 0 && !self.scan.is_empty() {
                let cost = |th: &[f64]| resid(th).map(|r| r.iter().map(|v| v * v).sum::<f64>());
                let scanned = self
                    .scan
                    .iter()
                    .filter_map(|th| cost(th).map(|c| (c, th)))
                    .min_by(|a, b| a.0.total_cmp(&b.0));
                if let Some((_, th)) = scanned {
                    starts.push(th.clone());
                }
            }
            best = None;
            for s in &starts {
                if let Some(f) = super::fit::levenberg_marquardt(&resid, s, &self.bounds, 12) {
                    if best.as_ref().is_none_or(|b| f.cost < b.cost) {
                        best = Some(f);
                    }
                }
            }
            let Some(b) = &best else { break };
            if round == refresh {
                break;
            }
            let q = self.params(&ctx.sim.params, &b.theta);
            let l = self.lambdas(ctx, &b.theta);
            let mods = Mods {
                lambda: l.as_deref(),
                ..Mods::default()
            };
            let Ok(run) = ctx.sim.run(log, &q, &mods) else {
                break;
            };
            let moved = run
                .slips
                .iter()
                .zip(&slips)
                .map(|(a, b)| (a[0] - b[0]).abs().max((a[1] - b[1]).abs()))
                .fold(0.0, f64::max);
            slips = run.slips;
            starts = vec![b.theta.clone()];
            if moved < 1e-9 {
                break;
            }
        }
        best
    }
}

/// Times the slips of a fit are refreshed by an exact run (see [`Spec::fit`]).
pub const SLIP_REFRESH: usize = 2;

/// Two effects fitted together: the sim's output changed by both, their changes superposed,
/// prediction = sim + Δa(θa) + Δb(θb) with Δ = (sim with the effect) − sim. Superposition is
/// exact where the effects act on different channels or terms (a sensor bias on top of a
/// camber change) and first order where they interact (two friction factors multiply: the
/// cross term Δa·Δb/sim is left out).
#[derive(Debug, Clone)]
pub struct Pair<'s> {
    /// The first effect (the verdict of the single-effect round).
    pub a: &'s Spec,
    /// The candidate second effect.
    pub b: &'s Spec,
}

impl Pair<'_> {
    /// The superposed prediction on `rows` (`None`: every row, exact runs).
    pub fn predict(
        &self,
        ctx: &Ctx,
        theta_a: &[f64],
        theta_b: &[f64],
        rows: Option<&[usize]>,
    ) -> Option<Vec<Out>> {
        let pa = self.a.predict(ctx, theta_a, rows)?;
        let pb = self.b.predict(ctx, theta_b, rows)?;
        let n = ctx.log.len();
        let all: Vec<usize>;
        let sel = match rows {
            Some(r) => r,
            None => {
                all = (0..n).collect();
                &all
            }
        };
        Some(
            sel.iter()
                .enumerate()
                .map(|(k, &i)| {
                    let s = ctx.base.out[i];
                    [
                        pa[k][0] + pb[k][0] - s[0],
                        pa[k][1] + pb[k][1] - s[1],
                        pa[k][2] + pb[k][2] - s[2],
                    ]
                })
                .collect(),
        )
    }

    /// Fits `b` alone on `rows` on top of `a` held at `theta_a` (from each of `b`'s starts and
    /// the best of its scan). Returns θb and the fall of the cost Σ(r/σ)² from `b`'s first start
    /// (no change) to θb.
    pub fn fit_second(
        &self,
        ctx: &Ctx,
        rows: &[usize],
        theta_a: &[f64],
    ) -> Option<(Vec<f64>, f64)> {
        let log = ctx.log;
        let noise = ctx.noise;
        let pa = self.a.predict(ctx, theta_a, Some(rows))?;
        // Stage 1: b on top of the fixed a.
        let resid_b = |th: &[f64]| -> Option<Vec<f64>> {
            let pb = self.b.predict(ctx, th, Some(rows))?;
            let mut r = Vec::with_capacity(3 * rows.len());
            for (k, &i) in rows.iter().enumerate() {
                let s = ctx.base.out[i];
                for c in 0..3 {
                    r.push((log.meas[i][c] - (pa[k][c] + pb[k][c] - s[c])) / noise[c]);
                }
            }
            r.iter().all(|v| v.is_finite()).then_some(r)
        };
        let mut starts = self.b.starts.clone();
        if !self.b.scan.is_empty() {
            let cost = |th: &[f64]| resid_b(th).map(|r| r.iter().map(|v| v * v).sum::<f64>());
            if let Some((_, th)) = self
                .b
                .scan
                .iter()
                .filter_map(|th| cost(th).map(|c| (c, th)))
                .min_by(|x, y| x.0.total_cmp(&y.0))
            {
                starts.push(th.clone());
            }
        }
        let mut best: Option<super::fit::Fit> = None;
        for s in &starts {
            if let Some(f) = super::fit::levenberg_marquardt(&resid_b, s, &self.b.bounds, 12) {
                if best.as_ref().is_none_or(|b| f.cost < b.cost) {
                    best = Some(f);
                }
            }
        }
        let c0 = resid_b(&self.b.starts[0]).map(|r| 0.5 * r.iter().map(|v| v * v).sum::<f64>())?;
        let best = best?;
        Some((best.theta, 2.0 * (c0 - best.cost)))
    }

    /// Fits both on `rows`: first `b` alone on top of `a` at `start_a`
    /// ([`Pair::fit_second`]), then both together from there. Returns (θa, θb).
    pub fn fit(&self, ctx: &Ctx, rows: &[usize], start_a: &[f64]) -> Option<(Vec<f64>, Vec<f64>)> {
        let log = ctx.log;
        let noise = ctx.noise;
        let tb = self
            .fit_second(ctx, rows, start_a)
            .map(|f| f.0)
            .unwrap_or_else(|| self.b.starts[0].clone());
        // Stage 2: both together.
        let na = start_a.len();
        let resid = |th: &[f64]| -> Option<Vec<f64>> {
            let p = self.predict(ctx, &th[..na], &th[na..], Some(rows))?;
            let mut r = Vec::with_capacity(3 * rows.len());
            for (k, &i) in rows.iter().enumerate() {
                for c in 0..3 {
                    r.push((log.meas[i][c] - p[k][c]) / noise[c]);
                }
            }
            r.iter().all(|v| v.is_finite()).then_some(r)
        };
        let cat = |x: &[f64], y: &[f64]| -> Vec<f64> { x.iter().chain(y).copied().collect() };
        let bounds = super::fit::Bounds {
            lo: cat(&self.a.bounds.lo, &self.b.bounds.lo),
            hi: cat(&self.a.bounds.hi, &self.b.bounds.hi),
            scale: cat(&self.a.bounds.scale, &self.b.bounds.scale),
        };
        let start = cat(start_a, &tb);
        let th = super::fit::levenberg_marquardt(&resid, &start, &bounds, 8)
            .map(|f| f.theta)
            .unwrap_or(start);
        Some((th[..na].to_vec(), th[na..].to_vec()))
    }
}
