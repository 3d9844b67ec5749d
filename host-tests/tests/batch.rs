//! `mf::eval_batch` against `mf::eval` at every point of the MFeval oracle (every file, every
//! useMode, MF 5.2, 6.1, 6.2 and the book's tyre): equal to the bit, in f64 and f32, every
//! output column and the flags.
use gough::math::{Backend, Float, Libm};
use gough::mf::{self, Columns, Flags, Input, Isa, Options, Output, Outputs, Params};
use gough_host::csvio;
use gough_host::mfrun::InputRow;
use std::path::{Path, PathBuf};

fn data() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("data")
}

fn tyre_for(stem: &str) -> PathBuf {
    let name = stem.strip_suffix("_mfeval40").unwrap_or(stem);
    data().join("tyres").join(format!("{name}.tir"))
}

/// One oracle file: its name, options, parameters and inputs.
type OracleFile = (String, Options, Params<f64>, Vec<Input<f64>>);

/// Every oracle file.
fn oracle() -> Vec<OracleFile> {
    let files = gough_host_tests::oracle_files();
    files
        .iter()
        .map(|f| {
            let name = f.file_stem().unwrap().to_str().unwrap().to_string();
            let mut parts = name.split("__");
            let (stem, _sweep, mode) = (
                parts.next().unwrap(),
                parts.next().unwrap(),
                parts.next().unwrap(),
            );
            let mode: u16 = mode.trim_start_matches("mode").parse().unwrap();
            let text = std::fs::read_to_string(tyre_for(stem)).unwrap();
            let p: Params<f64> = gough::tir::parse(&text).unwrap().params;
            let rows = csvio::read_with::<InputRow>(f, true).unwrap();
            let inputs = rows.rows.iter().map(InputRow::input).collect();
            (name, Options::from_use_mode(mode).unwrap(), p, inputs)
        })
        .collect()
}

/// The batch's 15 value columns and flags at every point (every column asked for).
fn batch<F: Float, M: Backend<F>>(
    p: &Params<F>,
    inputs: &[Input<F>],
    opts: &Options,
) -> (Vec<[F; 15]>, Vec<Flags>) {
    batch_by(p, inputs, |cols, out| {
        mf::eval_batch::<F, M>(p, cols, opts, out).unwrap();
    })
}

/// The 15 value columns and flags that `run` writes at every point (every column asked for).
fn batch_by<F: Float>(
    p: &Params<F>,
    inputs: &[Input<F>],
    run: impl FnOnce(&Columns<'_, F>, &mut Outputs<'_, F>),
) -> (Vec<[F; 15]>, Vec<Flags>) {
    let col = |f: fn(&Input<F>) -> F| inputs.iter().map(f).collect::<Vec<F>>();
    let (fz, kappa, alpha, gamma, vx, phit) = (
        col(|i| i.fz),
        col(|i| i.kappa),
        col(|i| i.alpha),
        col(|i| i.gamma),
        col(|i| i.vx),
        col(|i| i.phit),
    );
    // p = None is INFLPRES: the column carries that value (what `None` gives).
    let pres: Vec<F> = inputs.iter().map(|i| i.p.unwrap_or(p.inflpres)).collect();
    let cols = Columns {
        fz: &fz,
        kappa: &kappa,
        alpha: &alpha,
        gamma: &gamma,
        vx: &vx,
        phit: Some(&phit),
        p: Some(&pres),
    };
    let n = inputs.len();
    let mut c: Vec<Vec<F>> = vec![vec![F::ZERO; n]; 15];
    let mut flags = vec![Flags::default(); n];
    {
        let mut it = c.iter_mut();
        let mut next = || Some(it.next().unwrap().as_mut_slice());
        let mut out = Outputs {
            fx: next(),
            fy: next(),
            fz: next(),
            mx: next(),
            my: next(),
            mz: next(),
            mu_x: next(),
            mu_y: next(),
            k_xk: next(),
            k_ya: next(),
            t: next(),
            m_zr: next(),
            sigma_x: next(),
            sigma_y: next(),
            kappa: next(),
            flags: Some(&mut flags),
        };
        run(&cols, &mut out);
    }
    let rows = (0..n).map(|i| core::array::from_fn(|k| c[k][i])).collect();
    (rows, flags)
}

