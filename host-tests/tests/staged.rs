//! The staged Magic Formula (`gough::mf::prepared`, issue 38) on every MFeval oracle sweep:
//! - the slip stage of a load stage built once per operating point (Fz, γ, φt, Vx, p) gives
//!   `mf::eval`'s Fx, Fy, Mz, t, Mzr (f64 Libm, f32 Libm, f32 Fast), and so meets the oracle
//!   within the budgets of `gough_host_tests::tolerance`; the friction stage remade by
//!   `with_mu(LMUX, LMUY)` gives the same;
//! - the slopes ∂/∂κ, ∂/∂α (`eval_d`) and ∂/∂λμ (`eval_d_mu`) equal central differences of
//!   `mf::eval` in f64 to 1e-6 relative (floor: 1e-6·FNOMIN per unit slip, ·R0 for Mz), away
//!   from kinks. A kink (a sign switch, a clip) is a point whose one-sided differences differ;
//!   those are counted, printed, and there the slope must equal one of the one-sided ones.
//!
//! Turn-slip sweeps (mode xx2) have no load stage (`Prepared::new` refuses them) and are
//! counted as skipped.

use gough::math::{Fast, Libm};
use gough::mf::prepared::{Operating, Partials, Prepared};
use gough::mf::{self, EvalError, Input, Options, Params};
use gough_host::csvio;
use gough_host::mfrun::{InputRow, Precision};
use gough_host_tests::tolerance;
use std::path::{Path, PathBuf};

fn data() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("data")
}

fn sweeps() -> Vec<(PathBuf, String, Options)> {
    let files = gough_host_tests::oracle_files();
    files
        .into_iter()
        .map(|f| {
            let stem = f.file_stem().unwrap().to_str().unwrap().to_string();
            let mut parts = stem.split("__");
            let tyre = parts.next().unwrap().to_string();
            let mode: u16 = parts
                .nth(1)
                .unwrap()
                .trim_start_matches("mode")
                .parse()
                .unwrap();
            (f, tyre, Options::from_use_mode(mode).unwrap())
        })
        .collect()
}

fn params(tyre: &str) -> Params<f64> {
    let name = tyre.strip_suffix("_mfeval40").unwrap_or(tyre);
    let text = std::fs::read_to_string(data().join("tyres").join(format!("{name}.tir"))).unwrap();
    gough::tir::parse(&text).unwrap().params
}

fn rows(path: &Path) -> Vec<Input<f64>> {
    let rows = csvio::read_with::<InputRow>(path, true).unwrap();
    rows.rows.iter().map(InputRow::input).collect()
}

fn f32_input(i: &Input<f64>) -> Input<f32> {
    Input {
        fz: i.fz as f32,
        kappa: i.kappa as f32,
        alpha: i.alpha as f32,
        gamma: i.gamma as f32,
        phit: i.phit as f32,
        vx: i.vx as f32,
        p: i.p.map(|x| x as f32),
    }
}

/// Builds a load stage only when the operating point changes (as a caller would), evaluates
/// the slip stage, and returns (Fx, Fy, Mz, t, Mzr) of it and of `mf::eval`.
struct Cached<F> {
    op: Option<Operating<F>>,
    prep: Option<Prepared<F>>,
    builds: usize,
}

impl<F: gough::math::Float> Cached<F> {
    fn new() -> Self {
        Cached {
            op: None,
            prep: None,
            builds: 0,
        }
    }
    fn get<M: gough::math::Backend<F>>(
        &mut self,
        p: &Params<F>,
        i: &Input<F>,
        opts: &Options,
    ) -> Result<Prepared<F>, EvalError> {
        let op = Operating::from(i);
        if self.op != Some(op) || self.prep.is_none() {
            self.prep = Some(Prepared::new::<M>(p, &op, opts)?);
            self.op = Some(op);
            self.builds += 1;
        }
        Ok(self.prep.unwrap())
    }
}

