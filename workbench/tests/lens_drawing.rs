//! The lens drawing: profiles, element outlines and their triangles, the stop and sensor
//! marks, ray fans and their ends, on constructed lenses and every bundled one.

use flarebench::lens_drawing::{
    Bounds, DEFAULT_FAN_RAYS, ElementFill, LensDrawing, RayEnd, RayFan, SurfaceLine, default_fans,
    ghost_fan, ray_fans, standard_fields, trace_path,
};
use flarebench::lens_library;
use flarebench_sdk::ghost::{GhostPath, enumerate_ghosts};
use flarebench_sdk::paraxial::analyse;
use flarebench_sdk::trace::{Ray, Sequence};
use flarebench_sdk::{LensSystem, Medium, Surface, SurfaceKind};
use proptest::prelude::*;

const D_LINE: f64 = 587.5618;

fn glass(nd: f64) -> Medium {
    Medium::Model { nd, vd: Some(60.0) }
}

/// Sag of a sphere of radius `r` at height `y`, written independently of `Surface::sag`.
fn sphere_sag(r: f64, y: f64) -> f64 {
    if r.is_infinite() {
        0.0
    } else {
        r - r.signum() * (r * r - y * y).sqrt()
    }
}

/// A stop 2 mm in front of a biconvex singlet (R 50 / −80, 6 mm of n 1.5168, semi-diameter
/// 12), the sensor at the paraxial focus.
fn singlet(stop_semi: f64) -> LensSystem {
    let mut sys = LensSystem::new(
        "singlet",
        vec![
            Surface::stop(2.0, stop_semi),
            Surface::spherical(50.0, 6.0, glass(1.5168), 12.0),
            Surface::spherical(-80.0, 50.0, Medium::Air, 12.0),
            Surface::sensor(20.0),
        ],
    );
    let p = analyse(&sys, D_LINE).unwrap();
    sys.surfaces[2].thickness = p.bfl_mm;
    sys.validate().unwrap();
    sys
}

fn bundled() -> Vec<(String, LensSystem)> {
    let names = lens_library::bundled_names();
    assert!(names.len() >= 10, "bundled lenses: {names:?}");
    names
        .into_iter()
        .map(|n| {
            let sys = lens_library::load(&n, true).unwrap().system;
            (n, sys)
        })
        .collect()
}

fn has_point(points: &[[f64; 2]], p: [f64; 2], tol: f64) -> bool {
    points
        .iter()
        .any(|q| (q[0] - p[0]).abs() <= tol && (q[1] - p[1]).abs() <= tol)
}

/// Twice the signed area (shoelace) of a closed polygon.
fn shoelace2(outline: &[[f64; 2]]) -> f64 {
    let n = outline.len();
    (0..n)
        .map(|i| {
            let (a, b) = (outline[i], outline[(i + 1) % n]);
            a[0] * b[1] - b[0] * a[1]
        })
        .sum()
}

fn triangle2(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1])
}

/// The triangles cover exactly the outline: every triangle wound like the outline, and their
/// areas add up to its area.
fn assert_triangles_cover(e: &ElementFill, what: &str) {
    let area = shoelace2(&e.outline);
    assert!(area.abs() > 0.0, "{what} {:?}: no area", e.rows);
    let mut sum = 0.0;
    for t in &e.triangles {
        let [a, b, c] = t.map(|i| e.outline[i as usize]);
        let t2 = triangle2(a, b, c);
        assert!(
            t2 * area >= 0.0,
            "{what} {:?}: triangle {t:?} wound against the outline",
            e.rows
        );
        sum += t2;
    }
    let scale = area.abs().max(1e-9);
    assert!(
        ((sum - area) / scale).abs() < 1e-9,
        "{what} {:?}: triangles {sum} vs outline {area}",
        e.rows
    );
}