fn fields<F: Copy>(o: &Output<F>) -> [F; 15] {
    [
        o.fx, o.fy, o.fz, o.mx, o.my, o.mz, o.mu_x, o.mu_y, o.k_xk, o.k_ya, o.t, o.m_zr, o.sigma_x,
        o.sigma_y, o.kappa,
    ]
}

#[test]
fn batch_equals_eval_to_the_bit_at_every_oracle_point() {
    let mut points = 0;
    for (name, opts, p64, inputs) in oracle() {
        let (rows, flags) = batch::<f64, Libm>(&p64, &inputs, &opts);
        for (i, input) in inputs.iter().enumerate() {
            let o = mf::eval::<f64, Libm>(&p64, input, &opts).unwrap();
            let want = fields(&o).map(f64::to_bits);
            assert_eq!(rows[i].map(f64::to_bits), want, "{name} f64 point {i}");
            assert_eq!(flags[i], o.flags, "{name} f64 point {i}");
        }
        let p32 = p64.cast::<f32>();
        let in32: Vec<Input<f32>> = inputs
            .iter()
            .map(|i| Input {
                fz: i.fz as f32,
                kappa: i.kappa as f32,
                alpha: i.alpha as f32,
                gamma: i.gamma as f32,
                phit: i.phit as f32,
                vx: i.vx as f32,
                p: i.p.map(|x| x as f32),
            })
            .collect();
        let (rows, flags) = batch::<f32, Libm>(&p32, &in32, &opts);
        for (i, input) in in32.iter().enumerate() {
            let o = mf::eval::<f32, Libm>(&p32, input, &opts).unwrap();
            assert_eq!(
                rows[i].map(f32::to_bits),
                fields(&o).map(f32::to_bits),
                "{name} f32 point {i}"
            );
            assert_eq!(flags[i], o.flags, "{name} f32 point {i}");
        }
        points += inputs.len();
    }
    println!("batch = eval to the bit at {points} oracle points, f64 and f32");
}

/// The lanes (`mf::eval_batch_lanes_on`, every instruction set this processor has: 16, 8 and 4
/// lanes) against `mf::eval::<f64, Libm>` at every oracle point (MF 5.2, 6.1, 6.2, the book's
/// tyre, every useMode): every output column within 1e-9·FNOMIN (N, N·m, and the
/// dimensionless and length columns in the same number), the flags equal; and the lanes did
/// evaluate the points, those with turn slip too (all but chunks mixing contact with none).
#[test]
fn lanes_within_1e9_fnomin_of_eval_at_every_oracle_point() {
    on_big_stack(lanes_at_every_oracle_point);
}

/// Runs `f` on a thread with 16 MiB of stack. This crate's tests are unoptimised, and so are
/// the lanes that `mf::eval_batch_lanes_on` compiles in it (it is `#[inline]`): unoptimised,
/// the 16 lanes overflow a test thread's 2 MiB (4 MiB was enough), as the doc of
/// `mf::eval_batch_lanes` says.
fn on_big_stack(f: fn()) {
    std::thread::Builder::new()
        .stack_size(16 << 20)
        .spawn(f)
        .unwrap()
        .join()
        .unwrap();
}

fn lanes_at_every_oracle_point() {
    for isa in [Isa::Avx512, Isa::Avx2, Isa::Baseline] {
        let (mut points, mut in_lanes, mut worst) = (0, 0, 0.0f64);
        // Points in chunks of 16 (the widest; a narrower chunk lies inside one) that mix
        // Fz > 0 with Fz ≤ 0: those the lanes may hand to `mf::eval`.
        let mut mixed = 0;
        // The turn-slip points, those of them in lanes, and in mixed chunks.
        let (mut turn_slip, mut turn_in_lanes, mut turn_mixed) = (0, 0, 0);
        for (name, opts, p64, inputs) in oracle() {
            let mut lanes = 0;
            let (rows, flags) = batch_by(&p64, &inputs, |cols, out| {
                lanes = mf::eval_batch_lanes_on(isa, &p64, cols, &opts, out).unwrap();
            });
            for (i, input) in inputs.iter().enumerate() {
                let o = mf::eval::<f64, Libm>(&p64, input, &opts).unwrap();
                for (k, (got, want)) in rows[i].iter().zip(fields(&o)).enumerate() {
                    let err = (got - want).abs() / p64.fnomin;
                    assert!(
                        err <= 1e-9,
                        "{name} {isa:?} point {i} column {k}: {got} vs {want}"
                    );
                    worst = worst.max(err);
                }
                assert_eq!(flags[i], o.flags, "{name} {isa:?} point {i}");
            }
            let mut file_mixed = 0;
            for c in inputs.chunks(16) {
                let contact = c.iter().filter(|i| i.fz > 0.0).count();
                if contact != 0 && contact != c.len() {
                    file_mixed += c.len();
                }
            }
            mixed += file_mixed;
            if opts.turn_slip {
                turn_slip += inputs.len();
                turn_in_lanes += lanes;
                turn_mixed += file_mixed;
            }
            points += inputs.len();
            in_lanes += lanes;
        }
        println!(
            "{isa:?}: {in_lanes} of {points} oracle points in lanes ({turn_in_lanes} of the \
             {turn_slip} with turn slip; {mixed} in chunks of 16 mixing Fz > 0 and Fz ≤ 0), \
             max |lanes − eval| = {worst:.1e}·FNOMIN"
        );
        // Only chunks that mix contact with no contact run point by point.
        assert!(
            in_lanes + mixed >= points,
            "{in_lanes} + {mixed} of {points}"
        );
        assert!(turn_slip > 0 && turn_in_lanes + turn_mixed >= turn_slip);
    }
}

