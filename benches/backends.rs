//! Host ns per combined-slip evaluation, per math backend (MF 6.1, limits on): f64 Libm, f32
//! Libm / Fast / Micromath, Q31.32 fixed point. Host timings only show relative costs on this
//! machine; device costs are counted in instructions under QEMU (issue 7, item 3).
//!
//! `cargo bench --bench backends --features fast,micromath,fixed`
use criterion::{criterion_group, criterion_main, Criterion};
use gough::fixed::{Fix, FixMath};
use gough::math::{Backend, Fast, Float, Libm, Micromath};
use gough::mf::{self, Input, Options, Params};
use std::hint::black_box;

const TIR: &str = include_str!("../host-tests/data/tyres/MagicFormula61_Parameters.tir");

/// 64 combined-slip operating points around the nominal load (braking, cornering, camber).
fn inputs<F: Float>(fnomin: f64) -> Vec<Input<F>> {
    (0..64)
        .map(|i| {
            let f = i as f64 / 63.0;
            Input {
                fz: F::from_f64(fnomin * (0.6 + 0.8 * f)),
                kappa: F::from_f64(-0.3 * f),
                alpha: F::from_f64(0.15 * (2.0 * f - 1.0)),
                gamma: F::from_f64(if i % 2 == 0 { 0.0 } else { 0.02 }),
                phit: F::ZERO,
                vx: F::from_f64(20.0),
                p: None,
            }
        })
        .collect()
}

fn one<F: Float, M: Backend<F>>(
    c: &mut criterion::BenchmarkGroup<'_, criterion::measurement::WallTime>,
    name: &str,
    p64: &Params<f64>,
) {
    let p = p64.cast::<F>();
    let ins = inputs::<F>(p64.fnomin);
    let opts = Options::default();
    c.bench_function(name, |b| {
        b.iter(|| {
            for i in &ins {
                black_box(mf::eval::<F, M>(&p, black_box(i), &opts).unwrap());
            }
        })
    });
}

fn bench(c: &mut Criterion) {
    let p64: Params<f64> = gough::tir::parse(TIR).unwrap().params;
    let mut g = c.benchmark_group("combined eval MF 6.1 (64 points)");
    g.throughput(criterion::Throughput::Elements(64));
    one::<f64, Libm>(&mut g, "f64 Libm", &p64);
    one::<f32, Libm>(&mut g, "f32 Libm", &p64);
    one::<f32, Fast>(&mut g, "f32 Fast", &p64);
    one::<f32, Micromath>(&mut g, "f32 Micromath", &p64);
    one::<Fix, FixMath>(&mut g, "Q31.32 FixMath", &p64);
    g.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20).measurement_time(std::time::Duration::from_secs(2));
    targets = bench
}
criterion_main!(benches);