/// The outline is a stack of trapezoids: up one side with y strictly rising, down the other
/// with y strictly falling at the same heights (the apex, where the sides meet, shared), the
/// second side strictly behind the first at every height. That makes it a simple polygon.
fn assert_stacked(e: &ElementFill, what: &str) {
    let o = &e.outline;
    let top = (1..o.len())
        .find(|&k| o[k][1] <= o[k - 1][1])
        .map_or(o.len(), |k| k);
    let front = &o[..top];
    let back = &o[top..];
    let apex = front.len() == back.len() + 2;
    assert!(
        apex || front.len() == back.len(),
        "{what} {:?}: sides of {} and {} points",
        e.rows,
        front.len(),
        back.len()
    );
    let inner = if apex {
        &front[1..front.len() - 1]
    } else {
        front
    };
    for (f, b) in inner.iter().zip(back.iter().rev()) {
        assert_eq!(f[1], b[1], "{what} {:?}: heights differ", e.rows);
        assert!(
            b[0] > f[0],
            "{what} {:?}: sides cross at y = {}",
            e.rows,
            f[1]
        );
    }
    assert!(back.windows(2).all(|w| w[1][1] < w[0][1]));
}

/// No two non-adjacent edges of the closed polygon meet (sweep over y).
fn assert_simple(outline: &[[f64; 2]], what: &str) {
    let n = outline.len();
    let edge = |i: usize| (outline[i], outline[(i + 1) % n]);
    let mut order: Vec<usize> = (0..n).collect();
    let ymin = |i: usize| edge(i).0[1].min(edge(i).1[1]);
    let ymax = |i: usize| edge(i).0[1].max(edge(i).1[1]);
    order.sort_by(|&a, &b| ymin(a).total_cmp(&ymin(b)));
    for (k, &i) in order.iter().enumerate() {
        for &j in &order[k + 1..] {
            if ymin(j) > ymax(i) {
                break;
            }
            let adjacent = (i + 1) % n == j || (j + 1) % n == i;
            if adjacent {
                continue;
            }
            let (a, b) = edge(i);
            let (c, d) = edge(j);
            let d1 = triangle2(a, b, c);
            let d2 = triangle2(a, b, d);
            let d3 = triangle2(c, d, a);
            let d4 = triangle2(c, d, b);
            let crosses = d1 * d2 <= 0.0 && d3 * d4 <= 0.0;
            let bbox = a[0].min(b[0]) <= c[0].max(d[0])
                && c[0].min(d[0]) <= a[0].max(b[0])
                && a[1].min(b[1]) <= c[1].max(d[1])
                && c[1].min(d[1]) <= a[1].max(b[1]);
            assert!(
                !(crosses && bbox),
                "{what}: edges {i} {:?} and {j} {:?} meet",
                edge(i),
                edge(j)
            );
        }
    }
}

/// Every point the drawing and the fans hold lies in `bounds`.
fn assert_bounded(d: &LensDrawing, fans: &[RayFan], what: &str) {
    let b: Bounds = d.bounds;
    let mut points: Vec<[f64; 2]> = Vec::new();
    points.extend(d.surfaces.iter().flat_map(|s| s.points.iter().copied()));
    points.extend(d.elements.iter().flat_map(|e| e.outline.iter().copied()));
    if let Some(s) = d.stop {
        points.extend(s.jaws().into_iter().flatten());
    }
    points.extend(d.sensor.line());
    points.extend(
        fans.iter()
            .flat_map(|f| &f.rays)
            .flat_map(|r| r.points.iter().copied()),
    );
    for p in points {
        assert!(
            p[0].is_finite() && p[1].is_finite(),
            "{what}: non-finite point {p:?}"
        );
        assert!(b.contains(p), "{what}: {p:?} outside {b:?}");
    }
}

