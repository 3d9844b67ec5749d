//! ns per combined-slip Fx/Fy/Mz evaluation (with Mx, My, t, Mzr, σ), per version, f32 and f64,
//! libm backend, limits on. Host only; device costs are counted in instructions under QEMU.
//!
//! Then, per slip-stage evaluation (`mf::prepared`), the slip stage alone and with its slopes.
//!
//! `cargo bench --bench mf_eval`
use criterion::{criterion_group, criterion_main, Criterion};
use gough::math::Libm;
use gough::mf::prepared::{Operating, Prepared};
use gough::mf::{self, Input, Options, Params};
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

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(30).measurement_time(std::time::Duration::from_secs(2));
    targets = bench
}
criterion_main!(benches);
