//! Every two-reflection ghost's energy share from the precise bounds search against the
//! Monte-Carlo reference (`ghost::monte_carlo::path_flux`), at 550 nm, for a lens and angles:
//! the figures of docs/accuracy.md. `cargo run --release -p flarebench-sdk --example
//! bounds_vs_mc -- LENS DEG[,DEG…] [RAYS]`.

use flarebench_sdk::ghost::bounds;
use flarebench_sdk::ghost::monte_carlo::{McSettings, path_flux};
use flarebench_sdk::ghost::{GridTrace, enumerate_ghosts};
use flarebench_sdk::io::read_lens;
use flarebench_sdk::trace::{InterfaceTableSet, Sequence};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let stem = args.get(1).map_or("heliar-tronnier", String::as_str);
    let degs: Vec<f64> = args
        .get(2)
        .map_or("10", String::as_str)
        .split(',')
        .map(|s| s.parse().expect("an angle"))
        .collect();
    let rays: usize = args.get(3).map_or(200_000, |s| s.parse().expect("a count"));
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../lenses")
        .join(format!("{stem}.xml"));
    let sys = read_lens(&path).expect("a bundled lens").system;
    let tables = InterfaceTableSet::for_system(&sys, 550.0);
    let mut scratch = GridTrace::default();
    let reference = bounds::reference_flux(&sys, &tables, &mut scratch);
    let settings = McSettings {
        rays,
        ..McSettings::default()
    };
    let direct = path_flux(&sys, &Sequence::forward(&sys, 550.0), 0.0, &settings);
    println!(
        "{stem}: direct flux bounds/MC {:.5} (MC ± {:.3}%)",
        reference / direct.mean,
        100.0 * direct.relative_error()
    );
    for deg in degs {
        let theta = deg.to_radians();
        let (mut worst, mut worst_sig, mut sum2, mut count, mut missed, mut missed_share) =
            (0.0_f64, 0.0_f64, 0.0, 0, 0, 0.0_f64);
        let mut worst_name = String::new();
        let mut total_mc = 0.0;
        let mut total_b = 0.0;
        for p in enumerate_ghosts(&sys) {
            let b = bounds::precise(&sys, p, &tables, theta, reference, &mut scratch);
            let seq = Sequence::ghost_path(&sys, 550.0, &p).expect("a ghost path");
            let g = path_flux(&sys, &seq, theta, &settings);
            let mc = g.mean / direct.mean;
            total_mc += mc;
            if mc <= 0.0 {
                continue;
            }
            let Some(b) = b else {
                missed += 1;
                missed_share = missed_share.max(mc);
                if mc > 1e-9 {
                    println!(
                        "  {p}: no light reported, MC share {mc:.3e} ± {:.2}%",
                        100.0 * g.relative_error()
                    );
                }
                continue;
            };
            total_b += b.energy_share;
            // Only ghosts the Monte-Carlo estimate pins down to 0.1%; the others that are off
            // by more than 3σ are listed.
            if g.relative_error() > 1e-3 {
                let r = b.energy_share / mc - 1.0;
                if r.abs() > 3.0 * g.relative_error() {
                    println!(
                        "  {p}: bounds/MC − 1 {:+.3}%, MC share {mc:.3e} ± {:.2}%",
                        100.0 * r,
                        100.0 * g.relative_error()
                    );
                }
                continue;
            }
            let r = b.energy_share / mc - 1.0;
            count += 1;
            sum2 += r * r;
            if r.abs() > worst.abs() {
                worst = r;
                worst_sig = 100.0 * g.relative_error();
                worst_name = p.to_string();
            }
        }
        println!(
            "{stem} {deg}°: {count} ghosts (MC σ ≤ 0.1%): bounds/MC − 1 rms {:.3}%, worst {:+.3}% ({worst_name}, MC σ {worst_sig:.3}%); total share bounds/MC {:.4}; lit but reported without light: {missed} (largest share {missed_share:.2e})",
            100.0 * (sum2 / count.max(1) as f64).sqrt(),
            100.0 * worst,
            total_b / total_mc
        );
    }
}