#[test]
fn singlet_outline_lies_on_the_analytic_sag() {
    let sys = singlet(10.0);
    let d = LensDrawing::new(&sys);
    assert_eq!(d.elements.len(), 1);
    let e = &d.elements[0];
    assert_eq!(e.rows, (1, 2));
    assert_eq!(e.n_d, 1.5168);
    assert_eq!(e.abbe, Some(60.0));
    let (z1, z2) = (2.0, 8.0);
    let on_front = |p: [f64; 2]| (p[0] - (z1 + sphere_sag(50.0, p[1]))).abs() < 1e-9;
    let on_back = |p: [f64; 2]| (p[0] - (z2 + sphere_sag(-80.0, p[1]))).abs() < 1e-9;
    for &p in &e.outline {
        assert!(p[1].abs() <= 12.0);
        assert!(on_front(p) || on_back(p), "{p:?} on neither surface");
    }
    let front = e.outline.iter().filter(|&&p| on_front(p)).count();
    let back = e.outline.iter().filter(|&&p| on_back(p)).count();
    assert!(front >= 64 && back >= 64, "{front} / {back} points");
    // The four rims, exactly.
    for (z0, r) in [(z1, 50.0), (z2, -80.0)] {
        for y in [12.0, -12.0] {
            assert!(has_point(&e.outline, [z0 + sphere_sag(r, y), y], 1e-12));
        }
    }
    // Every profile point is an outline vertex; the profiles span the semi-diameters.
    for s in &d.surfaces[1..3] {
        assert_eq!(s.kind, SurfaceKind::Refracting);
        assert_eq!(s.points.first().unwrap()[1], -12.0);
        assert_eq!(s.points.last().unwrap()[1], 12.0);
        for &p in &s.points {
            assert!(has_point(&e.outline, p, 0.0), "{p:?}");
        }
    }
    assert_triangles_cover(e, "singlet");
    assert_stacked(e, "singlet");
    assert_simple(&e.outline, "singlet");
}

#[test]
fn profiles_follow_conics_and_aspheres() {
    let mut s = Surface::spherical(30.0, 5.0, glass(1.6), 10.0);
    s.conic = -1.5;
    s.aspheric[1] = 2e-5;
    let sys = LensSystem::new(
        "asphere",
        vec![
            Surface::stop(1.0, 8.0),
            s.clone(),
            Surface::spherical(-40.0, 30.0, Medium::Air, 10.0),
            Surface::sensor(20.0),
        ],
    );
    let d = LensDrawing::new(&sys);
    let line = &d.surfaces[1].points;
    for p in line {
        let c: f64 = 1.0 / 30.0;
        let r2 = p[1] * p[1];
        let want = 1.0 + c * r2 / (1.0 + (1.0 - (1.0 - 1.5) * c * c * r2).sqrt()) + 2e-5 * r2 * r2;
        assert!((p[0] - want).abs() < 1e-12, "{p:?} vs {want}");
    }
    // Smooth: no chord strays from the curve by more than a micron at its midpoint.
    for w in line.windows(2) {
        let y = 0.5 * (w[0][1] + w[1][1]);
        let mid = 1.0 + s.sag(y.abs()).unwrap();
        assert!((mid - 0.5 * (w[0][0] + w[1][0])).abs() < 1e-3);
    }
}

#[test]
fn plano_convex_with_different_semi_diameters_gets_a_flat_step() {
    // Convex front (R 40, semi-diameter 10), flat back (semi-diameter 14), 6 mm thick.
    let sys = LensSystem::new(
        "plano-convex",
        vec![
            Surface::stop(1.0, 9.0),
            Surface::spherical(40.0, 6.0, glass(1.5), 10.0),
            Surface::spherical(0.0, 70.0, Medium::Air, 14.0),
            Surface::sensor(20.0),
        ],
    );
    sys.validate().unwrap();
    let d = LensDrawing::new(&sys);
    let e = &d.elements[0];
    let z_rim = 1.0 + sphere_sag(40.0, 10.0);
    for y in [1.0, -1.0] {
        // Front rim, the step's outer end, the back's rim on the edge parallel to the axis.
        assert!(has_point(&e.outline, [z_rim, 10.0 * y], 1e-12));
        assert!(has_point(&e.outline, [z_rim, 14.0 * y], 1e-12));
        assert!(has_point(&e.outline, [7.0, 14.0 * y], 1e-12));
    }
    // Between the two semi-diameters the front side is the step: one z, perpendicular to the
    // axis; no vertex lies off the step, the convex profile or the flat back.
    for &p in &e.outline {
        let on_step = p[1].abs() >= 10.0 && (p[0] - z_rim).abs() < 1e-12;
        // (`Surface::sag` and `sphere_sag` agree to rounding.)
        let on_front = p[1].abs() <= 10.0 && (p[0] - 1.0 - sphere_sag(40.0, p[1])).abs() < 1e-12;
        let on_back = p[0] == 7.0;
        assert!(on_step || on_front || on_back, "{p:?}");
    }
    // The top edge: from the step's outer end straight to the back rim.
    let n = e.outline.len();
    let top = (0..n)
        .find(|&k| has_point(&e.outline[k..=k], [z_rim, 14.0], 1e-12))
        .expect("step end");
    assert_eq!(e.outline[(top + 1) % n], [7.0, 14.0]);
    assert_triangles_cover(e, "plano-convex");
    assert_stacked(e, "plano-convex");
    assert_simple(&e.outline, "plano-convex");

    // The other way round (the flat side smaller): the step is on the back.
    let mut flipped = sys.clone();
    flipped.surfaces[1].semi_diameter = 14.0;
    flipped.surfaces[1].curvature = 1.0 / 80.0;
    flipped.surfaces[2].semi_diameter = 10.0;
    let e = &LensDrawing::new(&flipped).elements[0];
    let z_rim = 1.0 + sphere_sag(80.0, 14.0);
    assert!(has_point(&e.outline, [z_rim, 14.0], 1e-12));
    assert!(has_point(&e.outline, [7.0, 14.0], 1e-12));
    assert!(has_point(&e.outline, [7.0, 10.0], 1e-12));
    assert_triangles_cover(e, "flipped");
    assert_simple(&e.outline, "flipped");
}

