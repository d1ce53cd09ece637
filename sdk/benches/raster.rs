//! Rasterizer throughput (exact-coverage, tiled, rayon) into a 1920 × 1080 image:
//!
//! - `small_100k`: 100 000 random small triangles (vertices within ±4 px of a random centre,
//!   mean area ≈ 5 px²), constant shade;
//! - `ghost_mesh`: a ghost-like 128 × 128-cell mesh (32 768 triangles) warped over ~900 × 900 px
//!   with three interpolated attributes (shade = attributes, as a ghost's colour × intensity);
//! - `full_screen`: two triangles covering the whole image (fill rate, every pixel interior).
//!
//! Run: `cargo bench -p flarebench-sdk --bench raster`. Throughput is in triangles.

use std::hint::black_box;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use flarebench_sdk::image::HdrImage;
use flarebench_sdk::raster::rasterize;

const W: usize = 1920;
const H: usize = 1080;

/// A small xorshift generator: the bench needs no cryptographic randomness, just a fixed set.
struct Rng(u64);

impl Rng {
    fn next_f32(&mut self) -> f32 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 40) as f32 / (1u64 << 24) as f32
    }
}

struct Mesh<const N: usize> {
    positions: Vec<[f32; 2]>,
    attrs: Vec<[f32; N]>,
    triangles: Vec<[u32; 3]>,
}

fn small_triangles(count: usize) -> Mesh<0> {
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    let mut positions = Vec::with_capacity(3 * count);
    for _ in 0..count {
        let (cx, cy) = (rng.next_f32() * W as f32, rng.next_f32() * H as f32);
        for _ in 0..3 {
            positions.push([
                cx + 8.0 * rng.next_f32() - 4.0,
                cy + 8.0 * rng.next_f32() - 4.0,
            ]);
        }
    }
    let triangles = (0..count as u32)
        .map(|i| [3 * i, 3 * i + 1, 3 * i + 2])
        .collect();
    Mesh {
        attrs: vec![[]; positions.len()],
        positions,
        triangles,
    }
}

/// A (cells + 1)² vertex grid over a disc-like warped region around the image centre.
fn ghost_mesh(cells: u32) -> Mesh<3> {
    let n = cells + 1;
    let mut positions = Vec::new();
    let mut attrs = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let (u, v) = (
                i as f32 / cells as f32 * 2.0 - 1.0,
                j as f32 / cells as f32 * 2.0 - 1.0,
            );
            // A barrel-like warp, as aberrations bend a ghost's grid.
            let r2 = u * u + v * v;
            let k = 450.0 * (1.0 - 0.15 * r2);
            positions.push([960.0 + k * u, 540.0 + 0.9 * k * v]);
            attrs.push([0.5 + 0.5 * u, 0.5 + 0.5 * v, 1.0 / (1.0 + r2)]);
        }
    }
    let mut triangles = Vec::new();
    for j in 0..cells {
        for i in 0..cells {
            let a = j * n + i;
            triangles.push([a, a + 1, a + n + 1]);
            triangles.push([a, a + n + 1, a + n]);
        }
    }
    Mesh {
        positions,
        attrs,
        triangles,
    }
}

fn bench(c: &mut Criterion) {
    // One image, written once before timing so that no page is first touched (and zeroed by
    // the kernel) inside the measurement; the iterations accumulate into it.
    let mut img = HdrImage::new(W, H);
    img.pixels.fill([1.0; 3]);
    let mut g = c.benchmark_group("raster_1920x1080");
    g.sample_size(20);

    let small = small_triangles(100_000);
    g.throughput(Throughput::Elements(small.triangles.len() as u64));
    g.bench_function("small_100k", |b| {
        b.iter(|| {
            rasterize(
                &mut img,
                &small.positions,
                &small.attrs,
                &small.triangles,
                |_| [1.0, 0.5, 0.25],
            );
            black_box(img.pixels[0]);
        })
    });

    let mesh = ghost_mesh(128);
    g.throughput(Throughput::Elements(mesh.triangles.len() as u64));
    g.bench_function("ghost_mesh_128", |b| {
        b.iter(|| {
            rasterize(
                &mut img,
                &mesh.positions,
                &mesh.attrs,
                &mesh.triangles,
                |a| [a[0] * a[2], a[1] * a[2], a[2]],
            );
            black_box(img.pixels[0]);
        })
    });

    let full = Mesh::<0> {
        positions: vec![
            [0.0, 0.0],
            [W as f32, 0.0],
            [W as f32, H as f32],
            [0.0, H as f32],
        ],
        attrs: vec![[]; 4],
        triangles: vec![[0, 1, 2], [0, 2, 3]],
    };
    g.throughput(Throughput::Elements((W * H) as u64));
    g.bench_function("full_screen_pixels", |b| {
        b.iter(|| {
            rasterize(
                &mut img,
                &full.positions,
                &full.attrs,
                &full.triangles,
                |_| [1.0; 3],
            );
            black_box(img.pixels[0]);
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
