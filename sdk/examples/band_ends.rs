//! Each two-reflection ghost's flux at the ends of the visible range (390 and 770 nm) and at
//! 580 nm (the centre of a one-band ghost), traced over the entrance rectangle found at 550 nm
//! against over its union with the rectangle found at that wavelength: what a ghost traced at
//! that band over its 550 nm rectangle alone would lose (`bounds::widened_for` is the fix).
//! Prints the ghosts losing more than 0.5% (above 1e-5 of the direct flux) and each angle's
//! total. `cargo run --release -p flarebench-sdk --example band_ends -- LENS DEG[,DEG…]`.
use flarebench_sdk::ghost::bounds;
use flarebench_sdk::ghost::{GridTrace, enumerate_ghosts, trace_grid};
use flarebench_sdk::io::read_lens;
use flarebench_sdk::trace::InterfaceTableSet;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let stem = args.get(1).map_or("heliar-tronnier", String::as_str);
    let degs: Vec<f64> = args
        .get(2)
        .map_or("10", String::as_str)
        .split(',')
        .map(|s| s.parse().unwrap())
        .collect();
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../lenses")
        .join(format!("{stem}.xml"));
    let sys = read_lens(&path).unwrap().system;
    let t550 = InterfaceTableSet::for_system(&sys, 550.0);
    let mut scratch = GridTrace::default();
    let reference = bounds::reference_flux(&sys, &t550, &mut scratch);
    let stop = flarebench_sdk::paraxial::stop_opening(&sys);
    let ends = [390.0, 580.0, 770.0];
    let tabs: Vec<_> = ends
        .iter()
        .map(|&l| InterfaceTableSet::for_system(&sys, l))
        .collect();
    for deg in degs {
        let theta = f64::to_radians(deg);
        let mut total = [0.0f64; 3];
        let mut lost = [0.0f64; 3];
        for p in enumerate_ghosts(&sys) {
            let Some(b) = bounds::precise(&sys, p, &t550, theta, reference, &mut scratch) else {
                continue;
            };
            for (k, t) in tabs.iter().enumerate() {
                let Some(bl) = bounds::precise(&sys, p, t, theta, reference, &mut scratch) else {
                    continue;
                };
                let u = b.entrance.union(&bl.entrance);
                let seq = bounds::ghost_sequence(&sys, p, t).unwrap();
                let n = 129;
                trace_grid(&seq, theta, b.entrance, n, stop, &mut scratch);
                let f0 = bounds::clipped_flux(&scratch, theta) / reference;
                trace_grid(&seq, theta, u, n, stop, &mut scratch);
                let f1 = bounds::clipped_flux(&scratch, theta) / reference;
                total[k] += f1;
                lost[k] += (f1 - f0).max(0.0);
                if f1 > 1e-5 && (f1 - f0) / f1 > 0.005 {
                    println!(
                        "  {deg}° {p} @{}nm: share {f1:.3e}, lost {:.1}% (rect 550 {:.2}×{:.2}, {}nm {:.2}×{:.2})",
                        ends[k],
                        100.0 * (f1 - f0) / f1,
                        b.entrance.width(),
                        b.entrance.height(),
                        ends[k],
                        bl.entrance.width(),
                        bl.entrance.height()
                    );
                }
            }
        }
        for k in 0..3 {
            println!(
                "{stem} {deg}° @{}nm: total {:.4e}, lost {:.3}%",
                ends[k],
                total[k],
                100.0 * lost[k] / total[k]
            );
        }
    }
}