#[test]
fn cemented_neighbours_share_their_common_surface() {
    let sys = LensSystem::new(
        "doublet",
        vec![
            Surface::stop(1.0, 10.0),
            Surface::spherical(60.0, 7.0, glass(1.62), 12.0),
            Surface::spherical(-40.0, 2.5, glass(1.72), 12.5),
            Surface::spherical(-150.0, 80.0, Medium::Air, 13.0),
            Surface::sensor(20.0),
        ],
    );
    sys.validate().unwrap();
    let d = LensDrawing::new(&sys);
    assert_eq!(d.elements.len(), 2);
    assert_eq!((d.elements[0].rows, d.elements[1].rows), ((1, 2), (2, 3)));
    let z2 = 8.0;
    let on_common =
        |p: &&[f64; 2]| p[1].abs() <= 12.5 && (p[0] - (z2 + sphere_sag(-40.0, p[1]))).abs() < 1e-12;
    let mut a: Vec<[f64; 2]> = d.elements[0]
        .outline
        .iter()
        .filter(on_common)
        .copied()
        .collect();
    let mut b: Vec<[f64; 2]> = d.elements[1]
        .outline
        .iter()
        .filter(on_common)
        .copied()
        .collect();
    a.sort_by(|p, q| p[1].total_cmp(&q[1]));
    b.sort_by(|p, q| p[1].total_cmp(&q[1]));
    assert!(a.len() > 64);
    assert_eq!(a, b);
    for e in &d.elements {
        assert_triangles_cover(e, "doublet");
        assert_simple(&e.outline, "doublet");
    }
}

#[test]
fn a_semi_diameter_beyond_the_sphere_is_clipped_where_the_sag_exists() {
    // R 10 with semi-diameter 12: invalid, but drawn (to the sphere's equator) without panic.
    let sys = LensSystem::new(
        "ball",
        vec![
            Surface::stop(1.0, 5.0),
            Surface::spherical(10.0, 12.0, glass(1.5), 12.0),
            Surface::spherical(-10.0, 20.0, Medium::Air, 12.0),
            Surface::sensor(20.0),
        ],
    );
    assert!(sys.validate().is_err());
    let d = LensDrawing::new(&sys);
    let line = &d.surfaces[1].points;
    let top = line.last().unwrap();
    assert!(top[1] <= 10.0 && top[1] > 10.0 - 1e-6, "{top:?}");
    assert!((top[0] - 11.0).abs() < 1e-3, "{top:?}");
    for e in &d.elements {
        assert_triangles_cover(e, "ball");
        assert_stacked(e, "ball");
    }
    let fans = default_fans(&sys);
    assert_bounded(&d, &fans, "ball");
}