/// The slip stage vs `mf::eval` and the oracle budget, in one float type and backend.
fn slip_stage_equals_eval<F: gough::math::Float, M: gough::math::Backend<F>>(
    prec: Precision,
    conv: impl Fn(&Input<f64>) -> Input<F>,
) {
    let (mut files, mut n, mut builds, mut skipped) = (0, 0, 0, 0);
    let mut worst = 0f64;
    for (path, tyre, opts) in sweeps() {
        if opts.turn_slip {
            skipped += 1;
            continue;
        }
        files += 1;
        let p64 = params(&tyre);
        let p: Params<F> = p64.cast();
        let budget = tolerance::force(p64.fnomin, prec);
        let mut cache = Cached::<F>::new();
        for i in rows(&path).iter().map(&conv) {
            let want = mf::eval::<F, M>(&p, &i, &opts).unwrap();
            let prep = cache.get::<M>(&p, &i, &opts).unwrap();
            let got = prep.eval::<M>(i.kappa, i.alpha).unwrap();
            let again = prep
                .eval_with::<M>(&prep.with_mu(p.lmux, p.lmuy), i.kappa, i.alpha)
                .unwrap();
            assert_eq!(got, again, "{path:?} {i:?}");
            let pairs = [
                (got.fx, want.fx, 1.0),
                (got.fy, want.fy, 1.0),
                (got.mz, want.mz, p64.unloaded_radius),
                (got.t, want.t, 1.0 / p64.fnomin),
                (got.m_zr, want.m_zr, p64.unloaded_radius),
            ];
            for (g, w, unit) in pairs {
                let e = (g.to_f64() - w.to_f64()).abs() / unit;
                worst = worst.max(e / p64.fnomin);
                assert!(e <= budget, "{path:?} {i:?}: {g:?} vs {w:?}");
            }
            assert_eq!(got.kappa.to_f64(), want.kappa.to_f64());
            assert_eq!(got.flags, want.flags, "{path:?} {i:?}");
            n += 1;
        }
        builds += cache.builds;
    }
    println!(
        "{prec:?} {}: {n} rows of {files} sweeps ({skipped} turn-slip sweeps skipped), {builds} load stages; max |slip stage − mf::eval| = {worst:.1e}·FNOMIN",
        core::any::type_name::<M>()
    );
    assert!(files >= 60 && n > 5000);
}

#[test]
fn slip_stage_is_eval_f64() {
    slip_stage_equals_eval::<f64, Libm>(Precision::F64, |i| *i);
}

#[test]
fn slip_stage_is_eval_f32() {
    slip_stage_equals_eval::<f32, Libm>(Precision::F32, f32_input);
    slip_stage_equals_eval::<f32, Fast>(Precision::F32, f32_input);
}

/// Central, forward and backward differences of g at step h.
fn diffs(g: &dyn Fn(f64) -> Partials<f64>, x: f64, h: f64) -> [Partials<f64>; 3] {
    let (a, b, c) = (g(x - h), g(x), g(x + h));
    let d = |u: Partials<f64>, v: Partials<f64>, s: f64| Partials {
        fx: (v.fx - u.fx) / s,
        fy: (v.fy - u.fy) / s,
        mz: (v.mz - u.mz) / s,
    };
    [d(a, c, 2.0 * h), d(b, c, h), d(a, b, h)]
}

#[derive(Default)]
struct Tally {
    n: usize,
    kinks: usize,
    worst: f64,
}

impl Tally {
    /// Checks one slope against the differences; `floor` is the absolute floor of each
    /// component \[N or N·m per unit\].
    fn check(&mut self, what: &str, d: Partials<f64>, fd: [Partials<f64>; 3], floor: [f64; 3]) {
        let [c, fwd, bwd] = fd;
        let comp = |p: Partials<f64>| [p.fx, p.fy, p.mz];
        let (d, c, fwd, bwd) = (comp(d), comp(c), comp(fwd), comp(bwd));
        let kink = (0..3).any(|k| (fwd[k] - bwd[k]).abs() > 1e-3 * (c[k].abs() + floor[k]));
        if kink {
            // The slope of the branch taken: one of the one-sided ones.
            self.kinks += 1;
            for k in 0..3 {
                let tol = 1e-3 * (d[k].abs() + floor[k]);
                assert!(
                    (d[k] - fwd[k]).abs() <= tol
                        || (d[k] - bwd[k]).abs() <= tol
                        || (d[k] - c[k]).abs() <= tol,
                    "{what} (kink) component {k}: {} vs one-sided {} / {}",
                    d[k],
                    fwd[k],
                    bwd[k]
                );
            }
            return;
        }
        self.n += 1;
        for k in 0..3 {
            let e = (d[k] - c[k]).abs() / (c[k].abs() + floor[k]);
            self.worst = self.worst.max(e);
            assert!(
                e <= 1e-6,
                "{what} component {k}: slope {} vs central difference {}",
                d[k],
                c[k]
            );
        }
    }
}

