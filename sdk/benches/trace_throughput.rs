//! Ray–surface steps per second through the Nikon 80–200 zoom (short end, 22 steps per ray)
//! for the scalar f64, batched f64 and batched f32 tracers, on every core (rayon).
//!
//! Run: `cargo bench -p flarebench-sdk --bench trace_throughput` (FLAREBENCH_BENCH_LENS=path
//! for another lens). Throughput is reported in
//! elements = ray–surface steps.

use std::hint::black_box;
use std::path::Path;

use criterion::{BatchSize, Criterion, Throughput, criterion_group, criterion_main};
use flarebench_sdk::io::read_lens;
use flarebench_sdk::trace::{Ray, RayBatch, Real, Sequence};
use rayon::prelude::*;

const RAYS: usize = 1 << 16;

/// A square grid of collimated rays at 8° over the front element.
fn rays(semi: f64) -> Vec<Ray> {
    let side = (RAYS as f64).sqrt() as usize;
    (0..side * side)
        .map(|i| {
            let (u, v) = (
                (i % side) as f64 / (side - 1) as f64,
                (i / side) as f64 / (side - 1) as f64,
            );
            let (x, y) = ((2.0 * u - 1.0) * semi, (2.0 * v - 1.0) * semi);
            let mut r = Ray::collimated(8f64.to_radians(), 0.0, y);
            r.origin.x = x;
            r
        })
        .collect()
}

fn batch<T: Real>(rays: &[Ray]) -> RayBatch<T> {
    let mut b = RayBatch::with_capacity(rays.len());
    for r in rays {
        b.push(r.origin.to_array().map(T::of), r.dir.to_array().map(T::of));
    }
    b
}

fn bench(c: &mut Criterion) {
    // FLAREBENCH_BENCH_LENS picks another lens file.
    let path = std::env::var_os("FLAREBENCH_BENCH_LENS").map_or_else(
        || Path::new(env!("CARGO_MANIFEST_DIR")).join("../lenses/nikon-zoom-short.xml"),
        Into::into,
    );
    let sys = read_lens(&path).unwrap_or_else(|e| panic!("{e}")).system;
    let seq = Sequence::forward(&sys, 550.0);
    let seq32 = seq.cast::<f32>();
    let rays = rays(sys.surfaces[0].semi_diameter);
    let steps = (rays.len() * seq.len()) as u64;
    let mut g = c.benchmark_group("nikon_zoom_steps");
    g.throughput(Throughput::Elements(steps));
    g.sample_size(20);
    g.bench_function("scalar_f64", |b| {
        b.iter(|| {
            rays.par_iter()
                .map(|r| seq.trace(black_box(r)).ray.origin.x)
                .sum::<f64>()
        })
    });
    let b64 = batch::<f64>(&rays);
    g.bench_function("batch_f64", |b| {
        b.iter_batched_ref(
            || b64.clone(),
            |bb| seq.trace_batch(bb),
            BatchSize::LargeInput,
        )
    });
    let b32 = batch::<f32>(&rays);
    g.bench_function("batch_f32", |b| {
        b.iter_batched_ref(
            || b32.clone(),
            |bb| seq32.trace_batch(bb),
            BatchSize::LargeInput,
        )
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