#[test]
fn crossing_sides_end_the_element_where_they_meet() {
    // A biconvex lens too thin for its semi-diameter: the surfaces meet at about 9.2 mm.
    let sys = LensSystem::new(
        "knife",
        vec![
            Surface::stop(1.0, 5.0),
            Surface::spherical(20.0, 4.0, glass(1.5), 12.0),
            Surface::spherical(-20.0, 20.0, Medium::Air, 12.0),
            Surface::sensor(20.0),
        ],
    );
    let e = &LensDrawing::new(&sys).elements[0];
    // sag 2 mm each: 20 − √(400 − y²) = 2 → y = √76.
    let ymax = e.outline.iter().map(|p| p[1]).fold(0.0, f64::max);
    assert!((ymax - 76f64.sqrt()).abs() < 1e-6, "{ymax}");
    assert_triangles_cover(e, "knife");
    assert_stacked(e, "knife");
    assert_simple(&e.outline, "knife");
}

#[test]
fn stop_and_sensor_marks() {
    let mut sys = singlet(10.0);
    sys.f_number = Some(16.0);
    let d = LensDrawing::new(&sys);
    let stop = d.stop.unwrap();
    assert_eq!((stop.row, stop.z), (0, 0.0));
    assert_eq!(stop.opening, flarebench_sdk::paraxial::stop_opening(&sys));
    assert!(stop.opening < 10.0);
    assert!((stop.outer - 12.0).abs() < 1e-12);
    let sensor = d.sensor;
    assert_eq!(sensor.row, 3);
    assert_eq!(sensor.z, sys.total_track());
    assert!((sensor.half_height - 0.5 * 36f64.hypot(24.0)).abs() < 1e-12);
}

#[test]
fn axial_fan_converges_near_the_paraxial_back_focus() {
    // f/12 or so: little spherical aberration.
    let sys = singlet(2.5);
    let p = analyse(&sys, D_LINE).unwrap();
    let fans = ray_fans(&sys, &[0.0], &[D_LINE], 9);
    assert_eq!(fans.len(), 1);
    assert_eq!(fans[0].rays.len(), 9);
    let focus = 8.0 + p.bfl_mm;
    for r in &fans[0].rays {
        assert_eq!(r.end, RayEnd::Sensor);
        // lead-in, stop, two surfaces, sensor.
        assert_eq!(r.points.len(), 5);
        assert!(r.points[0][0] < 0.0, "starts in front of the lens");
        let [a, b] = [r.points[3], r.points[4]];
        if a[1].abs() < 1e-9 {
            continue; // the axial ray
        }
        let z_cross = a[0] - a[1] * (b[0] - a[0]) / (b[1] - a[1]);
        assert!(
            (z_cross - focus).abs() < 0.002 * p.efl_mm,
            "crosses at {z_cross}, paraxial focus {focus}"
        );
        // And lands near the axis.
        assert!(b[1].abs() < 0.05, "{b:?}");
    }
}

#[test]
fn a_ray_beyond_the_semi_diameter_ends_vignetted_there() {
    let sys = singlet(20.0);
    let seq = Sequence::forward(&sys, D_LINE);
    let r = trace_path(&seq, &Ray::collimated(0.0, 0.0, 13.0), [-5.0, 13.0]);
    assert_eq!(r.end, RayEnd::Vignetted { row: 1 });
    assert_eq!(r.points.len(), 3, "lead-in, stop, surface 1");
    let last = *r.points.last().unwrap();
    assert!((last[0] - (2.0 + sphere_sag(50.0, 13.0))).abs() < 1e-9);
    assert!((last[1] - 13.0).abs() < 1e-12);
    // Outside the stop's opening: vignetted at the stop.
    let sys = singlet(10.0);
    let seq = Sequence::forward(&sys, D_LINE);
    let r = trace_path(&seq, &Ray::collimated(0.0, 0.0, 11.0), [-5.0, 11.0]);
    assert_eq!(r.end, RayEnd::Vignetted { row: 0 });
    assert_eq!(r.points, vec![[-5.0, 11.0], [0.0, 11.0]]);
}

