//! ns per combined-slip Fx/Fy/Mz evaluation (with Mx, My, t, Mzr, σ), per version, f32 and f64,
//! libm backend, limits on. Host only; device costs are counted in instructions under QEMU.
//!
//! Then, per slip-stage evaluation (`mf::prepared`), the slip stage alone and with its slopes.
//!
//! Then the batch (`mf::eval_batch`, issue 57): Fx, Fy, Mz at 4,096 random combined-slip points
//! per iteration, MF 5.2, 6.1, 6.2, f64 (`Libm`) and f32 (`Libm`; `Fast` with the
//! feature), points/s in criterion's "thrpt" — and the scalar `mf::eval` over the same points;
//! and the f64 lanes (`mf::eval_batch_lanes_on`: AVX-512F, AVX2, two lanes; the instruction
//! sets are detected at run time, with the `std` feature, which the dev-dependency below
//! turns on).
//!
//! `cargo bench --bench mf_eval` (`-- batch` for the batch groups alone)
use criterion::{criterion_group, criterion_main, Criterion};
use gough::math::{Backend, Float, Libm};
use gough::mf::prepared::{Operating, Prepared};
use gough::mf::{self, Columns, Input, Options, Outputs, Params};
use std::hint::black_box;

const FILES: &[(&str, &str)] = &[
    (
        "Delft96 (FITTYP 5)",
        include_str!("../host-tests/data/tyres/335_65R22_5_G275MSA_60psi.tir"),
    ),
    (
        "MF 5.2",
        include_str!("../host-tests/data/tyres/MagicFormula52_Parameters.tir"),
    ),
    (
        "MF 6.1",
        include_str!("../host-tests/data/tyres/MagicFormula61_Parameters.tir"),
    ),
    (
        "MF 6.2",
        include_str!("../host-tests/data/tyres/MagicFormula62_Parameters.tir"),
    ),
];

/// 64 combined-slip operating points around the nominal load (braking, cornering, camber).
fn inputs(fnomin: f64) -> Vec<Input<f64>> {
    (0..64)
        .map(|i| {
            let f = i as f64 / 63.0;
            Input {
                fz: fnomin * (0.6 + 0.8 * f),
                kappa: -0.3 * f,
                alpha: 0.15 * (2.0 * f - 1.0),
                gamma: if i % 2 == 0 { 0.0 } else { 0.02 },
                phit: 0.0,
                vx: 20.0,
                p: None,
            }
        })
        .collect()
}

fn bench(c: &mut Criterion) {
    let opts = Options::default();
    for (name, text) in FILES {
        let p64: Params<f64> = gough::tir::parse(text).unwrap().params;
        let p32 = p64.cast::<f32>();
        let in64 = inputs(p64.fnomin);
        let in32: Vec<Input<f32>> = in64
            .iter()
            .map(|i| Input {
                fz: i.fz as f32,
                kappa: i.kappa as f32,
                alpha: i.alpha as f32,
                gamma: i.gamma as f32,
                phit: 0.0,
                vx: i.vx as f32,
                p: None,
            })
            .collect();
        let mut g = c.benchmark_group(format!("combined eval/{name}"));
        g.throughput(criterion::Throughput::Elements(in64.len() as u64));
        g.bench_function("f64", |b| {
            b.iter(|| {
                for i in &in64 {
                    black_box(mf::eval::<f64, Libm>(&p64, black_box(i), &opts).unwrap());
                }
            })
        });
        g.bench_function("f32", |b| {
            b.iter(|| {
                for i in &in32 {
                    black_box(mf::eval::<f32, Libm>(&p32, black_box(i), &opts).unwrap());
                }
            })
        });
        g.finish();

        // The staged evaluation (`mf::prepared`): one load stage, then the slip stage at each
        // of the 64 slips (f32, as on the device; moments off, as the estimator runs it).
        let staged = Options {
            moments: false,
            ..Options::default()
        };
        let mut g = c.benchmark_group(format!("slip stage/{name}"));
        g.throughput(criterion::Throughput::Elements(in32.len() as u64));
        let load = Prepared::new::<Libm>(&p32, &Operating::from(&in32[0]), &staged).unwrap();
        g.bench_function("mf::eval f32 (moments off)", |b| {
            b.iter(|| {
                for i in &in32 {
                    let i = Input {
                        fz: in32[0].fz,
                        gamma: in32[0].gamma,
                        ..*i
                    };
                    black_box(mf::eval::<f32, Libm>(&p32, black_box(&i), &staged).unwrap());
                }
            })
        });
        g.bench_function("slip stage f32", |b| {
            b.iter(|| {
                for i in &in32 {
                    black_box(load.eval::<Libm>(black_box(i.kappa), i.alpha).unwrap());
                }
            })
        });
        g.bench_function("slip stage + d/dkappa, d/dalpha f32", |b| {
            b.iter(|| {
                for i in &in32 {
                    black_box(
                        load.eval_d::<Libm>(load.mu(), black_box(i.kappa), i.alpha)
                            .unwrap(),
                    );
                }
            })
        });
        g.bench_function("slip stage + d/dkappa, d/dalpha, d/dlambda_mu f32", |b| {
            b.iter(|| {
                for i in &in32 {
                    black_box(
                        load.eval_d_mu::<Libm>(1.0, black_box(i.kappa), i.alpha)
                            .unwrap(),
                    );
                }
            })
        });
        g.finish();
    }
}

