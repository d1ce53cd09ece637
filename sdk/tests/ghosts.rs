//! Ghost enumeration, batched ghost throughput and ghost bounds.

use flarebench_sdk::LensSystem;
use flarebench_sdk::ghost::bounds::{self, BoundsMode};
use flarebench_sdk::ghost::{
    GhostPath, GridTrace, enumerate_ghosts, reflecting_surfaces, trace_grid,
};
use flarebench_sdk::paraxial::stop_opening;
use flarebench_sdk::trace::{InterfaceTableSet, Ray, RayBatch, Sequence};
use flarebench_test_support::load_lens;

/// Batched ghost weights from the interface tables against the scalar Fresnel throughput: the
/// tables are interpolated linearly in cos θ over 256 entries; absolute part.
const TABLE_WEIGHT_ABS_TOL: f64 = 1e-6;
/// The relative part of the same bound.
const TABLE_WEIGHT_REL_TOL: f64 = 1e-4;
/// Asymmetry of an on-axis ghost's entrance rectangle, as a fraction of its size: the grid's
/// sampling.
const ON_AXIS_SYMMETRY_FRACTION: f64 = 0.05;
/// Approximate against precise entrance bounds, as a fraction of the larger side: the traced
/// rectangle has one grid cell of margin; paraxial optics ignores aberration.
const APPROXIMATE_BOUNDS_FRACTION: f64 = 0.25;
/// An interpolated energy share against the mean of its neighbours: f64 rounding.
const INTERPOLATION_TOL: f64 = 1e-12;

fn lens(stem: &str) -> LensSystem {
    load_lens(stem)
}

#[test]
fn every_pair_of_reflecting_surfaces_is_a_ghost() {
    let heliar = lens("heliar-tronnier");
    // 8 glass–air or glass–glass interfaces (the stop and the sensor do not reflect).
    assert_eq!(reflecting_surfaces(&heliar), vec![0, 1, 2, 3, 4, 6, 7, 8]);
    let g = enumerate_ghosts(&heliar);
    assert_eq!(g.len(), 8 * 7 / 2);
    assert!(g.iter().all(|p| p.first() > p.second()));
    // Paths with reflections on both sides of the stop (surface 5) are included.
    assert!(g.contains(&GhostPath::two(7, 2)));
    let nikon = lens("nikon-zoom-short");
    let n = reflecting_surfaces(&nikon).len();
    assert_eq!(enumerate_ghosts(&nikon).len(), n * (n - 1) / 2);
}

#[test]
fn batched_ghost_weights_match_the_scalar_throughput() {
    let sys = lens("heliar-tronnier");
    for (first, second) in [(8, 7), (4, 1), (7, 2)] {
        let seq = Sequence::ghost(&sys, 520.0, first, second).unwrap();
        let tabled = seq.clone().with_interface_tables();
        let mut b = RayBatch::<f64>::with_capacity(64);
        let rays: Vec<Ray> = (0..40)
            .map(|i| Ray::collimated(0.05, 0.0, -3.0 + 0.15 * i as f64))
            .collect();
        for r in &rays {
            b.push(r.origin.to_array(), r.dir.to_array());
        }
        tabled.trace_batch(&mut b);
        let mut checked = 0;
        for (i, r) in rays.iter().enumerate() {
            let s = seq.trace(r);
            if !s.completed {
                continue;
            }
            let w = b.packets()[i / 64].weight[i % 64];
            // Tables are interpolated linearly in cos θ over 256 entries.
            assert!(
                (w - s.throughput).abs()
                    <= TABLE_WEIGHT_ABS_TOL + TABLE_WEIGHT_REL_TOL * s.throughput,
                "{first}-{second} ray {i}: {w} vs {}",
                s.throughput
            );
            checked += 1;
        }
        assert!(checked > 10);
    }
}