#[test]
fn total_internal_reflection_ends_the_ray_on_that_surface() {
    // A flat-fronted block of n 1.8 with a strongly convex back (R −10): a ray parallel to the
    // axis 7 mm up meets the back at 44° from its normal, past the critical angle (33.7°).
    let sys = LensSystem::new(
        "tir",
        vec![
            Surface::stop(1.0, 9.0),
            Surface::spherical(0.0, 12.0, glass(1.8), 9.0),
            Surface::spherical(-10.0, 20.0, Medium::Air, 9.0),
            Surface::sensor(20.0),
        ],
    );
    sys.validate().unwrap();
    let seq = Sequence::forward(&sys, D_LINE);
    let r = trace_path(&seq, &Ray::collimated(0.0, 0.0, 7.0), [-3.0, 7.0]);
    assert_eq!(r.end, RayEnd::TotalInternalReflection { row: 2 });
    assert_eq!(r.end.row(), Some(2));
    let last = *r.points.last().unwrap();
    assert!(
        (last[0] - (13.0 + sphere_sag(-10.0, 7.0))).abs() < 1e-9,
        "{last:?}"
    );
    assert!((last[1] - 7.0).abs() < 1e-9);
    // The tracer completed the lead-in, the stop and the front face; the last point is where
    // it reflected.
    assert_eq!(r.completed, 3);
    assert_eq!(r.points.len(), 4);
    assert_eq!(r.completed_points(), &r.points[..3]);
    // Near the axis the same lens refracts.
    let r = trace_path(&seq, &Ray::collimated(0.0, 0.0, 3.0), [-3.0, 3.0]);
    assert_eq!(r.end, RayEnd::Sensor);
}

#[test]
fn a_ray_that_misses_a_surface_ends_at_its_vertex_plane() {
    // A hemisphere-like front (R 5, semi-diameter 4.9) and a ray 6 mm up: its line never
    // meets the sphere.
    let sys = LensSystem::new(
        "miss",
        vec![
            Surface::spherical(5.0, 5.0, glass(1.5), 4.9),
            Surface::spherical(0.0, 5.0, Medium::Air, 4.9),
            Surface::stop(10.0, 3.0),
            Surface::sensor(20.0),
        ],
    );
    sys.validate().unwrap();
    let seq = Sequence::forward(&sys, D_LINE);
    let r = trace_path(&seq, &Ray::collimated(0.0, 0.0, 6.0), [-3.0, 6.0]);
    assert_eq!(r.end, RayEnd::Missed { row: 0 });
    assert_eq!(r.points, vec![[-3.0, 6.0], [0.0, 6.0]]);
    assert_eq!(r.completed, 1);
}

#[test]
fn a_ghost_fan_goes_back_and_forth() {
    let sys = lens_library::load("heliar-tronnier", true).unwrap().system;
    let fan = ghost_fan(&sys, GhostPath::two(4, 1), 0.0, D_LINE, 5);
    assert_eq!(fan.rays.len(), 5);
    assert_eq!((fan.field_deg, fan.wavelength_nm), (0.0, D_LINE));
    for r in &fan.rays {
        assert!(
            r.points.windows(2).any(|w| w[1][0] < w[0][0] - 1e-9),
            "no backward leg: {:?}",
            r.points
        );
    }
    // Surfaces 0..=4, back 3..=1, forward 2..=8 and the sensor, after the lead-in: the
    // unvignetted rays have them all and end on the sensor.
    let through: Vec<_> = fan
        .rays
        .iter()
        .filter(|r| r.end == RayEnd::Sensor)
        .collect();
    assert!(!through.is_empty());
    for r in through {
        assert_eq!(r.points.len(), 1 + 5 + 3 + 8);
        assert!((r.points.last().unwrap()[0] - sys.total_track()).abs() < 1e-9);
    }
    // A path the lens does not have: no rays.
    assert!(
        ghost_fan(&sys, GhostPath::two(1, 4), 0.0, D_LINE, 5)
            .rays
            .is_empty()
    );
}