/// The batch's columns: `n` random combined-slip points (a fixed LCG): Fz 0.4–1.6·FNOMIN, κ
/// ±0.3, α ±0.25 rad, γ ±0.05 rad, Vx 5–40 m/s.
struct Points<F> {
    fz: Vec<F>,
    kappa: Vec<F>,
    alpha: Vec<F>,
    gamma: Vec<F>,
    vx: Vec<F>,
}

fn points<F: Float>(fnomin: f64, n: usize) -> Points<F> {
    let mut s = 0x9e37_79b9_7f4a_7c15u64;
    let mut u = move || {
        s = s
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut pts = Points {
        fz: vec![],
        kappa: vec![],
        alpha: vec![],
        gamma: vec![],
        vx: vec![],
    };
    for _ in 0..n {
        pts.fz.push(F::from_f64(fnomin * (0.4 + 1.2 * u())));
        pts.kappa.push(F::from_f64(0.6 * u() - 0.3));
        pts.alpha.push(F::from_f64(0.5 * u() - 0.25));
        pts.gamma.push(F::from_f64(0.1 * u() - 0.05));
        pts.vx.push(F::from_f64(5.0 + 35.0 * u()));
    }
    pts
}

fn batch_of<F: Float, M: Backend<F>>(
    g: &mut criterion::BenchmarkGroup<'_, criterion::measurement::WallTime>,
    label: &str,
    p: &Params<F>,
) {
    let pts = points::<F>(p.fnomin.to_f64(), BATCH);
    let cols = Columns {
        fz: &pts.fz,
        kappa: &pts.kappa,
        alpha: &pts.alpha,
        gamma: &pts.gamma,
        vx: &pts.vx,
        phit: None,
        p: None,
    };
    let opts = Options::default();
    let (mut fx, mut fy, mut mz) = (
        vec![F::ZERO; BATCH],
        vec![F::ZERO; BATCH],
        vec![F::ZERO; BATCH],
    );
    g.bench_function(format!("eval_batch {label} (Fx, Fy, Mz)"), |b| {
        b.iter(|| {
            let mut out = Outputs {
                fx: Some(&mut fx),
                fy: Some(&mut fy),
                mz: Some(&mut mz),
                ..Outputs::default()
            };
            mf::eval_batch::<F, M>(p, black_box(&cols), &opts, &mut out).unwrap();
        })
    });
    g.bench_function(format!("eval {label} (every output)"), |b| {
        b.iter(|| {
            for i in 0..BATCH {
                let input = Input {
                    fz: pts.fz[i],
                    kappa: pts.kappa[i],
                    alpha: pts.alpha[i],
                    gamma: pts.gamma[i],
                    phit: F::ZERO,
                    vx: pts.vx[i],
                    p: None,
                };
                black_box(mf::eval::<F, M>(p, black_box(&input), &opts).unwrap());
            }
        })
    });
}

/// `mf::eval_batch_lanes_on` (f64 lanes, `Lanewise`) on `isa` over the same points as
/// [`batch_of`]'s, Fx, Fy, Mz asked for.
fn lanes_of(
    g: &mut criterion::BenchmarkGroup<'_, criterion::measurement::WallTime>,
    isa: mf::Isa,
    p: &Params<f64>,
) {
    let pts = points::<f64>(p.fnomin, BATCH);
    let cols = Columns {
        fz: &pts.fz,
        kappa: &pts.kappa,
        alpha: &pts.alpha,
        gamma: &pts.gamma,
        vx: &pts.vx,
        phit: None,
        p: None,
    };
    let opts = Options::default();
    let (mut fx, mut fy, mut mz) = (vec![0.0; BATCH], vec![0.0; BATCH], vec![0.0; BATCH]);
    g.bench_function(format!("eval_batch_lanes f64 {isa:?} (Fx, Fy, Mz)"), |b| {
        b.iter(|| {
            let mut out = Outputs {
                fx: Some(&mut fx),
                fy: Some(&mut fy),
                mz: Some(&mut mz),
                ..Outputs::default()
            };
            let n = mf::eval_batch_lanes_on(isa, p, black_box(&cols), &opts, &mut out).unwrap();
            assert_eq!(n, BATCH);
        })
    });
}

/// Points per batch iteration.
const BATCH: usize = 4096;

fn batch(c: &mut Criterion) {
    for (name, text) in &FILES[1..] {
        let p64: Params<f64> = gough::tir::parse(text).unwrap().params;
        let p32 = p64.cast::<f32>();
        let mut g = c.benchmark_group(format!("batch/{name}"));
        g.throughput(criterion::Throughput::Elements(BATCH as u64));
        batch_of::<f64, Libm>(&mut g, "f64 Libm", &p64);
        for isa in [mf::Isa::Avx512, mf::Isa::Avx2, mf::Isa::Baseline] {
            lanes_of(&mut g, isa, &p64);
        }
        batch_of::<f32, Libm>(&mut g, "f32 Libm", &p32);
        #[cfg(feature = "fast")]
        batch_of::<f32, gough::math::Fast>(&mut g, "f32 Fast", &p32);
        g.finish();
    }
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(30).measurement_time(std::time::Duration::from_secs(2));
    targets = bench, batch
}
criterion_main!(benches);