#[test]
fn precise_bounds_hold_every_passing_ray_and_are_symmetric_on_axis() {
    let sys = lens("heliar-tronnier");
    let mut scratch = GridTrace::default();
    let tables = InterfaceTableSet::for_system(&sys, 550.0);
    let reference = bounds::reference_flux(&sys, &tables, &mut scratch);
    assert!(reference > 0.0);
    let path = GhostPath::two(4, 3);
    let b = bounds::precise(&sys, path, &tables, 0.0, reference, &mut scratch)
        .expect("ghost 4-3 reaches the sensor");
    let e = b.entrance;
    assert!(
        (e.x0 + e.x1).abs() < ON_AXIS_SYMMETRY_FRACTION * e.width(),
        "{e:?}"
    );
    assert!(
        (e.y0 + e.y1).abs() < ON_AXIS_SYMMETRY_FRACTION * e.height(),
        "{e:?}"
    );
    assert!(
        b.energy_share > 0.0 && b.energy_share < 0.05,
        "{}",
        b.energy_share
    );
    // A dense grid over the whole front finds no passing ray outside the bounds.
    let seq = Sequence::ghost(&sys, 550.0, 4, 3).unwrap().cast::<f32>();
    let wide = bounds::entrance_search_rect(&sys, 0.0);
    let mut g = GridTrace::default();
    trace_grid(&seq, 0.0, wide, 161, stop_opening(&sys), &mut g);
    for k in 0..g.n * g.n {
        if g.passes(k) {
            let (i, j) = (k % g.n, k / g.n);
            let x = wide.x0 + wide.width() * i as f64 / 160.0;
            let y = wide.y0 + wide.height() * j as f64 / 160.0;
            assert!(
                x >= e.x0 && x <= e.x1 && y >= e.y0 && y <= e.y1,
                "({x}, {y}) outside {e:?}"
            );
        }
    }
}

/// Off axis too, for every ghost: a dense grid over the whole front finds no passing ray
/// outside the precise bounds. At 10° the Heliar's ghost 6-4 enters through a thin, wide
/// slice whose tip was all the search's first coarse pass caught; the search then kept a
/// rectangle a third too narrow and cut the ghost (fixed: a rectangle the ghost reaches the
/// side of is widened and traced again).
#[test]
fn precise_bounds_hold_every_passing_ray_off_axis() {
    let sys = lens("heliar-tronnier");
    let theta = 10f64.to_radians();
    let tables = InterfaceTableSet::for_system(&sys, 550.0);
    let mut scratch = GridTrace::default();
    let reference = bounds::reference_flux(&sys, &tables, &mut scratch);
    let wide = bounds::entrance_search_rect(&sys, theta);
    let n = 241;
    let mut g = GridTrace::default();
    let mut checked = 0;
    for path in enumerate_ghosts(&sys) {
        let Some(b) = bounds::precise(&sys, path, &tables, theta, reference, &mut scratch) else {
            continue;
        };
        let e = b.entrance;
        let seq = bounds::ghost_sequence(&sys, path, &tables).unwrap();
        trace_grid(&seq, theta, wide, n, stop_opening(&sys), &mut g);
        for k in (0..n * n).filter(|&k| g.passes(k)) {
            let (i, j) = (k % n, k / n);
            let x = wide.x0 + wide.width() * i as f64 / (n - 1) as f64;
            let y = wide.y0 + wide.height() * j as f64 / (n - 1) as f64;
            assert!(
                x >= e.x0 && x <= e.x1 && y >= e.y0 && y <= e.y1,
                "{path}: ({x}, {y}) outside {e:?}"
            );
        }
        checked += 1;
    }
    assert!(checked > 10);
}

