//! ns per combined-slip Fx/Fy/Mz evaluation (with Mx, My, t, Mzr, σ), per version, f32 and f64,
//! libm backend, limits on. Host only; device costs are counted in instructions under QEMU.
//!
//! `cargo bench --bench mf_eval`
use criterion::{criterion_group, criterion_main, Criterion};
use gough::math::Libm;
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
    }
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(30).measurement_time(std::time::Duration::from_secs(2));
    targets = bench
}
criterion_main!(benches);