#[test]
fn slopes_are_central_differences() {
    let (mut tk, mut ta, mut tm, mut ts) = (
        Tally::default(),
        Tally::default(),
        Tally::default(),
        Tally::default(),
    );
    for (path, tyre, opts) in sweeps() {
        if opts.turn_slip {
            continue;
        }
        let p = params(&tyre);
        let (fz0, r0) = (p.fnomin, p.unloaded_radius);
        let floor = [1e-6 * fz0, 1e-6 * fz0, 1e-6 * fz0 * r0];
        let mut cache = Cached::<f64>::new();
        // Every 4th row: the slopes cost three evaluations each way.
        for i in rows(&path).iter().step_by(4) {
            let prep = cache.get::<Libm>(&p, i, &opts).unwrap();
            let (v, d) = prep.eval_d::<Libm>(prep.mu(), i.kappa, i.alpha).unwrap();
            let plain = prep.eval::<Libm>(i.kappa, i.alpha).unwrap();
            assert_eq!(v, plain, "values of eval_d are eval's");
            let at = |k: f64, a: f64, q: &Params<f64>| {
                let o = mf::eval::<f64, Libm>(
                    q,
                    &Input {
                        kappa: k,
                        alpha: a,
                        ..*i
                    },
                    &opts,
                )
                .unwrap();
                Partials {
                    fx: o.fx,
                    fy: o.fy,
                    mz: o.mz,
                }
            };
            let what = format!("{path:?} {i:?}");
            let h = 1e-6;
            tk.check(
                &format!("d/dkappa {what}"),
                d.kappa,
                diffs(&|k| at(k, i.alpha, &p), i.kappa, h),
                floor,
            );
            ta.check(
                &format!("d/dalpha {what}"),
                d.alpha,
                diffs(&|a| at(i.kappa, a, &p), i.alpha, h),
                floor,
            );
            if p.lmux == p.lmuy {
                let (vm, dm) = prep.eval_d_mu::<Libm>(p.lmux, i.kappa, i.alpha).unwrap();
                assert_eq!(vm, plain);
                assert_eq!(dm.slip, d, "the κ, α slopes do not depend on carrying λμ");
                let scaled = |l: f64| {
                    let mut q = p.clone();
                    q.lmux = l;
                    q.lmuy = l;
                    at(i.kappa, i.alpha, &q)
                };
                tm.check(
                    &format!("d/dlmu {what}"),
                    dm.lmu,
                    diffs(&scaled, p.lmux, h),
                    floor,
                );
            }
            // Both scalings times s (the friction estimator's slope in a road's μ), at s = 1,
            // also where the file's λμx and λμy differ.
            let (vs, ds) = prep
                .eval_d_scale::<Libm>(p.lmux, p.lmuy, i.kappa, i.alpha)
                .unwrap();
            assert_eq!(vs, plain);
            assert_eq!(
                ds.slip, d,
                "the κ, α slopes do not depend on carrying the scale"
            );
            let times = |s: f64| {
                let mut q = p.clone();
                q.lmux = p.lmux * s;
                q.lmuy = p.lmuy * s;
                at(i.kappa, i.alpha, &q)
            };
            ts.check(
                &format!("d/ds {what}"),
                ds.lmu,
                diffs(&times, 1.0, h),
                floor,
            );
        }
    }
    for (name, t) in [
        ("kappa", &tk),
        ("alpha", &ta),
        ("lambda_mu", &tm),
        ("scale", &ts),
    ] {
        println!(
            "d/d{name}: {} points within {:.1e} relative of central differences; {} kinks (one-sided slopes checked)",
            t.n, t.worst, t.kinks
        );
        // Many sweep rows sit exactly on α = 0 or κ = 0, where Mz has its sign kinks.
        assert!(
            t.n > 1000 && t.kinks * 6 < t.n,
            "{name}: {} kinks of {}",
            t.kinks,
            t.n
        );
    }
}