#[test]
fn approximate_bounds_are_close_to_precise_ones_near_the_axis() {
    let sys = lens("heliar-tronnier");
    let mut scratch = GridTrace::default();
    let theta = 2f64.to_radians();
    let tables = InterfaceTableSet::for_system(&sys, 550.0);
    let reference = bounds::reference_flux(&sys, &tables, &mut scratch);
    let mut compared = 0;
    for path in enumerate_ghosts(&sys) {
        let (Some(p), Some(a)) = (
            bounds::precise(&sys, path, &tables, theta, reference, &mut scratch),
            bounds::approximate(&sys, path, 550.0, theta),
        ) else {
            continue;
        };
        // The traced rectangle has one grid cell of margin; paraxial optics ignores aberration.
        let tol = APPROXIMATE_BOUNDS_FRACTION * p.entrance.width().max(p.entrance.height());
        for (x, y) in [
            (p.entrance.x0, a.entrance.x0),
            (p.entrance.x1, a.entrance.x1),
            (p.entrance.y0, a.entrance.y0),
            (p.entrance.y1, a.entrance.y1),
        ] {
            assert!(
                (x - y).abs() < tol,
                "{path}: precise {:?} vs approximate {:?}",
                p.entrance,
                a.entrance
            );
        }
        compared += 1;
    }
    assert!(compared > 10, "only {compared} ghosts compared");
}

#[test]
fn bounds_tables_interpolate_and_refuse_other_lenses() {
    use flarebench_sdk::ghost::table::{BoundsTable, angle_steps};
    let sys = lens("heliar-tronnier");
    let angles = angle_steps(2.0, 0.5);
    assert_eq!(angles, vec![0.0, 0.5, 1.0, 1.5, 2.0]);
    let table = BoundsTable::compute(&sys, &angles, BoundsMode::Precise, 550.0, &|| {});
    table.check_for(&sys).unwrap();
    let g = table.ghost_index(GhostPath::two(4, 3)).unwrap();
    let (a, b) = (table.bounds[g][1].unwrap(), table.bounds[g][2].unwrap());
    let mid = table.lookup(g, 0.75).unwrap();
    assert_eq!(mid.entrance, a.entrance.union(&b.entrance));
    assert!((mid.energy_share - 0.5 * (a.energy_share + b.energy_share)).abs() < INTERPOLATION_TOL);
    assert_eq!(table.lookup(g, 1.0).unwrap(), b);
    assert!(table.lookup(g, 2.5).is_none());
    let text = serde_json::to_string(&table).unwrap();
    let back: BoundsTable = serde_json::from_str(&text).unwrap();
    assert!(back == table, "the JSON round trip changed the table");
    let mut other = sys.clone();
    other.surfaces[0].thickness += 0.01;
    assert!(
        table
            .check_for(&other)
            .unwrap_err()
            .contains("not this prescription")
    );
    // Approximate mode is quick and finds the same ghosts with light near the axis.
    let approx = BoundsTable::compute(&sys, &angles, BoundsMode::Approximate, 550.0, &|| {});
    let lit = |t: &BoundsTable| t.bounds.iter().filter(|b| b[0].is_some()).count();
    assert!(
        lit(&approx) + 2 >= lit(&table),
        "{} vs {}",
        lit(&approx),
        lit(&table)
    );
}

/// Every four-reflection path the enumeration lists is exactly the set of surface quadruples
/// that `Sequence::ghost_path` accepts (brute force over every quadruple of surfaces), and
/// the count follows the closed form.
#[test]
fn four_reflection_paths_are_every_valid_quadruple() {
    use flarebench_sdk::ghost::{enumerate_four_reflection_ghosts, four_reflection_count};
    for stem in ["heliar-tronnier", "cooke-triplet-25mm"] {
        let sys = lens(stem);
        let listed = enumerate_four_reflection_ghosts(&sys);
        let n = sys.surfaces.len();
        let mut brute = Vec::new();
        for a in 0..n {
            for b in 0..n {
                for c in 0..n {
                    for d in 0..n {
                        let p = GhostPath::four(a, b, c, d);
                        if Sequence::ghost_path(&sys, 550.0, &p).is_ok() {
                            brute.push(p);
                        }
                    }
                }
            }
        }
        assert_eq!(listed, brute, "{stem}: listed in (a, b, c, d) order");
        let r = reflecting_surfaces(&sys).len();
        assert_eq!(listed.len(), four_reflection_count(r), "{stem}");
    }
    // The Heliar: 8 reflecting surfaces, 658 four-reflection paths; the two-reflection list
    // is unchanged.
    let heliar = lens("heliar-tronnier");
    assert_eq!(enumerate_four_reflection_ghosts(&heliar).len(), 658);
    assert_eq!(enumerate_ghosts(&heliar).len(), 28);
    let nikon = lens("nikon-zoom-short");
    assert_eq!(reflecting_surfaces(&nikon).len(), 21);
    assert_eq!(enumerate_four_reflection_ghosts(&nikon).len(), 36_785);
}