/// One bundled tyre file's parameters.
fn tyre(stem: &str) -> Params<f64> {
    let text = std::fs::read_to_string(tyre_for(stem)).unwrap();
    gough::tir::parse(&text).unwrap().params
}

/// The lanes at points that take different sides of the value branches within one chunk
/// (Vx from −1 to 29 m/s: reverse, low speed; κ, α, Fz beyond the file's limits; γ = 0 and
/// not): within 1e-9·FNOMIN of `mf::eval`, the flags equal, on every instruction set, with
/// the moments and σ asked for; every point in lanes.
#[test]
fn lanes_agree_with_eval_across_branches() {
    on_big_stack(lanes_across_branches);
}

fn lanes_across_branches() {
    let p = tyre("MagicFormula61_Parameters");
    let n = 203; // not a multiple of any width: the last chunk is padded
    let f = |i: usize| ((i * 37) % n) as f64 / (n - 1) as f64;
    let col = |g: &dyn Fn(usize) -> f64| (0..n).map(g).collect::<Vec<f64>>();
    let fz = col(&|i| p.fnomin * (0.2 + 4.8 * f(i)));
    let kappa = col(&|i| -1.2 + 1.8 * f((i * 7) % n));
    let alpha = col(&|i| 1.1 * (2.0 * f((i * 11) % n) - 1.0));
    let gamma = col(&|i| {
        if i % 3 == 0 {
            0.0
        } else {
            0.3 * f((i * 5) % n) - 0.1
        }
    });
    let vx = col(&|i| 30.0 * f((i * 13) % n) - 1.0);
    // Turn slip: φt from −2 to 2 /m, 0 on every fourth point (with γ = 0 on every third: chunks
    // with and without camber spin, with and without spin at all).
    let phit = col(&|i| {
        if i % 4 == 0 {
            0.0
        } else {
            4.0 * f((i * 17) % n) - 2.0
        }
    });
    for turn_slip in [false, true] {
        lanes_across_branches_with(&p, [&fz, &kappa, &alpha, &gamma, &vx, &phit], turn_slip);
    }
}

