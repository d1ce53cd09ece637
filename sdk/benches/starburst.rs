//! Starburst computation (issue #4 target: a 1024² starburst with 64 wavelengths ≤ 150 ms on
//! 2 cores):
//!
//! - `transform_1024`: a 6-blade iris rasterised with 256 texels across, padded 4× to 1024²,
//!   Fourier transformed, `|F|²` centred and normalised;
//! - `spectral_1024_64`: the spectral sum over 64 CIE-weighted wavelengths of that spectrum;
//! - `full_1024_64`: both (what one uncached light costs).
//!
//! Run: `cargo bench -p flarebench-sdk --bench starburst`.

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use flarebench_sdk::aperture::Aperture;
use flarebench_sdk::color::{LightSpectrum, SpectralSampling};
use flarebench_sdk::starburst::{PowerSpectrum, StarburstPattern, StarburstSettings};

fn bench(c: &mut Criterion) {
    let iris = Aperture::Iris {
        blades: 6,
        rotation_rad: 0.2,
        roundness: 0.1,
    };
    let settings = StarburstSettings::default();
    assert_eq!(settings.fft_size(), 1024);
    let sampling = SpectralSampling::new(64, LightSpectrum::D65).expect("D65 is visible");
    let mut g = c.benchmark_group("starburst");
    g.sample_size(20);
    g.bench_function("transform_1024", |b| {
        b.iter(|| PowerSpectrum::compute(black_box(&iris), None, &settings).expect("valid"))
    });
    let spectrum = PowerSpectrum::compute(&iris, None, &settings).expect("valid");
    g.bench_function("spectral_1024_64", |b| {
        b.iter(|| StarburstPattern::new(black_box(&spectrum), &sampling))
    });
    g.bench_function("full_1024_64", |b| {
        b.iter(|| {
            let s = PowerSpectrum::compute(black_box(&iris), None, &settings).expect("valid");
            StarburstPattern::new(&s, &sampling)
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
