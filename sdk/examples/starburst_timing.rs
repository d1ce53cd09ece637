//! Times one uncached starburst (6-blade iris, 256 texels padded 4× to 1024², 64 wavelengths)
//! in wall-clock and in this process's CPU time, which a busy machine inflates less: on a
//! shared machine, CPU time ÷ cores used bounds what an idle machine's wall-clock time would be.
//!
//! Run: `cargo run --release -p flarebench-sdk --example starburst_timing [REPEATS]`.

use std::time::Instant;

use flarebench_sdk::aperture::Aperture;
use flarebench_sdk::color::{LightSpectrum, SpectralSampling};
use flarebench_sdk::starburst::{PowerSpectrum, StarburstPattern, StarburstSettings};

/// User + system CPU time of this process (seconds), from /proc/self/stat (Linux); None
/// elsewhere.
fn cpu_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    // Fields after the parenthesised command name; utime and stime are the 12th and 13th.
    let rest = &stat[stat.rfind(')')? + 2..];
    let f: Vec<&str> = rest.split_whitespace().collect();
    let ticks: f64 = f.get(11)?.parse::<f64>().ok()? + f.get(12)?.parse::<f64>().ok()?;
    // The kernel's USER_HZ is 100 on Linux.
    Some(ticks / 100.0)
}

fn main() {
    let repeats: usize = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(20);
    let iris = Aperture::Iris {
        blades: 6,
        rotation_rad: 0.2,
        roundness: 0.1,
    };
    let settings = StarburstSettings::default();
    let sampling = SpectralSampling::new(64, LightSpectrum::D65).expect("D65 is visible");
    // Warm up (thread pool, FFT plans, page faults).
    let s = PowerSpectrum::compute(&iris, None, &settings).expect("valid");
    std::hint::black_box(StarburstPattern::new(&s, &sampling));
    let (mut t_fft, mut t_sum) = (0.0, 0.0);
    let cpu0 = cpu_seconds();
    let wall0 = Instant::now();
    for _ in 0..repeats {
        let t = Instant::now();
        let s = PowerSpectrum::compute(&iris, None, &settings).expect("valid");
        t_fft += t.elapsed().as_secs_f64();
        let t = Instant::now();
        std::hint::black_box(StarburstPattern::new(&s, &sampling));
        t_sum += t.elapsed().as_secs_f64();
    }
    let wall = wall0.elapsed().as_secs_f64();
    let n = repeats as f64;
    println!(
        "1024² starburst, 64 wavelengths, {} threads, {repeats} repeats: wall {:.1} ms each \
         (transform {:.1} ms, spectral sum {:.1} ms)",
        rayon::current_num_threads(),
        1e3 * wall / n,
        1e3 * t_fft / n,
        1e3 * t_sum / n
    );
    if let (Some(a), Some(b)) = (cpu0, cpu_seconds()) {
        println!("CPU time {:.1} ms each", 1e3 * (b - a) / n);
    }
}