/// `lanes_across_branches` on its columns (fz, κ, α, γ, Vx, φt), with or without turn slip.
fn lanes_across_branches_with(p: &Params<f64>, cols: [&[f64]; 6], turn_slip: bool) {
    let [fz, kappa, alpha, gamma, vx, phit] = cols;
    let n = fz.len();
    let cols = Columns {
        fz,
        kappa,
        alpha,
        gamma,
        vx,
        phit: turn_slip.then_some(phit),
        p: None,
    };
    let opts = Options {
        turn_slip,
        ..Options::default()
    };
    for isa in [Isa::Avx512, Isa::Avx2, Isa::Baseline] {
        let mut c: [Vec<f64>; 6] = std::array::from_fn(|_| vec![0.0; n]);
        let mut flags = vec![Flags::default(); n];
        let [fx, fy, mz, mx, my, sy] = &mut c;
        let mut out = Outputs {
            fx: Some(fx),
            fy: Some(fy),
            mz: Some(mz),
            mx: Some(mx),
            my: Some(my),
            sigma_y: Some(sy),
            flags: Some(&mut flags),
            ..Outputs::default()
        };
        let in_lanes = mf::eval_batch_lanes_on(isa, p, &cols, &opts, &mut out).unwrap();
        assert_eq!(in_lanes, n, "{isa:?} turn slip {turn_slip}");
        let mut seen = Flags::default();
        for i in 0..n {
            let input = Input {
                fz: fz[i],
                kappa: kappa[i],
                alpha: alpha[i],
                gamma: gamma[i],
                phit: if turn_slip { phit[i] } else { 0.0 },
                vx: vx[i],
                p: None,
            };
            let o = mf::eval::<f64, Libm>(p, &input, &opts).unwrap();
            for (k, w) in [o.fx, o.fy, o.mz, o.mx, o.my, o.sigma_y].iter().enumerate() {
                let err = (c[k][i] - w).abs() / p.fnomin;
                assert!(
                    err <= 1e-9,
                    "{isa:?} turn slip {turn_slip} point {i} column {k}: {} vs {w}",
                    c[k][i]
                );
            }
            assert_eq!(flags[i], o.flags, "{isa:?} turn slip {turn_slip} point {i}");
            seen.insert(o.flags);
        }
        // The points did take the branches in question.
        for f in [
            Flags::REVERSE,
            Flags::LOW_SPEED,
            Flags::KAPPA,
            Flags::ALPHA,
            Flags::GAMMA,
            Flags::FZ_HIGH,
        ] {
            assert!(seen.contains(f), "{f:?} never raised");
        }
    }
}

/// `mf::eval_batch_lanes_scaled`: every oracle point with its own factors on λμx, λμy, λKx, λKy
/// (0.7–1.3, a different one at each point) against `mf::eval` on the file with those factors
/// multiplied in: within 1e-9·FNOMIN, the flags equal; a scale column of the wrong length is an
/// error before anything is written.
#[test]
fn scaled_lanes_equal_eval_on_each_points_parameters() {
    on_big_stack(scaled_lanes);
}

fn scaled_lanes() {
    let frac = |x: f64| x - x.floor();
    let (mut points, mut worst) = (0, 0.0f64);
    for (name, opts, p64, inputs) in oracle() {
        let n = inputs.len();
        let factor = |k: f64| -> Vec<f64> {
            (0..n)
                .map(|i| 0.7 + 0.6 * frac((i as f64 + k) * 0.618_033_988_7))
                .collect()
        };
        let (lmux, lmuy, lkx, lky) = (factor(0.1), factor(0.3), factor(0.5), factor(0.7));
        let scales = mf::Scales {
            lmux: Some(&lmux),
            lmuy: Some(&lmuy),
            lkx: Some(&lkx),
            lky: Some(&lky),
        };
        let mut lanes = 0;
        let (rows, flags) = batch_by(&p64, &inputs, |cols, out| {
            lanes =
                mf::eval_batch_lanes_scaled(Isa::Auto, &p64, cols, &scales, &opts, out).unwrap();
        });
        for (i, input) in inputs.iter().enumerate() {
            let mut q = p64.clone();
            q.lmux *= lmux[i];
            q.lmuy *= lmuy[i];
            q.lkx *= lkx[i];
            q.lky *= lky[i];
            let o = mf::eval::<f64, Libm>(&q, input, &opts).unwrap();
            for (k, (got, want)) in rows[i].iter().zip(fields(&o)).enumerate() {
                let err = (got - want).abs() / p64.fnomin;
                assert!(err <= 1e-9, "{name} point {i} column {k}: {got} vs {want}");
                worst = worst.max(err);
            }
            assert_eq!(flags[i], o.flags, "{name} point {i}");
        }
        assert!(lanes > 0, "{name}: no point in lanes");
        points += n;
    }
    println!(
        "scaled lanes = eval on each point's λ at {points} oracle points, max {worst:.1e}·FNOMIN"
    );
    // A scale column of another length than the inputs.
    let (_, _, p64, inputs) = oracle().swap_remove(0);
    let short = vec![1.0; inputs.len() - 1];
    let scales = mf::Scales {
        lky: Some(&short),
        ..mf::Scales::default()
    };
    let opts = Options::default();
    batch_by(&p64, &inputs, |cols, out| {
        let e = mf::eval_batch_lanes_scaled(Isa::Auto, &p64, cols, &scales, &opts, out);
        assert!(
            matches!(e, Err(mf::BatchError::Length { column: "lky", .. })),
            "{e:?}"
        );
    });
}