/// A scaling that is not finite is refused with `NonFinite(P)`, as `eval_d_mu` refuses one, and
/// a bad slip before it; never a NaN out.
#[test]
fn a_scaled_friction_stage_refuses_what_is_not_finite() {
    use gough::mf::InputField;
    let p = params("MagicFormula61_Parameters");
    let op = Operating {
        fz: p.fnomin,
        gamma: 0.0,
        phit: 0.0,
        vx: 20.0,
        p: None,
    };
    let prep = Prepared::new::<Libm>(&p, &op, &Options::default()).unwrap();
    for (lx, ly) in [
        (f64::NAN, 1.0),
        (1.0, f64::INFINITY),
        (f64::NEG_INFINITY, f64::NAN),
    ] {
        assert_eq!(
            prep.eval_d_scale::<Libm>(lx, ly, 0.0, 0.01).err(),
            Some(EvalError::NonFinite(InputField::P)),
            "{lx} {ly}"
        );
    }
    assert!(matches!(
        prep.eval_d_scale::<Libm>(1.0, 1.0, f64::NAN, 0.01),
        Err(EvalError::NonFinite(_))
    ));
    let (f, d) = prep.eval_d_scale::<Libm>(0.3, 0.25, 0.0, 0.01).unwrap();
    assert!([f.fx, f.fy, f.mz, d.lmu.fx, d.lmu.fy, d.lmu.mz]
        .iter()
        .all(|v| v.is_finite()));
}

/// `Prepared::adjusted` is the file with λKx, λt scaled, QBZ1–QBZ3 scaled and QHZ1 shifted: on
/// every oracle sweep that has a load stage, an adjusted load stage gives what `mf::eval` gives
/// on the file so changed (f64, within 1e-9 of FNOMIN and of FNOMIN·R0).
#[test]
fn an_adjusted_load_stage_is_the_file_with_the_keys_changed() {
    use gough::mf::prepared::Adjust;
    let a = Adjust {
        kx: 0.93,
        trail: 1.07,
        trail_shape: 0.95,
        trail_shift: 0.0015,
    };
    let mut checked = 0;
    for (path, tyre, opts) in sweeps() {
        if opts.turn_slip {
            continue;
        }
        let p = params(&tyre);
        let mut q = p.clone();
        q.lkx *= a.kx;
        q.ltr *= a.trail;
        q.qbz1 *= a.trail_shape;
        q.qbz2 *= a.trail_shape;
        q.qbz3 *= a.trail_shape;
        q.qhz1 += a.trail_shift;
        let (tol_f, tol_m) = (1e-9 * p.fnomin, 1e-9 * p.fnomin * p.unloaded_radius);
        for i in rows(&path) {
            let Ok(prep) = Prepared::new::<Libm>(&p, &Operating::from(&i), &opts) else {
                continue;
            };
            let Ok(f) = prep.adjusted(&a).eval::<Libm>(i.kappa, i.alpha) else {
                continue;
            };
            let o = mf::eval::<f64, Libm>(&q, &i, &opts).unwrap();
            assert!(
                (f.fx - o.fx).abs() <= tol_f
                    && (f.fy - o.fy).abs() <= tol_f
                    && (f.mz - o.mz).abs() <= tol_m,
                "{}: {:?}: adjusted {} {} {}, file changed {} {} {}",
                path.display(),
                i,
                f.fx,
                f.fy,
                f.mz,
                o.fx,
                o.fy,
                o.mz
            );
            checked += 1;
        }
    }
    assert!(checked > 1000, "{checked} points");
    // NONE is the file, to the bit.
    let p = params("MagicFormula61_Parameters");
    let i = Input {
        fz: 5000.0,
        alpha: 0.05,
        kappa: -0.03,
        vx: 20.0,
        ..Input::default()
    };
    let prep = Prepared::new::<Libm>(&p, &Operating::from(&i), &Options::default()).unwrap();
    let (f0, f1) = (
        prep.eval::<Libm>(i.kappa, i.alpha).unwrap(),
        prep.adjusted(&Adjust::NONE)
            .eval::<Libm>(i.kappa, i.alpha)
            .unwrap(),
    );
    assert_eq!((f0.fx, f0.fy, f0.mz), (f1.fx, f1.fy, f1.mz));
}