#[test]
fn surface_at_finds_the_surface_under_a_point() {
    let sys = singlet(10.0);
    let d = LensDrawing::new(&sys);
    let line: &SurfaceLine = &d.surfaces[1];
    let p = line.points[line.points.len() / 3];
    assert_eq!(d.surface_at(p[0], p[1], 0.05), Some(1));
    // Slightly off the profile, still within the tolerance.
    assert_eq!(d.surface_at(p[0] + 0.03, p[1], 0.05), Some(1));
    let q = d.surfaces[2].points[5];
    assert_eq!(d.surface_at(q[0], q[1], 0.05), Some(2));
    // The stop's jaw and the sensor.
    assert_eq!(d.surface_at(0.0, 11.0, 0.05), Some(0));
    assert_eq!(d.surface_at(d.sensor.z, -20.0, 0.05), Some(3));
    // Far away, or inside the glass away from both surfaces.
    assert_eq!(d.surface_at(500.0, 500.0, 1.0), None);
    assert_eq!(d.surface_at(5.0, 0.0, 0.5), None);
    // Nearest first.
    let near = d.surfaces_near(2.0, 0.0, 10.0);
    assert_eq!(near[0].0, 1);
    assert!(near.windows(2).all(|w| w[0].1 <= w[1].1));
    // Inside the glass.
    assert_eq!(d.element_at(5.0, 0.0), Some(0));
    assert_eq!(d.element_at(5.0, 20.0), None);
}

#[test]
fn standard_fields_follow_the_film_diagonal() {
    let sys = singlet(10.0);
    let p = analyse(&sys, D_LINE).unwrap();
    let [a, b, c] = standard_fields(&sys).unwrap();
    let full = (0.5 * 36f64.hypot(24.0) / p.efl_mm).atan().to_degrees();
    assert_eq!(a, 0.0);
    assert!((c - full).abs() < 1e-12);
    assert!((b - 0.7 * full).abs() < 1e-12);
    // No paraxial data without a stop.
    let mut no_stop = sys.clone();
    no_stop.surfaces.remove(0);
    assert_eq!(standard_fields(&no_stop), None);
    let d = LensDrawing::new(&no_stop);
    assert!(d.stop.is_none());
    assert_bounded(&d, &default_fans(&no_stop), "no stop");
}

/// One curated lens in this many has every ghost's fan drawn in the default tier (the lenses
/// at the top of `lenses/` all have; the slow tier draws every lens's).
const GHOST_FAN_SAMPLE_STEP: usize = 16;

#[test]
fn every_bundled_lens_draws() {
    every_bundled_lens_draws_with_ghost_fans_every(GHOST_FAN_SAMPLE_STEP);
}

#[test]
#[ignore = "slow tier: every ghost's fan of every curated lens; by default one lens in 16"]
fn every_bundled_lens_draws_every_ghost_fan() {
    every_bundled_lens_draws_with_ghost_fans_every(1);
}

/// Every bundled lens's section, outlines and fans; the ghosts' fans of the core lenses and of
/// one curated lens in `ghost_fan_step`.
fn every_bundled_lens_draws_with_ghost_fans_every(ghost_fan_step: usize) {
    let core = lens_library::core_names();
    for (k, (name, sys)) in bundled().into_iter().enumerate() {
        let is_core = core.contains(&name);
        let d = LensDrawing::new(&sys);
        assert_eq!(d.surfaces.len(), sys.surfaces.len(), "{name}");
        assert!(d.stop.is_some(), "{name}");
        assert!(!d.elements.is_empty(), "{name}");
        for s in &d.surfaces {
            let want = sys.surfaces[s.row].semi_diameter;
            let top = s.points.last().unwrap()[1];
            assert!(
                (top - want).abs() < 1e-12,
                "{name} row {}: {top} vs {want}",
                s.row
            );
        }
        for e in &d.elements {
            let what = format!("{name} {:?}", e.rows);
            assert_triangles_cover(e, &what);
            assert_stacked(e, &what);
            assert_simple(&e.outline, &what);
        }
        let fans = default_fans(&sys);
        assert_eq!(fans.len(), 3, "{name}");
        assert_bounded(&d, &fans, &name);
        // The axial fan reaches the sensor: all of it, except where the paraxial entrance
        // pupil is wider than the front element (the Kreitzer telephoto's file scales the
        // surfaces by 4 but not the semi-diameters: its pupil is 129 mm across, its front
        // element 71 mm), whose outer rays are blocked there. A curated lens's patent clear
        // apertures may clip its outermost axial rays (a fast lens's real pupil differs from
        // the paraxial one): its middle ray must get through.
        let ends: Vec<RayEnd> = fans[0].rays.iter().map(|r| r.end).collect();
        let p = analyse(&sys, sys.default_wavelength_nm()).unwrap();
        if is_core && 0.5 * p.entrance_pupil_diameter_mm < sys.surfaces[0].semi_diameter {
            assert!(
                ends.iter().all(|&e| e == RayEnd::Sensor),
                "{name}: {ends:?}"
            );
        } else {
            assert_eq!(
                ends[DEFAULT_FAN_RAYS / 2],
                RayEnd::Sensor,
                "{name}: {ends:?}"
            );
        }
        // Other fans and every ghost, at the full field: no panic, finite points.
        if !is_core && k % ghost_fan_step != 0 {
            continue;
        }
        let fields = standard_fields(&sys).unwrap();
        let more = ray_fans(&sys, &fields, &[450.0, 650.0], 5);
        assert_eq!(more.len(), 6);
        for g in enumerate_ghosts(&sys) {
            let fan = ghost_fan(&sys, g, fields[2], D_LINE, 3);
            for r in fan.rays.iter().chain(more.iter().flat_map(|f| &f.rays)) {
                assert!(r.points.len() >= 2, "{name} {g}");
                assert!(
                    r.points.iter().flatten().all(|v| v.is_finite()),
                    "{name} {g}"
                );
            }
        }
    }
}