/// A table computed with four-reflection ghosts holds those whose bound reaches the
/// threshold, is version 4, round-trips through JSON, and a version-3 table reads as before;
/// tables of the old versions 1 and 2 (energies against the direct image at each angle) are
/// refused with a note to compute them again.
#[test]
fn bounds_tables_with_four_reflection_ghosts() {
    use flarebench_sdk::ghost::table::{BoundsTable, TableOptions, VERSION, VERSION_FOUR};
    use flarebench_sdk::ghost::{ReflectionOrder, enumerate_four_reflection_ghosts};
    let sys = lens("heliar-tronnier");
    let angles = [0.0, 1.0];
    let two = BoundsTable::compute(&sys, &angles, BoundsMode::Approximate, 550.0, &|| {});
    assert_eq!(two.version, VERSION);
    assert!(!two.has_four_reflections());
    let text = serde_json::to_string(&two).unwrap();
    assert!(!text.contains("four_reflection") && !text.contains("third"));
    let started = std::sync::atomic::AtomicUsize::new(0);
    let options = TableOptions {
        reflections: ReflectionOrder::Four,
        four_reflection_bound_threshold: 1e-8,
    };
    let four = BoundsTable::compute_with(
        &sys,
        &angles,
        BoundsMode::Approximate,
        550.0,
        &options,
        &|n| started.store(n, std::sync::atomic::Ordering::Relaxed),
        &|| {},
    );
    assert_eq!(four.version, VERSION_FOUR);
    four.check_for(&sys).unwrap();
    assert_eq!(four.four_reflection_paths, Some(658));
    let kept = four.ghosts.iter().filter(|g| g.is_four()).count();
    assert!(kept > 0 && kept < 658, "{kept} kept");
    assert_eq!(
        started.load(std::sync::atomic::Ordering::Relaxed),
        28 + kept
    );
    assert_eq!(&four.ghosts[..28], &two.ghosts[..]);
    // Every four-reflection path the table left out has a bound below the threshold at both
    // angles, so the lowest-bound path of all is not in it.
    assert!(kept < enumerate_four_reflection_ghosts(&sys).len());
    let text = serde_json::to_string(&four).unwrap();
    assert!(text.contains(r#""version":4"#) && text.contains(r#""third":"#));
    let back: BoundsTable = serde_json::from_str(&text).unwrap();
    assert!(back == four);
    // A version-3 file with a four-reflection path, or a version-4 file without the threshold,
    // is refused.
    let mut bad = four.clone();
    bad.version = VERSION;
    assert!(bad.check_for(&sys).is_err());
    let mut bad = two.clone();
    bad.version = VERSION_FOUR;
    assert!(bad.check_for(&sys).is_err());
    for (old, table) in [(1, &two), (2, &four)] {
        let mut stale = table.clone();
        stale.version = old;
        let err = stale.check_for(&sys).unwrap_err();
        assert!(err.contains("run `flarebench precompute` again"), "{err}");
    }
    // A version-3 file of two-reflection ghosts reads, and writes back unchanged.
    let fp = flarebench_sdk::ghost::table::fingerprint(&sys);
    let written = format!(
        r#"{{"format":"flarebench-ghost-bounds","version":3,"lens":"heliar-tronnier","lens_fingerprint":"{fp}","mode":"approximate","wavelength_nm":550.0,"angles_deg":[0.0],"ghosts":[{{"first":1,"second":0}}],"bounds":[[null]]}}"#
    );
    let t: BoundsTable = serde_json::from_str(&written).unwrap();
    t.check_for(&sys).unwrap();
    assert_eq!(t.ghosts, vec![GhostPath::two(1, 0)]);
    assert!(!t.has_four_reflections());
    assert_eq!(serde_json::to_string(&t).unwrap(), written);
}