/// A random system: a few surfaces of any shape and medium (not necessarily valid), a stop
/// somewhere among them, the sensor last.
fn arb_system() -> impl Strategy<Value = LensSystem> {
    let surface = (
        prop_oneof![Just(0.0), -0.3..0.3f64],
        prop_oneof![Just(0.0), -3.0..3.0f64],
        prop_oneof![Just(0.0), -1e-4..1e-4f64],
        0.0..15.0f64,
        0.2..20.0f64,
        prop_oneof![Just(None), (1.4..2.0f64).prop_map(Some)],
    )
        .prop_map(|(c, k, a4, t, sd, nd)| {
            let mut s = Surface::spherical(0.0, t, nd.map_or(Medium::Air, glass), sd);
            s.curvature = c;
            s.conic = k;
            s.aspheric[1] = a4;
            s
        });
    (
        prop::collection::vec(surface, 1..6),
        0usize..6,
        0.0..10.0f64,
        0.2..15.0f64,
        prop_oneof![Just(0.0), 1.0..25.0f64],
        prop_oneof![Just(None), (1.0..22.0f64).prop_map(Some)],
    )
        .prop_map(|(mut surfaces, at, t, sd, sensor, f_number)| {
            let at = at.min(surfaces.len());
            surfaces.insert(at, Surface::stop(t, sd));
            surfaces.push(Surface::sensor(sensor));
            let mut sys = LensSystem::new("random", surfaces);
            sys.f_number = f_number;
            sys
        })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    #[test]
    fn any_system_draws_without_panic(sys in arb_system()) {
        let d = LensDrawing::new(&sys);
        for e in &d.elements {
            assert_triangles_cover(e, "random");
            assert_stacked(e, "random");
        }
        let fans = default_fans(&sys);
        assert_bounded(&d, &fans, "random");
        for g in enumerate_ghosts(&sys).into_iter().take(6) {
            let _ = ghost_fan(&sys, g, 5.0, 500.0, 3);
        }
        let _ = d.surface_at(1.0, 1.0, 0.1);
    }
}

#[test]
fn degenerate_systems_do_not_panic() {
    let empty = LensSystem::new("empty", Vec::new());
    let d = LensDrawing::new(&empty);
    assert!(d.surfaces.is_empty() && d.elements.is_empty() && d.stop.is_none());
    assert!(ray_fans(&empty, &[0.0], &[D_LINE], 3)[0].rays.is_empty());
    let sensor_only = LensSystem::new("sensor", vec![Surface::sensor(0.0)]);
    let _ = LensDrawing::new(&sensor_only);
    let _ = default_fans(&sensor_only);
    // Odd fields and wavelengths give empty fans.
    let sys = singlet(10.0);
    let fans = ray_fans(&sys, &[95.0, f64::NAN], &[-1.0, D_LINE], 3);
    assert_eq!(fans.len(), 4);
    assert!(fans.iter().all(|f| f.rays.is_empty()));
}
